#!/bin/sh
# The sphere fast path against LAMMPS on the same settled pile (a correctness check, not a time
# check): settles a small pile of spheres with LAMMPS (tests/bench/lammps/in.settle3d, the input of
# the project's LAMMPS speed reference) into OUT, then bench_dem --lammps-data runs lahar and
# LAMMPS (library) on it and fails unless the sphere-sphere contact counts agree within 2 % and the
# kinetic energies after the warm-up and at the end within a factor 1.1 (the dashpots differ in
# form, bench_lammps.c). Skips (77) without the `lmp` program or a bench_dem built with liblammps.
# usage: dem_lammps_check.sh BENCH_DEM OUT [nx nz]
set -u
[ $# -ge 2 ] || { echo "usage: $0 BENCH_DEM OUT [nx nz]" >&2; exit 2; }
bench=$1 out=$2 nx=${3:-8} nz=${4:-8}
here=$(cd "$(dirname "$0")" && pwd)
command -v lmp >/dev/null 2>&1 || { echo "dem_lammps_check: no lmp (Debian package lammps): skipped"; exit 77; }
mkdir -p "$out" || exit 2
cd "$out" || exit 2
data=settled3d_${nx}_${nz}.data
if [ ! -s "$data" ]; then
    lmp -in "$here/bench/lammps/in.settle3d" -var nx "$nx" -var nz "$nz" -var nsettle 15000 -log settle.log \
        -screen none || { echo "dem_lammps_check: LAMMPS failed to settle the pile (see $out/settle.log)"; exit 2; }
fi
"$bench" --lammps-data "$data" --warm-steps 1000 --steps 2000 --threads 2 --check-contacts 0.02 --check-ke 1.1 > bench.txt 2>&1
rc=$?
cat bench.txt
grep -q "LAMMPS comparison not built" bench.txt && { echo "dem_lammps_check: bench_dem without liblammps: skipped"; exit 77; }
exit $rc
