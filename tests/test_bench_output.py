#!/usr/bin/env python3
"""Checks what `lahar bench --quick` wrote (tests/bench.cmake): never its speed, only that the
tables and plots are there and consistent with the runs they summarise.
usage: test_bench_output.py OUT SECTIONS CASES   (comma lists, as given to lahar bench)"""
import csv
import json
import math
import os
import re
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools"))
import bench  # noqa: E402  (the column list and error definitions under test)
import case_override  # noqa: E402

failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures.append(what)


def png_ok(path):
    try:
        with open(path, "rb") as f:
            head = f.read(8)
        return head == b"\x89PNG\r\n\x1a\n" and os.path.getsize(path) > 5000
    except OSError:
        return False


def rows_of(path):
    with open(path, newline="") as f:
        r = csv.DictReader(f)
        return r.fieldnames, list(r)


def num(s):
    try:
        return float(s)
    except (TypeError, ValueError):
        return float("nan")


def check_case(out, name):
    path = os.path.join(out, f"{name}.csv")
    check(os.path.exists(path), f"{name}: {path} written")
    if not os.path.exists(path):
        return
    cols, rows = rows_of(path)
    check(cols == bench.CSV_COLUMNS, f"{name}: CSV columns are {bench.CSV_COLUMNS}")
    base = [r for r in rows if r["family"] == "base"]
    check(len({r["dx"] for r in base}) >= 2, f"{name}: at least 2 resolutions of the case settings")
    check(len({(r["family"], r["setting"]) for r in rows}) >= 2, f"{name}: at least one changed setting")
    dim = 3 if name.endswith("3d") else 2
    for r in rows:
        lab = f"{name}/{r['label']}"
        n, steps, wall, pps = num(r["particles"]), num(r["steps"]), num(r["wall_s"]), num(r["particle_steps_per_s"])
        check(r["exit_status"] in ("0", "1"), f"{lab}: run finished (exit {r['exit_status']}; 1 = a bound missed)")
        check(n > 0 and steps > 0 and wall > 0 and num(r["cpu_s"]) > 0, f"{lab}: particles, steps, wall and CPU time > 0")
        check(math.isclose(pps, n * steps / wall, rel_tol=1e-4), f"{lab}: particle_steps_per_s = particles x steps / wall")
        check(num(r["peak_rss_mb"]) > 1.0, f"{lab}: peak memory recorded ({r['peak_rss_mb']} MB)")
        # the error column is the maximum of the check.json values the bench names for the case
        chk = json.load(open(os.path.join(out, "runs", name, r["label"], "check.json")))
        vals = {k: v["value"] for k, v in chk["metrics"].items()}
        vals.update({k: v for k, v in chk["info"].items() if isinstance(v, (int, float))})
        want = max(vals[k] for k in bench.BENCH[name]["error"])
        if bench.BENCH[name].get("converged"):
            # an experiment's case: the check's deviation from it is exp_deviation, and the error is
            # against the converged solution the error_reference names
            check(math.isclose(num(r["exp_deviation"]), want, rel_tol=1e-5) and 0.0 <= want < 10.0,
                  f"{lab}: exp_deviation {r['exp_deviation']} = max of check.json {bench.BENCH[name]['error']} ({want:.6g})")
            check(r["error_reference"].startswith(("Richardson", "finest run")),
                  f"{lab}: error_reference names the converged solution ({r['error_reference']})")
            is_ref = r["family"] == "base" and r["error_reference"].startswith(f"finest run dx {num(r['dx']):.4g} ")
            check(math.isnan(num(r["error"])) if is_ref else 0.0 < num(r["error"]) < 10.0,
                  f"{lab}: error against the converged solution {r['error']}"
                  + (" (nan: this run is the reference)" if is_ref else " is a number"))
        else:
            check(math.isclose(num(r["error"]), want, rel_tol=1e-5) and 0.0 <= want < 10.0,
                  f"{lab}: error {r['error']} = max of check.json {bench.BENCH[name]['error']} ({want:.6g})")
        # a soil setting reached the case's own soil material (bench.SOIL_SETTINGS, `{soil}`)
        if r["family"] == "soil_av":
            case = case_override.load_case(os.path.join(out, "runs", name, r["label"] + ".yaml"))
            mat = case["materials"][bench.BENCH[name]["soil"]]
            check(mat.get("av_alpha") == 1.0 and mat.get("av_beta") == 1.0,
                  f"{lab}: the copy's soil material has the paper's av_alpha, av_beta = 1, 1 ({mat})")
        # the copy has the run's dx: the particle count follows the lattice, n ~ dx^-D
        ref = min(base, key=lambda b: num(b["dx"]))
        if r["family"] == "base" and r is not ref:
            expect = num(ref["particles"]) * (num(ref["dx"]) / num(r["dx"])) ** dim
            check(abs(n / expect - 1.0) < 0.3, f"{lab}: {int(n)} particles ~ {expect:.0f} from the finer run's dx^-{dim}")
    check(png_ok(os.path.join(out, f"{name}_pareto.png")), f"{name}: {name}_pareto.png is a PNG")
    md = open(os.path.join(out, "summary.md")).read()
    check(re.search(rf"^\| {name} \|", md, re.M) is not None, f"{name}: a row in summary.md")


def main(out, sections, cases):
    check(os.path.exists(os.path.join(out, "summary.md")), "summary.md written")
    if "pareto" in sections:
        for name in cases:
            check_case(out, name)
    if "subcycle" in sections:
        _, rows = rows_of(os.path.join(out, "subcycle.csv"))
        sub, forced = rows
        check(sub["exit_status"] == "0" and forced["exit_status"] == "0", "subcycle: both runs finished")
        check(num(sub["dem_substeps"]) > num(sub["steps"]), "subcycle: the stiff boulders make the DEM node subcycle")
        check(num(forced["dem_substeps"]) == num(forced["steps"]),
              "subcycle: with dt_max = the DEM's stable dt there is one DEM substep per step")
        check(num(forced["steps"]) > num(sub["steps"]), "subcycle: the forced run takes more coordinator steps")
        # the boulders' end positions were read from both runs' bodies.h5 (a number, and the boulders moved)
        check(math.isfinite(num(sub["body_position_diff_mm"])) and num(sub["body_moved_mm"]) > 0,
              "subcycle: the boulders' positions of both runs compared")
    if "overhead" in sections:
        _, rows = rows_of(os.path.join(out, "overhead.csv"))
        for size in ("large", "floor"):
            sized = [r for r in rows if r["size"] == size]
            check({r["mode"] for r in sized} == {"processes", "in-process"}, f"overhead/{size}: a run per mode")
            check(all(r["exit_status"] == "0" for r in sized), f"overhead/{size}: the runs finished")
            check(len({r["steps"] for r in sized}) == 1, f"overhead/{size}: both modes take the same steps (same run)")
            check(all(num(r["body_state_messages"]) > 0 for r in sized), f"overhead/{size}: the boulders exchange BODY_STATE")
        large = [num(r["particles"]) for r in rows if r["size"] == "large"]
        floor = [num(r["particles"]) for r in rows if r["size"] == "floor"]
        check(min(large) > 4 * max(floor), "overhead: the protocol-floor scene is much smaller than the large one")
        for r in rows:
            check(all(num(r[k]) >= 0 for k in ("sph_compute_ms_per_step", "sph_wait_ms_per_step",
                                              "dem_wait_ms_per_step")), f"overhead/{r['size']}/{r['mode']}: per-step times >= 0")
            # the steps' wall time is the run's minus its start-up and end: positive, and less
            check(0 < num(r["stepping_s"]) < num(r["wall_s"]) and 0 < num(r["setup_s"]) < num(r["wall_s"]),
                  f"overhead/{r['size']}/{r['mode']}: 0 < stepping_s, setup_s < wall_s")
    print(f"{len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit("usage: test_bench_output.py OUT SECTIONS CASES")
    sys.exit(main(sys.argv[1], sys.argv[2].split(","), sys.argv[3].split(",")))
