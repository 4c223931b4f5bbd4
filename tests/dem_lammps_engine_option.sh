#!/bin/bash
# `lahar-dem --engine NAME` runs a case with another DEM engine than its dem.engine, with the same
# command line otherwise. A DEM-only case (dem.engine: spheropoly: a Hertz ball dropped on a plane,
# normal impacts only) is run (1) by `lahar run` as usual and (2) with `lahar run --no-spawn` and
# `lahar-dem --engine lammps` started by hand, both inside a private user + network namespace
# (multicast on lo only). Passes when run 2 says it used the lammps engine (summary.json
# nodes.dem.engine_detail), both finish, and the ball's heights agree within 1e-9 m (the engines
# are equal to round-off in normal impacts, test_dem_lammps); and when an unknown --engine is
# refused with exit 2 and the registered names.
# usage: dem_lammps_engine_option.sh BIN_DIR OUT PYTHON
set -u
[ $# -eq 3 ] || { echo "usage: $0 BIN_DIR OUT PYTHON" >&2; exit 2; }
bin=$1 out=$2 py=$3
URL='udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608'
rm -rf "$out" && mkdir -p "$out" && cd "$out" || exit 2
fail() { echo "FAIL: $*" >&2; exit 1; }

"$bin/lahar-dem" --engine nosuch > nosuch.out 2> nosuch.err
rc=$?
[ $rc -eq 2 ] && grep -q "not a registered DEM engine (registered: spheropoly, lammps)" nosuch.err ||
    fail "lahar-dem --engine nosuch: exit $rc, $(cat nosuch.err)"
echo "ok: lahar-dem --engine nosuch: exit 2, $(cat nosuch.err)"

cat > case.yaml <<'YAML'
dimensions: 3
gravity: [0, 0, -9.81]
time: {end: 0.5, dt_max: 1e-3, output_interval: 0.01}
materials:
  rock: {density: 2650, model: hertz, young: 1e7, poisson: 0.25, restitution: 0.6, friction: 0.5}
dem: {engine: spheropoly}
bodies:
  - {name: ball, shape: sphere, radius: 0.05, material: rock, position: [0, 0, 0.2]}
  - {name: floor, shape: plane, motion: fixed, normal: [0, 0, 1], size: [2, 2], radius: 0.02, material: rock, position: [0, 0, 0]}
YAML
"$bin/lahar" run case.yaml -o sp -q || fail "lahar run (spheropoly) failed"
unshare --user --map-root-user --net bash -c "
    ip link set lo up; ip link set lo multicast on; ip route add 224.0.0.0/4 dev lo
    '$bin/lahar-dem' --engine lammps --lcm-url '$URL' 2> dem.err & dem=\$!
    '$bin/lahar' run case.yaml -o lm -q --no-spawn --lcm-url '$URL'; echo \$? > coord_rc
    wait \$dem; echo \$? > dem_rc" || fail "could not make a private network namespace"
[ "$(cat coord_rc)" = 0 ] && [ "$(cat dem_rc)" = 0 ] || { cat dem.err; fail "run with lahar-dem --engine lammps: coordinator exit $(cat coord_rc), lahar-dem exit $(cat dem_rc)"; }
"$py" - <<'PY'
import json, sys, h5py, numpy as np
s = json.load(open("lm/summary.json"))
detail = s["nodes"]["dem"]["engine_detail"]
if not detail.startswith("lammps"):
    print("FAIL: lahar-dem --engine lammps ran", detail); sys.exit(1)
a = h5py.File("lm/bodies.h5", "r")["snapshots"]
b = h5py.File("sp/bodies.h5", "r")["snapshots"]
keys = sorted(a.keys())
assert keys == sorted(b.keys()) and len(keys) == 51
z = [a[k]["position"][0][2] for k in keys]
worst = max(float(np.abs(a[k]["position"][0] - b[k]["position"][0]).max()) for k in keys)
bounced = min(z) < 0.0701 and z[-1] > min(z)
print("engine_detail: %s; lowest centre %.4f m; max |z_lammps - z_spheropoly| = %.3g m (tolerance 1e-9)" % (detail, min(z), worst))
sys.exit(0 if worst <= 1e-9 and bounced else 1)
PY
