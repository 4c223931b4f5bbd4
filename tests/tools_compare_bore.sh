#!/bin/sh
# tools/compare_bore.py: its reference, the shallow-water shock a wall reflects, against the
# hydraulic jump's conjugate depths (Belanger) in the bore's frame and mass conservation across it,
# for Froude numbers 1.2-4; its measurement on a synthetic run (the case
# cases/bore_reflection_2d.yaml, snapshots of a sharp bore of known speed 0.6 m/s and depth 0.17 m
# on a 10 mm lattice, a wall force 140 N/m with a ripple): speed, depth, force and the arriving
# stream recovered, the --check verdicts at bounds either side of them; exit 2 with a message on a
# missing run, an unknown wall, a window with too few snapshots or backwards, a case without a
# constant-velocity inlet and one whose stream runs towards -x.
# usage: tools_compare_bore.sh SRC_DIR OUT_DIR PYTHON
set -u
src=$1 out=$2 py=$3
fail() { echo "tools_compare_bore: $*" >&2; exit 1; }
rm -rf "$out" && mkdir -p "$out"
tool="$src/tools/compare_bore.py"
. "$src/tests/tools_test_lib.sh"  # bad

# the reference: in the frame moving with the bore the stream arrives at u1 + w and leaves at rest
# relative to the wall, i.e. at w: Belanger's h2/h1 = (sqrt(1 + 8 Fr^2) - 1) / 2, Fr = (u1 + w) / sqrt(g h1)
"$py" - "$src/tools" <<'PY' || fail "the shallow-water reference"
import math, sys
sys.path.insert(0, sys.argv[1])
import compare_bore
g, h1 = 9.81, 0.05
for froude in (1.2, 2.0, 3.0, 4.0):
    u1 = froude * math.sqrt(g * h1)
    h2, w = compare_bore.bore_reference(h1, u1, g)
    fr = (u1 + w) / math.sqrt(g * h1)
    belanger = h1 * (math.sqrt(1 + 8 * fr * fr) - 1) / 2
    assert abs(h2 / belanger - 1) < 1e-9, (froude, h2, belanger)
    assert abs(w * (h2 - h1) - h1 * u1) < 1e-12, (froude, w)  # mass: the bore stores what arrives
    print("Froude %.1f: h2/h1 %.4f, w %.4f m/s, Belanger %.4f" % (froude, h2 / h1, w, belanger / h1))
h2, w = compare_bore.bore_reference(0.05, 1.4, g)
assert abs(h2 - 0.1746) < 5e-5 and abs(w - 0.5617) < 5e-5, (h2, w)  # the numbers the case file states
PY

# a synthetic run: every 0.1 s to 6 s a sharp bore at x = face - 0.1 - 0.6 t, h1 = 0.05 m upstream
# moving at 1.3 m/s, 0.17 m at rest behind (whole particles at dx = 10 mm), the wall's force
# 140 + 20 sin(2 pi t / 0.5) N/m
run="$out/synthetic"
"$py" - "$run" "$src/cases/bore_reflection_2d.yaml" <<'PY' || fail "cannot write the synthetic run"
import json, os, sys
import h5py
import numpy as np
run, case = sys.argv[1], sys.argv[2]
os.makedirs(run)
json.dump({"case": os.path.abspath(case), "status": "finished"}, open(os.path.join(run, "summary.json"), "w"))
dx, face = 0.01, 4.0
cols = (np.arange(400) + 0.5) * dx  # to 3.995 m, in front of the face
with h5py.File(os.path.join(run, "particles.h5"), "w") as f:
    f.create_group("header").attrs["dx"] = dx
    for k, t in enumerate(np.arange(61) * 0.1):
        xb = face - 0.1 - 0.6 * t
        x, y, vx = [], [], []
        for c in cols:
            n = 17 if c > xb else 5
            x += [c] * n
            y += list((np.arange(n) + 0.5) * dx)
            vx += [0.0 if c > xb else 1.3] * n
        s = f.create_group("snapshots/%06d" % k)
        s.attrs["time"] = t
        s["x"], s["y"], s["vx"] = np.array(x), np.array(y), np.array(vx)
        s["density"] = np.full(len(x), 1000.0)
        s["inlet"] = np.full(len(x), -1, dtype=np.int32)
with h5py.File(os.path.join(run, "forces.h5"), "w") as f:
    t = np.arange(60001) * 1e-4
    force = np.zeros((len(t), 2, 3))
    force[:, 1, 0] = 140 + 20 * np.sin(2 * np.pi * t / 0.5)
    f.attrs["body_names"] = np.array(["floor", "wall"], dtype=object)
    f["t"], f["force"] = t, force
PY
"$py" "$tool" "$run" --json "$out/synthetic.json" -o "$out/synthetic.png" > "$out/synthetic.txt" ||
  fail "exit $? on the synthetic run: $(cat "$out/synthetic.txt")"
cat "$out/synthetic.txt"
[ -s "$out/synthetic.png" ] || fail "no PNG"
"$py" - "$out/synthetic.json" <<'PY' || fail "the synthetic run's metrics"
import json, sys
m = json.load(open(sys.argv[1]))
assert abs(m["speed"]["run"] / 0.6 - 1) < 0.005, m["speed"]  # the front on 20 mm columns, fitted over 4 s
assert m["speed"]["rms_m"] < 0.02, m["speed"]
assert abs(m["depth"]["run"] / 0.17 - 1) < 1e-9, m["depth"]
assert abs(m["force"]["run"] / 140 - 1) < 1e-3, m["force"]  # the ripple's 8 whole periods
assert abs(m["stream_at_bore"]["u"] - 1.3) < 1e-9 and abs(m["stream_at_bore"]["h"] - 0.05) < 1e-9, m["stream_at_bore"]
assert abs(m["force"]["reference"] - 149.58) < 0.01 and abs(m["speed"]["reference"] - 0.5617) < 1e-4, m
PY
# speed +6.8 %, force -6.4 %, depth -2.6 % against the reference
"$py" "$tool" "$run" --no-plot --json "$out/c.json" --check > "$out/check1.txt"
[ $? -eq 1 ] && grep -q "FAIL speed" "$out/check1.txt" && grep -q "FAIL force" "$out/check1.txt" &&
  ! grep -q "FAIL depth" "$out/check1.txt" || fail "--check at the default 5 %: $(cat "$out/check1.txt")"
"$py" "$tool" "$run" --no-plot --json "$out/c.json" --check --speed-tol 0.07 --force-tol 0.07 --depth-tol 0.03 \
  > "$out/check0.txt" || fail "--check at 7 / 7 / 3 %: exit $?, $(cat "$out/check0.txt")"
"$py" "$tool" "$run" --no-plot --json "$out/c.json" --check --speed-tol 0.07 --force-tol 0.07 --depth-tol 0.02 \
  > "$out/check2.txt"
[ $? -eq 1 ] && grep -q "FAIL depth" "$out/check2.txt" || fail "--check with depth at 2 %: $(cat "$out/check2.txt")"

bad no_run "summary.json" "$out/nosuchrun"
bad no_wall "no box named 'dam'" "$run" --wall dam
bad window_backwards "T0 must be below T1" "$run" --window 5 1
bad window_late "snapshots in the window" "$run" --window 7 9
mkdir -p "$out/no_inlet"
echo "{\"case\": \"$src/cases/dam_break_lobovsky_2d.yaml\", \"status\": \"finished\"}" > "$out/no_inlet/summary.json"
bad no_inlet "constant .velocity." "$out/no_inlet"
mkdir -p "$out/upstream_wall"
"$py" "$src/tools/case_override.py" "$src/cases/bore_reflection_2d.yaml" "$out/upstream_wall/case.yaml" \
  "inlets.upstream.normal=[-1,0]" || fail "case_override"
echo "{\"case\": \"$out/upstream_wall/case.yaml\", \"status\": \"finished\"}" > "$out/upstream_wall/summary.json"
bad inlet_backwards "runs towards +x" "$out/upstream_wall"
echo "tools_compare_bore: ok"
