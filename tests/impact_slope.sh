#!/bin/sh
# granular_impact_3d at another slope: copies the case with gravity = 9.81 (sin theta, 0, -cos theta)
# (tools/case_override.py; the chute's frame, see the case) and runs tests/validation_check.sh on
# the copy with the remaining arguments (dx=, end=, threads=, NAME<=V ...). The bounds are the case's.
# usage: impact_slope.sh LAHAR CASE OUT THETA_DEG [validation_check.sh overrides ...]
set -u
[ $# -ge 4 ] || { echo "usage: $0 LAHAR CASE OUT THETA_DEG [overrides ...]" >&2; exit 2; }
lahar=$1 case=$2 out=$3 theta=$4
shift 4
here=$(dirname "$0")
mkdir -p "$out" || exit 2
g=$(awk -v t="$theta" 'BEGIN { r = t * atan2(0, -1) / 180; printf "[%.6f,0,%.6f]", 9.81 * sin(r), -9.81 * cos(r) }')
python3 "$here/../tools/case_override.py" "$case" "$out/slope.yaml" "gravity=$g" || exit 2
exec sh "$here/validation_check.sh" "$lahar" "$out/slope.yaml" "$out" "$@"
