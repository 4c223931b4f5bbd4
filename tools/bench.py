#!/usr/bin/env python3
"""lahar bench: run time against error, co-simulation overhead and DEM subcycling.

usage: lahar bench -o OUT [--quick] [--sections pareto,overhead,subcycle] [--cases A,B]
                   [--threads N] [--cost wall|cpu] [--resume] [--timeout S] [--keep] [--list]
       (or tools/bench.py --lahar build/bin/lahar -o OUT ...)

Sections (default: all three):
  pareto    every validation case at >= 4 resolutions (the case's settings) plus one-at-a-time
            changes of the settings that trade speed for accuracy (kernel, CFL number, delta-SPH,
            artificial sound speed c0; for soil the artificial viscosity: lahar's 0.1, 0 against
            the paper's 1, 1; only the settings that mean something for the scene) at two
            resolutions; each run is `lahar check --in-process`
            on a copy of the case (tools/case_override.py) with a shorter time.end. Writes
            OUT/<case>.csv, OUT/<case>_pareto.png (error against wall time, Pareto front drawn) and
            OUT/summary.md (the cheapest setting within a stated error per case).
  overhead  the boulder pool (docs/bench/cases/boulder_pool_2d.yaml, free boulders sinking in
            water, >= 20,000 particles) run as separate processes over LCM and --in-process:
            wall-time ratio, per-node compute and wait time per step (OUT/overhead.csv, .md).
            --engine lammps: the pool with segment walls and disc boulders on the LAMMPS engine.
  subcycle  the same pool with stiff boulders (kn 1e8) at a coarser dx: the DEM node subcycling
            inside the SPH step against the whole run forced down to the DEM's stable step
            (time.dt_max = dt_stable): OUT/subcycle.csv, .md.
--quick: 2 resolutions and few settings per case, overhead and subcycle at small sizes (a smoke
test of the tool, about 1-3 min; the numbers are not the benchmark's). The default run needs
about 840 s of CPU for the pareto section (7-15 min on 2 idle cores).
Speed figures are wall times on whatever machine runs this: on a shared or loaded machine they
are noisy (each row records the load average at its start and the CPU time used).
Exit status: 0 done (runs that fail are recorded in the CSV with their exit status), 2 bad
usage or the lahar executable missing."""
import argparse
import csv
import json
import math
import os
import re
import shutil
import signal
import subprocess
import sys
import textwrap
import time

TOOLS = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(TOOLS)
sys.path.insert(0, TOOLS)
import lahar_py  # noqa: E402

lahar_py.require("yaml", "numpy", "matplotlib", "h5py")
import case_override  # noqa: E402

CASES_DIR = os.path.join(ROOT, "cases")
DEFAULT_TIMEOUT = 900.0  # seconds after which one run is stopped (--timeout)
BENCH_CASES_DIR = os.path.join(ROOT, "docs", "bench", "cases")

# --------------------------------------------------------------------------------------------
# What is swept. `dx`: the resolutions of the base setting (coarse to fine; dx divides the
# periodic lengths); `vary_at`: indices into dx where the settings are varied; `error`: the
# check.json values whose maximum is the run's error; `target`: the error the summary picks the
# cheapest setting within; `overrides`: applied to every run (shorter end times).
# Settings: (family, value, {path: value}); c0 values are factors of the case's c0.
SETTINGS = [
    ("kernel", "quintic", {"sph.kernel": "quintic"}),
    ("kernel", "wendland2", {"sph.kernel": "wendland2"}),
    ("cfl", "0.4", {"sph.cfl": 0.4}),
    ("cfl", "0.1", {"sph.cfl": 0.1}),
    ("delta", "0", {"sph.delta": 0.0}),
    ("c0", "x0.5", {"sph.c0": 0.5}),
    ("c0", "x2", {"sph.c0": 2.0}),
]
QUICK_SETTINGS = ["kernel=wendland2", "cfl=0.4", "soil_av=paper"]
# The soil's own trade (Drucker-Prager SPH, sph_node/soil/sph_soil.h): lahar's default artificial
# viscosity alpha = 0.1, beta = 0 against the paper's alpha = beta = 1 (Trujillo-Vela et al. 2020, section 5.3);
# `{soil}` is replaced by the name of the case's soil material.
SOIL_SETTINGS = [
    ("soil_av", "paper", {"materials.{soil}.av_alpha": 1.0, "materials.{soil}.av_beta": 1.0}),
]

# A series a check writes into check.json (plot panel `panel`, curve `curve`), `info` key added to
# it: for the dam breaks the front position x = column width + advance (the check's front is the
# furthest particle centre; with the column width the dx/2 lattice offset drops out).
FRONT_SERIES = dict(panel="surge front (furthest particle along the flow)", curve="lahar", add_info="column_width")

BENCH = {
    "poiseuille_2d": dict(
        file="poiseuille_2d.yaml", overrides={"time.end": 30.0},
        dx=[0.1 / 10, 0.1 / 16, 0.1 / 20, 0.1 / 25, 0.1 / 40], vary_at=[1, 2],
        error=["steady_l2_rel_error", "plate_force_rel_error"], target=0.01,
        error_note="max(steady L2 of u against the transient series at t = 30 s, plate force) (Trujillo-Vela et al. 2020, eq. 28-32)"),
    "cylinder_array_2d": dict(
        file="cylinder_array_2d.yaml", overrides={},
        dx=[0.2 / 20, 0.2 / 25, 0.2 / 32, 0.2 / 40], vary_at=[0, 1],
        error=["K_rel_error"], target=0.05,
        error_note="K against Sangani & Acrivos at c = 0.1 after the case's 200 s (with its particle shifting)"),
    "hydrostatic_2d": dict(
        file="hydrostatic_2d.yaml", overrides={"time.end": 1.0},
        dx=[0.02, 0.0125, 0.01, 0.0075, 0.005], vary_at=[1, 2],
        error=["wall_force_rel_error", "pressure_l2_rel_error"], target=0.03,
        error_note="max(wall force, pressure L2) against rho g h^2/2, rho g (h - y), late window of 1 s"),
    # The dam breaks' reference is an experiment: their error is the front's deviation from the
    # converged front of lahar's own dx sweep (`converged`), and the deviation from Martin & Moyce
    # is reported beside it (`experiment`): the experiment's gate opening delays its front by an
    # offset that no refinement removes, so mixing the two would rank the coarsest run best.
    "dam_break_2d": dict(
        file="dam_break_2d.yaml", overrides={"time.end": 0.35},
        dx=[0.1 / 10, 0.1 / 14, 0.1 / 20, 0.1 / 28, 0.1 / 40], vary_at=[1, 2],
        error=["front_rel_error"], converged=FRONT_SERIES, target=0.05,
        error_note="surge front against the converged front of the dx sweep (Richardson), largest deviation "
                   "over the distance it runs to the wall; deviation from Martin & Moyce 1952 (n^2 = 2) beside it"),
    "dam_break_3d": dict(
        # the column made 0.1 wide (height 2 x width, the tank's full 0.25 m across) so that the
        # Martin & Moyce front applies; the case's 0.3 m column has no published front to compare
        # dx down to 0.1/40 (320,000 particles, 72 CPU minutes): the three finest runs' order moved
        # 2.05, 0.79, 2.26 as the sweep ended at 0.1/20, 0.1/28, 0.1/40 (the front moves in steps of
        # dx); with 0.1/40 in, 0.1/20 is within 5 % against each converged front tried (the three-run
        # Richardson, the finest run, a fit of the four finest: docs/bench/summary.md)
        file="dam_break_3d.yaml", overrides={"time.end": 0.35, "sph.blocks.0.box.hi": [0.1, 0.25, 0.2]},
        dx=[0.1 / 4, 0.1 / 5, 0.1 / 7, 0.1 / 10, 0.1 / 14, 0.1 / 20, 0.1 / 28, 0.1 / 40], vary_at=[0, 1], timeout=7200.0,
        error=["front_rel_error"], converged=FRONT_SERIES, target=0.05,
        error_note="surge front against the converged front of the dx sweep (Richardson; column 0.1 x 0.25 x 0.2 m "
                   "instead of the case's 0.3 m wide one); deviation from Martin & Moyce 1952 (n^2 = 2) beside it"),
    # soil cases: `families` names the settings that mean something for the scene (the
    # soil has no delta-SPH and no c0: its sound speed is the P-wave speed of its material)
    "soil_geostatic_2d": dict(
        file="soil_geostatic_2d.yaml", overrides={}, soil="sand",  # the 0.1 m period needs dx <= 0.0128
        dx=[0.1 / 8, 0.1 / 10, 0.1 / 20, 0.1 / 40], vary_at=[1, 2], families=["kernel", "cfl", "soil_av"],
        error=["sigma_v_rel_error", "K0_rel_error", "creep_rel"], target=0.05,
        error_note="max(sigma_v against rho g z, K0 against nu/(1-nu), creep) of the soil at rest, 1 s"),
    "soil_block_incline_2d": dict(
        file="soil_block_incline_2d.yaml", overrides={}, soil="block",
        dx=[0.01, 0.005, 0.0025, 0.00125], vary_at=[0, 1], families=["kernel", "cfl", "soil_av"],
        error=["accel_rel_error"], target=0.05,
        error_note="sliding block's acceleration against g (sin theta - mu_phi cos theta) (Trujillo-Vela et al. 2020, eq. 22-27)"),
    "darcy_column_2d": dict(
        file="darcy_column_2d.yaml", overrides={}, soil="skeleton",
        dx=[0.1 / 8, 0.1 / 10, 0.1 / 20, 0.1 / 40], vary_at=[1, 2], families=["kernel", "cfl", "delta", "c0", "soil_av"],
        error=["darcy_velocity_rel_error"], target=0.05,
        error_note="water's velocity through the soil against Darcy k_h i (Trujillo-Vela et al. 2020, eq. 8-10)"),
}
QUICK = {
    "poiseuille_2d": dict(dx=[0.1 / 10, 0.1 / 16], vary_at=[0], overrides={"time.end": 10.0}),
    "cylinder_array_2d": dict(dx=[0.2 / 20, 0.2 / 25], vary_at=[0], overrides={"time.end": 20.0}),
    "hydrostatic_2d": dict(dx=[0.02, 0.0125], vary_at=[0], overrides={"time.end": 0.3}),
    "dam_break_2d": dict(dx=[0.1 / 10, 0.1 / 14], vary_at=[0], overrides={"time.end": 0.25}),
    "dam_break_3d": dict(dx=[0.1 / 3, 0.1 / 4], vary_at=[0],
                         overrides={"time.end": 0.2, "sph.blocks.0.box.hi": [0.1, 0.25, 0.2]}),
    "soil_geostatic_2d": dict(dx=[0.1 / 8, 0.1 / 10], vary_at=[0], overrides={"time.end": 0.3}),
    "soil_block_incline_2d": dict(dx=[0.01, 0.005], vary_at=[0], overrides={}),
    "darcy_column_2d": dict(dx=[0.1 / 8, 0.1 / 10], vary_at=[0], overrides={"time.end": 0.05}),
}

COST_KEY = {"wall": "wall_s", "cpu": "cpu_s"}
CSV_COLUMNS = ["case", "label", "family", "setting", "dx", "particles", "steps", "sim_time", "wall_s",
               "particle_steps_per_s", "cpu_s", "process_wall_s", "peak_rss_mb", "rss_per_particle_kb",
               "error", "error_metrics", "exp_deviation", "error_reference", "dem_substeps", "exit_status", "load_avg", "threads", "overrides"]


def log(msg):
    print(msg, flush=True)


# --------------------------------------------------------------------------------------------
# One run: lahar run/check as a child, with its rusage (peak memory, CPU time) from wait4.
def _vm_hwm_kb(pid):
    """Peak resident set (VmHWM) of one process, kB; 0 when it is gone."""
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1])
    except (OSError, ValueError):
        pass
    return 0


def _descendants(pid):
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        try:
            for t in os.listdir(f"/proc/{p}/task"):
                with open(f"/proc/{p}/task/{t}/children") as f:
                    kids = [int(k) for k in f.read().split()]
                out += kids
                todo += kids
        except (OSError, ValueError):
            pass
    return out


def run_timeout(args, spec=None):
    """Seconds after which one run is stopped: --timeout, else the pareto case's own, else DEFAULT_TIMEOUT."""
    if args.timeout is not None:
        return args.timeout
    return (spec or {}).get("timeout", DEFAULT_TIMEOUT)


def run_lahar(lahar, cmd, case_path, out, threads, in_process=True, timeout=600.0, check_plot=False):
    """Runs lahar as a child; returns its exit status, wall and CPU time (wait4) and peak memory:
    the sum over lahar and the nodes it starts of each process's VmHWM, sampled every 50 ms (wait4's
    ru_maxrss cannot be used: Linux carries the forking Python's high-water mark across exec)."""
    argv = [lahar, cmd, case_path, "-o", out, "-q"]
    if threads:
        argv += ["--threads", str(threads)]
    if in_process:
        argv.append("--in-process")
    env = dict(os.environ)
    if not check_plot:
        env["LAHAR_CHECK_NO_PLOT"] = "1"
    if os.path.isdir(out):
        shutil.rmtree(out)
    load = os.getloadavg()[0]
    t0 = time.monotonic()
    hwm = {}
    with open(out + ".log", "w") as logf:
        p = subprocess.Popen(argv, stdout=logf, stderr=subprocess.STDOUT, env=env, start_new_session=True)
        status, ru = None, None
        while True:
            for q in [p.pid] + _descendants(p.pid):
                hwm[q] = max(hwm.get(q, 0), _vm_hwm_kb(q))
            pid, st, r = os.wait4(p.pid, os.WNOHANG)
            if pid == p.pid:
                status, ru = st, r
                break
            if time.monotonic() - t0 > timeout:
                os.killpg(p.pid, signal.SIGTERM)
                time.sleep(2.0)
                try:
                    os.killpg(p.pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                _, st, r = os.wait4(p.pid, 0)
                status, ru = None, r
                break
            time.sleep(0.05)
        p.returncode = 0  # reaped by wait4 above; keep Popen from waiting again
    wall = time.monotonic() - t0
    code = "timeout" if status is None else (os.waitstatus_to_exitcode(status))
    return dict(exit_status=code, process_wall_s=wall, cpu_s=ru.ru_utime + ru.ru_stime,
                peak_rss_mb=sum(hwm.values()) / 1024.0, load_avg=load)


def read_json(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def summary_numbers(out):
    """Particles, steps, wall time of the stepping loop and DEM substeps from OUT/summary.json."""
    s = read_json(os.path.join(out, "summary.json")) or {}
    sph = s.get("nodes", {}).get("sph", {})
    m = re.search(r"(\d+) particles", sph.get("engine_detail", ""))
    return dict(particles=int(m.group(1)) if m else 0, steps=int(s.get("steps", 0)),
                sim_time=float(s.get("sim_time", 0.0)), wall_s=float(s.get("wall_time_s", float("nan"))),
                dem_substeps=int(s.get("dem_substeps", 0)), summary=s)


def check_error(out, names):
    """max of the named check.json values (metrics or information); NaN when one is missing."""
    c = read_json(os.path.join(out, "check.json"))
    if not c:
        return float("nan"), ""
    vals = {k: v.get("value") for k, v in c.get("metrics", {}).items()}
    vals.update({k: v for k, v in c.get("info", {}).items() if isinstance(v, (int, float))})
    got = [(n, vals.get(n)) for n in names]
    text = ";".join(f"{n}={v:.4g}" if isinstance(v, (int, float)) else f"{n}=nan" for n, v in got)
    nums = [v for _, v in got if isinstance(v, (int, float)) and math.isfinite(v)]
    return (max(nums) if len(nums) == len(names) else float("nan")), text


def read_series(out, series):
    """(t, y) of one curve of check.json's plot panels (numpy arrays), y + info[add_info]; None when
    the run has no check.json or no such curve."""
    import numpy as np
    c = read_json(os.path.join(out, "check.json"))
    if not c:
        return None
    for panel in c.get("plot", {}).get("panels", []):
        if panel.get("title") != series["panel"]:
            continue
        for curve in panel.get("curves", []):
            if curve.get("label") == series["curve"] and curve.get("x"):
                add = float(c.get("info", {}).get(series.get("add_info"), 0.0)) if series.get("add_info") else 0.0
                return np.asarray(curve["x"], float), np.asarray(curve["y"], float) + add
    return None


def converged_reference(curves):
    """The converged solution of a dx sweep. curves: {dx: y} on one time grid, >= 2 resolutions.
    With three or more: Richardson extrapolation from the three finest (y* = y3 + (y3 - y2) dx3^p /
    (dx2^p - dx3^p), p from the L2 norms of the differences, Roache 1998 / Celik et al. 2008's
    procedure for non-constant refinement ratios); when they do not converge monotonically, or
    with two runs, the finest run stands in for it. Returns (y*, description, dx of the run that
    is the reference itself or None)."""
    import numpy as np
    dxs = sorted(curves, reverse=True)
    fine = dxs[-1]
    if len(dxs) >= 3:
        d1, d2, d3 = dxs[-3:]
        y1, y2, y3 = curves[d1], curves[d2], curves[d3]
        e12, e23 = float(np.linalg.norm(y1 - y2)), float(np.linalg.norm(y2 - y3))
        p = lahar_py.richardson_order((d1, d2, d3), e12 / e23 if e23 > 0 else float("inf"))
        if p is not None:
            return (y3 + (y3 - y2) * d3 ** p / (d2 ** p - d3 ** p),
                    f"Richardson from dx {d1:.4g}, {d2:.4g}, {d3:.4g} (observed order {p:.2f})", None)
        why = f"dx {d1:.4g}, {d2:.4g}, {d3:.4g} not in the asymptotic range (difference ratio {e12 / e23 if e23 else float('inf'):.3g})"
    else:
        why = "only two resolutions"
    return curves[fine], f"finest run dx {fine:.4g} ({why})", fine


def converged_errors(rows, spec, rundir):
    """For a case whose reference is an experiment: each run's error against the converged solution
    of the case-settings dx sweep (largest |y - y*| over the window, over the range y* covers in it),
    the experiment's deviation (the check.json values of spec['error']) moved to exp_deviation. The
    window ends when the first base run's y stops rising (the front reaches the wall)."""
    import numpy as np
    ser = {r["label"]: read_series(os.path.join(rundir, r["label"]), spec["converged"]) for r in rows}
    def exact_dx(r):  # the planned dx (a resumed row's dx was rounded to 6 digits in the CSV)
        return min(spec["dx"], key=lambda d: abs(d - r["dx"]))
    base = {exact_dx(r): ser[r["label"]] for r in rows if r["family"] == "base" and ser[r["label"]] is not None}
    for r in rows:
        r["exp_deviation"] = check_error(os.path.join(rundir, r["label"]), spec["error"])[0]
        r["error"], r["error_reference"] = float("nan"), ""
    if len(base) < 2:
        for r in rows:
            r["error_reference"] = "no converged solution (fewer than two resolutions finished)"
        return None
    t = min((s[0] for s in base.values()), key=len)
    end = len(t)
    for dx, (ts, ys) in base.items():  # the free run: until y comes within 2 dx of its largest value
        yi = np.interp(t, ts, ys)
        stop = np.nonzero(yi >= yi.max() - 2.0 * dx)[0]
        end = min(end, int(stop[0]) + 1 if len(stop) else len(t))
    t = t[:end]
    curves = {dx: np.interp(t, ts, ys) for dx, (ts, ys) in base.items()}
    ystar, desc, ref_dx = converged_reference(curves)
    span = float(ystar.max() - ystar.min())
    for r in rows:
        s = ser[r["label"]]
        r["error_reference"] = desc + f", t <= {t[-1]:.3g} s"
        if s is None or span <= 0 or (r["family"] == "base" and exact_dx(r) == ref_dx):
            continue  # the reference run itself has no error of its own
        r["error"] = float(np.max(np.abs(np.interp(t, s[0], s[1]) - ystar))) / span
    return desc


def fmt(v, nd=4):
    if isinstance(v, float):
        return "nan" if math.isnan(v) else f"{v:.{nd}g}"
    return str(v)


# --------------------------------------------------------------------------------------------
# Section 1: run time against error
def plan_case(name, spec, quick):
    """The runs of one case: (label, family, setting, dx, overrides)."""
    runs = []
    doc = case_override.load_case(os.path.join(CASES_DIR, spec["file"]))
    c0 = case_override.get_path(doc, "sph.c0")
    for i, dx in enumerate(spec["dx"]):
        runs.append((f"base_dx{dx:.5g}", "base", "case", dx, {}))
    families = spec.get("families")
    for i in spec["vary_at"]:
        dx = spec["dx"][i]
        for family, value, ov in SETTINGS + SOIL_SETTINGS:
            if families is None and family in (f for f, _, _ in SOIL_SETTINGS):
                continue  # a water case: no soil to set
            if families is not None and family not in families:
                continue
            if quick and f"{family}={value}" not in QUICK_SETTINGS:
                continue
            ov = {k.replace("{soil}", spec.get("soil", "")): v for k, v in ov.items()}
            if family == "c0":
                if not isinstance(c0, (int, float)):
                    continue
                ov["sph.c0"] = c0 * ov["sph.c0"]
            runs.append((f"{family}_{value}_dx{dx:.5g}", family, value, dx, ov))
    return runs


def bench_case(args, name, spec, outdir):
    rundir = os.path.join(outdir, "runs", name)
    os.makedirs(rundir, exist_ok=True)
    rows = []
    runs = plan_case(name, spec, args.quick)
    done = read_csv_rows(os.path.join(outdir, f"{name}.csv")) if args.resume else {}
    log(f"== {name}: {len(runs)} runs (error: {spec['error_note']})"
        + (f", {sum(1 for r in runs if r[0] in done)} taken from the existing {name}.csv" if done else ""))
    for label, family, setting, dx, ov in runs:
        if label in done:
            rows.append(done[label])
            continue
        overrides = dict(spec["overrides"])
        overrides["sph.dx"] = dx
        overrides.update(ov)
        case_path = os.path.join(rundir, label + ".yaml")
        out = os.path.join(rundir, label)
        case_override.override_case(os.path.join(CASES_DIR, spec["file"]), case_path, overrides)
        r = run_lahar(args.lahar, "check", case_path, out, args.threads,
                      timeout=run_timeout(args, spec))
        s = summary_numbers(out)
        # exit 1 = a check metric out of its bound: the run itself is fine, its error is recorded
        ok = r["exit_status"] in (0, 1) and s["steps"] > 0 and s["sim_time"] > 0
        err, err_text = check_error(out, spec["error"]) if ok else (float("nan"), "")
        n, steps, wall = s["particles"], s["steps"], s["wall_s"]
        row = dict(case=name, label=label, family=family, setting=setting, dx=dx, particles=n, steps=steps,
                   sim_time=s["sim_time"], wall_s=wall,
                   particle_steps_per_s=(n * steps / wall) if wall and wall > 0 else float("nan"),
                   cpu_s=r["cpu_s"], process_wall_s=r["process_wall_s"], peak_rss_mb=r["peak_rss_mb"],
                   rss_per_particle_kb=(r["peak_rss_mb"] * 1024.0 / n) if n else float("nan"),
                   error=err, error_metrics=err_text, dem_substeps=s["dem_substeps"],
                   exit_status=r["exit_status"], load_avg=r["load_avg"], threads=args.threads,
                   overrides=" ".join(f"{k}={v}" for k, v in overrides.items()))
        rows.append(row)
        log(f"  {label:28s} n={n:6d} steps={steps:6d} wall={fmt(wall, 3):>7s} s  "
            f"pps={fmt(row['particle_steps_per_s'], 3):>8s}  err={fmt(err, 3):>8s}  exit={r['exit_status']}")
        if not args.keep:
            for f in os.listdir(out) if os.path.isdir(out) else []:
                if f.endswith(".h5"):
                    os.remove(os.path.join(out, f))
    if spec.get("converged"):
        log(f"  error against the converged solution: {converged_errors(rows, spec, rundir)}")
    else:
        for r in rows:
            r["exp_deviation"], r["error_reference"] = float("nan"), "the case's check reference"
    write_csv(os.path.join(outdir, f"{name}.csv"), rows, CSV_COLUMNS)
    plot_pareto(os.path.join(outdir, f"{name}_pareto.png"), name, spec, rows, COST_KEY[args.cost])
    return rows


def read_csv_rows(path):
    """Rows of an earlier OUT/<case>.csv by label (--resume), numbers as numbers."""
    if not os.path.exists(path):
        return {}
    out = {}
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            row = {}
            for k, v in r.items():
                try:
                    row[k] = int(v) if re.fullmatch(r"-?\d+", v or "") else float(v)
                except (TypeError, ValueError):
                    row[k] = v
            for k in ("label", "family", "setting", "error_metrics", "overrides", "case", "error_reference"):
                row[k] = r[k]
            if row.get("exit_status") in (0, 1):
                out[r["label"]] = row
    return out


def write_csv(path, rows, columns):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=columns, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: (fmt(v, 6) if isinstance(v, float) else v) for k, v in r.items()})


COST_LABEL = {"wall_s": "wall time of the run [s]", "cpu_s": "CPU time of the run (user + system) [s]"}


def pareto_front(rows, cost="wall_s"):
    """Rows not dominated in (cost, error), by increasing cost."""
    good = sorted((r for r in rows if math.isfinite(r["error"]) and math.isfinite(r[cost])),
                  key=lambda r: (r[cost], r["error"]))
    front, best = [], float("inf")
    for r in good:
        if r["error"] < best:
            front.append(r)
            best = r["error"]
    return front


def plot_pareto(path, name, spec, rows, cost="wall_s"):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7.5, 5.0), dpi=90)
    markers = {"base": "o", "kernel": "s", "cfl": "^", "delta": "D", "c0": "v", "soil_av": "P"}
    fam_order = ["base", "kernel", "cfl", "delta", "c0", "soil_av"]
    for fam in fam_order:
        for setting in sorted({r["setting"] for r in rows if r["family"] == fam}):
            pts = [r for r in rows if r["family"] == fam and r["setting"] == setting
                   and math.isfinite(r["error"]) and r["error"] > 0]
            if pts:
                lab = "case settings (dx sweep)" if fam == "base" else f"{fam} = {setting}"
                ax.scatter([r[cost] for r in pts], [r["error"] for r in pts], marker=markers.get(fam, "x"),
                           s=42 if fam == "base" else 30, label=lab, alpha=0.85)
                if fam == "base":
                    ax.plot([r[cost] for r in pts], [r["error"] for r in pts], lw=0.6, color="grey")
                    for r in pts:
                        ax.annotate(f"{r['particles']}", (r[cost], r["error"]), fontsize=7,
                                    xytext=(4, 3), textcoords="offset points")
    front = [r for r in pareto_front(rows, cost) if r["error"] > 0]
    if front:
        ax.step([r[cost] for r in front], [r["error"] for r in front], where="post", color="k", lw=1.6,
                label="Pareto front")
        ax.scatter([r[cost] for r in front], [r["error"] for r in front], s=110, facecolors="none",
                   edgecolors="k", lw=1.3)
    ax.axhline(spec["target"], color="r", ls=":", lw=1, label=f"target {spec['target']:g}")
    failed = [r for r in rows if not math.isfinite(r["error"])]
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(COST_LABEL[cost])
    ax.set_ylabel("error")
    title = f"{name}: error against {'wall' if cost == 'wall_s' else 'CPU'} time"
    if failed:
        title += f" ({len(failed)} runs failed: " + ", ".join(r["label"] for r in failed[:3]) + \
                 (" ..." if len(failed) > 3 else "") + ")"
    ax.set_title(title, fontsize=9)
    note = textwrap.wrap("error: " + spec["error_note"], 160)
    fig.text(0.01, 0.01, "\n".join(note), fontsize=6.5)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="best", title="numbers: particles", title_fontsize=7)
    fig.tight_layout(rect=(0, 0.03 * len(note), 1, 1))
    fig.savefig(path)
    plt.close(fig)


def summary_markdown(results, cost="wall_s"):
    """Per case: the cheapest run (by `cost`) whose error is within the target, and the most
    accurate run."""
    lines = ["| case | error (what) | target | cheapest within target | particles | wall [s] | CPU [s] | error | "
             "most accurate | particles | wall [s] | CPU [s] | error |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]

    def desc(r):
        return f"{r['family']} {r['setting']}, dx {r['dx']:.4g}" if r["family"] != "base" else \
            f"case settings, dx {r['dx']:.4g}"

    def cells(r):
        return [desc(r), str(r["particles"]), fmt(r["wall_s"], 3), fmt(r["cpu_s"], 3), fmt(r["error"], 3)] if r \
            else ["none", "", "", "", ""]
    for name, (spec, rows) in results.items():
        ok = [r for r in rows if math.isfinite(r["error"]) and math.isfinite(r[cost])]
        within = sorted((r for r in ok if r["error"] <= spec["target"]), key=lambda r: r[cost])
        best = min(ok, key=lambda r: r["error"]) if ok else None
        lines.append("| " + " | ".join([name, spec["error_note"], f"{spec['target']:g}"] +
                                       cells(within[0] if within else None) + cells(best)) + " |")
    notes = []
    for name, (spec, rows) in results.items():
        if not spec.get("converged"):
            continue
        base = sorted((r for r in rows if r["family"] == "base"), key=lambda r: -r["dx"])
        refs = {r.get("error_reference", "") for r in rows} - {""}
        notes.append(f"- {name}: error against the {', '.join(sorted(refs)) or 'converged solution'}. Deviation "
                     "from the experiment (check.json " + ", ".join(spec["error"]) + ") of the case-settings runs, "
                     "coarse to fine: " + ", ".join(f"dx {r['dx']:.4g}: {fmt(r.get('exp_deviation', float('nan')), 3)}"
                                                    for r in base) + ".")
    return "\n".join(lines) + "\n" + ("\n" + "\n".join(notes) + "\n" if notes else "")


# --------------------------------------------------------------------------------------------
# Section 2: co-simulation overhead (processes over LCM against in-process)
def per_step(s, node, key):
    v = s.get("nodes", {}).get(node, {}).get(key)
    return 1e3 * v / s["steps"] if isinstance(v, (int, float)) and s.get("steps") else float("nan")


def overhead_row(args, case_path, out, mode, rep, size):
    r = run_lahar(args.lahar, "run", case_path, out, args.threads, in_process=(mode == "in-process"),
                  timeout=run_timeout(args))
    s = summary_numbers(out)
    sj = s["summary"]
    row = dict(size=size, mode=mode, repeat=rep, particles=s["particles"], steps=s["steps"], wall_s=s["wall_s"],
               wall_ms_per_step=(1e3 * s["wall_s"] / s["steps"]) if s["steps"] else float("nan"),
               setup_s=float(sj.get("setup_s", float("nan"))), stepping_s=float(sj.get("stepping_s", float("nan"))),
               stepping_ms_per_step=(1e3 * float(sj.get("stepping_s", float("nan"))) / s["steps"]
                                     if s["steps"] else float("nan")),
               cpu_s=r["cpu_s"], peak_rss_mb=r["peak_rss_mb"],
               sph_compute_ms_per_step=per_step(sj, "sph", "compute_s"),
               sph_wait_ms_per_step=per_step(sj, "sph", "wait_s"),
               dem_compute_ms_per_step=per_step(sj, "dem", "compute_s"),
               dem_wait_ms_per_step=per_step(sj, "dem", "wait_s"),
               coordinator_wait_ms_per_step=(1e3 * sj.get("coordinator_wait_s", float("nan")) / s["steps"]
                                             if s["steps"] else float("nan")),
               body_state_messages=sj.get("channels", {}).get("LAHAR_BODY_STATE", {}).get("messages", 0),
               exit_status=r["exit_status"], load_avg=r["load_avg"])
    log(f"  {size:5s} {mode:10s} n={row['particles']} steps={row['steps']} wall={fmt(row['wall_s'], 4)} s "
        f"({fmt(row['wall_ms_per_step'], 3)} ms/step) cpu={fmt(row['cpu_s'], 4)} s "
        f"sph wait {fmt(row['sph_wait_ms_per_step'], 3)} ms/step exit={r['exit_status']}")
    if not args.keep:
        for f in os.listdir(out) if os.path.isdir(out) else []:
            if f.endswith(".h5"):
                os.remove(os.path.join(out, f))
    return row


def median(xs):
    xs = sorted(xs)
    return float("nan") if not xs else (xs[len(xs) // 2] if len(xs) % 2 else 0.5 * (xs[len(xs) // 2 - 1] + xs[len(xs) // 2]))


def bench_overhead(args, outdir):
    """Pairs of runs (processes, in-process; the order alternates) of the boulder pool: `large` at
    >= 20,000 particles, and `floor` at dx 20 mm (about 400 particles), whose wall time per step is
    almost all protocol: the difference of the two modes there is the per-step cost of LCM over
    UDP multicast against the in-process queue."""
    # the native engine takes the pool with polygon and box boulders; another engine (--engine
    # lammps) the same pool with what it can represent: segment walls, disc boulders
    if args.engine == "spheropoly":
        src = os.path.join(BENCH_CASES_DIR, "boulder_pool_2d.yaml")
    else:
        src = os.path.join(BENCH_CASES_DIR, "boulder_pool_discs_2d.yaml")
    dx, end = (0.004, 0.02) if args.quick else (0.0025, args.overhead_end)
    d = os.path.join(outdir, "runs", "overhead")
    sizes = {"large": (dx, end), "floor": (0.02, 0.1 if args.quick else 0.5)}
    rows = []
    log(f"== overhead ({args.engine} engine): {src} at dx {dx} (and {sizes['floor'][0]}), end {end} s, {args.repeat} pair(s) of runs")
    for size, (sdx, send) in sizes.items():
        case_path = os.path.join(d, f"pool_{size}.yaml")
        case_override.override_case(src, case_path, {"sph.dx": sdx, "time.end": send, "dem.engine": args.engine})
        for rep in range(args.repeat):
            modes = ("processes", "in-process") if rep % 2 == 0 else ("in-process", "processes")
            for mode in modes:
                rows.append(overhead_row(args, case_path, os.path.join(d, f"{size}_{mode}_{rep}"), mode, rep, size))
    write_csv(os.path.join(outdir, "overhead.csv"), rows, list(rows[0].keys()))

    def ratios(size, key):
        out = []
        for rep in range(args.repeat):
            pair = {r["mode"]: r for r in rows if r["size"] == size and r["repeat"] == rep and r["exit_status"] == 0}
            if len(pair) == 2 and pair["in-process"][key] > 0:
                out.append(pair["processes"][key] / pair["in-process"][key])
        return out
    step_r, wall_r, cpu_r = ratios("large", "stepping_s"), ratios("large", "wall_s"), ratios("large", "cpu_s")
    fl = {m: median([r["stepping_ms_per_step"] for r in rows if r["size"] == "floor" and r["mode"] == m
                     and r["exit_status"] == 0]) for m in ("processes", "in-process")}
    lg = median([r["stepping_ms_per_step"] for r in rows if r["size"] == "large" and r["mode"] == "in-process"
                 and r["exit_status"] == 0])
    setup = {m: median([r["setup_s"] for r in rows if r["size"] == "large" and r["mode"] == m
                        and r["exit_status"] == 0]) for m in ("processes", "in-process")}
    md = ["| scene | mode | pair | particles | steps | wall [s] | start-up [s] | steps [ms/step] | CPU [s] | "
          "SPH compute / wait [ms/step] | DEM compute / wait [ms/step] | coordinator wait [ms/step] | "
          "BODY_STATE msgs | exit | load |", "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        md.append(f"| {r['size']} | {r['mode']} | {r['repeat']} | {r['particles']} | {r['steps']} | {fmt(r['wall_s'], 4)} | "
                  f"{fmt(r['setup_s'], 3)} | {fmt(r['stepping_ms_per_step'], 3)} | {fmt(r['cpu_s'], 4)} | "
                  f"{fmt(r['sph_compute_ms_per_step'], 3)} / {fmt(r['sph_wait_ms_per_step'], 3)} | "
                  f"{fmt(r['dem_compute_ms_per_step'], 3)} / {fmt(r['dem_wait_ms_per_step'], 3)} | "
                  f"{fmt(r['coordinator_wait_ms_per_step'], 3)} | {r['body_state_messages']} | {r['exit_status']} | "
                  f"{fmt(r['load_avg'], 2)} |")
    ratio = median(step_r)
    protocol = fl["processes"] - fl["in-process"]
    md += ["", f"Wall-time ratio processes / in-process of the steps (summary.json `stepping_s`) at "
           f"{rows[0]['particles']} particles, median of {len(step_r)} pair(s): **{fmt(ratio, 3)}** "
           f"(pairs: {', '.join(fmt(x, 3) for x in step_r)}; target <= 1.05); of the whole run, start-up "
           f"(median {fmt(setup['processes'], 3)} s as processes, {fmt(setup['in-process'], 3)} s in-process) and end "
           f"included: {fmt(median(wall_r), 3)}; CPU-time ratio {fmt(median(cpu_r), 3)}.",
           f"Protocol floor (dx {sizes['floor'][0]}): {fmt(fl['processes'], 3)} ms/step as processes, "
           f"{fmt(fl['in-process'], 3)} ms/step in-process: LCM over UDP costs {fmt(protocol, 3)} ms/step more, "
           f"{fmt(100.0 * protocol / lg, 2) if lg > 0 else 'nan'} % of the large scene's "
           f"{fmt(lg, 3)} ms/step in-process."]
    with open(os.path.join(outdir, "overhead.md"), "w") as f:
        f.write("\n".join(md) + "\n")
    log(f"  ratio processes / in-process: steps {fmt(ratio, 3)}, whole run {fmt(median(wall_r), 3)} "
        f"(CPU {fmt(median(cpu_r), 3)}); "
        f"protocol {fmt(protocol, 3)} ms/step")
    return ratio


# --------------------------------------------------------------------------------------------
# Section 3: DEM subcycling against the global step forced down to the DEM step
def final_body_positions(out):
    """{body name: position at the last snapshot} of the free bodies in OUT/bodies.h5, and its time
    and the bodies' largest displacement from the first snapshot."""
    import h5py
    import numpy as np
    with h5py.File(os.path.join(out, "bodies.h5"), "r") as f:
        names = lahar_py.text_names(f["header/body_name"][()])
        free = np.asarray(f["header/motion"][()]) == 0  # LAHAR_MOTION_FREE (common/scene/scene.h)
        snaps = sorted(f["snapshots"])
        first, last = f["snapshots"][snaps[0]], f["snapshots"][snaps[-1]]
        x0, x1 = np.asarray(first["position"]), np.asarray(last["position"])
        t = float(last.attrs.get("time", float("nan")))
    pos = {names[b]: x1[b] for b in range(len(names)) if free[b]}
    moved = max((float(np.linalg.norm(x1[b] - x0[b])) for b in range(len(names)) if free[b]), default=0.0)
    return pos, t, moved


def bench_subcycle(args, outdir):
    """The boulder pool with stiff rock run twice: DEM subcycling (the default) against the whole run
    forced down to the DEM's stable step. Besides the cost, the free boulders' positions at the end
    against those of the forced run: the error subcycling makes (with that of the coupling's
    dt-dependent K_n, which the forced run's smaller step also changes)."""
    src = os.path.join(BENCH_CASES_DIR, "boulder_pool_2d.yaml")
    # dx 5 mm also in --quick: at 8-10 mm the run forced to the DEM step stops at t ~ 4 ms on
    # stability.density_band (a free-surface particle beside a falling boulder drops below 0.5 rho0)
    dx, end = (0.005, 0.01) if args.quick else (0.005, args.subcycle_end)
    d = os.path.join(outdir, "runs", "subcycle")
    base = {"sph.dx": dx, "time.end": end, "materials.rock.kn": 1.0e8}
    rows, finals = [], []
    log(f"== subcycle: {src} with kn = 1e8 at dx {dx}, end {end} s")
    dt_dem = None
    for variant in ("subcycling", "global dt = DEM dt"):
        ov = dict(base)
        if variant != "subcycling":
            ov["time.dt_max"] = dt_dem
        tag = "sub" if variant == "subcycling" else "forced"
        case_path = os.path.join(d, f"{tag}.yaml")
        case_override.override_case(src, case_path, ov)
        out = os.path.join(d, tag)
        r = run_lahar(args.lahar, "run", case_path, out, args.threads,
                      timeout=run_timeout(args))
        s = summary_numbers(out)
        sj = s["summary"]
        dem = sj.get("nodes", {}).get("dem", {})
        sph = sj.get("nodes", {}).get("sph", {})
        if dt_dem is None:
            dt_dem = float(dem.get("dt_stable", 0.0)) or 1e-6
        rows.append(dict(variant=variant, particles=s["particles"], steps=s["steps"], dem_substeps=s["dem_substeps"],
                         dem_dt_stable=dem.get("dt_stable", float("nan")),
                         sph_dt_stable=sph.get("dt_stable", float("nan")), wall_s=s["wall_s"], cpu_s=r["cpu_s"],
                         sph_compute_s=sph.get("compute_s", float("nan")),
                         dem_compute_s=dem.get("compute_s", float("nan")),
                         exit_status=r["exit_status"], load_avg=r["load_avg"]))
        log(f"  {variant:20s} steps={s['steps']} substeps={s['dem_substeps']} wall={fmt(s['wall_s'], 4)} s "
            f"exit={r['exit_status']}")
        try:
            finals.append(final_body_positions(out))
        except (OSError, KeyError) as e:
            log(f"  {variant}: no body positions ({e})")
            finals.append(None)
        if not args.keep:
            for f in os.listdir(out) if os.path.isdir(out) else []:
                if f.endswith(".h5"):
                    os.remove(os.path.join(out, f))
    # the subcycled boulders against the forced run's at the same (last) snapshot time
    diff_mm, moved_mm = float("nan"), float("nan")
    if all(finals) and finals[0][1] == finals[1][1] and set(finals[0][0]) == set(finals[1][0]):
        import numpy as np
        diff_mm = 1e3 * max(float(np.linalg.norm(finals[0][0][b] - finals[1][0][b])) for b in finals[0][0])
        moved_mm = 1e3 * finals[1][2]
    for r in rows:
        r["body_position_diff_mm"] = diff_mm if r["variant"] == "subcycling" else 0.0
        r["body_moved_mm"] = moved_mm
    write_csv(os.path.join(outdir, "subcycle.csv"), rows, list(rows[0].keys()))
    gain = rows[1]["wall_s"] / rows[0]["wall_s"] if rows[0]["wall_s"] > 0 else float("nan")
    md = ["| variant | particles | coordinator steps | DEM substeps | DEM dt_stable [s] | SPH dt [s] | wall [s] | "
          "SPH compute [s] | DEM compute [s] | load |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        md.append(f"| {r['variant']} | {r['particles']} | {r['steps']} | {r['dem_substeps']} | "
                  f"{fmt(r['dem_dt_stable'], 3)} | {fmt(r['sph_dt_stable'], 3)} | {fmt(r['wall_s'], 4)} | "
                  f"{fmt(r['sph_compute_s'], 4)} | {fmt(r['dem_compute_s'], 4)} | {fmt(r['load_avg'], 2)} |")
    md.append("")
    md.append(f"Gain of subcycling (wall time forced / subcycling): **{fmt(gain, 3)}**")
    md.append("")
    md.append(f"Against the forced run, the free boulders' positions at t = "
              f"{fmt(finals[0][1] if finals and finals[0] else float('nan'), 4)} s differ by at most "
              f"**{fmt(diff_mm, 3)} mm** ({fmt(diff_mm / dx / 1e3, 3)} dx; the forced run's boulders moved up to "
              f"{fmt(moved_mm, 4)} mm): the error of subcycling, with that of the coupling's step-dependent "
              f"penalty stiffness K_n = 0.1 m_min / dt^2 (Trujillo-Vela et al. 2020 eq. 15).")
    with open(os.path.join(outdir, "subcycle.md"), "w") as f:
        f.write("\n".join(md) + "\n")
    log(f"  gain: {fmt(gain, 3)}")
    return gain


# --------------------------------------------------------------------------------------------
def main(argv):
    ap = argparse.ArgumentParser(prog="lahar bench", description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog="\n\n".join(__doc__.split("\n\n")[2:]))
    ap.add_argument("-o", "--output", required=True, help="output directory (created)")
    ap.add_argument("--lahar", default=os.path.join(ROOT, "build", "bin", "lahar"), help="the lahar executable")
    ap.add_argument("--quick", action="store_true", help="2 resolutions and 2 settings per case, small scenes")
    ap.add_argument("--sections", default="pareto,overhead,subcycle", help="comma list of pareto, overhead, subcycle")
    ap.add_argument("--cases", default=",".join(BENCH), help="comma list of the cases of the pareto section")
    ap.add_argument("--threads", type=int, default=2, help="OpenMP threads per node (default 2)")
    ap.add_argument("--timeout", type=float, default=None,
                    help=f"seconds after which one run is stopped (default {DEFAULT_TIMEOUT:g}; the pareto sweeps of "
                         "cases with longer runs set their own, dam_break_3d 7200)")
    ap.add_argument("--repeat", type=int, default=9,
                    help="pairs of runs of the overhead section (median is used; on a 2-core VM one pair varies by "
                         "+-20 %% and a median of 9 by about +-5 %%, docs/bench/cosim_overhead.md)")
    ap.add_argument("--overhead-end", type=float, default=0.02, help="simulated time of the overhead runs [s]")
    ap.add_argument("--engine", default="spheropoly",
                    help="DEM engine of the overhead runs (spheropoly: the boulder pool; lammps: the same pool "
                         "with segment walls and disc boulders, docs/bench/cases/boulder_pool_discs_2d.yaml)")
    ap.add_argument("--subcycle-end", type=float, default=0.1, help="simulated time of the subcycling runs [s]")
    ap.add_argument("--cost", choices=("wall", "cpu"), default="wall",
                    help="what the Pareto plots and the summary call cheaper: wall time (default) or CPU time "
                         "(steadier on a loaded machine)")
    ap.add_argument("--resume", action="store_true",
                    help="pareto: take the runs already in OUT/<case>.csv (finished ones) instead of running them again")
    ap.add_argument("--keep", action="store_true", help="keep the runs' HDF5 files (deleted by default)")
    ap.add_argument("--list", action="store_true", help="print the planned runs and exit")
    args = ap.parse_args(argv)
    sections = [s.strip() for s in args.sections.split(",") if s.strip()]
    bad = [s for s in sections if s not in ("pareto", "overhead", "subcycle")]
    cases = [c.strip() for c in args.cases.split(",") if c.strip()]
    badc = [c for c in cases if c not in BENCH]
    if bad or badc:
        sys.stderr.write(f"lahar bench: unknown {'section' if bad else 'case'} {', '.join(bad or badc)} "
                         f"(sections: pareto, overhead, subcycle; cases: {', '.join(BENCH)})\n")
        return 2
    if args.quick:
        args.repeat = 1
    specs = {}
    for c in cases:
        spec = dict(BENCH[c])
        if args.quick:
            spec.update(QUICK[c])
        specs[c] = spec
    if args.list:
        for c, spec in specs.items():
            for label, family, setting, dx, ov in plan_case(c, spec, args.quick):
                print(c, label, json.dumps({**spec["overrides"], "sph.dx": dx, **ov}))
        return 0
    if not os.access(args.lahar, os.X_OK):
        sys.stderr.write(f"lahar bench: {args.lahar} is not an executable (build first, or --lahar PATH)\n")
        return 2
    os.makedirs(args.output, exist_ok=True)
    t0 = time.monotonic()
    md = [f"# lahar bench{' --quick' if args.quick else ''}", "",
          f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, {args.threads} OpenMP threads per node, "
          f"{os.cpu_count()} CPUs, load average at start {os.getloadavg()[0]:.2f}. Wall times are noisy on a "
          "shared machine; cpu_s in the CSVs is the CPU time the run used.", ""]
    if "pareto" in sections:
        results = {}
        for c, spec in specs.items():
            results[c] = (spec, bench_case(args, c, spec, args.output))
        md += [f"## Run time against error (cheapest setting by {args.cost} time within the target error)", "",
               summary_markdown(results, COST_KEY[args.cost])]
    if "overhead" in sections:
        bench_overhead(args, args.output)
        md += ["## Co-simulation overhead", "", open(os.path.join(args.output, "overhead.md")).read()]
    if "subcycle" in sections:
        bench_subcycle(args, args.output)
        md += ["## DEM subcycling", "", open(os.path.join(args.output, "subcycle.md")).read()]
    md.append(f"Total bench time {time.monotonic() - t0:.0f} s.")
    with open(os.path.join(args.output, "summary.md"), "w") as f:
        f.write("\n".join(md) + "\n")
    log(f"lahar bench: wrote {os.path.join(args.output, 'summary.md')} ({time.monotonic() - t0:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
