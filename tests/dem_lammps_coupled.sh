#!/bin/sh
# A coupled SPH-DEM run with the LAMMPS engine through `lahar run` (processes in the run's own
# private network namespace), against the same case with the spheropoly engine: a steel disc
# (2D) dropped into a water tank, sinking under the fluid's loads and settling on the floor.
#
# Passes when both runs finish (exit 0) and the discs' trajectories (every snapshot) agree within
# TOL = 1e-5 m. Why that tolerance: the engines share the contact law (dem_contact.c), the
# integrator (velocity Verlet, loads constant over the coupling step) and the substep rule, and
# test_dem_lammps shows them equal to round-off under fluid loads and in normal impacts. What
# differs is the lever arm of wall contact torques (LAMMPS: r, spheropoly: r - delta/2, here
# delta/2r ~ 1e-3 for a disc resting with delta = m g / kn) and the spring kept on Coulomb slip
# (README.md of the engine), both acting only once the disc touches the floor at the end; measured
# 6e-8 m. A broken load path moves the disc by far more: the previous step's load in the first
# half kick of a step turns the disc at half the rate and moves it 0.4 mm within 0.3 s.
# usage: dem_lammps_coupled.sh LAHAR OUT PYTHON
set -u
[ $# -eq 3 ] || { echo "usage: $0 LAHAR OUT PYTHON" >&2; exit 2; }
lahar=$1 out=$2 py=$3
rm -rf "$out" && mkdir -p "$out" || exit 2
for engine in lammps spheropoly; do
    cat > "$out/$engine.yaml" <<YAML
dimensions: 2
gravity: [0, -9.81]
time: {end: 1.0, dt_max: 1.0e-3, output_interval: 0.05}
materials:
  wall: {density: 2700, model: linear, kn: 1.0e6, restitution: 0.3, friction: 0.5}
  steel: {density: 7800, model: linear, kn: 1.0e6, restitution: 0.3, friction: 0.5}
dem: {engine: $engine}
bodies:
  - {name: floor, shape: segment, motion: fixed, material: wall, radius: 0.002, vertices: [[0.15, 0], [0, 0]]}
  - {name: wall_left, shape: segment, motion: fixed, material: wall, radius: 0.002, vertices: [[0, 0], [0, 0.25]]}
  - {name: wall_right, shape: segment, motion: fixed, material: wall, radius: 0.002, vertices: [[0.15, 0.25], [0.15, 0]]}
  - {name: disc, shape: disc, material: steel, radius: 0.0125, position: [0.05, 0.14]}
sph:
  dx: 0.005
  density: 1000
  viscosity: 2.0
  c0: 20
  blocks:
    - {name: water, box: {lo: [0, 0], hi: [0.15, 0.1]}}
YAML
    "$lahar" run "$out/$engine.yaml" -o "$out/$engine" -q --overwrite
    rc=$?
    [ $rc -eq 0 ] || { echo "FAIL: lahar run with dem.engine: $engine exited $rc" >&2; cat "$out/$engine/summary.json" >&2; exit 1; }
done
"$py" - "$out/lammps" "$out/spheropoly" <<'PY'
import sys, h5py, numpy as np
TOL = 1e-5
a = h5py.File(sys.argv[1] + "/bodies.h5", "r")["snapshots"]
b = h5py.File(sys.argv[2] + "/bodies.h5", "r")["snapshots"]
keys = sorted(a.keys())
assert keys == sorted(b.keys()) and len(keys) == 21, "snapshots differ: %s vs %s" % (len(keys), len(b.keys()))
worst = max(float(np.abs(a[k]["position"][3] - b[k]["position"][3]).max()) for k in keys)
y0, y1 = a[keys[0]]["position"][3][1], a[keys[-1]]["position"][3][1]
touched = int((h5py.File(sys.argv[1] + "/forces.h5", "r")["ncontacts"][:, 3] > 0).sum())
print("dem_lammps_coupled: disc sank %.4f m, %d steps in contact with the floor, max |x_lammps - x_spheropoly| = %.3g m (tolerance %g)" % (y0 - y1, touched, worst, TOL))
ok = worst <= TOL and y0 - y1 > 0.1 and touched > 0
print("ok" if ok else "FAIL")
sys.exit(0 if ok else 1)
PY
