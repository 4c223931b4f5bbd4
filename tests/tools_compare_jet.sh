#!/bin/sh
# tools/compare_jet.py: its reference, the free-streamline jet on a wall, against what the theory
# must satisfy (the pressure integrated along the plate equals the jet's momentum flux rho U^2 b;
# the stagnation point's curvature; the inverse q(s) inverts s(q)); its measurement on a synthetic
# run (the case cases/jet_impingement_2d.yaml, its 17 probes reading the reference with a known
# deficit near the axis and a ripple, the plate's force 1.02 rho U^2 b with a ripple): every probe's
# difference, the stagnation deficit, the force and the probes' integral recovered; the --check
# verdicts at bounds either side of them; exit 2 with a message on a missing run, an unknown plate,
# a window backwards or after the run, a case without an inlet of constant velocity and one whose
# inlet is only partly wetted; in 3D (cases/jet_impingement_3d.yaml) the stagnation point and the
# force rho U^2 A recovered from a synthetic run, the off-axis probes without a reference, exit 2
# without a probe on the axis.
# usage: tools_compare_jet.sh SRC_DIR OUT_DIR PYTHON
set -u
src=$1 out=$2 py=$3
fail() { echo "tools_compare_jet: $*" >&2; exit 1; }
rm -rf "$out" && mkdir -p "$out"
tool="$src/tools/compare_jet.py"
. "$src/tests/tools_test_lib.sh"  # bad

"$py" - "$src/tools" <<'PY' || fail "the free-streamline reference"
import math, sys
sys.path.insert(0, sys.argv[1])
import numpy as np
import compare_jet as cj
b, u, rho = 0.02, 10.0, 1000.0
q_dyn = 0.5 * rho * u * u
# the plate carries the jet's momentum flux: int p ds over the whole plate = rho U^2 b
s = np.linspace(-8 * b, 8 * b, 8001)
p = np.array([cj.wall_pressure(x, b, rho, u) for x in s])
total = cj.trapezoids(p, s)
assert abs(total / (rho * u * u * b) - 1) < 1e-4, total
# near the stagnation point q = pi s / (4 b): p = q_dyn (1 - (pi s / 4 b)^2)
for x in (1e-4 * b, 1e-3 * b):
    assert abs((1 - cj.wall_pressure(x, b, rho, u) / q_dyn) / (math.pi * x / (4 * b)) ** 2 - 1) < 1e-3, x
assert cj.wall_pressure(0.0, b, rho, u) == q_dyn
for q in (0.1, 0.5, 0.9, 0.999):
    assert abs(cj.speed_at(cj.distance_of_speed(q, b), b) - q) < 1e-12, q
# the numbers the case file states: half the stagnation pressure at |s| = 0.95 b, 3.5 % at 2 b
assert abs(cj.distance_of_speed(math.sqrt(0.5), b) / b - 0.953) < 1e-3
assert abs(cj.wall_pressure(2 * b, b, rho, u) / q_dyn - 0.0347) < 1e-4
print("free-streamline jet: int p ds = %.6f rho U^2 b" % (total / (rho * u * u * b)))
PY

# a synthetic run: the case's 17 probes every 0.1 ms to 0.03 s reading p(s) (1 - 0.06 exp(-(s/b)^2))
# + 5 kPa sin(2 pi t / 1 ms); the plate's force 2040 + 200 sin(2 pi t / 1 ms) N/m
run="$out/synthetic"
"$py" - "$run" "$src/cases/jet_impingement_2d.yaml" "$src/tools" <<'PY' || fail "cannot write the synthetic run"
import json, os, sys
sys.path.insert(0, sys.argv[3])
import h5py
import numpy as np
import compare_jet as cj
run, case = sys.argv[1], sys.argv[2]
os.makedirs(run)
json.dump({"case": os.path.abspath(case), "status": "finished"}, open(os.path.join(run, "summary.json"), "w"))
b, u, rho = 0.02, 10.0, 1000.0
t = np.arange(301) * 1e-4
ripple = np.sin(2 * np.pi * t / 1e-3)
with h5py.File(os.path.join(run, "gauges.h5"), "w") as f:
    for y in range(-40, 41, 5):
        g = f.create_group("probes/p%+03d" % y)
        s = y / 1000.0
        g.attrs["kind"], g.attrs["body"] = "pressure", "plate"
        g.attrs["position"] = np.array([0.06, s, 0.0])
        g["t"] = t
        g["p"] = cj.wall_pressure(s, b, rho, u) * (1 - 0.06 * np.exp(-(s / b) ** 2)) + 5000 * ripple
with h5py.File(os.path.join(run, "forces.h5"), "w") as f:
    force = np.zeros((len(t), 1, 3))
    force[:, 0, 0] = 2040 + 200 * ripple
    f.attrs["body_names"] = np.array(["plate"], dtype=object)
    f["t"], f["force"] = t, force
with h5py.File(os.path.join(run, "particles.h5"), "w") as f:
    f.create_group("header").attrs["dx"] = 0.001
PY
"$py" "$tool" "$run" --json "$out/synthetic.json" -o "$out/synthetic.png" > "$out/synthetic.txt" ||
  fail "exit $? on the synthetic run: $(cat "$out/synthetic.txt")"
cat "$out/synthetic.txt"
[ -s "$out/synthetic.png" ] || fail "no PNG"
"$py" - "$out/synthetic.json" "$src/tools" <<'PY' || fail "the synthetic run's metrics"
import json, math, sys
sys.path.insert(0, sys.argv[2])
import compare_jet as cj
m = json.load(open(sys.argv[1]))
b = 0.02
assert len(m["pressure"]["probes"]) == 17 and m["case"]["plate"] == "plate", m["case"]
assert abs(m["case"]["b"] - b) < 1e-12 and abs(m["case"]["u"] - 10) < 1e-12 and abs(m["case"]["nozzle_distance"] - 0.06) < 1e-12
for r in m["pressure"]["probes"]:  # the window 0.015-0.03 s holds 15 whole ripple periods
    want = -0.06 * math.exp(-(r["s"] / b) ** 2) * cj.wall_pressure(r["s"], b, 1000, 10) / 50000
    assert abs(r["diff"] - want) < 2e-3, r
assert abs(m["pressure"]["max_abs_diff"] - 0.06) < 2e-3, m["pressure"]["max_abs_diff"]
assert m["stagnation"]["probe"] == "p+00" and abs(m["stagnation"]["rel"] + 0.06) < 2e-3, m["stagnation"]
assert abs(m["force"]["rel"] - 0.02) < 1e-3 and abs(m["force"]["reference"] - 2000) < 1e-9, m["force"]
assert 0.03 < -m["probe_integral"]["rel"] < 0.05, m["probe_integral"]
assert abs(m["reference_deficit_at_nozzle"] - 0.00155) < 5e-5, m["reference_deficit_at_nozzle"]
PY
# pressure 6.0 % of rho U^2/2, force +2.0 %
"$py" "$tool" "$run" --no-plot --json "$out/c.json" --check > "$out/check1.txt"
[ $? -eq 1 ] && grep -q "FAIL pressure" "$out/check1.txt" && ! grep -q "FAIL force" "$out/check1.txt" ||
  fail "--check at the default bounds: $(cat "$out/check1.txt")"
"$py" "$tool" "$run" --no-plot --json "$out/c.json" --check --pressure-tol 0.065 > "$out/check0.txt" ||
  fail "--check with pressure at 6.5 %: exit $?, $(cat "$out/check0.txt")"
"$py" "$tool" "$run" --no-plot --json "$out/c.json" --check --pressure-tol 0.065 --force-tol 0.015 > "$out/check2.txt"
[ $? -eq 1 ] && grep -q "FAIL force" "$out/check2.txt" || fail "--check with force at 1.5 %: $(cat "$out/check2.txt")"

# 3D (cases/jet_impingement_3d.yaml): only the stagnation point and the force have a reference; a
# synthetic run with the axis probe at 0.7 rho U^2 / 2, the others off the axis, the force 1.05 rho U^2 A
run3="$out/synthetic3d"
"$py" - "$run3" "$src/cases/jet_impingement_3d.yaml" <<'PY' || fail "cannot write the synthetic 3D run"
import json, os, sys
import h5py
import numpy as np
run, case = sys.argv[1], sys.argv[2]
os.makedirs(run)
json.dump({"case": os.path.abspath(case), "status": "finished"}, open(os.path.join(run, "summary.json"), "w"))
t = np.arange(201) * 1e-4
with h5py.File(os.path.join(run, "gauges.h5"), "w") as f:
    for name, y, z, p in (("axis", 0, 0, 35000), ("side", 0.01, 0, 20000), ("corner", 0.007, 0.007, 15000)):
        g = f.create_group("probes/" + name)
        g.attrs["kind"], g.attrs["body"] = "pressure", "plate"
        g.attrs["position"] = np.array([0.06, y, z])
        g["t"], g["p"] = t, np.full(len(t), float(p))
with h5py.File(os.path.join(run, "forces.h5"), "w") as f:
    force = np.zeros((len(t), 1, 3))
    force[:, 0, 0] = 42.0
    f.attrs["body_names"] = np.array(["plate"], dtype=object)
    f["t"], f["force"] = t, force
PY
"$py" "$tool" "$run3" --window 0.01 0.02 --json "$out/synthetic3d.json" -o "$out/synthetic3d.png" > "$out/synthetic3d.txt" ||
  fail "exit $? on the synthetic 3D run: $(cat "$out/synthetic3d.txt")"
cat "$out/synthetic3d.txt"
"$py" - "$out/synthetic3d.json" <<'PY' || fail "the synthetic 3D run's metrics"
import json, sys
m = json.load(open(sys.argv[1]))
assert m["case"]["dim"] == 3 and abs(m["case"]["area"] - 4e-4) < 1e-12 and abs(m["case"]["b"] - 0.02) < 1e-12, m["case"]
assert abs(m["stagnation"]["rel"] + 0.3) < 1e-9 and m["stagnation"]["probe"] == "axis", m["stagnation"]
assert abs(m["pressure"]["max_abs_diff"] - 0.3) < 1e-9, m["pressure"]  # only the axis has a reference
assert [r["reference"] for r in m["pressure"]["probes"]][1:] == [None, None], m["pressure"]
assert abs(m["force"]["reference"] - 40) < 1e-9 and abs(m["force"]["rel"] - 0.05) < 1e-9, m["force"]
assert m["probe_integral"] is None and m["reference_deficit_at_nozzle"] is None
PY
"$py" "$tool" "$run3" --window 0.01 0.02 --no-plot --json "$out/c.json" --check --pressure-tol 0.35 --force-tol 0.06 \
  > "$out/check3.txt" || fail "--check 3D at 35 / 6 %: exit $?, $(cat "$out/check3.txt")"
"$py" "$tool" "$run3" --window 0.01 0.02 --no-plot --json "$out/c.json" --check --pressure-tol 0.25 --force-tol 0.06 \
  > "$out/check4.txt"
[ $? -eq 1 ] && grep -q "FAIL pressure" "$out/check4.txt" || fail "--check 3D with pressure at 25 %: $(cat "$out/check4.txt")"
"$py" - "$run3" <<'PY' || fail "cannot move the axis probe"
import h5py, sys
with h5py.File(sys.argv[1] + "/gauges.h5", "r+") as f:
    f["probes/axis"].attrs["position"] = [0.06, 0.004, 0.0]
PY
bad no_axis_probe "no probe on the jet's axis" "$run3" --window 0.01 0.02

bad no_run "summary.json" "$out/nosuchrun"
bad no_plate "no body named 'wall'" "$run" --plate wall
bad window_backwards "T0 must be below T1" "$run" --window 0.03 0.01
bad window_late "samples in the window" "$run" --window 0.05 0.06
mkdir -p "$out/no_inlet"
echo "{\"case\": \"$src/cases/dam_break_lobovsky_2d.yaml\", \"status\": \"finished\"}" > "$out/no_inlet/summary.json"
bad no_inlet "constant .velocity." "$out/no_inlet"
mkdir -p "$out/part_wetted"
"$py" "$src/tools/case_override.py" "$src/cases/jet_impingement_2d.yaml" "$out/part_wetted/case.yaml" \
  "inlets.nozzle.level=0.01" || fail "case_override"
echo "{\"case\": \"$out/part_wetted/case.yaml\", \"status\": \"finished\"}" > "$out/part_wetted/summary.json"
bad part_wetted "covers only part of the section" "$out/part_wetted"
echo "tools_compare_jet: ok"
