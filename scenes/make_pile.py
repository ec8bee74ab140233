#!/usr/bin/env python3
"""Writes a box pile scene in the layout of scenes/pile.xml, grown to nx x ny x nz boxes.

Usage: make_pile.py NX NY NZ NAME NCONMAX NJMAX NSTACK > scenes/NAME.xml

Every box is a free cube of half-size 25 mm and 0.1 kg; centres are 51 mm apart (1 mm gaps),
the grid is centred on the origin in x and y, the lowest layer rests on the floor, and the tool
(a 5 mm sphere of 0.1 kg) sits 2 mm above the top box of a centre column. The sizes only
affect MuJoCo (rigidtouch sizes its buffers from the scene itself; MuJoCo's default jacobian,
auto, is already sparse at these sizes, nv >= 60, so the file does not set it):
MuJoCo 2.2's mjData holds njmax x njmax and njmax x nv arrays in one buffer whose size is an
int (at most 2 GB), and its Newton solver takes 3 nv^2 numbers of the stack. pile400 gets the
rows its settled pile needs (about 2000 contacts of 4 pyramidal rows); pile1000 would need about
16000 rows, but the buffer limit allows about 8000 at nv = 6006, so MuJoCo cannot hold its
contacts (its gates say so).
"""
import sys


def main():
    nx, ny, nz = (int(a) for a in sys.argv[1:4])
    name, nconmax, njmax, nstack = sys.argv[4], int(sys.argv[5]), int(sys.argv[6]), int(sys.argv[7])
    pitch, half = 0.051, 0.025
    x0, y0 = -pitch * (nx - 1) / 2, -pitch * (ny - 1) / 2
    cx, cy = (nx - 1) // 2, (ny - 1) // 2
    top = half + pitch * (nz - 1) + half
    out = [
        f'<!-- Benchmark scene "{name}": {nx * ny * nz} boxes on a {nx} x {ny} x {nz} grid, centres at',
        f'     ({x0:.4f} + 0.051 x, {y0:.4f} + 0.051 y, 0.025 + 0.051 z), box_i with',
        f'     i = x + {nx} y + {nx * ny} z, the tool 2 mm above the top box of column ({cx}, {cy}).',
        '     Written by scenes/make_pile.py; same box, mass and spacing as pile.xml.',
        '     The tool is pushed down by a constant 2 N that is not part of this file. -->',
        f'<mujoco model="{name}">',
        '  <option timestep="0.001" gravity="0 0 -9.81"/>',
        '  <!-- sizes for MuJoCo only; rigidtouch ignores them -->',
        f'  <size nconmax="{nconmax}" njmax="{njmax}" nstack="{nstack}"/>',
        '  <worldbody>',
        '    <geom name="floor" type="plane" size="0 0 1"/>',
    ]
    for z in range(nz):
        for y in range(ny):
            for x in range(nx):
                i = x + nx * y + nx * ny * z
                out += [
                    f'    <body name="box_{i}" pos="{x0 + pitch * x:.4f} {y0 + pitch * y:.4f} '
                    f'{half + pitch * z:.3f}">',
                    '      <freejoint/>',
                    f'      <geom name="box_{i}" type="box" size="0.025 0.025 0.025" mass="0.1"/>',
                    '    </body>',
                ]
    out += [
        f'    <body name="tool" pos="{x0 + pitch * cx:.4f} {y0 + pitch * cy:.4f} {top + 0.007:.3f}">',
        '      <freejoint/>',
        '      <geom name="tool" type="sphere" size="0.005" mass="0.1"/>',
        '    </body>',
        '  </worldbody>',
        '</mujoco>',
    ]
    print('\n'.join(out))


if __name__ == '__main__':
    main()
