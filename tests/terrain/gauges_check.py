"""Trackers and control volumes in OUT/gauges.h5 against the closed form of
tests/terrain/gauges_uniform_2d.yaml (uniform translation). usage: gauges_check.py OUT"""
import math
import sys

import h5py
import numpy as np

out = sys.argv[1]
ok = True


def check(name, got, want, tol):
    global ok
    err = float(np.max(np.abs(np.asarray(got, dtype=float) - np.asarray(want, dtype=float))))
    good = err <= tol
    ok = ok and good
    print("%-40s max error %.3e (bound %.1e) %s" % (name, err, tol, "pass" if good else "FAIL"))


with h5py.File(out + "/gauges.h5", "r") as f:
    a = f["trackers/A"]
    t = a["t"][:]
    check("tracker A x = 0.055 + t", a["x"][:], 0.055 + t, 1e-9)
    check("tracker A y = 0.045", a["y"][:], 0.045, 1e-9)
    check("tracker A vx = 1", a["vx"][:], 1.0, 1e-9)
    check("tracker A vy = 0", a["vy"][:], 0.0, 1e-9)
    check("tracker A id constant", a["id"][:], a["id"][0], 0.0)
    ok = ok and len(t) > 10
    cv = f["control_volumes/all"]
    M, mb = 20.0, 2650.0 * math.pi * 0.02 ** 2
    check("all: mass_water = 20 kg/m", cv["mass_water"][:], M, 1e-9)
    check("all: ek_water = M u^2/2", cv["ek_water"][:], 0.5 * M, 1e-9)
    check("all: ek_bodies = m_B u^2/2", cv["ek_bodies"][:], 0.5 * mb, 1e-9)
    check("all: ek = sum (eq. 39)", cv["ek"][:], 0.5 * M + 0.5 * mb, 1e-9)
    check("all: flux_water = M u / 2", cv["flux_water"][:], M / 2.0, 1e-9)
    check("all: soil parts 0", np.concatenate([cv["ek_soil"][:], cv["mass_soil"][:], cv["flux_soil"][:]]), 0.0, 0.0)
    fr = f["control_volumes/front"]
    tf = fr["t"][:]
    check("front: 100 Hz samples at 0, 0.01 .. 0.05", tf, np.arange(6) * 0.01, 1e-9)
    check("front: empty at t = 0", [fr["mass_water"][0], fr["ek"][0]], 0.0, 0.0)
    check("front: mass at 0.05 s = 5 kg/m", fr["mass_water"][-1], 5.0, 1e-9)
    check("front: ek at 0.05 s = 2.5 J/m", fr["ek"][-1], 2.5, 1e-9)
    check("front: flux at 0.05 s = 100 kg/(m s)", fr["flux_water"][-1], 100.0, 1e-7)
print("PASS" if ok else "FAIL")
sys.exit(0 if ok else 1)
