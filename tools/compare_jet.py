#!/usr/bin/python3
"""Compare a run of cases/jet_impingement_2d.yaml (or _3d.yaml) with the free-streamline solution of
a jet that hits a wall normally.

  tools/compare_jet.py OUT [--plate NAME] [--window T0 T1] [-o FILE.png] [--json FILE] [--no-plot]
                       [--check [--pressure-tol F] [--force-tol F]]

A plane jet of width b and speed U (the case's first inlet: its whole section wetted, b the length
of its `edge`, U a constant `velocity`, the jet along the inlet's normal) hits a plate (a body;
--plate, default the body the pressure probes sit on) at right angles. Reference: the steady
potential flow with free surfaces, gravity and viscosity neglected (the hodograph solution of the
free-streamline theory; derivation in docs/bench/jet_impingement.md). Along the plate, at a
distance s from the jet's axis, the speed is q U and the pressure

    p(s) = rho U^2 (1 - q^2) / 2,   |s| = (2 b / pi) (artanh q + arctan q),

rho U^2 / 2 at the stagnation point; the force on the plate is the jet's momentum flux rho U^2 b
(per metre), exactly, whatever the pressure distribution. On the axis the jet slows the same way,
at a distance d from the plate at the speed s U with d = (2 b / pi) (artanh s + arctan s): the
reference holds for a nozzle far from the plate, and the tool reports the speed deficit the theory
gives at the inlet's distance (0.16 % of the dynamic pressure at 3 b).

In 3D (the inlet's section the rectangle of `edge` and `edge2`, area A, b = sqrt(A)) only two
things are exact for any section: the stagnation pressure rho U^2 / 2 (Bernoulli along the axis)
and the force rho U^2 A. A probe on the axis (within 0.05 b of it) is compared with the first; the
others are reported with their distance s from the axis, without a reference.

Reads OUT/gauges.h5 (the pressure probes on the plate), OUT/forces.h5 and the case
(OUT/summary.json). Metrics over the window T0-T1 (default: the second half of the case's
time.end, 0.015-0.03 s in 2D, 0.01-0.02 s in 3D; the flow is steady after about 10 b / U), printed
and written to --json (default OUT/jet.json):
  pressure    per probe the window mean against p(s), the difference as a fraction of rho U^2 / 2;
              the largest |difference| over the probes is checked
  stagnation  the probe nearest the axis: its mean / (rho U^2 / 2) - 1
  force       the plate's mean force along the jet against rho U^2 b (3D: rho U^2 A), relative
              difference, and its rms about the mean
  probe_integral  2D: the probes' means integrated along the plate (trapezoids over their span)
              against the reference's integral over the same span (reported: whether the wall
              pressure the probes read and the force the plate carries agree)
With --check: exit 1 unless max |difference| <= --pressure-tol (default 0.05) and |force /
(momentum flux) - 1| <= --force-tol (default 0.03). The PNG shows the mean pressure along the plate
against p(s) and the force against time. Exit 2 on a run or case this tool cannot read (what is
missing and what to do is printed)."""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lahar_py  # noqa: E402

lahar_py.require("h5py", "numpy", "matplotlib", "yaml")
import h5py  # noqa: E402
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import yaml  # noqa: E402


STAGNATION_OFF_AXIS = 0.05  # 3D: a probe this many jet widths from the axis reads the stagnation point


InputError = lahar_py.InputError


def distance_of_speed(q, b):
    """The distance from the stagnation point, along the plate or along the axis, at which the
    free-streamline jet of width b moves at q U (0 <= q < 1)."""
    return (2.0 * b / np.pi) * (np.arctanh(q) + np.arctan(q))


def speed_at(s, b):
    """q(|s|) / U: the inverse of distance_of_speed, by bisection (monotone in q)."""
    s = abs(s)
    lo, hi = 0.0, 1.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if distance_of_speed(mid, b) < s:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def wall_pressure(s, b, rho, u):
    """The reference pressure on the plate at distance s from the jet's axis."""
    q = speed_at(s, b)
    return 0.5 * rho * u * u * (1.0 - q * q)


def read_case(out, plate):
    """The jet (width b: in 2D the section's length, in 3D the square root of its area; the
    section's area per metre or in m^2; speed, axis point, direction; in 2D the direction along
    the plate), the rest density, the dimension."""
    path = lahar_py.run_case(out)
    with open(path) as fh:
        case = yaml.safe_load(fh)
    dim = case.get("dimensions")
    if dim not in (2, 3):
        raise InputError(f"{path}: dimensions {dim}: this tool reads a 2D or 3D case")
    inlets = [i for i in case.get("inlets") or [] if "velocity" in i and "edge" in i and (dim == 2 or "edge2" in i)]
    if not inlets:
        raise InputError(f"{path}: inlets: none with an `edge`{' and `edge2`' if dim == 3 else ''} and a constant "
                         "`velocity`: the reference needs the jet's section and speed (cases/jet_impingement_2d.yaml)")
    inlet = inlets[0]
    edges = [np.array(inlet["edge"], float)] + ([np.array(inlet["edge2"], float)] if dim == 3 else [])
    normal = np.array(inlet["normal"], float)
    normal /= np.linalg.norm(normal)
    g = np.array(case.get("gravity", [0.0] * dim), float)
    down = g / np.linalg.norm(g) if np.linalg.norm(g) > 0 else np.zeros(dim)
    extent = sum(abs(float(e @ down)) for e in edges)
    if float(inlet.get("level", np.inf)) < extent - 1e-12:
        raise InputError(f"{path}: inlets: level {inlet['level']} covers only part of the section (its "
                         f"vertical extent {extent:g} m): this tool needs the whole section wetted, the jet "
                         "as wide as the inlet's edges")
    bodies = {b.get("name") for b in case.get("bodies") or []}
    if plate is not None and plate not in bodies:
        raise InputError(f"{path}: bodies: no body named '{plate}' (bodies: {', '.join(map(str, bodies))}); "
                         "give the plate with --plate NAME")
    area = float(np.linalg.norm(edges[0])) if dim == 2 else float(np.linalg.norm(np.cross(edges[0], edges[1])))
    return {"dim": dim, "b": area if dim == 2 else float(np.sqrt(area)), "area": area, "u": float(inlet["velocity"]),
            "rho": float(case["sph"]["density"]), "normal": normal,
            "axis": np.array(inlet["position"], float) + 0.5 * sum(edges),
            "along": edges[0] / np.linalg.norm(edges[0])}


def read_probes(out, plate):
    """The plate's name (the probes' body when --plate is not given) and {name: (position, t, p)}
    of the pressure probes on it."""
    path = os.path.join(out, "gauges.h5")
    probes = {}
    try:
        with h5py.File(path, "r") as f:
            for name, g in f["probes"].items():
                if g.attrs.get("kind") in (b"pressure", "pressure") and "body" in g.attrs:
                    body = lahar_py.text_names([g.attrs["body"]])[0]
                    probes[name] = (body, np.array(g.attrs["position"], float), g["t"][()], g["p"][()])
    except (OSError, KeyError) as e:
        raise InputError(f"{path}: {e}; give the output directory of a run of cases/jet_impingement_2d.yaml")
    on = sorted({v[0] for v in probes.values()})
    if plate is None:
        if len(on) != 1:
            raise InputError(f"{path}: pressure probes on {len(on)} bodies ({', '.join(on) or 'none'}); "
                             "give the plate with --plate NAME")
        plate = on[0]
    chosen = {k: v[1:] for k, v in probes.items() if v[0] == plate}
    if len(chosen) < 3:
        raise InputError(f"{path}: {len(chosen)} pressure probes on '{plate}'; need at least 3 along the plate")
    return plate, chosen


def trapezoids(y, x):
    return float(0.5 * np.sum((y[1:] + y[:-1]) * np.diff(x)))


def plate_force(out, plate, normal):
    t, force = lahar_py.body_force(out, plate, "--plate NAME")
    return t, force[:, : len(normal)] @ normal


def measure(out, plate, window):
    c = read_case(out, plate)
    plate, probes = read_probes(out, plate)
    t0, t1 = window
    b, u, rho, dim = c["b"], c["u"], c["rho"], c["dim"]
    q_dyn = 0.5 * rho * u * u
    rows = []
    for name, (x, t, p) in probes.items():
        sel = (t >= t0) & (t <= t1)
        if sel.sum() < 2:
            raise InputError(f"{out}: probe {name} has {sel.sum()} samples in the window {t0:g}-{t1:g} s "
                             f"(run to {t[-1] if len(t) else 0:g} s): run the case to {t1:g} s or give --window")
        r = x[:dim] - c["axis"]
        if dim == 2:  # signed, along the plate
            s = float(r @ c["along"])
            ref = wall_pressure(s, b, rho, u)
        else:  # the distance from the axis in the plate's plane; only the stagnation point is known
            s = float(np.linalg.norm(r - (r @ c["normal"]) * c["normal"]))
            ref = q_dyn if s <= STAGNATION_OFF_AXIS * b else None
        mean = float(p[sel].mean())
        rows.append({"name": name, "s": s, "run": mean, "reference": ref,
                     "diff": None if ref is None else (mean - ref) / q_dyn, "rms": float(p[sel].std())})
    rows.sort(key=lambda r: r["s"])
    stag = min(rows, key=lambda r: abs(r["s"]))
    if stag["reference"] is None:
        raise InputError(f"{out}: no probe on the jet's axis (the nearest, {stag['name']}, is {stag['s']:g} m off "
                         f"it): put one where the axis meets the plate")
    distance = float(np.mean([(probes[r["name"]][0][:dim] - c["axis"]) @ c["normal"] for r in rows]))
    tf, fn = plate_force(out, plate, c["normal"])
    fsel = (tf >= t0) & (tf <= t1)
    f_ref = rho * u * u * c["area"]
    halves = np.array_split(fn[fsel], 2)
    m = {"case": {"dim": dim, "b": b, "area": c["area"], "u": u, "rho": rho, "nozzle_distance": distance,
                  "plate": plate},
         "window": [t0, t1],
         "reference_deficit_at_nozzle": 1.0 - speed_at(distance, b) ** 2 if dim == 2 else None,
         "pressure": {"probes": rows, "max_abs_diff": max(abs(r["diff"]) for r in rows if r["diff"] is not None)},
         "stagnation": {"probe": stag["name"], "s": stag["s"], "run": stag["run"], "reference": stag["reference"],
                        "rel": stag["run"] / q_dyn - 1.0},
         "force": {"run": float(fn[fsel].mean()), "reference": f_ref, "rel": float(fn[fsel].mean()) / f_ref - 1.0,
                   "rms": float(fn[fsel].std()),
                   "halves_rel": [float(h.mean()) / f_ref - 1.0 for h in halves if len(h)]},
         "probe_integral": None}
    if dim == 2:
        ss = np.array([r["s"] for r in rows])
        fine = np.linspace(ss[0], ss[-1], 401)
        ref_int = trapezoids(np.array([wall_pressure(s, b, rho, u) for s in fine]), fine)
        run_int = trapezoids(np.array([r["run"] for r in rows]), ss)
        m["probe_integral"] = {"span": [float(ss[0]), float(ss[-1])], "run": run_int, "reference": ref_int,
                               "rel": run_int / ref_int - 1.0}
    return m, {"tf": tf, "fn": fn}


def plot(m, s, png):
    c = m["case"]
    b, q_dyn = c["b"], 0.5 * c["rho"] * c["u"] ** 2
    fig, ax = plt.subplots(2, 1, figsize=(8, 8))
    rows = m["pressure"]["probes"]
    span = max(abs(r["s"]) for r in rows)
    if c["dim"] == 2:
        fine = np.linspace(-span, span, 401)
        ax[0].plot(fine / b, [wall_pressure(x, b, c["rho"], c["u"]) / q_dyn for x in fine], "r-",
                   label="free-streamline jet: (1 - q^2), |s| = (2b/pi)(artanh q + arctan q)")
    else:
        ax[0].plot([0], [1], "r*", ms=12, label="stagnation point: rho U^2 / 2 (Bernoulli on the axis)")
    ax[0].errorbar([r["s"] / b for r in rows], [r["run"] / q_dyn for r in rows],
                   yerr=[r["rms"] / q_dyn for r in rows], fmt="o", ms=4, capsize=2,
                   label=f"probes: mean over {m['window'][0]:g}-{m['window'][1]:g} s (bars: rms per step)")
    ax[0].set_xlabel("s / b along the plate" if c["dim"] == 2 else "s / b from the axis (b = sqrt(section))")
    ax[0].set_ylabel("p / (rho U^2 / 2)")
    ax[0].legend(loc="lower center", fontsize=8)
    tf, fn = s["tf"], s["fn"]
    f_ref = m["force"]["reference"]
    ax[1].plot(tf, fn / f_ref, color="0.8", lw=0.5, label="force on the plate along the jet, each step")
    ax[1].plot(tf, lahar_py.running_mean(tf, fn, 2.0 * b / c["u"]) / f_ref, "b", lw=1,
               label="its running mean over 2 b / U")
    ax[1].axhline(1.0, color="r", ls="--", label="rho U^2 b" if c["dim"] == 2 else "rho U^2 A")
    ax[1].axvspan(*m["window"], color="y", alpha=0.15,
                  label=f"window: mean {1 + m['force']['rel']:.3f} of it")
    ax[1].set_ylim(0, 2)
    ax[1].set_xlabel("t [s]")
    ax[1].set_ylabel("F / momentum flux")
    ax[1].legend(loc="lower right", fontsize=8)
    fig.suptitle(f"jet on a wall ({c['dim']}D): b = {b:g} m, U = {c['u']:g} m/s, nozzle {c['nozzle_distance'] / b:.1f} b "
                 f"from the plate, dx = {m.get('dx', float('nan')):g} m", fontsize=10)
    fig.tight_layout()
    lahar_py.save_png(fig, png, lahar_py.fail_usage)


def run_dx(out):
    try:
        with h5py.File(os.path.join(out, "particles.h5"), "r") as f:
            return float(f["header"].attrs["dx"])
    except (OSError, KeyError):
        return float("nan")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    lahar_py.compare_cli(ap, "jet")
    ap.add_argument("--plate", help="the plate body's name (default: the body the pressure probes are on)")
    ap.add_argument("--window", type=float, nargs=2, metavar=("T0", "T1"),
                    help="time window of the comparison, s (default: the second half of the case's time.end)")
    ap.add_argument("--pressure-tol", type=float, default=0.05,
                    help="bound on the largest |mean - p(s)| / (rho U^2 / 2) over the probes")
    ap.add_argument("--force-tol", type=float, default=0.03, help="bound on |force / (rho U^2 b) - 1|")
    a = ap.parse_args()
    if a.window is None:
        try:
            with open(lahar_py.run_case(a.out)) as fh:
                end = float(yaml.safe_load(fh)["time"]["end"])
        except (OSError, KeyError, TypeError, ValueError) as e:
            sys.stderr.write(f"compare_jet: {a.out}: {e}: give --window T0 T1\n")
            return 2
        a.window = [0.5 * end, end]
    if not a.window[0] < a.window[1]:
        lahar_py.fail_usage(f"--window {a.window[0]:g} {a.window[1]:g}: T0 must be below T1")
    try:
        m, s = measure(a.out, a.plate, a.window)
    except InputError as e:
        sys.stderr.write(f"compare_jet: {e}\n")
        return 2
    m["dx"] = run_dx(a.out)
    c = m["case"]
    unit = "N/m" if c["dim"] == 2 else "N"
    deficit = m["reference_deficit_at_nozzle"]
    print(f"{c['dim']}D jet b = {c['b']:g} m, U = {c['u']:g} m/s, nozzle {c['nozzle_distance']:g} m from the plate "
          f"'{c['plate']}'" + (f" (the theory's deficit there {100 * deficit:.2f} %)" if deficit is not None else "")
          + f", dx = {m['dx']:g} m (b/dx = {c['b'] / m['dx']:.0f}); window {a.window[0]:g}-{a.window[1]:g} s")
    w = max(8, max(len(r["name"]) for r in m["pressure"]["probes"]))
    print(f"  {'probe':<{w}}   s/b     mean [Pa]   reference [Pa]   difference / (rho U^2/2)   rms [Pa]")
    for r in m["pressure"]["probes"]:
        ref = f"{r['reference']:14.0f} {100 * r['diff']:+14.1f} %" if r["reference"] is not None else f"{'-':>14} {'-':>16}"
        print(f"  {r['name']:<{w}} {r['s'] / c['b']:+6.2f} {r['run']:12.0f} {ref} {r['rms']:16.0f}")
    print(f"  largest |difference| {100 * m['pressure']['max_abs_diff']:.1f} % of rho U^2/2; stagnation "
          f"({m['stagnation']['probe']}) {100 * m['stagnation']['rel']:+.1f} %")
    f = m["force"]
    print(f"  force on the plate {f['run']:.2f} {unit}   momentum flux {f['reference']:.2f} {unit}   {100 * f['rel']:+.1f} %   "
          f"(rms {f['rms']:.3g} {unit}; window halves " + " / ".join(f"{100 * h:+.1f} %" for h in f["halves_rel"]) + ")")
    pi = m["probe_integral"]
    if pi is not None:
        print(f"  probes integrated over s = {pi['span'][0]:g}..{pi['span'][1]:g} m: {pi['run']:.1f} N/m, the "
              f"reference over that span {pi['reference']:.1f} N/m ({100 * pi['rel']:+.1f} %)")
    with open(a.json or os.path.join(a.out, "jet.json"), "w") as fh:
        lahar_py.dump_json(m, fh)
    if not a.no_plot:
        plot(m, s, a.output or os.path.join(a.out, "jet.png"))
    if a.check:
        bad = []
        if not m["pressure"]["max_abs_diff"] <= a.pressure_tol:
            bad.append(f"pressure {100 * m['pressure']['max_abs_diff']:.1f} % of rho U^2/2 outside "
                       f"{100 * a.pressure_tol:g} %")
        if not abs(f["rel"]) <= a.force_tol:
            bad.append(f"force {100 * f['rel']:+.1f} % outside +-{100 * a.force_tol:g} %")
        return lahar_py.check_verdict("compare_jet", bad)
    return 0


if __name__ == "__main__":
    sys.exit(main())
