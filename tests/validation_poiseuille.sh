#!/bin/sh
# Issue 3, Poiseuille flow (Trujillo-Vela et al. 2020 section 5.1): `lahar check` on cases/poiseuille_2d.yaml with
# 20 particles across H (the case, dx = 5 mm) and with 40 (dx = 2.5 mm); passes when both runs meet
# the case's bounds (steady L2 <= 1 %, plate force <= 1 %), the 40-across run meets the issue's
# steady L2 <= 0.5 %, and both errors fall from 20 to 40 across.
# usage: validation_poiseuille.sh LAHAR CASE OUT
set -u
here=$(dirname "$0")
lahar=$1 case=$2 out=$3
"$here/validation_check.sh" "$lahar" "$case" "$out/n20" dx=0.005 || exit 1
"$here/validation_check.sh" "$lahar" "$case" "$out/n40" dx=0.0025 || exit 1
python3 - "$out/n20/run/check.json" "$out/n40/run/check.json" <<'PY'
import json, sys
m20, m40 = (json.load(open(f))["metrics"] for f in sys.argv[1:3])
e = {k: (m20[k]["value"], m40[k]["value"]) for k in ("steady_l2_rel_error", "plate_force_rel_error")}
ok = e["steady_l2_rel_error"][1] <= 0.005
print("40 across: steady_l2_rel_error = %.4g (issue bound 0.005) %s" % (e["steady_l2_rel_error"][1], "pass" if ok else "FAIL"))
for k, (a, b) in e.items():
    print("%s: %.4g (20 across) -> %.4g (40 across) %s" % (k, a, b, "falls" if b < a else "does NOT fall"))
    ok = ok and b < a
sys.exit(0 if ok else 1)
PY
