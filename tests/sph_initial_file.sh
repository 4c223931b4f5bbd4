#!/bin/sh
# Initial fields from an HDF5 file (block key initial: {file: F.h5}) against the same fields as
# expressions: cases/taylor_green_2d.yaml at 25 x 25 for 0.04 s, once with its velocity:/pressure:
# expressions, once with vx, vy, pressure written by h5py in lattice order (x outermost). The first
# snapshot must agree to 1e-12 (libm against numpy cosines) and the third to 1e-10.
# usage: sph_initial_file.sh LAHAR CASE OUT PYTHON
set -u
lahar=$1 case=$2 out=$3 py=$4
tools=$(dirname "$0")/../tools
mkdir -p "$out" || exit 2
"$py" - "$out/tg25.h5" <<'PY' || exit 2
import sys, h5py, numpy as np
n = 25; c = (np.arange(n) + 0.5) / n
X, Y = np.meshgrid(c, c, indexing="ij"); X = X.ravel(); Y = Y.ravel()
with h5py.File(sys.argv[1], "w") as f:
    f["vx"] = -np.cos(2 * np.pi * X) * np.sin(2 * np.pi * Y)
    f["vy"] = np.sin(2 * np.pi * X) * np.cos(2 * np.pi * Y)
    f["pressure"] = -0.25 * (np.cos(4 * np.pi * X) + np.cos(4 * np.pi * Y))
PY
"$py" "$tools/case_override.py" "$case" "$out/expr.yaml" sph.dx=0.04 time.end=0.04 >/dev/null || exit 2
"$py" "$tools/case_override.py" "$out/expr.yaml" "$out/file.yaml" "sph.blocks.0.velocity=~" "sph.blocks.0.pressure=~" \
    "sph.blocks.0.initial={file: $out/tg25.h5}" >/dev/null || exit 2
for v in expr file; do
    "$lahar" run "$out/$v.yaml" -o "$out/$v" --in-process -q --threads 1 --overwrite || exit 1
done
"$py" - "$out/expr/particles.h5" "$out/file/particles.h5" <<'PY'
import sys, h5py, numpy as np
a = h5py.File(sys.argv[1], "r")["snapshots"]; b = h5py.File(sys.argv[2], "r")["snapshots"]
bad = 0
for k, tol in (("000000", 1e-12), ("000002", 1e-10)):
    for d in ("x", "y", "vx", "vy", "density"):
        e = float(np.abs(a[k][d][:] - b[k][d][:]).max())
        print("snapshot %s %-8s max |expr - file| = %.3g (tolerance %g)" % (k, d, e, tol))
        bad |= not e <= tol
sys.exit(1 if bad else 0)
PY
