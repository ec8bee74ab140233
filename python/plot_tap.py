#!/usr/bin/env python3
"""One tap of a rigidtouch trace: the force the device displayed against its force limit, the
requested force and its penalty and impulsive (Eq. 9) parts, a zoom on the first 40 ms with the
impulse instants, penetration and velocity, and the spectrum of the displayed force and of its
transient part over the collision window.

Usage: plot_tap.py TRACE.csv --out FIG.png [--tap K] [--limit N] [--title T] [--before-ms 5]
                   [--after-ms 150] [--full] [--dump PLOTTED.json] [--joint JOINT.csv]

With --joint (a moving wall's joint trace, written by rigidtouch tap beside the trace), a bottom
panel shows the joint's angle (or position) and velocity over the whole tap.
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
    parser.add_argument("--limit", type=float, default=0.0,
                        help="the device's force limit [N], drawn as a line (0: no limit)")
    parser.add_argument("--before-ms", type=float, default=5.0,
                        help="time shown before contact onset [ms]")
    parser.add_argument("--after-ms", type=float, default=150.0,
                        help="time shown after contact onset [ms]")
    parser.add_argument("--zoom-ms", type=float, default=40.0)
    parser.add_argument("--full", action="store_true", help="show the whole tap")
    parser.add_argument("--title", default=None,
                        help="figure title (default: the trace's file name and the tap)")
    parser.add_argument("--dump", default=None, help="also write what is plotted as JSON")
    parser.add_argument("--parts-label", default="impulses (Eq. 9 force)",
                        help="what the renderer adds to the penalty force, for the legend")
    parser.add_argument("--window-ms", default=None,
                        help="the tap metrics' spectral window (rigidtouch tap passes it)")
    parser.add_argument("--resolution-hz", default=None, help="its resolution")
    parser.add_argument("--repetition", default=None,
                        help="the tap metrics' repetition rate of the transient, as stated")
    parser.add_argument("--joint", default=None,
                        help="a moving wall's joint trace (rigidtouch tap writes it)")
    parser.add_argument("--material-model", nargs=5, default=None,
                        metavar=("NAME", "A", "B", "F", "V"),
                        help="the material the renderer used, drawn beside the rendered force: "
                        "Q(t) = A v e^(-B t) sin(2 pi f t) from the contact onset, A [N s/m], "
                        "B [1/s], f [Hz], v the tap's impact speed [m/s]")
    args = parser.parse_args()
    model = None
    if args.material_model:
        try:
            a, b, f, v = (float(x) for x in args.material_model[1:])
        except ValueError:
            print(f"error: --material-model: A, B, F and V must be numbers, got "
                  f"{' '.join(args.material_model[1:])}", file=sys.stderr)
            return 2
        model = {"name": args.material_model[0], "amplitude_Ns_per_m": a, "decay_per_s": b,
                 "frequency_hz": f, "impact_speed_mps": v}

    plt = trace_io.import_pyplot()
    import tap_panels
    try:
        columns = trace_io.read_trace(args.trace)
        after = float("inf") if args.full else args.after_ms
        before = float("inf") if args.full else args.before_ms
        s = tap_panels.tap_series(columns, args.tap, before, after)
        joint = (tap_panels.joint_series(args.joint, args.tap, s["onset_s"])
                 if args.joint else None)
    except SystemExit as error:
        print(error, file=sys.stderr)
        return 2

    plt.rcParams.update({"font.size": 8, "axes.titlesize": 9})
    fig, axes = plt.subplots(3 if joint else 2, 2, figsize=(10, 9.5 if joint else 7))
    tap_panels.draw_force(axes[0][0], s, args.limit, parts=True, parts_label=args.parts_label)
    axes[0][0].set_title(f"displayed peak {s['displayed_peak_N']:.2f} N, requested peak "
                         f"{s['requested_peak_N']:.2f} N")
    tap_panels.draw_force(axes[0][1], s, args.limit, parts=True, zoom_ms=args.zoom_ms,
                          legend=False, parts_label=args.parts_label)
    if model:
        s["material_model"] = tap_panels.draw_material_model(axes[0][1], model, args.zoom_ms)
    axes[0][1].set_title(f"first {args.zoom_ms:g} ms ({len(s['impulse_ms'])} impulse instants "
                         "in the tap shown)")
    for ax in (axes[0][0], axes[0][1], axes[1][0]):
        ax.set_xlabel("time from contact onset [ms]")
    tap_panels.draw_motion(axes[1][0], s)
    tap_panels.draw_spectrum(axes[1][1], s, repetition=args.repetition)
    axes[1][1].set_title(tap_panels.spectrum_title(args.window_ms, args.resolution_hz))
    if joint:
        grid = axes[2][0].get_gridspec()
        axes[2][0].remove()
        axes[2][1].remove()
        ax = fig.add_subplot(grid[2, :])
        tap_panels.draw_joint(ax, joint)
        ax.set_title("the wall's joint over the whole tap")
        s["joint"] = joint
    name = os.path.splitext(os.path.basename(args.trace))[0]
    fig.suptitle(args.title or f"{name}, tap {args.tap}", fontsize=10)
    fig.tight_layout()
    try:
        fig.savefig(args.out, dpi=150)
    except OSError as error:
        print(f"error: cannot write figure '{args.out}': {error.strerror}", file=sys.stderr)
        return 2
    if args.dump:
        s["label"] = args.title or f"{name}, tap {args.tap}"
        try:
            tap_panels.dump(args.dump, [s], args.limit)
        except OSError as error:
            print(f"error: cannot write '{args.dump}': {error.strerror}", file=sys.stderr)
            return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
