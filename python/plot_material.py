#!/usr/bin/env python3
"""A fitted material (rigidtouch material fit --plot): the recorded taps over the fitted decaying
sinusoid, the amplitude against the impact speed with the fitted line, and the power spectrum of
the data and of the model.

Usage: plot_material.py FIGURE.json --out FIG.png
FIGURE.json is what `material fit` writes for it (analysis::MaterialFigureJson).
Exit codes: 0 figure written, 2 bad arguments or data, 3 matplotlib missing.
"""

import argparse
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import trace_io  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", help="the fit's figure data (JSON)")
    parser.add_argument("--out", required=True, help="output image (PNG, PDF or SVG)")
    parser.add_argument("--dpi", type=float, default=150.0)
    args = parser.parse_args()
    try:
        with open(args.data, encoding="utf-8") as f:
            fig_data = json.load(f)
        taps = fig_data["taps"]
        unit = fig_data["unit"]
    except (OSError, ValueError, KeyError) as error:
        print(f"error: {args.data}: {error}", file=sys.stderr)
        return 2

    plt = trace_io.import_pyplot()
    plt.rcParams.update({"font.size": 8, "axes.titlesize": 9})
    fig, (ax_t, ax_a, ax_s) = plt.subplots(1, 3, figsize=(13.0, 3.8))
    cmap = plt.get_cmap("viridis")
    speeds = [t["impact_speed_mps"] for t in taps]
    v_max = max(speeds) if speeds else 1.0
    for t in taps:
        color = cmap(0.1 + 0.8 * t["impact_speed_mps"] / v_max)
        ax_t.plot(t["time_ms"], t["signal"], color=color, lw=0.6, alpha=0.6)
        ax_t.plot(t["time_ms"], t["model"], color=color, lw=1.0, ls="--")
    ax_t.set_xlabel("time from the fitted onset t0 [ms]")
    ax_t.set_ylabel(f"signal [{unit}]")
    ax_t.set_title(f"{fig_data['name']}: {len(taps)} taps (thin) and the fit (dashed); "
                   f"colour: impact speed")

    amps = [t["amplitude"] for t in taps]
    errs = [t["amplitude_sd"] for t in taps]
    ax_a.errorbar(speeds, amps, yerr=errs, fmt="o", ms=3, color="k", label="per tap (1 sd)")
    line_v = [0.0, 1.1 * v_max]
    slope = fig_data["slope"]
    ax_a.plot(line_v, [slope * v for v in line_v], color="C3",
              label=f"A = {slope:.4g} v (± {fig_data['slope_sd']:.2g}) [{unit}/(m/s)]; "
                    f"residual {fig_data['residual_rms']:.2g}")
    ax_a.set_xlabel("impact speed v [m/s]")
    ax_a.set_ylabel(f"amplitude A at onset [{unit}]")
    ax_a.set_xlim(left=0.0)
    ax_a.set_ylim(bottom=0.0)
    ax_a.legend(loc="upper left")
    ax_a.set_title("amplitude against impact speed")

    # the spectra of the fastest tap (its data and its model), in dB of power
    if taps:
        t = taps[speeds.index(v_max)]
        bin_hz = t["spectrum_bin_hz"]
        peak = max(max(t["spectrum_data"]), max(t["spectrum_model"]), 1e-300)
        for key, label, style in (("spectrum_data", "data", "-"), ("spectrum_model", "model", "--")):
            p = t[key]
            freqs = [k * bin_hz for k in range(len(p))]
            db = [10.0 * math.log10(max(x, 1e-300) / peak) for x in p]
            ax_s.plot(freqs, db, style, lw=0.9, label=label)
        ax_s.axvline(fig_data["frequency_hz"], color="C3", lw=0.6, ls=":",
                     label=f"f = {fig_data['frequency_hz']:.4g} Hz")
        ax_s.set_xlim(0.0, min(freqs[-1], 4.0 * fig_data["frequency_hz"]))
        ax_s.set_ylim(-60.0, 3.0)
        ax_s.set_xlabel("frequency [Hz]")
        ax_s.set_ylabel("power [dB re peak]")
        ax_s.legend(loc="upper right")
        ax_s.set_title(f"spectrum of the fastest tap ({v_max:.3g} m/s)")
    fig.tight_layout()
    try:
        fig.savefig(args.out, dpi=args.dpi)
    except (OSError, ValueError) as error:
        print(f"error: cannot write {args.out}: {error}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
