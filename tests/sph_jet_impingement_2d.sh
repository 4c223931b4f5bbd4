#!/bin/sh
# cases/jet_impingement_2d.yaml against the free-streamline jet on a wall (tools/compare_jet.py),
# at dx 2 mm and at the case's 1 mm (b/dx = 10 and 20), each on one thread:
#   - the force on the plate within 5 % / 4 % of the momentum flux rho U^2 b (measured +1.5 / +1.4 %);
#   - the mean pressure of every probe (17, from -2 b to 2 b) within 18 % / 9 % of rho U^2 / 2 of
#     the reference (measured: largest -13.2 / -6.5 %, at the stagnation point);
#   - the stagnation point's deficit falls with dx at an observed order in [0.5, 1.6] (measured 1.0).
# Measured values: docs/bench/jet_impingement.md.
# usage: sph_jet_impingement_2d.sh LAHAR SRC_DIR OUT_DIR PYTHON
set -u
lahar=$1 src=$2 out=$3 py=$4
fail() { echo "sph_jet_impingement_2d: $*" >&2; exit 1; }
rm -rf "$out" && mkdir -p "$out"
check="$src/tests/experiment_check.py"
case="$src/cases/jet_impingement_2d.yaml"
"$py" "$check" "$lahar" "$out/dx2" "$case" compare_jet.py sph.dx=0.002 'sph.blocks.jet.box.hi=[0.002,0.01]' \
  -- --pressure-tol 0.18 --force-tol 0.05 || fail "dx 2 mm outside its bounds"
"$py" "$check" "$lahar" "$out/dx1" "$case" compare_jet.py -- --pressure-tol 0.09 --force-tol 0.04 ||
  fail "dx 1 mm outside its bounds"
"$py" - "$out/dx2/jet.json" "$out/dx1/jet.json" <<'PY' || fail "the stagnation deficit does not converge"
import json, math, sys
coarse, fine = (json.load(open(p)) for p in sys.argv[1:3])
assert abs(coarse["dx"] / fine["dx"] - 2) < 1e-9, (coarse["dx"], fine["dx"])
e2, e1 = abs(coarse["stagnation"]["rel"]), abs(fine["stagnation"]["rel"])
order = math.log(e2 / e1, 2)
print("stagnation deficit %.1f %% at dx %g m, %.1f %% at dx %g m: order %.2f"
      % (100 * e2, coarse["dx"], 100 * e1, fine["dx"], order))
assert 0.5 <= order <= 1.6, order
PY
echo "sph_jet_impingement_2d: ok"
