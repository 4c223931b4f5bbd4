#!/usr/bin/python3
"""Stability stress suite (issue 4): sweeps that find the limits of the solver, and the CI checks
that an unstable setting is caught (exit 1, status "unstable", what/where/when, a readable final
snapshot) while a stable one finishes.

  stress.py sweep [--full] [--only NAME[,NAME]] [--out DIR] [--lahar PATH] [--threads N]
  stress.py ci NAME [--out DIR] [--lahar PATH]

Every run is `lahar run CASE -o OUT --in-process` on a copy of a case from cases/ (or a scene
written here) with keys overridden (override(): dotted keys, e.g. sph.c0=2). A sweep walks one
setting from safe to unsafe and reports, per setting, how the run ended, what caught a failure
(density band, crossing, overlap, non-finite state, dt collapse: common/protocol/instability.h), where and
when, and an accuracy figure; then the largest stable setting. Tables go to stdout and OUT/*.csv.
"""
import argparse
import copy
import csv
import json
import math
import os
import subprocess
import sys
import time

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
CASES = os.path.join(ROOT, "cases")


# ---- cases and runs --------------------------------------------------------------------------
# Variants of a case are made with tools/case_override.py (the one way the tools copy a case with
# keys changed); scenes that exist only here are written as documents with its writer.
sys.path.insert(0, os.path.join(ROOT, "tools"))
import case_override  # noqa: E402


def load_case(name):
    return case_override.load_case(os.path.join(CASES, name))


def override(case, **keys):
    """A copy of case with dotted keys set: override(c, **{"sph.c0": 2, "time.end": 0.3})."""
    c = copy.deepcopy(case)
    for path, v in keys.items():
        case_override.set_path(c, path, v)
    return c


class Run:
    """One `lahar run`: exit status, summary.json, wall time."""

    def __init__(self, args, case, out, label):
        self.out = out
        os.makedirs(out, exist_ok=True)
        path = os.path.join(out, "case.yaml")
        case_override.write_case(case, path, "%s (tests/stress/stress.py)" % label)
        t0 = time.time()
        p = subprocess.run([args.lahar, "run", path, "-o", os.path.join(out, "run"), "-q", "--in-process", "--overwrite",
                            "--threads", str(args.threads)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           text=True)
        self.wall = time.time() - t0
        self.rc = p.returncode
        self.stderr = p.stderr
        try:
            with open(os.path.join(out, "run", "summary.json")) as f:
                self.summary = json.load(f)
        except (OSError, ValueError):
            # exit 2: the case loader refused the setting (its message names the key and the range)
            self.summary = {"status": "rejected" if p.returncode == 2 else "no summary", "steps": 0, "sim_time": 0.0,
                            "message": p.stderr.strip()}
        self.status = self.summary.get("status", "?")
        self.inst = self.summary.get("instability")

    @property
    def stable(self):
        return self.rc == 0 and self.status == "finished"

    def caught(self):
        """'what (caught by, where, when)' of a failed run, '' when it finished."""
        if self.stable:
            return ""
        u = self.inst
        if not u:
            return "%s: %s" % (self.status, self.summary.get("message", "")[:80])
        w = u["where"]
        place = ("%s %d%s" % (w["kind"], w["id"], " '%s'" % w["name"] if w["name"] else "")) if w["kind"] else w["name"]
        return "%s (%s; %s; step %d, t = %.4g s)" % (u["what"], u["caught_by"], place, u["when"]["step"],
                                                    u["when"]["time"])

    def particles(self):
        return os.path.join(self.out, "run", "particles.h5")

    def bodies(self):
        return os.path.join(self.out, "run", "bodies.h5")


def density_errors(path, rho0=1000.0):
    """(max, p99) of |rho/rho0 - 1| over every particle of every snapshot: the worst particle (a
    splash, a wall layer) and the bulk compressibility error; NaN without a particle file."""
    if not os.path.exists(path):
        return float("nan"), float("nan")
    worst, p99 = 0.0, 0.0
    with h5py.File(path, "r") as f:
        for name in f["snapshots"]:
            g = f["snapshots"][name]
            if "density" in g and g["density"].shape[0]:
                r = np.abs(np.asarray(g["density"]) / rho0 - 1.0)
                r = r[np.isfinite(r)]
                if r.size:
                    worst = max(worst, float(np.max(r)))
                    p99 = max(p99, float(np.percentile(r, 99)))
    return worst, p99


def max_density_error(path, rho0=1000.0):
    return density_errors(path, rho0)[0]


# ---- sweeps -----------------------------------------------------------------------------------

def table(args, name, title, header, rows, limit):
    print("\n== %s: %s" % (name, title))
    widths = [max(len(str(h)), *(len(str(r[i])) for r in rows)) for i, h in enumerate(header)]
    print("  " + "  ".join(str(h).ljust(w) for h, w in zip(header, widths)))
    for r in rows:
        print("  " + "  ".join(str(c).ljust(w) for c, w in zip(r, widths)))
    print("  -> %s" % limit)
    with open(os.path.join(args.out, name + ".csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(rows)
    with open(os.path.join(args.out, "limits.txt"), "a") as f:
        f.write("%s: %s\n" % (name, limit))
    sys.stdout.flush()


def largest_stable(values, runs):
    """The largest setting below which every run finished (the sweep is ordered safe to unsafe)."""
    best = None
    for v, r in zip(values, runs):
        if not r.stable:
            break
        best = v
    return best


def dam_break(args, dx, end, **keys):
    case = load_case("dam_break_2d.yaml")
    keys.setdefault("sph.dx", dx)
    keys.setdefault("time.end", end)
    keys.setdefault("time.output_interval", 0.02)
    case.pop("check", None)
    return override(case, **keys)


def sweep_cfl(args):
    """CFL number of the acoustic step limit (sph.cfl, with the force limit sph.cfl_force alike) on
    the 2D dam break; accuracy: the compressibility error max |rho/rho0 - 1|."""
    dx, end = (0.0025, 1.0) if args.full else (0.005, 0.6)
    # the case loader allows (0, 1]: beyond it a run is refused (reported as "rejected")
    values = [0.25, 0.4, 0.5, 0.6, 0.75, 0.9, 1.0, 1.2]
    rows, runs = [], []
    for cfl in values:
        r = Run(args, dam_break(args, dx, end, **{"sph.cfl": cfl, "sph.cfl_force": cfl}),
                os.path.join(args.out, "cfl", str(cfl)), "dam break, cfl %g" % cfl)
        runs.append(r)
        err, p99 = density_errors(r.particles())
        rows.append([cfl, r.status, r.summary.get("steps", 0), "%.3g" % r.summary.get("sim_time", 0),
                     "%.3f" % err, "%.4f" % p99, "%.1f" % r.wall, r.caught()])
    best = largest_stable(values, runs)
    table(args, "cfl", "2D dam break (dx %g m, %g s), sph.cfl = sph.cfl_force" % (dx, end),
          ["cfl", "status", "steps", "t_end", "max|rho/rho0-1|", "p99", "wall_s", "caught"], rows,
          "largest stable cfl: %s" % best)


def sweep_c0(args):
    """Artificial sound speed c0 on the 2D dam break (U_ref = sqrt(2 g H) = 2 m/s, default c0 = 10
    U_ref = 20 m/s): too low and the compressibility error grows until the density band (or a
    crossing) stops the run."""
    dx, end = (0.0025, 1.0) if args.full else (0.005, 0.6)
    values = [40, 20, 15, 10, 7, 5, 3, 2, 1]
    rows, runs = [], []
    for c0 in values:
        r = Run(args, dam_break(args, dx, end, **{"sph.c0": c0}), os.path.join(args.out, "c0", str(c0)),
                "dam break, c0 %g" % c0)
        runs.append(r)
        err, p99 = density_errors(r.particles())
        rows.append([c0, "%.2g" % (c0 / 2.0), r.status, r.summary.get("steps", 0), "%.3g" % r.summary.get("sim_time", 0),
                     "%.3f" % err, "%.4f" % p99, "%.1f" % r.wall, r.caught()])
    best = largest_stable(values, runs)
    ok1 = [v for v, row in zip(values, rows) if row[2] == "finished" and float(row[6]) <= 0.01]
    table(args, "c0", "2D dam break (dx %g m, %g s), sph.c0 (U_ref = 2 m/s)" % (dx, end),
          ["c0", "c0/U_ref", "status", "steps", "t_end", "max|rho/rho0-1|", "p99", "wall_s", "caught"], rows,
          "lowest c0 that finishes: %s m/s; lowest with p99 density error <= 1 %%: %s m/s" %
          (best, min(ok1) if ok1 else None))


def dem_drop_case(kn, safety, v0, end=0.1):
    """A 2D disc (r = 0.05 m, rock, 20.8 kg/m) thrown at v0 from 0.01 m above a fixed floor (linear
    contact kn, e = 0.5); v0 = 0 starts it resting on the floor."""
    return {
        "dimensions": 2, "gravity": [0, -9.81],
        "time": {"end": end, "dt_max": 1e-3, "output_interval": 0.01},
        "materials": {"rock": {"density": 2650, "model": "linear", "kn": kn, "restitution": 0.5, "friction": 0.3}},
        "dem": {"dt_safety": safety},
        "bodies": [
            {"name": "disc", "shape": "disc", "radius": 0.05, "material": "rock",
             "position": [0, 0.06 if v0 > 0 else 0.05], "velocity": [0, -v0]},
            {"name": "floor", "shape": "segment", "motion": "fixed", "material": "rock", "radius": 0.01,
             "vertices": [[-1, -0.01], [1, -0.01]]},
        ],
    }


def rebound_ratio(r, v0, end):
    """Restitution measured from the last snapshot: the disc leaves the floor at v_r after hitting
    it at v_i (0.01 m of free fall), then flies: v_r = v_end + g (end - t_contact)."""
    g, gap = 9.81, 0.01
    t_hit = (-v0 + math.sqrt(v0 * v0 + 2 * g * gap)) / g
    v_hit = v0 + g * t_hit
    with h5py.File(r.bodies(), "r") as f:
        last = f["snapshots"][sorted(f["snapshots"])[-1]]
        vy = float(np.asarray(last["velocity"])[0][1])
    return (vy + g * (end - t_hit)) / v_hit


def sweep_dem(args):
    """DEM contact stiffness against the step. The engine substeps with h = dem.dt_safety x the
    contact period T = 2 pi sqrt(m*/kn), so what a user sets is dt_safety (= h / T), for any kn.
    (a) impact: a disc thrown at 5 m/s onto a floor; accuracy = the measured restitution against
        e = 0.5 (contact too soft for the impact: the overlap check stops it);
    (b) resting: the disc resting on the floor for 0.2 s; leapfrog on the damped contact spring is
        stable for omega h < 2 (sqrt(1 + zeta^2) - zeta), h / T < 0.257 at e = 0.5, and pumps energy
        into the body above it (measured before the loader refused it: the disc jumped 7 cm at
        h / T = 0.29). The case loader now refuses dt_safety above 0.9 x that bound ("rejected")."""
    kns = [1e6, 1e8, 1e9, 1e10] if args.full else [1e6, 1e8, 1e10]
    safeties = [0.02, 0.05, 0.1, 0.15, 0.2, 0.23, 0.3, 0.5] if args.full else [0.02, 0.1, 0.2, 0.23, 0.3]
    rows, limits = [], []
    for kn in kns:
        runs, accurate = [], []
        for s in safeties:
            r = Run(args, dem_drop_case(kn, s, 5.0), os.path.join(args.out, "dem", "impact_%g_%g" % (kn, s)),
                    "DEM impact kn %g dt_safety %g" % (kn, s))
            runs.append(r)
            e = rebound_ratio(r, 5.0, 0.1) if r.stable else float("nan")
            if r.stable and abs(e / 0.5 - 1) <= 0.05:
                accurate.append(s)
            rows.append(["impact 5 m/s", "%g" % kn, s, r.status, r.summary.get("dem_substeps", 0),
                         "%.3f" % e if e == e else "-", "%.1f" % r.wall, r.caught()])
        limits.append("impact kn %g: finishes up to %s, e within 5 %% up to %s" %
                      (kn, largest_stable(safeties, runs), max(accurate) if accurate else None))
    for kn in kns[1:2] + kns[-1:]:
        runs = []
        for s in safeties:
            r = Run(args, dem_drop_case(kn, s, 0.0, end=0.2), os.path.join(args.out, "dem", "rest_%g_%g" % (kn, s)),
                    "DEM resting kn %g dt_safety %g" % (kn, s))
            runs.append(r)
            y = float("nan")
            if r.stable:
                with h5py.File(r.bodies(), "r") as f:
                    last = f["snapshots"][sorted(f["snapshots"])[-1]]
                    y = float(np.asarray(last["position"])[0][1])
            rows.append(["resting", "%g" % kn, s, r.status, r.summary.get("dem_substeps", 0),
                         "y %.5f" % y if y == y else "-", "%.1f" % r.wall, r.caught()])
        limits.append("resting kn %g: stable up to dt_safety %s" % (kn, largest_stable(safeties, runs)))
    table(args, "dem_stiffness", "DEM disc on a floor, dem.dt_safety = substep / contact period",
          ["scene", "kn", "dt_safety", "status", "substeps", "e_meas (0.5)", "wall_s", "caught"], rows,
          "; ".join(limits))


def boulder_case(c0, v0, dx, end):
    """2D: a 2 t boulder (disc of 2000 kg per metre, rock 2650 kg/m^3: r = 0.49 m) hitting still
    water 2 m deep in a 4 m tank at v0 (vertical), until it is about 1.5 m down (before the floor:
    water trapped between a boulder and the floor is another test)."""
    r = math.sqrt(2000.0 / (2650.0 * math.pi))
    return {
        "dimensions": 2, "gravity": [0, -9.81],
        "time": {"end": end, "dt_max": 1e-3, "output_interval": end / 10},
        "materials": {"rock": {"density": 2650, "model": "linear", "kn": 1e8, "restitution": 0.3, "friction": 0.5}},
        "bodies": [
            {"name": "boulder", "shape": "disc", "radius": round(r, 4), "material": "rock",
             "position": [2.0, 2.0 + r + 2 * dx], "velocity": [0, -v0]},
            {"name": "floor", "shape": "segment", "motion": "fixed", "material": "rock", "radius": 0.02,
             "vertices": [[-0.02, -0.02], [4.02, -0.02]]},
            {"name": "left", "shape": "segment", "motion": "fixed", "material": "rock", "radius": 0.02,
             "vertices": [[-0.02, -0.02], [-0.02, 3.0]]},
            {"name": "right", "shape": "segment", "motion": "fixed", "material": "rock", "radius": 0.02,
             "vertices": [[4.02, -0.02], [4.02, 3.0]]},
        ],
        "sph": {"dx": dx, "c0": c0, "alpha": 0.02,
                "blocks": [{"name": "pool", "box": {"lo": [0, 0], "hi": [4.0, 2.0]}}]},
        "output": {"fields": ["velocity", "density", "pressure", "id"]},
    }


def sweep_boulder(args):
    """A 2 t boulder hitting still water at 20 m/s: sph.c0 from 1 to 10 x the impact speed."""
    dx, end = (0.02, 0.08) if args.full else (0.04, 0.08)
    values = [400, 200, 100, 60, 40, 20]
    rows, runs = [], []
    for c0 in values:
        r = Run(args, boulder_case(c0, 20.0, dx, end), os.path.join(args.out, "boulder", str(c0)),
                "boulder 20 m/s, c0 %g" % c0)
        runs.append(r)
        err = max_density_error(r.particles())
        v = float("nan")
        if r.stable:
            with h5py.File(r.bodies(), "r") as f:
                last = f["snapshots"][sorted(f["snapshots"])[-1]]
                v = float(np.asarray(last["velocity"])[0][1])
        rows.append([c0, "%.2g" % (c0 / 20.0), r.status, r.summary.get("steps", 0),
                     "%.3g" % r.summary.get("sim_time", 0), "%.3f" % err, "%.2f" % v if v == v else "-",
                     "%.1f" % r.wall, r.caught()])
    best = largest_stable(values, runs)
    table(args, "boulder", "2D: 2 t boulder (r = 0.49 m) into 2 m of still water at 20 m/s (dx %g m, %g s)" % (dx, end),
          ["c0", "c0/v_impact", "status", "steps", "t_end", "max|rho/rho0-1|", "v_boulder_end", "wall_s", "caught"],
          rows, "lowest c0 that finishes: %s m/s" % best)


def float_case(density, dx, end):
    """2D: a 0.1 x 0.1 m box of the given density released at the surface of a 0.4 m tank 0.15 m deep."""
    return {
        "dimensions": 2, "gravity": [0, -9.81],
        "time": {"end": end, "dt_max": 1e-3, "output_interval": end / 10},
        "materials": {"wall": {"density": 2650, "model": "linear", "kn": 1e6, "restitution": 0.5, "friction": 0.3},
                      "body": {"density": density, "model": "linear", "kn": 1e6, "restitution": 0.5, "friction": 0.3}},
        "bodies": [
            {"name": "floor", "shape": "segment", "motion": "fixed", "material": "wall", "radius": 0.004,
             "vertices": [[-0.004, -0.004], [0.404, -0.004]]},
            {"name": "left", "shape": "segment", "motion": "fixed", "material": "wall", "radius": 0.004,
             "vertices": [[-0.004, -0.004], [-0.004, 0.4]]},
            {"name": "right", "shape": "segment", "motion": "fixed", "material": "wall", "radius": 0.004,
             "vertices": [[0.404, -0.004], [0.404, 0.4]]},
            {"name": "box", "shape": "box", "size": [0.1, 0.1], "radius": 0.004, "material": "body",
             "position": [0.2, 0.15 + 0.05 + 0.005]},
        ],
        "sph": {"dx": dx, "alpha": 0.05, "blocks": [{"name": "water", "box": {"lo": [0, 0], "hi": [0.4, 0.15]}}]},
        "output": {"fields": ["velocity", "density", "pressure", "id"]},
    }


def sweep_density_ratio(args):
    """Bodies of density ratio 0.1 ... 2.65 to water dropped on its surface (light bodies are the
    hard ones for a staggered coupling: added mass)."""
    dx, end = (0.005, 1.0) if args.full else (0.01, 0.5)
    values = [2.65, 2.0, 1.5, 1.0, 0.5, 0.25, 0.1]
    rows, runs = [], []
    for ratio in values:
        r = Run(args, float_case(1000.0 * ratio, dx, end), os.path.join(args.out, "density_ratio", str(ratio)),
                "box density ratio %g" % ratio)
        runs.append(r)
        y = float("nan")
        if r.stable:
            with h5py.File(r.bodies(), "r") as f:
                last = f["snapshots"][sorted(f["snapshots"])[-1]]
                y = float(np.asarray(last["position"])[3][1])
        rows.append([ratio, r.status, r.summary.get("steps", 0), "%.3g" % r.summary.get("sim_time", 0),
                     "%.3f" % y if y == y else "-", "%.1f" % r.wall, r.caught()])
    stable = [v for v, r in zip(values, runs) if r.stable]
    table(args, "density_ratio", "2D box dropped on water, body density / water density (dx %g m, %g s)" % (dx, end),
          ["ratio", "status", "steps", "t_end", "y_box_end", "wall_s", "caught"], rows,
          "stable density ratios: %s" % stable)


def soil_wall_case(v0, dx, end):
    """2D: a 0.1 x 0.05 m block of the granular_collapse_2d bars (Bui et al. 2008: rho 2650,
    E 0.84 MPa, nu 0.3, phi 19.8 deg) sliding on a floor at v0 into a fixed wall 0.05 m ahead."""
    soil = load_case("granular_collapse_2d.yaml")["materials"]["bars"]
    return {
        "dimensions": 2, "gravity": [0, -9.81],
        "time": {"end": end, "dt_max": 1e-3, "output_interval": end / 10},
        "materials": {"wall": {"density": 2700, "model": "linear", "kn": 1e6, "restitution": 0.5, "friction": 0.3},
                      "bars": dict(soil)},
        "bodies": [
            {"name": "floor", "shape": "box", "motion": "fixed", "material": "wall", "radius": 0.001,
             "size": [0.44, 0.02], "position": [0.2, -0.01]},
            {"name": "wall", "shape": "box", "motion": "fixed", "material": "wall", "radius": 0.001,
             "size": [0.02, 0.3], "position": [0.21, 0.15]},
        ],
        "sph": {"dx": dx, "blocks": [{"name": "block", "phase": "soil", "material": "bars",
                                      "box": {"lo": [0.05, 0], "hi": [0.15, 0.05]}, "velocity": [v0, 0]}]},
        "output": {"fields": ["velocity", "density", "id"]},
    }


def sweep_soil(args):
    """A fast soil flow hitting a wall: the block of soil_wall_case at speeds up to 20 m/s (debris
    flows reach 10-20 m/s); accuracy: the largest soil density error max |rho/rho0 - 1|."""
    dx, end = (0.0025, 0.1) if args.full else (0.005, 0.06)
    values = [1, 2, 5, 10, 20, 40]
    rows, runs = [], []
    for v0 in values:
        r = Run(args, soil_wall_case(v0, dx, end), os.path.join(args.out, "soil_wall", str(v0)),
                "soil block at %g m/s into a wall" % v0)
        runs.append(r)
        err, p99 = density_errors(r.particles(), 2650.0)
        rows.append([v0, r.status, r.summary.get("steps", 0), "%.3g" % r.summary.get("sim_time", 0),
                     "%.3f" % err, "%.4f" % p99, "%.1f" % r.wall, r.caught()])
    best = largest_stable(values, runs)
    table(args, "soil_wall", "2D soil block (bars of granular_collapse_2d) into a wall (dx %g m, %g s)" % (dx, end),
          ["v0", "status", "steps", "t_end", "max|rho/rho0-1|", "p99", "wall_s", "caught"], rows,
          "fastest impact that finishes: %s m/s" % best)


def sweep_hydrostatic_long(args):
    """A 10^6-step hydrostatic tank (full suite only): water at rest in the 2D tank of the CI
    coupling test at a coarse dx, stepped 10^6 times; it must finish, stay within the density
    band and keep its free surface."""
    if not args.full:
        print("\n== hydrostatic_1e6: only with --full (10^6 steps)")
        return
    dx = 0.01
    case = {
        "dimensions": 2, "gravity": [0, -9.81],
        "time": {"end": 1.0, "dt_max": 1e-3, "output_interval": 0.5},
        "materials": {"wall": {"density": 2650, "model": "linear", "kn": 1e5, "restitution": 0.5, "friction": 0.3}},
        "bodies": [
            {"name": "left", "shape": "segment", "motion": "fixed", "material": "wall", "radius": 0.002,
             "vertices": [[-0.002, -0.002], [-0.002, 0.2]]},
            {"name": "right", "shape": "segment", "motion": "fixed", "material": "wall", "radius": 0.002,
             "vertices": [[0.202, -0.002], [0.202, 0.2]]},
            {"name": "floor", "shape": "segment", "motion": "fixed", "material": "wall", "radius": 0.002,
             "vertices": [[-0.002, -0.002], [0.202, -0.002]]},
        ],
        "sph": {"dx": dx, "alpha": 0.1, "blocks": [{"name": "water", "box": {"lo": [0, 0], "hi": [0.2, 0.1]}}]},
        "output": {"fields": ["velocity", "density", "pressure", "id"]},
    }
    # dt = cfl h / c0 with the default c0 = 10 sqrt(2 g H): the end time that gives 10^6 steps
    c0 = 10 * math.sqrt(2 * 9.81 * 0.1)
    dt = 0.25 * 1.3 * dx / c0
    case["time"]["end"] = round(1e6 * dt, 6)
    case["time"]["output_interval"] = case["time"]["end"] / 4
    r = Run(args, case, os.path.join(args.out, "hydrostatic_1e6"), "hydrostatic tank, 1e6 steps")
    err = max_density_error(r.particles())
    spread = float("nan")
    if r.stable:
        with h5py.File(r.particles(), "r") as f:
            last = f["snapshots"][sorted(f["snapshots"])[-1]]
            x, y = np.asarray(last["x"]), np.asarray(last["y"])
            top = [y[(x >= a) & (x < a + 0.02)].max() for a in np.arange(0, 0.2, 0.02)]
            spread = max(top) - min(top)
    rows = [[r.summary.get("steps", 0), "%.4g" % r.summary.get("sim_time", 0), r.status, "%.4f" % err,
             "%.4f" % spread if spread == spread else "-", "%.0f" % r.wall, r.caught()]]
    table(args, "hydrostatic_1e6", "2D tank at rest, dx %g m, 10^6 steps" % dx,
          ["steps", "t_end", "status", "max|rho/rho0-1|", "surface_spread_m", "wall_s", "caught"], rows,
          "%s after %d steps" % (r.status, r.summary.get("steps", 0)))


SWEEPS = {
    "cfl": sweep_cfl, "c0": sweep_c0, "dem_stiffness": sweep_dem, "boulder": sweep_boulder,
    "soil_wall": sweep_soil, "density_ratio": sweep_density_ratio, "hydrostatic_1e6": sweep_hydrostatic_long,
}


# ---- CI checks ---------------------------------------------------------------------------------

def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


def check_caught(r, what, kind, rho0=1000.0):
    """An unstable run: exit 1, status "unstable", the report's fields, the final snapshots readable,
    marked, at the failing step, and (for a particle) holding the named particle where the report
    says."""
    s = r.summary
    if r.rc != 1 or r.status != "unstable":
        fail("exit %d, status %r (expected 1, 'unstable'): %s" % (r.rc, r.status, s.get("message", "")))
    u = s.get("instability")
    if not u or u["what"] != what or u["where"]["kind"] != kind:
        fail("instability %r, expected what %r kind %r" % (u, what, kind))
    for key in ("what", "caught_by", "where", "when", "value", "limit", "message"):
        if key not in u:
            fail("instability has no %r" % key)
    if u["message"] not in s["message"] or u["message"] not in r.stderr:
        fail("the message is not in summary.json's message and on stderr")
    step, t = u["when"]["step"], u["when"]["time"]
    if kind and ("step %d" % step) not in u["message"]:
        fail("the message does not name the step: " + u["message"])
    fs = s.get("final_snapshot", {})
    files = [f for f in ("particles.h5", "bodies.h5") if os.path.exists(os.path.join(r.out, "run", f))]
    for fname in files:
        if fname not in fs:
            fail("summary.json final_snapshot does not list " + fname)
        with h5py.File(os.path.join(r.out, "run", fname), "r") as f:
            g = f[fs[fname]["group"]]
            if g.name != sorted(f["snapshots"], key=lambda n: int(n))[-1] and g.name.split("/")[-1] != sorted(f["snapshots"])[-1]:
                fail("%s: final_snapshot is not the last snapshot" % fname)
            mark = g.attrs.get("instability", g.attrs.get("stopped"))
            if mark is None:
                fail("%s: the final snapshot is not marked" % fname)
            if abs(float(g.attrs["time"]) - t) > 1e-9 * max(1.0, t):
                fail("%s: final snapshot at t = %.9g, the report says %.9g" % (fname, float(g.attrs["time"]), t))
            if fname == "particles.h5" and kind == "particle":
                ids = np.asarray(g["id"])
                i = np.nonzero(ids == u["where"]["id"])[0]
                if len(i) != 1:
                    fail("particle %d not in the final snapshot" % u["where"]["id"])
                i = int(i[0])
                pos = np.array([g["x"][i], g["y"][i], g["z"][i]])
                if u["where"]["position"] is not None and not np.allclose(pos, u["where"]["position"], rtol=1e-6,
                                                                          atol=1e-9):
                    fail("particle %d at %s in the snapshot, the report says %s" % (u["where"]["id"], pos,
                                                                                   u["where"]["position"]))
                if what == "density out of band":
                    rho = float(g["density"][i]) / rho0
                    if abs(rho - u["value"]) > 1e-5 * rho:
                        fail("rho/rho0 %.6g in the snapshot, the report says %.6g" % (rho, u["value"]))
                    if 0.5 <= rho <= 2.0 and u["limit"] in (0.5, 2.0):
                        fail("rho/rho0 %.4g is inside the default band" % rho)
    print("caught: %s" % r.caught())
    print("  message: %s" % u["message"])
    print("  final snapshot: %s" % ", ".join("%s %s (step %d)" % (k, v["group"], v["step"]) for k, v in fs.items()))


def ci(args):
    name = args.name
    if name == "density_band":
        # c0 = 1 m/s (U_ref = 2 m/s): the column compresses by far more than 2x under its weight
        r = Run(args, dam_break(args, 0.005, 0.3, **{"sph.c0": 1}), os.path.join(args.out, name), name)
        check_caught(r, "density out of band", "particle")
    elif name == "dt_collapse":
        # the dam break at default settings with a dt_collapse threshold so tight (0.9) that the
        # growing CFL speed of the front (dt = cfl h / (c0 + |v|max)) trips it: the mechanism
        r = Run(args, dam_break(args, 0.005, 0.3, **{"stability.dt_collapse": 0.9}), os.path.join(args.out, name), name)
        check_caught(r, "dt collapse", "")
        u = r.summary["instability"]
        if not (u["value"] < 0.9 * u["limit"] / 0.9 * 1.0000001 and u["caught_by"] == "coordinator"):
            fail("dt %g is not below the limit %g" % (u["value"], u["limit"]))
    elif name == "overlap":
        # a disc at 5 m/s on a contact far too soft for it (kn 1e6: it would sink 23 mm into a
        # floor whose sweep radius is 10 mm)
        r = Run(args, dem_drop_case(1e6, 0.02, 5.0), os.path.join(args.out, name), name)
        check_caught(r, "overlap", "body")
        u = r.summary["instability"]
        if u["where"]["name"] != "disc" or not u["value"] > u["limit"]:
            fail("overlap report %r" % u)
    elif name == "runaway":
        # a body thrown at 1e16 m/s leaves any sane domain within one step: caught with its name
        case = {
            "dimensions": 3, "time": {"end": 0.01, "dt_max": 1e-3, "output_interval": 0.005},
            "materials": {"rock": {"density": 2650, "young": 1e8, "restitution": 0.5, "friction": 0.5}},
            "bodies": [
                {"name": "ball", "shape": "sphere", "radius": 0.05, "material": "rock", "position": [0, 0, 1]},
                {"name": "bullet", "shape": "sphere", "radius": 0.05, "material": "rock", "position": [1, 0, 1],
                 "velocity": [1e16, 0, 0]},
                {"name": "floor", "shape": "plane", "motion": "fixed", "normal": [0, 0, 1], "size": [2, 2],
                 "radius": 0.02, "material": "rock", "position": [0, 0, 0]},
            ],
        }
        r = Run(args, case, os.path.join(args.out, name), name)
        check_caught(r, "runaway", "body")
        u = r.summary["instability"]
        if u["where"]["name"] != "bullet" or u["where"]["id"] != 1 or not u["where"]["position"][0] > 1e12 * 0.999:
            fail("runaway report %r" % u)
    elif name == "soil_wall":
        # a soil block into a wall at 20 m/s (about the soil's P-wave speed, 20.7 m/s): squeezed past
        # 2 x its rest density against the wall, caught; at 2 m/s it finishes (its density only
        # thins where the block spreads, which the band allows soil)
        r = Run(args, soil_wall_case(20, 0.005, 0.06), os.path.join(args.out, name, "fast"), "soil wall 20 m/s")
        check_caught(r, "density out of band", "particle", 2650.0)
        u = r.summary["instability"]
        if not (u["value"] > 2.0 and u["limit"] == 2.0 and "soil particle" in u["message"]):
            fail("soil report %r" % u)
        r = Run(args, soil_wall_case(2, 0.005, 0.06), os.path.join(args.out, name, "slow"), "soil wall 2 m/s")
        if not r.stable or r.inst:
            fail("2 m/s: exit %d status %s: %s" % (r.rc, r.status, r.summary.get("message", "")))
        print("2 m/s: finished, %d steps to t = %g s" % (r.summary["steps"], r.summary["sim_time"]))
    elif name == "stable":
        # the same scenes at safe settings finish
        for label, case in (("dam_break", dam_break(args, 0.005, 0.3)), ("dem", dem_drop_case(1e9, 0.02, 5.0))):
            r = Run(args, case, os.path.join(args.out, name, label), label)
            if not r.stable or r.inst:
                fail("%s: exit %d status %s: %s" % (label, r.rc, r.status, r.summary.get("message", "")))
            print("%s: finished, %d steps to t = %g s" % (label, r.summary["steps"], r.summary["sim_time"]))
    else:
        fail("unknown CI check " + name)
    print("PASS: " + name)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("command", choices=["sweep", "ci"])
    ap.add_argument("name", nargs="?", help="ci: the check (density_band, dt_collapse, overlap, runaway, soil_wall, stable)")
    ap.add_argument("--full", action="store_true", help="sweep: finer resolutions, longer runs, the 10^6-step tank")
    ap.add_argument("--only", help="sweep: comma-separated sweeps (%s)" % ", ".join(SWEEPS))
    ap.add_argument("--out", default="stress_out")
    ap.add_argument("--lahar", default=os.path.join(ROOT, "build", "bin", "lahar"))
    ap.add_argument("--threads", type=int, default=1)
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    if args.command == "ci":
        ci(args)
        return
    names = args.only.split(",") if args.only else list(SWEEPS)
    open(os.path.join(args.out, "limits.txt"), "w").close()
    t0 = time.time()
    for n in names:
        if n not in SWEEPS:
            fail("unknown sweep %s (%s)" % (n, ", ".join(SWEEPS)))
        SWEEPS[n](args)
    print("\nlimits (also in %s/limits.txt), %.0f s wall:" % (args.out, time.time() - t0))
    print(open(os.path.join(args.out, "limits.txt")).read())


if __name__ == "__main__":
    main()
