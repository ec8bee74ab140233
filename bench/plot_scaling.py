#!/usr/bin/env python3
"""Draws the step time against the number of bodies (log-log) as an SVG, with no dependencies.

Usage: plot_scaling.py docs/figures/scaling.csv docs/figures/scaling.svg

The CSV has the columns bodies,engine,median_us (one row per measured scene and engine; an
engine missing at a size is left out there). Lines join each engine's points; the dashed lines
are the 1 ms haptic period and the 0.5 ms goal.
"""
import csv
import math
import sys

COLOURS = {'rigidtouch': '#1b6ac9', 'rigidtouch_2threads': '#7a3fc4', 'bullet': '#d9731a',
           'mujoco': '#2a9d3a'}
W, H, L, R, T, B = 660, 420, 70, 150, 20, 50


def main():
    rows = list(csv.DictReader(open(sys.argv[1])))
    series = {}
    for r in rows:
        series.setdefault(r['engine'], []).append((float(r['bodies']), float(r['median_us'])))
    xs = [p[0] for s in series.values() for p in s]
    ys = [p[1] for s in series.values() for p in s] + [500.0, 1000.0]
    x0, x1 = math.floor(math.log10(min(xs))), math.ceil(math.log10(max(xs)))
    y0, y1 = math.floor(math.log10(min(ys))), math.ceil(math.log10(max(ys)))

    def px(x):
        return L + (math.log10(x) - x0) / (x1 - x0) * (W - L - R)

    def py(y):
        return H - B - (math.log10(y) - y0) / (y1 - y0) * (H - T - B)

    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" '
           f'font-family="sans-serif" font-size="12">',
           f'<rect width="{W}" height="{H}" fill="white"/>']
    for e in range(x0, x1 + 1):
        x = px(10 ** e)
        out.append(f'<line x1="{x:.1f}" y1="{T}" x2="{x:.1f}" y2="{H - B}" stroke="#ddd"/>')
        out.append(f'<text x="{x:.1f}" y="{H - B + 16}" text-anchor="middle">{10 ** e}</text>')
    for e in range(y0, y1 + 1):
        y = py(10 ** e)
        out.append(f'<line x1="{L}" y1="{y:.1f}" x2="{W - R}" y2="{y:.1f}" stroke="#ddd"/>')
        out.append(f'<text x="{L - 6}" y="{y + 4:.1f}" text-anchor="end">{10 ** e:g}</text>')
    for level, label in ((1000.0, '1 ms period'), (500.0, '0.5 ms goal')):
        y = py(level)
        out.append(f'<line x1="{L}" y1="{y:.1f}" x2="{W - R}" y2="{y:.1f}" stroke="#900" '
                   f'stroke-dasharray="5,4"/>')
        out.append(f'<text x="{W - R + 4}" y="{y + 4:.1f}" fill="#900">{label}</text>')
    out.append(f'<text x="{(L + W - R) / 2}" y="{H - 12}" text-anchor="middle">bodies '
               f'(boxes in the scene)</text>')
    out.append(f'<text x="16" y="{(T + H - B) / 2}" text-anchor="middle" '
               f'transform="rotate(-90 16 {(T + H - B) / 2})">median step time [us], h = 1 ms</text>')
    for i, (engine, pts) in enumerate(sorted(series.items())):
        pts.sort()
        c = COLOURS.get(engine, 'black')
        path = ' '.join(f'{px(x):.1f},{py(y):.1f}' for x, y in pts)
        out.append(f'<polyline points="{path}" fill="none" stroke="{c}" stroke-width="2"/>')
        for x, y in pts:
            out.append(f'<circle cx="{px(x):.1f}" cy="{py(y):.1f}" r="3.5" fill="{c}"/>')
        out.append(f'<text x="{W - R + 4}" y="{T + 20 + 16 * i}" fill="{c}">{engine}</text>')
    out.append('</svg>')
    open(sys.argv[2], 'w').write('\n'.join(out) + '\n')


if __name__ == '__main__':
    main()
