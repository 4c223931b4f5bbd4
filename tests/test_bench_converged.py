#!/usr/bin/env python3
"""The converged solution `lahar bench` measures an experiment case's error against
(tools/bench.py converged_reference; tools/lahar_py.py richardson_order) and the converged value of a
scalar the convergence tools report (lahar_py.richardson_extrapolate): on synthetic dx sweeps
y(dx) = y* + C dx^p with known y* and p, and on sweeps that do not converge monotonically (where
the finest run must stand in, or no value be given). Exit 0 when every check holds."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools"))
import bench  # noqa: E402
import lahar_py  # noqa: E402
import numpy as np  # noqa: E402

failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures.append(what)


t = np.linspace(0.0, 0.3, 31)
exact = 0.1 + 2.0 * t ** 2                      # a front position, y*(t)
shape = np.sin(7.0 * t) + 0.3                   # the error's shape in t, C(t)
dxs = [0.1 / 10, 0.1 / 14, 0.1 / 20, 0.1 / 28, 0.1 / 40]  # the bench's non-constant refinement ratios
for p in (0.8, 1.0, 2.0, 3.2):
    curves = {dx: exact + shape * dx ** p for dx in dxs}
    ystar, desc, ref = bench.converged_reference(curves)
    err = float(np.max(np.abs(ystar - exact)))
    check(ref is None and desc.startswith("Richardson"), f"p = {p}: Richardson used ({desc})")
    check(err < 1e-9, f"p = {p}: y* recovered to {err:.2e} (< 1e-9)")
    got = float(desc.split("observed order ")[1].rstrip(")"))
    check(abs(got - p) < 0.01, f"p = {p}: observed order {got} (within 0.01)")

# the error falls with dx against y*, and is the largest |y - y*| over y*'s range
curves = {dx: exact + shape * dx for dx in dxs}
ystar, _, _ = bench.converged_reference(curves)
errs = [float(np.max(np.abs(curves[dx] - ystar))) for dx in dxs]
check(all(a > b for a, b in zip(errs, errs[1:])), f"errors fall with dx: {['%.3g' % e for e in errs]}")

# not converging: the difference grows under refinement -> the finest run stands in, named
osc = {dx: exact + shape * (0.01 if i % 2 else -0.01) * (1 + i) for i, dx in enumerate(dxs)}
ystar, desc, ref = bench.converged_reference(osc)
check(ref == min(dxs) and np.array_equal(ystar, osc[min(dxs)]) and "asymptotic" in desc,
      f"no monotone convergence: the finest run is the reference ({desc})")
ystar, desc, ref = bench.converged_reference({dxs[0]: exact, dxs[1]: exact + 0.01})
check(ref == dxs[1] and "two resolutions" in desc, f"two runs: the finer is the reference ({desc})")
check(lahar_py.richardson_order((0.01, 0.005, 0.0025), 2.0 ** 1.5) is not None
      and abs(lahar_py.richardson_order((0.01, 0.005, 0.0025), 2.0 ** 1.5) - 1.5) < 1e-9,
      "constant ratio 2: ratio 2^1.5 gives p = 1.5")
check(lahar_py.richardson_order((0.01, 0.005, 0.0025), 0.5) is None, "ratio < 1 (diverging): no order")
# a scalar (a sustained pressure) at the non-constant ratios of a 20 / 15 / 10 mm sweep
for p, c in ((1.3, -40.0), (0.6, 2.0), (2.5, 900.0)):
    d = (0.02, 0.015, 0.01)
    got = lahar_py.richardson_extrapolate(d, [3.0 + c * x ** p for x in d])
    check(got is not None and abs(got[0] - 3.0) < 1e-9 and abs(got[1] - p) < 1e-9,
          f"scalar, p = {p}: q* = 3 and p recovered ({got})")
check(lahar_py.richardson_extrapolate((0.02, 0.015, 0.01), (2.0, 2.5, 2.3)) is None,
      "scalar, differences of opposite sign: no converged value")
check(lahar_py.richardson_extrapolate((0.02, 0.015, 0.01), (2.0, 2.0, 2.3)) is None,
      "scalar, a zero difference: no converged value")
# 2.32, 2.72, 3.35: the second difference larger than any order >= 0.25 allows at these ratios
check(lahar_py.richardson_extrapolate((0.02, 0.015, 0.01), (2.32, 2.72, 3.35)) is None,
      "scalar, differences growing faster than dx^0.25 allows: no converged value")
check(lahar_py.richardson_extrapolate((0.02, 0.015, 0.01), (2.0, float("nan"), 2.3)) is None,
      "scalar, a run without the value: no converged value")
print(f"{len(failures)} failures")
sys.exit(1 if failures else 0)
