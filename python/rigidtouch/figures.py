"""Figures from sweep results (JSON lines written by rigidtouch.sweeps).

Z-width map: per renderer and device, the stiffness x damping grid coloured passive (the energy
the device delivered to the user never rose above zero over the run, ``passive`` in a record) or
not, with Colgate and Schenkel's passivity bound b > K T / 2 + |B| drawn over it, read with b the
damping the wall renders, T the haptic period and no further virtual damper (B = 0): the line
b = K T / 2. Rate-hardness map: per renderer, rate hardness [N/m] over stiffness and a second
swept quantity (haptic rate by default).

    python3 -m rigidtouch.figures zwidth results.jsonl --out zwidth.png
    python3 -m rigidtouch.figures rate-hardness results.jsonl --out hardness.png [--y speed]
"""

import argparse
import math
import sys

from .sweeps import read_results


def _edges(values, log):
    # cell edges around sorted centres: midpoints (geometric on a log axis)
    v = sorted(values)
    if len(v) == 1:
        return [v[0] / 1.2, v[0] * 1.2] if log else [v[0] - 0.5, v[0] + 0.5]
    if log:
        mids = [math.sqrt(a * b) for a, b in zip(v, v[1:])]
        return [v[0] ** 2 / mids[0]] + mids + [v[-1] ** 2 / mids[-1]]
    mids = [(a + b) / 2 for a, b in zip(v, v[1:])]
    return [2 * v[0] - mids[0]] + mids + [2 * v[-1] - mids[-1]]


def _panels(records, keys):
    panels = {}
    for r in records:
        if r.get("ok"):
            panels.setdefault(tuple(r[k] for k in keys), []).append(r)
    return panels


def _grid(recs, x, y, value):
    xs = sorted({r[x] for r in recs})
    ys = sorted({r[y] for r in recs})
    import numpy
    grid = numpy.full((len(ys), len(xs)), numpy.nan)
    for r in recs:
        grid[ys.index(r[y]), xs.index(r[x])] = value(r)
    return xs, ys, grid


def zwidth_figure(records, out, *, dpi=90):
    """Draws the Z-width map of `records` (a results file or its records) to `out` (PNG).
    Returns the panels drawn: {(renderer, device): (passive points, points)}."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap
    if isinstance(records, str):
        records = read_results(records)
    panels = _panels(records, ("renderer", "device"))
    if not panels:
        raise ValueError("no successful sweep points to draw")
    fig, axes = plt.subplots(1, len(panels), figsize=(3.6 * len(panels) + 0.4, 3.4),
                             squeeze=False, sharey=True, constrained_layout=True)
    summary = {}
    for ax, ((renderer, device), recs) in zip(axes[0], sorted(panels.items())):
        xs, ys, grid = _grid(recs, "stiffness_N_per_m", "damping_Ns_per_m",
                             lambda r: 1.0 if r["passive"] else 0.0)
        ax.pcolormesh(_edges(xs, True), _edges(ys, False), grid,
                      cmap=ListedColormap(["#d6604d", "#4393c3"]), vmin=0, vmax=1)
        periods = sorted({r["timestep_s"] for r in recs})
        import numpy
        k = numpy.logspace(math.log10(min(xs)), math.log10(max(xs)), 200)  # straight on log x
        for t in periods:
            ax.plot(k, k * t / 2, "k--", lw=1.2,
                    label=f"b = K T / 2, T = {1e3 * t:g} ms")
        ax.set_xscale("log")
        ax.set_ylim(min(ys), max(ys))
        ax.set_xlabel("wall stiffness K [N/m]")
        ax.set_title(f"{renderer}, {device}", fontsize=10)
        ax.legend(loc="upper left", fontsize=7)
        summary[(renderer, device)] = (int(sum(r["passive"] for r in recs)), len(recs))
    axes[0][0].set_ylabel("wall damping b [N s/m]")
    fig.suptitle("Z-width: blue passive (energy to the user never > 0), red active", fontsize=10)
    fig.savefig(out, dpi=dpi)
    plt.close(fig)
    return summary


def rate_hardness_figure(records, out, *, y="rate", dpi=90):
    """Draws rate hardness [N/m] over stiffness and `y` ("rate": 1 / timestep_s [Hz], or a swept
    parameter such as "speed") per renderer to `out` (PNG)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm
    if isinstance(records, str):
        records = read_results(records)
    ok = [r for r in records if r.get("ok") and r.get("rate_hardness_N_per_m")]
    for r in ok:
        r["_y"] = round(1.0 / r["timestep_s"], 6) if y == "rate" else r["params"][y]
    panels = _panels(ok, ("renderer",))
    if not panels:
        raise ValueError("no successful sweep points with a rate hardness to draw")
    values = [r["rate_hardness_N_per_m"] for r in ok if r["rate_hardness_N_per_m"] > 0]
    norm = LogNorm(min(values), max(values))
    fig, axes = plt.subplots(1, len(panels), figsize=(3.6 * len(panels) + 1.0, 3.4),
                             squeeze=False, sharey=True, constrained_layout=True)
    for ax, ((renderer,), recs) in zip(axes[0], sorted(panels.items())):
        xs, ys, grid = _grid(recs, "stiffness_N_per_m", "_y", lambda r: r["rate_hardness_N_per_m"])
        mesh = ax.pcolormesh(_edges(xs, True), _edges(ys, y == "rate"), grid, norm=norm,
                             cmap="viridis")
        ax.set_xscale("log")
        if y == "rate":
            ax.set_yscale("log")
            ax.minorticks_off()
        ax.set_yticks(ys)
        ax.set_yticklabels([f"{v:g}" for v in ys])
        ax.set_xlabel("wall stiffness K [N/m]")
        ax.set_title(renderer, fontsize=10)
    axes[0][0].set_ylabel("haptic rate [Hz]" if y == "rate" else y)
    fig.colorbar(mesh, ax=axes[0].tolist(), label="rate hardness [N/m]")
    fig.savefig(out, dpi=dpi)
    plt.close(fig)


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python3 -m rigidtouch.figures",
                                     description="figures from sweep results")
    parser.add_argument("kind", choices=["zwidth", "rate-hardness"])
    parser.add_argument("results", help="results file of a sweep (JSON lines)")
    parser.add_argument("--out", required=True, help="PNG to write")
    parser.add_argument("--y", default="rate", help="rate-hardness: the second axis")
    args = parser.parse_args(argv)
    try:
        if args.kind == "zwidth":
            for (renderer, device), (passive, n) in zwidth_figure(args.results, args.out).items():
                print(f"{renderer} on {device}: {passive} of {n} points passive")
        else:
            rate_hardness_figure(args.results, args.out, y=args.y)
    except (OSError, ValueError, KeyError) as e:
        print(f"rigidtouch: error: {args.results}: {e}", file=sys.stderr)
        return 2
    print(f"figure: {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
