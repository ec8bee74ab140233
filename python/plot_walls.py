#!/usr/bin/env python3
"""The three walls of the perception study side by side (one tap each): wall 0 single impulse,
wall 1 impulse train at 250 Hz, wall 2 impulse train at 50 Hz. Each panel shows the penalty
force, the impulsive force and their sum along the wall normal, impulses marked.

Usage: plot_walls.py WALL0.csv WALL1.csv WALL2.csv --out FIG.png [--tap K] [--labels A B C]
Exit codes: 0 figure written, 2 bad arguments or trace, 3 matplotlib missing.
"""

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import trace_io  # noqa: E402

DEFAULT_LABELS = ["wall 0: single impulse", "wall 1: train 250 Hz", "wall 2: train 50 Hz"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("traces", nargs=3, help="trace CSV of wall 0, wall 1 and wall 2")
    parser.add_argument("--out", required=True, help="output image (PNG, PDF or SVG)")
    parser.add_argument("--tap", type=int, default=0, help="scripted tap index (default 0)")
    parser.add_argument("--labels", nargs=3, default=DEFAULT_LABELS, help="panel titles")
    parser.add_argument("--before-ms", type=float, default=5.0)
    parser.add_argument("--after-ms", type=float, default=150.0)
    args = parser.parse_args()

    plt = trace_io.import_pyplot()
    panels = []
    try:
        for path in args.traces:
            columns = trace_io.read_trace(path)
            panels.append((columns, trace_io.tap_rows(columns, args.tap)))
    except SystemExit as error:
        print(error, file=sys.stderr)
        return 2

    fig, axes = plt.subplots(1, 3, figsize=(13, 4), sharey=True)
    for ax, label, (columns, rows) in zip(axes, args.labels, panels):
        time_s = columns["time_s"]
        penalty = trace_io.normal_component(columns, "penalty_f", "N")
        impulsive = trace_io.normal_component(columns, "impulsive_f", "N")
        onset = next((i for i in rows if columns["tool_contacts"][i] > 0), rows[0])
        t0 = time_s[onset]
        rows = [i for i in rows if -args.before_ms <= (time_s[i] - t0) * 1e3 <= args.after_ms]
        t_ms = [(time_s[i] - t0) * 1e3 for i in rows]
        # the sum first, wide and grey, so the parts stay visible on top of it
        ax.step(t_ms, [penalty[i] + impulsive[i] for i in rows], where="post", label="sum",
                color="0.55", linewidth=2.4)
        ax.step(t_ms, [penalty[i] for i in rows], where="post", label="penalty",
                color="tab:blue", linewidth=1.1)
        ax.step(t_ms, [impulsive[i] for i in rows], where="post", label="impulsive (Eq. 9)",
                color="tab:orange", linewidth=1.1)
        impulse_rows = [i for i in rows if columns["impulses"][i] > 0]
        for n, i in enumerate(impulse_rows):
            ax.axvline((time_s[i] - t0) * 1e3, color="tab:gray", linestyle=":", linewidth=0.8,
                       label="impulse" if n == 0 else None)
        ax.set_title(f"{label} ({len(impulse_rows)} impulses)")
        ax.set_xlabel("time from contact onset [ms]")
        ax.grid(True, alpha=0.3)
    axes[0].set_ylabel("force along wall normal [N]")
    axes[0].legend(loc="best")
    fig.tight_layout()
    try:
        fig.savefig(args.out, dpi=150)
    except OSError as error:
        print(f"error: cannot write figure '{args.out}': {error.strerror}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
