#!/usr/bin/env python3
"""Force against time for one tap of a rigidtouch trace: the penalty part, the impulsive part
(Eq. 9) and their sum, all along the wall normal, with the impulse instants marked.

Usage: plot_tap.py TRACE.csv --out FIG.png [--tap K] [--before-ms 5] [--after-ms 150] [--full]
Exit codes: 0 figure written, 2 bad arguments or trace, 3 matplotlib missing.
"""

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import trace_io  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("trace", help="trace CSV written by rigidtouch")
    parser.add_argument("--out", required=True, help="output image (PNG, PDF or SVG)")
    parser.add_argument("--tap", type=int, default=0, help="scripted tap index (default 0)")
    parser.add_argument("--before-ms", type=float, default=5.0,
                        help="time shown before contact onset [ms]")
    parser.add_argument("--after-ms", type=float, default=150.0,
                        help="time shown after contact onset [ms]")
    parser.add_argument("--full", action="store_true", help="show the whole tap")
    parser.add_argument("--title", default=None)
    args = parser.parse_args()

    plt = trace_io.import_pyplot()
    try:
        columns = trace_io.read_trace(args.trace)
        rows = trace_io.tap_rows(columns, args.tap)
    except SystemExit as error:
        print(error, file=sys.stderr)
        return 2

    time_s = columns["time_s"]
    penalty = trace_io.normal_component(columns, "penalty_f", "N")
    impulsive = trace_io.normal_component(columns, "impulsive_f", "N")
    device = trace_io.normal_component(columns, "device_f", "N")
    onset = next((i for i in rows if columns["tool_contacts"][i] > 0), rows[0])
    t0 = time_s[onset]
    if not args.full:
        rows = [i for i in rows
                if -args.before_ms <= (time_s[i] - t0) * 1e3 <= args.after_ms]
    t_ms = [(time_s[i] - t0) * 1e3 for i in rows]
    total = [penalty[i] + impulsive[i] for i in rows]

    fig, ax = plt.subplots(figsize=(7, 4))
    # forces are held over each tick (zero-order hold): draw them as steps
    # the sum first, wide and grey, so the parts stay visible on top of it
    ax.step(t_ms, total, where="post", label="sum", color="0.55", linewidth=2.4)
    ax.step(t_ms, [penalty[i] for i in rows], where="post", label="penalty", color="tab:blue",
            linewidth=1.1)
    ax.step(t_ms, [impulsive[i] for i in rows], where="post", label="impulsive (Eq. 9)",
            color="tab:orange", linewidth=1.1)
    if any(abs(device[i] - (penalty[i] + impulsive[i])) > 1e-9 for i in rows):
        ax.step(t_ms, [device[i] for i in rows], where="post", label="displayed (after limits)",
                color="tab:red", linestyle="--")
    impulse_rows = [i for i in rows if columns["impulses"][i] > 0]
    for n, i in enumerate(impulse_rows):
        ax.axvline((time_s[i] - t0) * 1e3, color="tab:gray", linestyle=":", linewidth=0.8,
                   label="impulse" if n == 0 else None)
    ax.set_xlabel("time from contact onset [ms]")
    ax.set_ylabel("force along wall normal [N]")
    ax.set_title(args.title or f"tap {args.tap}: {len(impulse_rows)} impulse(s)")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best")
    fig.tight_layout()
    try:
        fig.savefig(args.out, dpi=150)
    except OSError as error:
        print(f"error: cannot write figure '{args.out}': {error.strerror}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
