#!/usr/bin/env python3
"""The face load tools/compare_spheric2.py reports for SPHERIC Test 2's box (face_load: the line
load of the pressures P1-P4 up the face and the height of its resultant) on profiles whose
integrals are worked out by hand: a uniform pressure, a hydrostatic one, a load that stops
between two probes, and none. Exit 0 when every check holds."""
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools"))
import compare_spheric2 as cs  # noqa: E402

failures = []


def check(got, want, what, tol=1e-9):
    ok = abs(got - want) <= tol * max(1.0, abs(want))
    print("%s %s: %.9g (want %.9g)" % ("ok  " if ok else "FAIL", what, got, want))
    if not ok:
        failures.append(what)


z = [cs.PROBES[n][1] for n in ("P1", "P2", "P3", "P4")]
top = cs.BOX_TOP_Z
check(top, 0.161, "the box's top")
for zi, want, n in zip(z, (0.021, 0.061, 0.101, 0.141), ("P1", "P2", "P3", "P4")):
    check(zi, want, n + "'s height (SPHERIC's)")

# uniform 5 kPa: 5000 x 0.161 N/m, resultant at mid-height
load, zc = cs.face_load(z, [5000.0] * 4)
check(load, 5000.0 * 0.161, "uniform: line load")
check(zc, 0.161 / 2, "uniform: resultant")

# hydrostatic under a level 0.3 m above the floor, p = rho g (0.3 - z) at the probes: linear between
# them, constant (the probes' end values) below P1 and above P4
rho_g = 1000.0 * 9.81
p = [rho_g * (0.3 - zi) for zi in z]
load_want = (p[0] * 0.021 + rho_g * ((0.3 * 0.141 - 0.141 ** 2 / 2) - (0.3 * 0.021 - 0.021 ** 2 / 2))
             + p[3] * (0.161 - 0.141))
moment_want = (p[0] * 0.021 ** 2 / 2 + rho_g * ((0.3 * 0.141 ** 2 / 2 - 0.141 ** 3 / 3) - (0.3 * 0.021 ** 2 / 2 - 0.021 ** 3 / 3))
               + p[3] * (0.161 ** 2 - 0.141 ** 2) / 2)
load, zc = cs.face_load(z, p)
check(load, load_want, "hydrostatic: line load")
check(zc, moment_want / load_want, "hydrostatic: resultant")

# 4 kPa at P1 and P2, none at P3 and P4: 4000 x 0.061 + the triangle 4000 x 0.04 / 2 = 324 N/m;
# moment 4000 x 0.061^2 / 2 + (4000 / 0.04) [0.101 z^2 / 2 - z^3 / 3] from 0.061 to 0.101
load, zc = cs.face_load(z, [4000.0, 4000.0, 0.0, 0.0])
moment = 4000.0 * 0.061 ** 2 / 2 + 1e5 * ((0.101 * 0.101 ** 2 / 2 - 0.101 ** 3 / 3) - (0.101 * 0.061 ** 2 / 2 - 0.061 ** 3 / 3))
check(load, 324.0, "load that stops between P2 and P3: line load")
check(zc, moment / 324.0, "load that stops between P2 and P3: resultant")

# no load: no resultant
load, zc = cs.face_load(z, [0.0] * 4)
check(load, 0.0, "no load: line load")
if not math.isnan(zc):
    print("FAIL no load: resultant %g, want nan" % zc)
    failures.append("no load: resultant")
else:
    print("ok   no load: resultant nan")

sys.exit(1 if failures else 0)
