#!/usr/bin/env python3
"""Write the heightmaps of cases/debris_flow_3d.yaml: a trapezoidal channel cut into a hillside
that runs from a steep reach onto a gentler one, and the upper surface of the debris mass that
fills a stretch of the channel (the `between: {top: ...}` of the case's soil and water blocks).

usage: make_channel_asc.py [-o DIR] [--cellsize M]

Writes DIR/debris_flow_3d_terrain.asc and DIR/debris_flow_3d_mass.asc (ESRI ASCII grids, nodes at
the cell centres, rows north to south: the format common/io/terrain.h reads). DIR defaults to the
folder of this script's ../cases. Pure geometry, no randomness: the same files every time.

The terrain z(x, y) = z0(x) + c(y), x downstream, y across, z up (metres):
  z0(x)  the thalweg's long profile: 20 deg from x = 0 to the slope break at X_BREAK = 30 m, then
         5 deg to x = 50 m; z0(50) = 0;
  c(y)   the cross-section: a trapezoidal channel DEPTH = 2 m deep with a bed HALF_BED = 1 m
         wide each side of y = 0 and 1:1 (45 deg) side slopes up to the banks at |y| = 3 m,
         then banks rising at 10 % to the grid's edge |y| = 6 m.
The mass: its surface is level across the channel, MASS_DEPTH = 1.5 m above the bed (vertically),
from x = MASS_X0 = 19 m to MASS_X1 = 29 m on the 20 deg reach, its front 1 m above the break; NODATA elsewhere (the loader takes a
NODATA top node as lying on the terrain: no material there).
The grid: cellsize 1 m (default), nodes x = 0 .. 50, y = -6 .. 6; the slope break, the bed's and
the banks' edges and the mass's ends lie on node lines, so the triangulated surface is exact (the
SPH coupling visits the terrain features within a kernel support of each particle near it: coarser
cells, fewer features; the channel needs no finer ones)."""
import argparse
import math
import os

X_LEN, Y_HALF = 50.0, 6.0
X_BREAK = 30.0
SLOPE_UP, SLOPE_DOWN = 20.0, 5.0
DEPTH, HALF_BED, BANK = 2.0, 1.0, 3.0
BANK_RISE = 0.1
MASS_X0, MASS_X1, MASS_DEPTH = 19.0, 29.0, 1.5
NODATA = -9999.0


def z0(x):
    """Elevation of the thalweg's long profile at x (before the channel is cut)."""
    low = math.tan(math.radians(SLOPE_DOWN))
    up = math.tan(math.radians(SLOPE_UP))
    if x >= X_BREAK:
        return low * (X_LEN - x)
    return low * (X_LEN - X_BREAK) + up * (X_BREAK - x)


def cross(y):
    """The cross-section c(y): -DEPTH on the bed, 1:1 sides, banks rising at BANK_RISE."""
    a = abs(y)
    if a <= HALF_BED:
        return -DEPTH
    if a <= BANK:
        return -DEPTH + (a - HALF_BED) * DEPTH / (BANK - HALF_BED)
    return BANK_RISE * (a - BANK)


def terrain(x, y):
    return z0(x) + cross(y)


def mass_top(x, y):
    if MASS_X0 - 1e-9 <= x <= MASS_X1 + 1e-9:
        return z0(x) - DEPTH + MASS_DEPTH
    return NODATA


def write_asc(path, f, cs):
    nx = int(round(X_LEN / cs)) + 1
    ny = int(round(2 * Y_HALF / cs)) + 1
    with open(path, "w") as out:
        out.write("ncols %d\nnrows %d\nxllcenter 0\nyllcenter %.10g\ncellsize %.10g\nNODATA_value %g\n"
                  % (nx, ny, -Y_HALF, cs, NODATA))
        for i in range(ny - 1, -1, -1):  # the northern row (largest y) first
            y = -Y_HALF + i * cs
            out.write(" ".join("%.6f" % f(j * cs, y) if f(j * cs, y) != NODATA else "%g" % NODATA
                               for j in range(nx)) + "\n")


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("-o", "--out", default=os.path.join(here, "..", "cases"))
    ap.add_argument("--cellsize", type=float, default=1.0)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    write_asc(os.path.join(a.out, "debris_flow_3d_terrain.asc"), terrain, a.cellsize)
    write_asc(os.path.join(a.out, "debris_flow_3d_mass.asc"), mass_top, a.cellsize)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
