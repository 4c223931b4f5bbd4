#!/bin/sh
# The impact tools on runs that end before the impact (a short first look at a case, the way a user
# tries a tool): plot_impact.py writes its table with first impact "none" (it raised a TypeError on
# first_impact_s = null), compare_spheric2.py exits 2 saying the water has not hit the box (it
# raised a ValueError on an empty array), compare_lobovsky.py --check fails on the impact time
# and reads "no value" against the spread (it printed nan), and plot_lobovsky_convergence.py's row
# says there is no impact; on a run that has not ended both compare tools exit 2 and say so.
# check.json and summary.json name the case by its absolute path.
# usage: tools_no_impact.sh LAHAR SRC_DIR OUT_DIR PYTHON
set -u
lahar=$1 src=$2 out=$3 py=$4
fail() { echo "tools_no_impact: $*" >&2; exit 1; }
mkdir -p "$out"
"$py" "$src/tools/case_override.py" "$src/cases/granular_impact_3d.yaml" "$out/gi.yaml" sph.dx=0.05 time.end=0.02 \
  time.output_interval=0.01 || fail "case_override granular_impact_3d"
(cd "$out" && "$lahar" check gi.yaml -o gi --in-process -q --overwrite --threads 1)
[ -f "$out/gi/check.json" ] || fail "lahar check wrote no check.json"
grep -q "\"case\":[[:space:]]*\"/" "$out/gi/check.json" || fail "check.json: \"case\" is not an absolute path"
"$py" "$src/tools/plot_impact.py" "$out/gi.png" "$out/gi" > "$out/gi.md" || fail "plot_impact.py failed on a run without impact"
grep -q '^| 45° | 0.05 | none |' "$out/gi.md" || { cat "$out/gi.md"; fail "plot_impact.py: no row with first impact 'none'"; }
[ -s "$out/gi.png" ] || fail "plot_impact.py wrote no PNG"

"$py" "$src/tools/case_override.py" "$src/cases/dam_break_obstacle_plane_2d.yaml" "$out/sp.yaml" sph.dx=0.04 \
  time.end=0.1 time.output_interval=0.05 || fail "case_override dam_break_obstacle_plane_2d"
# Run from OUT_DIR with the case named relative to it, the tools from elsewhere: they find the case
# through summary.json's absolute "case" (a relative one sent them looking in their own directory)
(cd "$out" && "$lahar" run sp.yaml -o sp --in-process -q --overwrite --threads 1) || fail "lahar run dam_break_obstacle_plane_2d"
grep -q "\"case\":[[:space:]]*\"/" "$out/sp/summary.json" || fail "summary.json: \"case\" is not an absolute path"
"$py" "$src/tools/compare_spheric2.py" "$out/sp" --no-plot 2> "$out/sp.err"
rc=$?
cat "$out/sp.err"
[ $rc -eq 2 ] || fail "compare_spheric2.py: exit $rc on a run without impact, expected 2"
grep -q "P1 never reaches" "$out/sp.err" || fail "compare_spheric2.py: no message saying why"

# a run that has not ended (lahar writes this summary.json when it starts; a killed run keeps it):
# both compare tools exit 2 saying so and how to go on (they raised a KeyError on "case")
mkdir -p "$out/sp_running" && cp "$out/sp/gauges.h5" "$out/sp_running/"
printf '{"status": "running", "message": "the run has not ended, or lahar was killed before it could write this summary"}\n' \
  > "$out/sp_running/summary.json"
for tool in compare_spheric2.py compare_lobovsky.py; do
  "$py" "$src/tools/$tool" "$out/sp_running" --no-plot 2> "$out/running.err"
  rc=$?
  cat "$out/running.err"
  [ $rc -eq 2 ] || fail "$tool: exit $rc on a run that has not ended, expected 2"
  grep -q "status running: .*lahar resume $out/sp_running" "$out/running.err" || fail "$tool: no message saying the run has not ended"
done

# compare_lobovsky.py --check on a run that ends before the water reaches the wall: exit 1 with
# the impact time among the failures and sensor 2 "no value" against the spread (NaN passed the
# impact-time test and read "outside by +0.0 %")
"$py" "$src/tools/case_override.py" "$src/cases/dam_break_lobovsky_2d.yaml" "$out/lb.yaml" sph.dx=0.02 \
  time.end=0.2 time.output_interval=0.1 || fail "case_override dam_break_lobovsky_2d"
(cd "$out" && "$lahar" run lb.yaml -o lb --in-process -q --overwrite --threads 1) || fail "lahar run dam_break_lobovsky_2d"
"$py" "$src/tools/compare_lobovsky.py" "$out/lb" --no-plot --check --spread-tol 0.05 > "$out/lb.txt" 2>&1
rc=$?
cat "$out/lb.txt"
[ $rc -eq 1 ] || fail "compare_lobovsky.py --check: exit $rc on a run without impact, expected 1"
grep -q "^FAIL: rise," "$out/lb.txt" || fail "compare_lobovsky.py: the impact time is not among the failures"
grep -q "10 ms mean 1.73-1.98 (1.86): no value" "$out/lb.txt" || fail "compare_lobovsky.py: sensor 2 not 'no value' against the spread"
grep -q "after the impact: no value" "$out/lb.txt" || fail "compare_lobovsky.py: sensor 2's series not 'no value' against the band"
# its lobovsky.json is strict JSON (null, not NaN, for the values the run has none of: jq and
# JavaScript reject NaN)
"$py" -c 'import json, sys
def bad(c): raise ValueError("non-standard constant " + c)
m = json.load(open(sys.argv[1]), parse_constant=bad)
assert m["rise"]["run"] is None, m["rise"]' "$out/lb/lobovsky.json" || fail "compare_lobovsky.py: lobovsky.json is not strict JSON with null for no value"
# plot_lobovsky_convergence.py on it: a row saying so, not "nan"
"$py" "$src/tools/plot_lobovsky_convergence.py" "$out/lbc.png" "delta=$out/lb" > "$out/lbc.md" || fail "plot_lobovsky_convergence.py: exit $?"
cat "$out/lbc.md"
grep -q '^| delta | 20 | none (no impact in the run) | .* | no value | no value | no value |$' "$out/lbc.md" ||
  fail "plot_lobovsky_convergence.py: no row saying the run has no impact"
echo "tools_no_impact: ok"
