#!/bin/sh
# tools/plot_spheric2_convergence.py: on the two SPHERIC Test 2 ctests' runs (3D at dx 40 mm, the
# centre plane at dx 5 mm, each already compared by compare_spheric2.py) a row per run whose
# impact, travel time, sustained loads and level distances are those of the run's spheric2.json
# ("none" for a load the run ended before), and with --peaks its P1 and P3 peaks and largest window
# means; on a synthetic series made from the plane's JSON
# (dx 20 / 15 / 10 mm, each quantity q* + C dx^p with known q* and p, the travel time not
# monotone) a "converged" row whose values are those q* and p, and "not monotone" for the travel
# time; "no order in 0.25-4" and "no value in a run" where a series shrinks too slowly or lacks a
# value; a PNG; exit 2 with a message on a run without spheric2.json, an argument that is not
# LABEL=RUN, two runs at one dx in a series and a PNG in a directory that does not exist.
# usage: tools_spheric2_convergence.sh SRC_DIR IMPACT_DIR OUT_DIR PYTHON
set -u
src=$1 runs=$2 out=$3 py=$4
fail() { echo "tools_spheric2_convergence: $*" >&2; exit 1; }
mkdir -p "$out"
tool="$src/tools/plot_spheric2_convergence.py"
. "$src/tests/tools_test_lib.sh"  # row, bad

"$py" "$tool" "$out/conv.png" "3D=$runs/spheric2_3d" "plane=$runs/spheric2_plane_2d/spheric2.json" > "$out/conv.md" ||
  fail "exit $? on the two runs"
cat "$out/conv.md"
[ -s "$out/conv.png" ] || fail "no PNG"
for s in 3D:spheric2_3d plane:spheric2_plane_2d; do
  label=${s%%:*} run=${s#*:}
  want=$("$py" -c 'import json, math, sys
m = json.load(open(sys.argv[1]))
def cell(v, e, scale, digits):
    return "none" if v is None else "%.*f (%+.1f %%)" % (digits, v * scale, 100 * (v / e - 1))
p = m["peaks"]
print("|".join(["%g" % (1e3 * m["dx"]), cell(m["impact"]["run"], m["impact"]["experiment"], 1, 4),
                cell(m["travel"]["run"], m["travel"]["experiment"], 1, 4),
                cell(p["P1"]["plateau"], p["P1"]["plateau_exp"], 1e-3, 2), cell(p["P3"]["plateau"], p["P3"]["plateau_exp"], 1e-3, 2),
                "%.0f / %.0f" % (1e3 * m["levels"]["H1"]["mean_abs_diff_m"], 1e3 * m["levels"]["H2"]["mean_abs_diff_m"])]))' \
    "$runs/$run/spheric2.json") || fail "cannot read $run's spheric2.json"
  got=$(row "$label" "$out/conv.md")
  [ "$got" = "$want" ] || fail "$label: the table's row '$got', spheric2.json's '$want'"
done

# --peaks: the same runs, a row per run whose P1 and P3 peaks and largest window means are those of
# its spheric2.json
"$py" "$tool" --peaks "$out/peaks.png" "3D=$runs/spheric2_3d" "plane=$runs/spheric2_plane_2d/spheric2.json" > "$out/peaks.md" ||
  fail "--peaks: exit $? on the two runs"
cat "$out/peaks.md"
[ -s "$out/peaks.png" ] || fail "--peaks: no PNG"
grep -q "P1 peak (one sample)" "$out/peaks.md" || fail "--peaks: no P1 peak column"
for s in 3D:spheric2_3d plane:spheric2_plane_2d; do
  label=${s%%:*} run=${s#*:}
  want=$("$py" -c 'import json, sys
m = json.load(open(sys.argv[1]))
cells = ["%g" % (1e3 * m["dx"])]
for n in ("P1", "P3"):
    for k in ("peak", "peak_mean"):
        v, e = m["peaks"][n][k], m["peaks"][n][k + "_exp"]
        cells.append("%.2f (%+.1f %%)" % (1e-3 * v, 100 * (v / e - 1)))
cells.append("%.0f / %.0f" % (1e3 * m["levels"]["H1"]["mean_abs_diff_m"], 1e3 * m["levels"]["H2"]["mean_abs_diff_m"]))
print("|".join(cells))' "$runs/$run/spheric2.json") || fail "cannot read $run's spheric2.json"
  got=$(row "$label" "$out/peaks.md")
  [ "$got" = "$want" ] || fail "--peaks: $label: the table's row '$got', spheric2.json's '$want'"
done

# a synthetic series: impact 0.9 x the experiment's + 2 dx (order 1), P1 0.9 x + 30 dx^0.8 kPa,
# P3 0.8 x - 900 dx^1.6 kPa, travel 0.27 / 0.26 / 0.265 s (not monotone)
"$py" -c 'import json, sys
m = json.load(open(sys.argv[1]))
for dx, travel in ((0.02, 0.27), (0.015, 0.26), (0.01, 0.265)):
    m["dx"] = dx
    m["impact"]["run"] = 0.9 * m["impact"]["experiment"] + 2.0 * dx
    m["travel"]["run"] = travel
    m["peaks"]["P1"]["plateau"] = 0.9 * m["peaks"]["P1"]["plateau_exp"] + 3e4 * dx ** 0.8
    m["peaks"]["P3"]["plateau"] = 0.8 * m["peaks"]["P3"]["plateau_exp"] - 9e5 * dx ** 1.6
    json.dump(m, open("%s/s%g.json" % (sys.argv[2], 1e3 * dx), "w"))' "$runs/spheric2_plane_2d/spheric2.json" "$out" ||
  fail "cannot write the synthetic series"
"$py" "$tool" "$out/syn.png" "syn=$out/s10.json,$out/s20.json,$out/s15.json" > "$out/syn.md" || fail "exit $? on the synthetic series"
cat "$out/syn.md"
want=$("$py" -c 'import json, sys
m = json.load(open(sys.argv[1])); p = m["peaks"]
print("dx 20, 15, 10 → 0|%.4f (-10.0 %%), order 1.00|not monotone|%.2f (-10.0 %%), order 0.80|%.2f (-20.0 %%), order 1.60|" % (
      0.9 * m["impact"]["experiment"], 0.9e-3 * p["P1"]["plateau_exp"], 0.8e-3 * p["P3"]["plateau_exp"]))' \
  "$runs/spheric2_plane_2d/spheric2.json") || fail "cannot read the plane's spheric2.json"
got=$(row "syn: converged" "$out/syn.md")
[ "$got" = "$want" ] || fail "synthetic series: converged row '$got', expected '$want'"
[ -s "$out/syn.png" ] || fail "synthetic series: no PNG"
[ "$(grep -c '^| syn | ' "$out/syn.md")" -eq 3 ] || fail "synthetic series: not one row per run"
[ -n "$(row syn "$out/syn.md" | head -1 | grep '^20|')" ] || fail "synthetic series: the coarsest run is not first"

# a series whose travel time shrinks too slowly for any order in 0.25-4 (0.270 / 0.264 / 0.256 s:
# differences 6 and 8 ms) and with no P1 load in its 15 mm run: the reasons, the rest as above
"$py" -c 'import json, sys
for dx, travel in ((20, 0.270), (15, 0.264), (10, 0.256)):
    m = json.load(open("%s/s%d.json" % (sys.argv[1], dx)))
    m["travel"]["run"] = travel
    if dx == 15:
        m["peaks"]["P1"]["plateau"] = None
    json.dump(m, open("%s/slow%d.json" % (sys.argv[1], dx), "w"))' "$out" || fail "cannot write the slow series"
"$py" "$tool" "$out/slow.png" "slow=$out/slow20.json,$out/slow15.json,$out/slow10.json" > "$out/slow.md" ||
  fail "exit $? on the slow series"
want=$(echo "$want" | awk -F'|' -v OFS='|' '{ $3 = "no order in 0.25-4 (difference ratio 0.75)"; $4 = "no value in a run"; print }')
got=$(row "slow: converged" "$out/slow.md")
[ "$got" = "$want" ] || fail "slow series: converged row '$got', expected '$want'"

# bad input: exit 2 and a message saying what is wrong
bad no_json "no readable spheric2.json" "$out/x.png" "a=$out/nothing"
echo '{"dx": 0.01, "rise": {}}' > "$out/other.json"
bad not_spheric "not the JSON of tools/compare_spheric2.py" "$out/x.png" "a=$out/other.json"
bad no_label "expected LABEL=RUN" "$out/x.png" "$runs/spheric2_3d"
bad no_run "expected LABEL=RUN" "$out/x.png" "a=,"
bad same_dx "two runs at the same dx" "$out/x.png" "a=$out/s10.json,$out/s10.json"
bad png_dir "does not exist" "$out/nowhere/x.png" "a=$runs/spheric2_3d"
echo "tools_spheric2_convergence: ok"
