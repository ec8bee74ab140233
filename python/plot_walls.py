#!/usr/bin/env python3
"""Renderers side by side, one column each (one tap): the force the device displayed against its
force limit (with the requested force), a zoom on the first 40 ms, penetration and velocity, and
the spectrum of the displayed force and of its transient part over the collision window. Each
panel has its own force axis, so a train's small impulses are not flattened by a clipped one.

Usage: plot_walls.py TRACE.csv... --out FIG.png [--labels A B ...] [--limit N] [--tap K]
                     [--dump PLOTTED.json] [--joints JOINT.csv...]

With --joints (a moving wall's joint trace per renderer, written by rigidtouch tap), a bottom row
shows each renderer's joint angle (or position) and velocity over the whole tap.
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
    parser.add_argument("traces", nargs="+", help="trace CSV of each renderer")
    parser.add_argument("--out", required=True, help="output image (PNG, PDF or SVG)")
    parser.add_argument("--tap", type=int, default=0, help="scripted tap index (default 0)")
    parser.add_argument("--labels", nargs="+", default=None,
                        help="column titles, one per trace (default: the file names)")
    parser.add_argument("--limit", type=float, default=0.0,
                        help="the device's force limit [N], drawn as a line (0: no limit)")
    parser.add_argument("--before-ms", type=float, default=5.0)
    parser.add_argument("--after-ms", type=float, default=150.0)
    parser.add_argument("--zoom-ms", type=float, default=40.0)
    parser.add_argument("--dpi", type=float, default=150.0)
    parser.add_argument("--dump", default=None, help="also write what is plotted as JSON")
    parser.add_argument("--repetitions", nargs="+", default=None,
                        help="the tap metrics' repetition rate of each trace's transient in "
                             "tap 0, as stated (rigidtouch tap passes them)")
    parser.add_argument("--window-ms", default=None,
                        help="the tap metrics' spectral window (rigidtouch tap passes it)")
    parser.add_argument("--resolution-hz", default=None, help="its resolution")
    parser.add_argument("--joints", nargs="+", default=None,
                        help="a moving wall's joint trace per trace (rigidtouch tap writes them)")
    args = parser.parse_args()
    labels = args.labels
    if labels is None:
        labels = (DEFAULT_LABELS if len(args.traces) == 3
                  else [os.path.splitext(os.path.basename(p))[0] for p in args.traces])
    if len(labels) != len(args.traces):
        print(f"error: {len(args.traces)} traces but {len(labels)} labels", file=sys.stderr)
        return 2
    if args.joints is not None and len(args.joints) != len(args.traces):
        print(f"error: {len(args.traces)} traces but {len(args.joints)} joint traces",
              file=sys.stderr)
        return 2
    repetitions = args.repetitions or [None] * len(args.traces)
    if len(repetitions) != len(args.traces):
        print(f"error: {len(args.traces)} traces but {len(repetitions)} repetitions",
              file=sys.stderr)
        return 2

    plt = trace_io.import_pyplot()
    import tap_panels
    panels = []
    try:
        for path in args.traces:
            columns = trace_io.read_trace(path)
            panels.append(tap_panels.tap_series(columns, args.tap, args.before_ms, args.after_ms))
        joints = [tap_panels.joint_series(path, args.tap, s["onset_s"])
                  for path, s in zip(args.joints, panels)] if args.joints else None
    except SystemExit as error:
        print(error, file=sys.stderr)
        return 2

    n = len(panels)
    plt.rcParams.update({"font.size": 8, "axes.titlesize": 9})
    rows = 5 if joints else 4
    fig, axes = plt.subplots(rows, n, figsize=(3.4 * n + 0.6, 2.6 * rows + 0.1), squeeze=False)
    legend = {}  # one legend for the whole figure: label -> handle
    for c, (label, s) in enumerate(zip(labels, panels)):
        s["label"] = label
        ax = axes[0][c]
        draw = tap_panels.draw_force
        draw(ax, s, args.limit, legend=False)
        ax.set_title(f"{label}\n{len(s['impulse_ms'])} impulse instants shown, "
                     f"displayed peak {s['displayed_peak_N']:.2f} N")
        ax.set_xlabel("time from contact onset [ms]")
        ax = axes[1][c]
        draw(ax, s, args.limit, zoom_ms=args.zoom_ms, legend=False)
        ax.set_title(f"first {args.zoom_ms:g} ms")
        ax.set_xlabel("time from contact onset [ms]")
        right = tap_panels.draw_motion(axes[2][c], s, legend=False)
        axes[2][c].set_xlabel("time from contact onset [ms]")
        for a in (axes[0][c], axes[1][c], axes[2][c], right):
            for handle, text in zip(*a.get_legend_handles_labels()):
                legend.setdefault(text, handle)
        tap_panels.draw_spectrum(axes[3][c], s, legend=True, repetition=repetitions[c])
        axes[3][c].set_title(tap_panels.spectrum_title(args.window_ms, args.resolution_hz))
        if joints:
            right = tap_panels.draw_joint(axes[4][c], joints[c], legend=False)
            axes[4][c].set_title("the wall's joint over the whole tap")
            for a in (axes[4][c], right):
                for handle, text in zip(*a.get_legend_handles_labels()):
                    legend.setdefault(text, handle)
            s["joint"] = joints[c]
    fig.suptitle(f"tap {args.tap}: the force the device displays against its limit, per renderer",
                 fontsize=10)
    # as many entries per row as the figure's width holds (about 1.75 per renderer's column)
    ncol = max(1, min(len(legend), 7, max(2, 7 * n // 4)))
    legend_rows = -(-len(legend) // ncol)
    fig.legend(list(legend.values()), list(legend.keys()), loc="upper center",
               bbox_to_anchor=(0.5, 0.975), ncol=ncol, fontsize=8, frameon=False)
    fig.tight_layout(rect=(0.0, 0.0, 1.0, 0.965 - 0.012 * legend_rows * 4 / rows))
    try:
        fig.savefig(args.out, dpi=args.dpi)
    except OSError as error:
        print(f"error: cannot write figure '{args.out}': {error.strerror}", file=sys.stderr)
        return 2
    if args.dump:
        try:
            tap_panels.dump(args.dump, panels, args.limit)
        except OSError as error:
            print(f"error: cannot write '{args.dump}': {error.strerror}", file=sys.stderr)
            return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
