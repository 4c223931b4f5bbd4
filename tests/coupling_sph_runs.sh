#!/usr/bin/env bash
# SPH-DEM coupling over the protocol, through `lahar run`: the SPH node's WCSPH solver,
# LOADS / BODY_STATE between the nodes, the force stream and contacts.h5.
#
#   coupling_sph_runs.sh TEST BIN_DIR TOOLS_DIR WORK_DIR
#   TEST: modes | far_body | hydrostatic | crossing | dem_killed
#
# modes        a box dropped into a small 2D tank of water: `lahar run --in-process` (memq://) and
#              `lahar run` (processes in lahar's own private network namespace) write bitwise the
#              same particles.h5, bodies.h5, forces.h5 and contacts.h5, and so does a run on 2
#              OpenMP threads; the water slows the box.
# far_body     the same scene with one more free box 5 m away from the water: LOADS and BODY_STATE
#              carry exactly the bytes of the run without it (the far body is never sent), the
#              work counters of summary.json (pairs, particle-body and body-body contacts) are the
#              same, and the water and the near box move bitwise as without it.
# hydrostatic  water at rest in a tank of three fixed DEM walls: the time-averaged force on a side
#              wall in forces.h5 equals rho g h^2 / 2 (per unit width) within 5 % at this CI
#              resolution (20 particles over h), the floor carries the weight within 2 %, and the
#              contact points of the wall marked record_contacts (contacts.h5) add up to the
#              wall's resultant with the centre of pressure at h/3 within 10 %.
# crossing     a jet at 20 m/s with a far too small speed of sound (c0 = 1 m/s: the CFL step lets a
#              particle move 0.3 dx per step) is driven through a thin wall: the run stops with
#              exit 1 and a message naming the body, the particle and the step, and the last
#              particle snapshot (the state after that step) has that particle inside the wall's
#              swept surface (closer than its radius to the core).
set -u
test_name=$1 bin=$2 tools=$3 work=$4
python=/usr/bin/python3
[ -x "$python" ] || python=python3
rm -rf "$work"
mkdir -p "$work"
cd "$work" || exit 2

fail() { echo "FAIL: $*" >&2; exit 1; }

# 2D tank, inner surfaces at x = 0, x = 0.2, y = 0 (wall cores one sweep radius behind), water
# 0.2 m x 0.1 m at dx = 5 mm (800 particles).
write_tank() { # file t_end output_interval alpha
    cat > "$1" <<YAML
dimensions: 2
gravity: [0, -9.81]
time: {end: $2, dt_max: 1e-3, output_interval: $3}
materials:
  wall: {density: 2650, model: linear, kn: 1.0e5, restitution: 0.5, friction: 0.3}
  wood: {density: 500, model: linear, kn: 1.0e5, restitution: 0.5, friction: 0.3}
sph:
  dx: 0.005
  alpha: $4
  blocks:
    - {name: water, box: {lo: [0, 0], hi: [0.2, 0.1]}}
bodies:
  - {name: left, shape: segment, motion: fixed, material: wall, radius: 0.002, vertices: [[-0.002, -0.002], [-0.002, 0.2]]}
  - {name: right, shape: segment, motion: fixed, material: wall, radius: 0.002, vertices: [[0.202, -0.002], [0.202, 0.2]], record_contacts: true}
  - {name: floor, shape: segment, motion: fixed, material: wall, radius: 0.002, vertices: [[-0.002, -0.002], [0.202, -0.002]]}
YAML
}

write_drop() { # file
    write_tank "$1" 0.15 0.05 0.05
    echo "  - {name: box, shape: box, size: [0.05, 0.05], radius: 0.002, material: wood, position: [0.1, 0.13], velocity: [0, -1]}" >> "$1"
}

summary() { # outdir python-expression on s
    "$python" -c "import json,sys; s=json.load(open('$1/summary.json')); print($2)"
}

case $test_name in
modes)
    write_drop drop.yaml
    "$bin/lahar" run drop.yaml -o ip -q --in-process --threads 1 || fail "in-process run failed"
    "$bin/lahar" run drop.yaml -o proc -q --threads 1 || fail "multi-process run failed"
    "$bin/lahar" run drop.yaml -o ip2 -q --in-process --threads 2 || fail "in-process run on 2 threads failed"
    [ "$(summary proc "s['mode']")" = processes ] || fail "mode is not processes"
    for f in particles.h5 bodies.h5 forces.h5 contacts.h5; do
        "$python" "$tools/h5_compare.py" --quiet ip/$f proc/$f || fail "$f differs between --in-process and processes"
        "$python" "$tools/h5_compare.py" --quiet ip/$f ip2/$f || fail "$f differs between 1 and 2 threads"
    done
    "$python" - ip <<'PY' || fail "wrong results"
import json, sys
import h5py, numpy as np
out = sys.argv[1]
s = json.load(open(out + "/summary.json"))
steps = s["steps"]
assert s["status"] == "finished", s["status"]
for ch in ("LAHAR_LOADS", "LAHAR_BODY_STATE"):
    assert s["channels"][ch]["messages"] == steps, (ch, s["channels"][ch]["messages"], steps)
# The box hits the water: the fluid's load on it (the only force besides gravity while it is off
# the floor) must have slowed it from 1 m/s + free fall to below half its free-fall speed.
with h5py.File(out + "/bodies.h5", "r") as f:
    last = f["snapshots"][sorted(f["snapshots"])[-1]]
    t = float(last.attrs["time"])
    v = np.asarray(last["velocity"])[3]
free = -1.0 - 9.81 * t
assert abs(v[1]) < 0.5 * abs(free), ("box not slowed by the water", v, free)
with h5py.File(out + "/forces.h5", "r") as f:
    F = np.asarray(f["force"])
    up = F[:, 3, 1].max()
assert up > 0, "no upward load on the box"
print("modes: %d steps, bitwise equal in both modes and on 1 and 2 threads; box at %.3f m/s at t = %.2f s (free fall: %.3f), peak fluid load %.1f N/m"
      % (steps, v[1], t, free, up))
PY
    ;;
far_body)
    write_drop near.yaml
    cp near.yaml far.yaml
    echo "  - {name: far_box, shape: box, size: [0.05, 0.05], radius: 0.002, material: wood, position: [5.0, 0.13], velocity: [0, -1]}" >> far.yaml
    "$bin/lahar" run near.yaml -o near -q --in-process --threads 1 || fail "run without the far body failed"
    "$bin/lahar" run far.yaml -o far -q --in-process --threads 1 || fail "run with the far body failed"
    "$python" "$tools/h5_compare.py" --quiet near/particles.h5 far/particles.h5 ||
        fail "the water moves differently with a body 5 m away"
    "$python" - near far <<'PY' || fail "a far body costs traffic"
import json, sys
import h5py, numpy as np
near, far = (json.load(open(d + "/summary.json")) for d in sys.argv[1:3])
assert near["steps"] == far["steps"], (near["steps"], far["steps"])
for ch in ("LAHAR_LOADS", "LAHAR_BODY_STATE"):
    # first publications only: re-sends on a NACK depend on timing (a slow sanitizer build)
    a, b = near["channels"][ch]["first_bytes"], far["channels"][ch]["first_bytes"]
    assert a == b, "%s: %d bytes without the far body, %d with it" % (ch, a, b)
# nor any work: the same pairs, particle-body and body-body contacts (summary.json "work")
for k in ("sph_passes", "pairs_fluid_fluid", "particle_body", "body_body"):
    assert near["work"][k] == far["work"][k], "%s: %d without the far body, %d with it" % (k, near["work"][k], far["work"][k])
assert far["work"]["particle_body"] > 0, "the near box and the walls must touch the water"
with h5py.File(sys.argv[1] + "/bodies.h5") as a, h5py.File(sys.argv[2] + "/bodies.h5") as b:
    for name in a["snapshots"]:
        pa, pb = np.asarray(a["snapshots"][name]["position"]), np.asarray(b["snapshots"][name]["position"])
        assert np.array_equal(pa, pb[:4]), name
    t = float(b["snapshots"][name].attrs["time"])
    y = float(np.asarray(b["snapshots"][name]["position"])[4][1])
# the far box falls freely (nothing touches it): y = y0 + v0 t - g t^2 / 2
exact = 0.13 - 1.0 * t - 0.5 * 9.81 * t * t
assert abs(y - exact) < 1e-9, (y, exact)
print("far_body: LOADS %d B and BODY_STATE %d B with and without the far body; far box in free fall (error %.1e m)"
      % (far["channels"]["LAHAR_LOADS"]["first_bytes"], far["channels"]["LAHAR_BODY_STATE"]["first_bytes"], abs(y - exact)))
PY
    ;;
hydrostatic)
    write_tank tank.yaml 0.6 0.05 0.1
    "$bin/lahar" run tank.yaml -o tank -q --in-process --threads 1 || fail "tank run failed"
    "$python" - tank <<'PY' || fail "hydrostatic wall force"
import sys
import h5py, numpy as np
out = sys.argv[1]
rho, g, h, width = 1000.0, 9.81, 0.1, 0.2
ref = rho * g * h * h / 2  # N/m on a side wall
weight = rho * g * h * width
with h5py.File(out + "/forces.h5", "r") as f:
    F, t = np.asarray(f["force"]), np.asarray(f["t"])
settled = t > 0.3  # after the initial compression wave (period ~4 h / c0 = 0.03 s) has damped
right, left, floor = F[settled, 1, 0].mean(), F[settled, 0, 0].mean(), F[settled, 2, 1].mean()
err = abs(right - ref) / ref
print("hydrostatic: right wall %.2f N/m, left %.2f N/m, rho g h^2/2 = %.2f N/m (error %.2f %%); floor %.2f N/m, weight %.2f N/m"
      % (right, left, ref, 100 * err, -floor, weight))
assert err < 0.05, err
assert abs(right + left) < 1e-6 * ref, "side forces do not balance"
assert abs(-floor - weight) / weight < 0.02, (floor, weight)
# contacts.h5: per snapshot the points on the marked wall add up to its resultant; the centre of
# pressure of a hydrostatic wall is at h/3 above the floor
ys = []
with h5py.File(out + "/contacts.h5", "r") as f:
    assert [x.decode() if isinstance(x, bytes) else x for x in f["header/groups"][:]] == ["right"]
    for name in sorted(f["snapshots"]):
        s = f["snapshots"][name]
        b = s["right"]
        pts, fs = np.asarray(b["points"]), np.asarray(b["forces"])
        assert pts.shape == fs.shape == (int(b.attrs["n"]), 3)
        total = fs.sum(axis=0)
        assert np.allclose(total, b.attrs["force"], rtol=1e-9, atol=1e-9), (name, total, b.attrs["force"])
        if float(s.attrs["time"]) > 0.3:
            ys.append((fs[:, 0] * pts[:, 1]).sum() / fs[:, 0].sum())
yc = float(np.mean(ys))
print("contacts.h5: %d snapshots; centre of pressure at %.4f m, h/3 = %.4f m" % (len(ys), yc, h / 3))
assert abs(yc - h / 3) / (h / 3) < 0.10, yc
PY
    ;;
dem_killed)
    # kill -9 the DEM node while the box sinks into the water: the coordinator exits 3; the force
    # stream the DEM node was writing (SWMR) opens with h5dump, as the closing message promises;
    # the SPH node, stopped while it waited for the box's state, ends particles.h5 with a snapshot
    # marked `stopped` (the coordinator's reason); summary.json lists the DEM node as killed.
    write_tank drop.yaml 30 0.05 0.05
    echo "  - {name: box, shape: box, size: [0.05, 0.05], radius: 0.002, material: wood, position: [0.1, 0.13], velocity: [0, -1]}" >> drop.yaml
    "$bin/lahar" run drop.yaml -o killed -q 2> stderr.txt &
    lahar_pid=$!
    dem_pid=""
    for _ in $(seq 200); do
        for stat in /proc/[0-9]*/stat; do
            read -r pid comm state ppid rest < "$stat" 2>/dev/null || continue
            [ "$ppid" = "$lahar_pid" ] && [ "$comm" = "(lahar-dem)" ] && dem_pid=$pid
        done
        [ -n "$dem_pid" ] && [ -e killed/forces.h5 ] && break
        sleep 0.05
    done
    [ -n "$dem_pid" ] || { kill -9 "$lahar_pid"; fail "no lahar-dem child found"; }
    sleep 1.0
    kill -9 "$dem_pid"
    wait "$lahar_pid"
    rc=$?
    cat stderr.txt
    [ "$rc" -eq 3 ] || fail "exit status $rc, expected 3 (node lost)"
    h5dump -H killed/forces.h5 > /dev/null || fail "forces.h5 of the killed DEM node does not open with h5dump"
    rows=$("$python" -c "import h5py; print(h5py.File('killed/forces.h5', 'r')['t'].shape[0])") ||
        fail "forces.h5 of the killed DEM node does not open with h5py"
    [ "$rows" -gt 0 ] || fail "forces.h5 has no rows"
    "$python" - <<'PY' || fail "particles.h5 does not end with a snapshot marked stopped"
import h5py, sys
with h5py.File("killed/particles.h5", "r") as f:
    last = sorted(f["snapshots"])[-1]
    mark = f["snapshots"][last].attrs.get("stopped")
    mark = mark.decode() if isinstance(mark, bytes) else mark
    print(f"last particle snapshot {last}: stopped = {mark!r}")
    sys.exit(0 if mark and "lost the DEM node" in mark else 1)
PY
    [ "$(summary killed "s['nodes']['dem']['exit_status']")" = 137 ] || fail "summary.json does not list the DEM node as killed (137)"
    echo "forces.h5: $rows rows readable after the DEM node was killed"
    ;;
crossing)
    cat > jet.yaml <<'YAML'
dimensions: 2
gravity: [0, 0]
time: {end: 0.05, dt_max: 1e-3, output_interval: 0.01}
materials:
  wall: {density: 2650, model: linear, kn: 1.0e5, restitution: 0.5, friction: 0.3}
bodies:
  - {name: thin_wall, shape: segment, motion: fixed, material: wall, radius: 0.002, vertices: [[0.1, -0.1], [0.1, 0.1]]}
sph:
  dx: 0.005
  c0: 1.0
  blocks:
    - {name: jet, box: {lo: [0.0, -0.02], hi: [0.05, 0.02]}, velocity: [20, 0]}
YAML
    "$bin/lahar" run jet.yaml -o jet -q --in-process --threads 1 2> stderr.txt
    rc=$?
    cat stderr.txt
    [ "$rc" -eq 1 ] || fail "exit status $rc, expected 1"
    "$python" - jet stderr.txt <<'PY' || fail "crossing report"
import json, re, sys
import h5py, numpy as np
s = json.load(open(sys.argv[1] + "/summary.json"))
assert s["status"] == "unstable" and s["exit_status"] == 1, s["status"]
m = re.search(r"particle (\d+) crossed the surface of body 0 'thin_wall' in step (\d+)", s["message"])
assert m, s["message"]
pid, k = int(m.group(1)), int(m.group(2))
assert k == s["steps"], (k, s["steps"])  # steps completed before the failing one
assert m.group(0) in open(sys.argv[2]).read(), "stderr does not carry the message"
with h5py.File(sys.argv[1] + "/particles.h5", "r") as f:
    last = f["snapshots"][sorted(f["snapshots"])[-1]]
    assert int(last.attrs["step"]) == k + 1, (int(last.attrs["step"]), k + 1)
    ids, x, y = np.asarray(last["id"]), np.asarray(last["x"]), np.asarray(last["y"])
i = int(np.nonzero(ids == pid)[0][0])
d = abs(x[i] - 0.1)  # distance to the wall's core (the segment x = 0.1, |y| <= 0.1)
assert abs(y[i]) <= 0.1 and d < 0.002, (x[i], y[i], d)
print("crossing: particle %d reported in step %d, %.2f mm from the core of a 2 mm wall in the last snapshot"
      % (pid, k, 1e3 * d))
PY
    ;;
*)
    echo "unknown test $test_name" >&2
    exit 2
    ;;
esac
echo "PASS: $test_name"
