#!/bin/sh
# granular_impact_3d variants for ctest: copies CASE with case keys changed (tools/case_override.py
# PATH=VALUE, plus theta=DEG for the slope: gravity = 9.81 (sin, 0, -cos), the chute's frame, see
# the case) and runs tests/validation_check.sh on the copy with the arguments after `--` (dx=,
# end=, threads=, NAME<=V ...). The bounds are the case's.
# With EXPECT_FAIL=METRIC the check must run to the end and fail (exit 1) on METRIC: the test that
# shows a metric catches broken physics (e.g. no bed friction).
# usage: impact_check.sh LAHAR CASE OUT [theta=DEG] [PATH=VALUE ...] -- [validation_check.sh args]
set -u
[ $# -ge 3 ] || { echo "usage: $0 LAHAR CASE OUT [theta=DEG] [PATH=VALUE ...] -- [args]" >&2; exit 2; }
lahar=$1 case=$2 out=$3
shift 3
here=$(dirname "$0")
mkdir -p "$out" || exit 2
set -- "$@" "--end--"
over=""
while [ "$1" != "--" ] && [ "$1" != "--end--" ]; do
    case $1 in
        theta=*) g=$(awk -v t="${1#theta=}" 'BEGIN { r = t * atan2(0, -1) / 180
                                                   printf "[%.6f,0,%.6f]", 9.81 * sin(r), -9.81 * cos(r) }')
                 over="$over gravity=$g" ;;
        *) over="$over $1" ;;
    esac
    shift
done
[ "$1" = "--" ] && shift
# shellcheck disable=SC2086
python3 "$here/../tools/case_override.py" "$case" "$out/variant.yaml" $over || exit 2
args=""
while [ "$1" != "--end--" ]; do args="$args $1"; shift; done
# shellcheck disable=SC2086
sh "$here/validation_check.sh" "$lahar" "$out/variant.yaml" "$out" $args
rc=$?
[ -z "${EXPECT_FAIL:-}" ] && exit $rc
[ $rc -eq 1 ] || { echo "impact_check: expected the check to fail on $EXPECT_FAIL (exit 1), got exit $rc"; exit 1; }
python3 - "$out/run/check.json" "$EXPECT_FAIL" <<'PY'
import json, sys
chk = json.load(open(sys.argv[1]))
m = chk["metrics"].get(sys.argv[2])
ok = m is not None and not m["pass"]
print("impact_check: %s = %s (bound %s) %s" % (sys.argv[2], m and m["value"], m and m["bound"],
      "fails as expected" if ok else "did NOT fail"))
sys.exit(0 if ok else 1)
PY
