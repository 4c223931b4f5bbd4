"""E_P, E_K (Trujillo-Vela et al. 2020 eq. 37-38) and E_R of a freely falling, spinning disc in
OUT/forces.h5 (dataset energy) against the closed form of tests/terrain/falling_disc_2d.yaml.
usage: body_energy_check.py OUT"""
import math
import sys

import h5py
import numpy as np

out = sys.argv[1]
rho, R, y0, w0, g = 2650.0, 0.1, 2.0, 5.0, 9.81
m = rho * math.pi * R * R
with h5py.File(out + "/forces.h5", "r") as f:
    t = f["t"][:]
    e = f["energy"][:, 0, :]
    units = f["energy"].attrs["units"]
    units = units.decode() if isinstance(units, bytes) else units
ep_ref = m * g * (y0 - 0.5 * g * t * t)
ek_ref = 0.5 * m * (g * t) ** 2
er_ref = 0.25 * m * R * R * w0 * w0
scale = m * g * y0
err_p = np.max(np.abs(e[:, 0] - ep_ref)) / scale
err_k = np.max(np.abs(e[:, 1] - ek_ref)) / scale
err_r = np.max(np.abs(e[:, 2] - er_ref)) / er_ref
print("rows %d, t_end %.3f s, units %s" % (len(t), t[-1], units))
print("max |E_P - m g (y0 - g t^2/2)| / (m g y0) = %.3e (bound 1e-9)" % err_p)
print("max |E_K - m (g t)^2/2| / (m g y0) = %.3e (bound 1e-9)" % err_k)
print("max |E_R - m R^2 w^2/4| / E_R = %.3e (bound 1e-9)" % err_r)
ok = len(t) > 100 and abs(t[-1] - 0.5) < 1e-9 and err_p < 1e-9 and err_k < 1e-9 and err_r < 1e-9 and units == "J/m"
print("PASS" if ok else "FAIL")
sys.exit(0 if ok else 1)
