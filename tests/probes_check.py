#!/usr/bin/python3
"""Pressure probes (case section probes:, sph_node/probes/sph_probes.h) in a tank at rest.

  probes_check.py LAHAR OUT [--dx M] [--wall penalty|ghost] [--tol F]
  probes_check.py LAHAR OUT --3d

--3d: cases/hydrostatic_3d.yaml (0.1 x 0.05 m, 0.1 m deep) at dx 10 mm to t = 0.1 s with a 20 mm
disc sensor on the x = 0.1 m wall, a 10 mm disc on the floor and a point in the water: each mean
over t > 0.05 s within tol x rho g h of rho g (h - z); a level gauge (kind: level) at the centre
reads h = 0.1 m within --level-tol x dx at every sample (measured 0.0088 dx).

Runs cases/hydrostatic_2d.yaml (0.4 m x 0.2 m of water, walls of DEM boxes) at dx (default 10 mm)
to t = 0.5 s with probes on the right wall (a point, and a 9 mm sensor), on the floor, in the
water, above it (dry) and one sampled at 100 Hz. Asserts:
  - every wetted probe's mean over t in [0.3, 0.5] s equals rho g (h - y) within tol x rho g h
    (default 1 %; h = 0.2 m the still water depth),
  - the dry probe reads 0 at every sample,
  - the 100 Hz probe has one sample per 10 ms slot: the k-th at the first step at or after k/100 s
    (t_k >= k/100 and t_k - k/100 below the largest step), and the others one per step,
  - the same tank without probes writes no gauges.h5,
  - a level gauge (kind: level, 100 Hz) at x = 0.2 m reads h at every sample within --level-tol x dx
    (default 0.05 dx; the kernel fraction is 1/2 on the surface of a half space: largest error
    measured 0.0016 dx in 2D, 0.0088 dx in 3D), and its floor attribute is the floor's top, 0.
Exit 0 when all hold, 1 otherwise."""
import argparse
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tools"))
import lahar_py  # noqa: E402

lahar_py.require("h5py", "numpy", "yaml")
import h5py  # noqa: E402
import numpy as np  # noqa: E402
import case_override  # noqa: E402

RHO, G, H = 1000.0, 9.81, 0.2


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("lahar")
    ap.add_argument("out")
    ap.add_argument("--dx", type=float, default=0.01)
    ap.add_argument("--wall", default="ghost", choices=["penalty", "ghost"])
    ap.add_argument("--tol", type=float, default=0.01)
    ap.add_argument("--level-tol", type=float, default=0.05, help="level error bound, in dx")
    ap.add_argument("--3d", dest="three", action="store_true")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    if a.three:
        return check_3d(a)
    case = os.path.join(HERE, "..", "cases", "hydrostatic_2d.yaml")
    probes = ("[{name: wall_05, position: [0.4, 0.05], body: wall_right},"
              " {name: wall_10_sensor, position: [0.4, 0.1], body: wall_right, size: 0.009},"
              " {name: floor_20, position: [0.2, 0.0], body: floor},"
              " {name: corner_03, position: [0.4, 0.003], body: wall_right, size: 0.0042},"
              " {name: fluid_10, position: [0.2, 0.1]},"
              " {name: fluid_03_100hz, position: [0.1, 0.03], rate: 100},"
              " {name: dry, position: [0.2, 0.25]},"
              " {name: level_20, kind: level, position: [0.2], rate: 100}]")
    base = [f"sph.dx={a.dx}", f"sph.wall_pressure={a.wall}", "time.end=0.5", "time.output_interval=0.5"]
    ok = True
    runs = {"with": base + [f"probes={probes}"], "without": base + ["time.end=0.01", "time.output_interval=0.01"]}
    for tag, ov in runs.items():
        yml = os.path.join(a.out, f"tank_{tag}.yaml")
        if case_override.main(["case_override.py", case, yml] + ov) != 0:
            return 1
        r = subprocess.run([a.lahar, "run", yml, "-o", os.path.join(a.out, tag), "--in-process", "--threads", "1", "-q", "--overwrite"])
        if r.returncode != 0:
            print(f"probes_check: lahar run {yml} exited {r.returncode}")
            return 1
    if os.path.exists(os.path.join(a.out, "without", "gauges.h5")):
        print("probes_check: FAIL a case without probes wrote gauges.h5")
        ok = False
    f = h5py.File(os.path.join(a.out, "with", "gauges.h5"), "r")
    ff = h5py.File(os.path.join(a.out, "with", "forces.h5"), "r")
    dt_max = float(np.diff(ff["t"][:]).max())
    for name in ("wall_05", "wall_10_sensor", "floor_20", "corner_03", "fluid_10", "fluid_03_100hz", "dry"):
        g = f["probes"][name]
        t, p = g["t"][:], g["p"][:]
        y = float(g.attrs["position"][1])
        if g["p"].attrs["units"] not in ("Pa", b"Pa"):
            print(f"probes_check: FAIL {name}: p has no units attribute Pa")
            ok = False
        if name == "dry":
            good = np.all(p == 0.0)
            print(f"probes_check: {name}: max |p| {np.abs(p).max():.3g} Pa (expect 0) {'ok' if good else 'FAIL'}")
            ok &= bool(good)
            continue
        ref = RHO * G * (H - y)
        m = (t >= 0.3) & (t <= 0.5)
        err = (p[m].mean() - ref) / (RHO * G * H)
        good = abs(err) <= a.tol
        print(f"probes_check: {name} (y = {y:.3f} m): mean p {p[m].mean():.1f} Pa over {m.sum()} samples, "
              f"rho g (h - y) = {ref:.1f} Pa, error {100 * err:+.3f} % of rho g h (bound {100 * a.tol:g} %), "
              f"std {100 * p[m].std() / (RHO * G * H):.3f} % {'ok' if good else 'FAIL'}")
        ok &= bool(good)
        if name == "fluid_03_100hz":
            k = np.arange(len(t))
            slots = int(np.floor(0.5 * 100 * (1 + 1e-12))) + 1
            good = len(t) == slots and np.all(t >= k / 100.0 - 1e-12) and np.all(t - k / 100.0 < dt_max + 1e-12)
            print(f"probes_check: {name}: {len(t)} samples in 0.5 s at 100 Hz (expect {slots}), largest lag "
                  f"{(t - k / 100.0).max():.2e} s (step <= {dt_max:.2e} s) {'ok' if good else 'FAIL'}")
            ok &= bool(good)
        elif len(t) != len(ff["t"][:]) + 1:
            print(f"probes_check: FAIL {name}: {len(t)} samples, expected one per step + t = 0 ({len(ff['t']) + 1})")
            ok = False
    ok &= check_level(f["probes"]["level_20"], H, a.dx, a.level_tol, 0.0, "level_20")
    print("probes_check:", "PASS" if ok else "FAIL")
    return 0 if ok else 1


def check_level(g, h, dx, tol, floor, name):
    """A level gauge in still water of depth h: every sample within tol dx of h, floor as given."""
    hs = g["h"][:]
    err = np.abs(hs - h).max() / dx
    good = (g.attrs["kind"] in ("level", b"level") and g["h"].attrs["units"] in ("m", b"m") and err <= tol
            and abs(float(g.attrs["floor"]) - floor) <= 1e-5 * dx and len(hs) > 1)
    print(f"probes_check: {name}: level {hs.mean():.5f} m (h = {h:g} m) over {len(hs)} samples, largest error "
          f"{err:.4f} dx (bound {tol:g} dx), floor {float(g.attrs['floor']):.2e} m {'ok' if good else 'FAIL'}")
    return bool(good)


def check_3d(a):
    h = 0.1
    yml = os.path.join(a.out, "tank_3d.yaml")
    probes = ("[{name: wall_x, position: [0.1, 0.025, 0.04], body: wall_xmax, size: 0.02},"
              " {name: floor, position: [0.05, 0.025, 0.0], body: floor, size: 0.01},"
              " {name: fluid, position: [0.05, 0.025, 0.05]},"
              " {name: level, kind: level, position: [0.05, 0.025]}]")
    ov = ["sph.dx=0.01", "time.end=0.1", "time.output_interval=0.1", f"probes={probes}"]
    if case_override.main(["case_override.py", os.path.join(HERE, "..", "cases", "hydrostatic_3d.yaml"), yml] + ov):
        return 1
    r = subprocess.run([a.lahar, "run", yml, "-o", os.path.join(a.out, "run3d"), "--in-process", "--threads", "1", "-q", "--overwrite"])
    if r.returncode != 0:
        print(f"probes_check: lahar run {yml} exited {r.returncode}")
        return 1
    f = h5py.File(os.path.join(a.out, "run3d", "gauges.h5"), "r")
    ok = True
    for name in ("wall_x", "floor", "fluid"):
        g = f["probes"][name]
        t, p = g["t"][:], g["p"][:]
        z = float(g.attrs["position"][2])
        ref = RHO * G * (h - z)
        m = t > 0.05
        err = (p[m].mean() - ref) / (RHO * G * h)
        good = abs(err) <= a.tol
        print(f"probes_check: 3D {name} (z = {z:.3f} m, size {float(g.attrs['size']) * 1000:g} mm): mean p "
              f"{p[m].mean():.1f} Pa, rho g (h - z) = {ref:.1f} Pa, error {100 * err:+.3f} % of rho g h "
              f"(bound {100 * a.tol:g} %) {'ok' if good else 'FAIL'}")
        ok &= bool(good)
    ok &= check_level(f["probes"]["level"], h, 0.01, a.level_tol, 0.0, "3D level")
    print("probes_check:", "PASS" if ok else "FAIL")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
