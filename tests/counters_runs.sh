#!/usr/bin/env bash
# "Nothing computed that a scene does not need": the work counters of summary.json
# ("work", coordinator/README.md) against independent counts, through `lahar run --in-process`.
#
#   counters_runs.sh TEST BIN_DIR TOOLS_DIR WORK_DIR
#   TEST: water_only | soil_water | fixed_bodies | processes | output_fields | dem_contacts
#
# water_only    a block of water without bodies, one step, 2D and 3D: no DEM node, no soil or
#               seepage work (soil-soil and fluid-soil pairs 0), no particle-body or body-body
#               work, no LOADS or BODY_STATE; the fluid-fluid pair count equals the pairs closer
#               than the kernel support (2 h) counted by brute force over the particle positions
#               of the snapshots, summed over the particle-particle passes (the set-up pass at
#               t_0 and the step's pass at t_1).
# soil_water    a soil block with k_h > 0 beside a water block, one step: fluid-fluid, soil-soil
#               and fluid-soil (seepage) pair counts each equal the brute-force count by phase.
# fixed_bodies  water in a tank of fixed walls: no DEM node is started and no per-step body
#               message is sent (no LOADS, BODY_STATE, and STATUS only from the SPH node); the
#               particle-body count equals the particles within the support of each wall's
#               swept surface by brute force (one step: two evaluations at t_0, one at t_1).
#               Then 0.1 s of the same tank with and without a free body 5 m away (which brings
#               the DEM node back): particles.h5 and contacts.h5 bitwise equal, the walls' force
#               rows in forces.h5 equal to 1e-12 (the DEM node averages them over its
#               substeps), the same body poses; the far body adds no particle-body work.
# processes     the one-step tank run as processes (lahar's private network namespace): only
#               lahar-sph joins (HELLO from the coordinator and the SPH node only), the particles
#               are bitwise those of the in-process run.
# output_fields the tank with output fields [velocity] and with every field: particles.h5
#               holds only the fields asked for, no value is computed for output without
#               pressure (output_derived 0) and one pressure per particle and snapshot with it;
#               the written pressure is the linear EOS c0^2 (rho - rho0) of the written density
#               (Trujillo-Vela et al. 2020 eq. 3) to 1e-9; positions and velocities are bitwise equal.
# dem_contacts  a DEM-only scene: a sphere set down touching a fixed plane settles into it and
#               stays in contact: one body-body contact in every substep, none at the engine's
#               set-up (touching is not a contact), so body_body = substeps; no particle work.
set -u
test_name=$1 bin=$2 tools=$3 work=$4
python=/usr/bin/python3
[ -x "$python" ] || python=python3
rm -rf "$work"
mkdir -p "$work"
cd "$work" || exit 2

fail() { echo "FAIL: $*" >&2; exit 1; }
run() { # case out [options]
    local c=$1 o=$2
    shift 2
    "$bin/lahar" run "$c" -o "$o" -q --in-process --threads 1 "$@" || fail "lahar run $c failed"
}

# 2D tank, inner surfaces at x = 0, x = 0.2, y = 0 (segment cores one sweep radius behind),
# water 0.2 x 0.1 m at dx = 5 mm (800 particles), cubic kernel h = 1.3 dx (support 13 mm).
write_tank() { # file end output_interval [fields]
    cat > "$1" <<YAML
dimensions: 2
gravity: [0, -9.81]
time: {end: $2, dt_max: 1e-3, output_interval: $3}
materials:
  wall: {density: 2650, model: linear, kn: 1.0e5, restitution: 0.5, friction: 0.3}
  wood: {density: 500, model: linear, kn: 1.0e5, restitution: 0.5, friction: 0.3}
sph:
  dx: 0.005
  kernel: cubic
  h_over_dx: 1.3
  c0: 15
  alpha: 0.05
  blocks:
    - {name: water, box: {lo: [0, 0], hi: [0.2, 0.1]}}
bodies:
  - {name: left, shape: segment, motion: fixed, material: wall, radius: 0.002, vertices: [[-0.002, -0.002], [-0.002, 0.2]]}
  - {name: right, shape: segment, motion: fixed, material: wall, radius: 0.002, vertices: [[0.202, -0.002], [0.202, 0.2]], record_contacts: true}
  - {name: floor, shape: segment, motion: fixed, material: wall, radius: 0.002, vertices: [[-0.002, -0.002], [0.202, -0.002]]}
YAML
    if [ $# -ge 4 ]; then
        printf 'output: {fields: %s}\n' "$4" >> "$1"
    fi
}

case $test_name in
water_only)
    # one step: t_end below the CFL step 0.25 h / c0 (2D: 0.25 * 0.013 / 15 = 2.2e-4 s)
    cat > w2.yaml <<'YAML'
dimensions: 2
gravity: [0, -9.81]
time: {end: 1e-4, dt_max: 1e-3, output_interval: 1e-4}
sph:
  dx: 0.01
  kernel: cubic
  h_over_dx: 1.3
  c0: 15
  blocks:
    - {name: water, box: {lo: [0, 0], hi: [0.2, 0.1]}}
YAML
    cat > w3.yaml <<'YAML'
dimensions: 3
gravity: [0, 0, -9.81]
time: {end: 1e-4, dt_max: 1e-3, output_interval: 1e-4}
sph:
  dx: 0.01
  kernel: wendland2
  h_over_dx: 1.2
  c0: 15
  blocks:
    - {name: water, box: {lo: [0, 0, 0], hi: [0.08, 0.06, 0.05]}}
YAML
    run w2.yaml w2
    run w3.yaml w3
    "$python" - w2 0.026 w3 0.024 <<'PY' || fail "water-only work"
import json, sys
import h5py, numpy as np

def pairs_within(x, support):
    """unordered pairs closer than the support, brute force over all pairs"""
    d2 = ((x[:, None, :] - x[None, :, :]) ** 2).sum(axis=2)
    iu = np.triu_indices(len(x), 1)
    return int((d2[iu] < support * support).sum())

for out, support in zip(sys.argv[1::2], map(float, sys.argv[2::2])):
    s = json.load(open(out + "/summary.json"))
    w = s["work"]
    assert s["status"] == "finished" and s["steps"] == 1, (out, s["status"], s["steps"])
    assert list(s["nodes"]) == ["sph"] and not w["dem_node"], (out, list(s["nodes"]))
    for k in ("pairs_soil_soil", "pairs_fluid_soil", "particle_body", "body_body", "dem_substeps"):
        assert w[k] == 0, (out, k, w[k])
    for ch in ("LAHAR_LOADS", "LAHAR_BODY_STATE"):
        assert w["channels"][ch]["messages"] == 0 and w["channels"][ch]["bytes"] == 0, (out, ch, w["channels"][ch])
    with h5py.File(out + "/particles.h5", "r") as f:
        snaps = [f["snapshots"][k] for k in sorted(f["snapshots"])]
        assert [int(g.attrs["step"]) for g in snaps] == [0, 1], [int(g.attrs["step"]) for g in snaps]
        counts = [pairs_within(np.stack([np.asarray(g[a]) for a in "xyz"], axis=1), support) for g in snaps]
        n = len(np.asarray(snaps[0]["x"]))
    # passes: the set-up evaluation at t_0 (no bodies: step 0 needs no second one) and the
    # step's evaluation at t_1
    assert w["sph_passes"] == 2, (out, w["sph_passes"])
    expect = counts[0] + counts[1]
    assert w["pairs_fluid_fluid"] == expect, (out, w["pairs_fluid_fluid"], counts)
    print("%s: %d particles, %d + %d pairs within %.3f m by brute force = pairs_fluid_fluid %d; soil, seepage, "
          "body work 0" % (out, n, counts[0], counts[1], support, w["pairs_fluid_fluid"]))
PY
    ;;
soil_water)
    # a soil block (k_h > 0: seepage) beside a water block, one step
    cat > sw.yaml <<'YAML'
dimensions: 2
gravity: [0, -9.81]
time: {end: 1e-6, dt_max: 1e-3, output_interval: 1e-6}
materials:
  sand: {model: soil, density: 2000, young: 1.0e6, poisson: 0.3, friction_angle: 30, cohesion: 0, permeability: 0.01}
sph:
  dx: 0.01
  kernel: cubic
  h_over_dx: 1.3
  c0: 15
  blocks:
    - {name: soil, phase: soil, material: sand, box: {lo: [0, 0], hi: [0.1, 0.06]}}
    - {name: water, box: {lo: [0.1, 0], hi: [0.2, 0.06]}}
YAML
    run sw.yaml sw
    "$python" - sw 0.026 <<'PY' || fail "soil and water work"
import json, sys
import h5py, numpy as np
out, support = sys.argv[1], float(sys.argv[2])
s = json.load(open(out + "/summary.json"))
w = s["work"]
assert s["status"] == "finished" and s["steps"] == 1, (s["status"], s["steps"], s["message"])
def pairs(x, ph):
    d2 = ((x[:, None, :] - x[None, :, :]) ** 2).sum(axis=2)
    iu = np.triu_indices(len(x), 1)
    near = d2[iu] < support * support
    a, b = ph[iu[0]], ph[iu[1]]
    return (int((near & (a == 0) & (b == 0)).sum()), int((near & (a != 0) & (b != 0)).sum()),
            int((near & (a != b)).sum()))
with h5py.File(out + "/particles.h5", "r") as f:
    c = [pairs(np.stack([np.asarray(g[a]) for a in "xy"], axis=1), np.asarray(g["phase"]))
         for g in (f["snapshots"][k] for k in sorted(f["snapshots"]))]
assert len(c) == 2 and w["sph_passes"] == 2, (len(c), w["sph_passes"])
got = (w["pairs_fluid_fluid"], w["pairs_soil_soil"], w["pairs_fluid_soil"])
expect = tuple(c[0][i] + c[1][i] for i in range(3))
assert got == expect and min(expect) > 0, (got, expect)
print("soil_water: fluid-fluid %d, soil-soil %d, fluid-soil %d pairs = brute force over both states" % got)
PY
    ;;
fixed_bodies)
    write_tank one.yaml 1e-4 1e-4
    run one.yaml one
    "$python" - one <<'PY' || fail "fixed bodies: messages or particle-body work"
import json, sys
import h5py, numpy as np
out = sys.argv[1]
s = json.load(open(out + "/summary.json"))
w, ch = s["work"], s["work"]["channels"]
assert s["status"] == "finished" and s["steps"] == 1, (s["status"], s["steps"])
assert list(s["nodes"]) == ["sph"] and not w["dem_node"], list(s["nodes"])
assert ch["LAHAR_LOADS"]["messages"] == 0 and ch["LAHAR_BODY_STATE"]["messages"] == 0, ch
# STATUS: the SPH node's ready (k = -1) and step 0, nothing from a DEM node
assert ch["LAHAR_STATUS"]["messages"] == s["steps"] + 1, ch["LAHAR_STATUS"]
assert w["body_body"] == 0 and w["dem_substeps"] == 0, w
# segment walls: core from a to b, sweep radius R; a particle couples when its distance to the
# swept surface is below the support 2 h = 2.6 dx
walls = [((-0.002, -0.002), (-0.002, 0.2)), ((0.202, -0.002), (0.202, 0.2)), ((-0.002, -0.002), (0.202, -0.002))]
R, support = 0.002, 2.6 * 0.005
def contacts(x):
    n = 0
    for a, b in walls:
        a, b = np.array(a), np.array(b)
        t = np.clip(((x - a) @ (b - a)) / ((b - a) @ (b - a)), 0.0, 1.0)
        d = np.linalg.norm(x - (a + t[:, None] * (b - a)), axis=1) - R
        n += int((d < support).sum())
    return n
with h5py.File(out + "/particles.h5", "r") as f:
    c = [contacts(np.stack([np.asarray(f["snapshots"][k][a]) for a in "xy"], axis=1)) for k in sorted(f["snapshots"])]
# evaluations of the coupling: set-up and step 0 (K_n of the granted dt) at t_0, the step at t_1
expect = 2 * c[0] + c[1]
assert w["particle_body"] == expect, (w["particle_body"], c)
for f in ("bodies.h5", "forces.h5", "contacts.h5"):
    h5py.File(out + "/" + f, "r").close()
print("fixed_bodies: no DEM node; LOADS 0, BODY_STATE 0, STATUS %d = steps + 1; particle_body %d = 2 x %d + %d by brute force"
      % (ch["LAHAR_STATUS"]["messages"], w["particle_body"], c[0], c[1]))
PY
    [ $? -eq 0 ] || exit 1
    write_tank tank.yaml 0.1 0.05
    cp tank.yaml far.yaml
    echo "  - {name: far_box, shape: box, size: [0.05, 0.05], radius: 0.002, material: wood, position: [5.0, 0.13]}" >> far.yaml
    run tank.yaml tank
    run far.yaml far
    "$python" "$tools/h5_compare.py" --quiet tank/particles.h5 far/particles.h5 ||
        fail "the particles differ between the run without a DEM node and the run with one"
    "$python" "$tools/h5_compare.py" --quiet tank/contacts.h5 far/contacts.h5 ||
        fail "contacts.h5 differs between the run without a DEM node and the run with one"
    "$python" - tank far <<'PY' || fail "fixed bodies: the run without a DEM node differs"
import json, sys
import h5py, numpy as np
a, b = sys.argv[1:3]
sa, sb = (json.load(open(d + "/summary.json")) for d in (a, b))
assert sa["steps"] == sb["steps"], (sa["steps"], sb["steps"])
assert not sa["work"]["dem_node"] and sb["work"]["dem_node"], "the far free body must bring the DEM node back"
ca, cb = sa["work"]["channels"], sb["work"]["channels"]
assert ca["LAHAR_LOADS"]["messages"] == 0 and cb["LAHAR_LOADS"]["messages"] == sb["steps"], (ca["LAHAR_LOADS"], cb["LAHAR_LOADS"])
assert ca["LAHAR_BODY_STATE"]["messages"] == 0, ca["LAHAR_BODY_STATE"]
for k in ("sph_passes", "pairs_fluid_fluid", "particle_body"):
    assert sa["work"][k] == sb["work"][k], (k, sa["work"][k], sb["work"][k])
with h5py.File(a + "/forces.h5", "r") as fa, h5py.File(b + "/forces.h5", "r") as fb:
    assert np.array_equal(np.asarray(fa["t"]), np.asarray(fb["t"]))
    for name in ("force", "torque"):
        x, y = np.asarray(fa[name]), np.asarray(fb[name])[:, :3]
        scale = np.abs(y).max()
        assert scale > 0 and np.abs(x - y).max() <= 1e-12 * scale, (name, np.abs(x - y).max(), scale)
with h5py.File(a + "/bodies.h5", "r") as fa, h5py.File(b + "/bodies.h5", "r") as fb:
    assert sorted(fa["snapshots"]) == sorted(fb["snapshots"])
    for k in fa["snapshots"]:
        for d in ("position", "quaternion"):
            x, y = np.asarray(fa["snapshots"][k][d]), np.asarray(fb["snapshots"][k][d])[:3]
            assert np.array_equal(x, y), (k, d, x, y)
print("fixed_bodies: %d steps without a DEM node (0 LOADS) = with one (%d LOADS): particles.h5 and contacts.h5 "
      "bitwise, wall forces to 1e-12" % (sa["steps"], cb["LAHAR_LOADS"]["messages"]))
PY
    ;;
processes)
    # the same one-step tank as `lahar run` without --in-process: nodes as processes in lahar's
    # own private network namespace; only lahar-sph is started
    write_tank one.yaml 1e-4 1e-4
    "$bin/lahar" run one.yaml -o proc -q --threads 1 || fail "lahar run (processes) failed"
    run one.yaml ip
    "$python" "$tools/h5_compare.py" --quiet ip/particles.h5 proc/particles.h5 || fail "processes and in-process differ"
    "$python" - proc <<'PY' || fail "processes: a DEM node took part"
import json, sys
s = json.load(open(sys.argv[1] + "/summary.json"))
w, ch = s["work"], s["work"]["channels"]
assert s["status"] == "finished" and s["mode"] == "processes", (s["status"], s["mode"])
assert list(s["nodes"]) == ["sph"] and not w["dem_node"], list(s["nodes"])
# HELLO: the coordinator's announcement and the SPH node's answer, no DEM node's
assert ch["LAHAR_HELLO"]["messages"] == 2, ch["LAHAR_HELLO"]
assert ch["LAHAR_STATUS"]["messages"] == s["steps"] + 1, ch["LAHAR_STATUS"]
assert ch["LAHAR_LOADS"]["messages"] == 0 and ch["LAHAR_BODY_STATE"]["messages"] == 0, ch
print("processes: only lahar-sph joined (2 HELLO, %d STATUS for %d step), same particles as in-process"
      % (ch["LAHAR_STATUS"]["messages"], s["steps"]))
PY
    ;;
output_fields)
    write_tank vel.yaml 0.02 0.01 "[velocity]"
    write_tank all.yaml 0.02 0.01
    run vel.yaml vel
    run all.yaml all
    "$python" - vel all <<'PY' || fail "output fields"
import json, sys
import h5py, numpy as np
a, b = sys.argv[1:3]
wa, wb = (json.load(open(d + "/summary.json"))["work"] for d in (a, b))
with h5py.File(a + "/particles.h5", "r") as fa, h5py.File(b + "/particles.h5", "r") as fb:
    keys = sorted(fa["snapshots"])
    assert keys == sorted(fb["snapshots"]) and len(keys) >= 3, keys
    n = 0
    for k in keys:
        ga, gb = fa["snapshots"][k], fb["snapshots"][k]
        assert sorted(ga) == ["vx", "vy", "vz", "x", "y", "z"], sorted(ga)
        assert {"density", "pressure", "phase", "id"} <= set(gb), sorted(gb)
        for d in ga:
            assert np.array_equal(np.asarray(ga[d]), np.asarray(gb[d])), (k, d)
        rho, p = np.asarray(gb["density"]), np.asarray(gb["pressure"])
        eos = 15.0 ** 2 * (rho - 1000.0)  # Trujillo-Vela et al. 2020 eq. 3, c0 = 15 m/s, rho0 = 1000 kg/m^3
        assert np.abs(p - eos).max() <= 1e-9 * np.abs(eos).max(), (k, np.abs(p - eos).max())
        n += len(rho)
assert wa["output_derived"] == 0, wa["output_derived"]
assert wb["output_derived"] == n, (wb["output_derived"], n)
print("output_fields: [velocity]: no density/pressure/phase/id written, 0 values computed for output; every field: "
      "%d pressures computed (one per particle and snapshot), = EOS of the written density" % n)
PY
    ;;
dem_contacts)
    # a sphere touching a plane (core distance = sum of the radii: not yet a contact) sinks to its
    # static overlap m g / k_n under gravity and stays in contact: the damped spring (e = 0.1)
    # never brings it back to zero overlap
    cat > rest.yaml <<'YAML'
dimensions: 3
gravity: [0, 0, -9.81]
time: {end: 0.05, dt_max: 1e-3, output_interval: 0.005}
materials:
  rock: {density: 2000, model: linear, kn: 1.0e5, restitution: 0.1, friction: 0.3}
bodies:
  - {name: floor, shape: plane, motion: fixed, material: rock, radius: 0.02, position: [0, 0, -0.02], normal: [0, 0, 1], size: [1.0, 1.0]}
  - {name: ball, shape: sphere, radius: 0.05, material: rock, position: [0, 0, 0.05]}
YAML
    run rest.yaml rest
    "$python" - rest <<'PY' || fail "body-body contact count"
import json, sys
import h5py, numpy as np
s = json.load(open(sys.argv[1] + "/summary.json"))
w = s["work"]
assert s["status"] == "finished" and w["dem_node"] and not w["sph_node"], (s["status"], w)
assert w["dem_substeps"] > s["steps"], w["dem_substeps"]
for k in ("sph_passes", "pairs_fluid_fluid", "particle_body", "pairs_soil_soil", "pairs_fluid_soil"):
    assert w[k] == 0, (k, w[k])
with h5py.File(sys.argv[1] + "/bodies.h5", "r") as f:
    z = [float(np.asarray(f["snapshots"][k]["position"])[1][2]) for k in sorted(f["snapshots"])]
assert z[0] == 0.05 and all(zz < 0.05 for zz in z[1:]), z  # touching at t = 0, in contact after
# one contact per force evaluation: none at the set-up (touching), one in every substep
assert w["body_body"] == w["dem_substeps"], (w["body_body"], w["dem_substeps"])
print("dem_contacts: sphere settling on a plane (z = %.6f m at the end, static overlap %.3g m): body_body %d = %d substeps"
      % (z[-1], 2000 * 4 / 3 * np.pi * 0.05 ** 3 * 9.81 / 1e5, w["body_body"], w["dem_substeps"]))
PY
    ;;
*)
    echo "unknown test $test_name" >&2
    exit 2
    ;;
esac
echo "PASS: $test_name"
