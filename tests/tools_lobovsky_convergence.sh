#!/bin/sh
# tools/plot_lobovsky_convergence.py on the two Lobovsky ctests' runs (delta-SPH and Riemann at
# dx 10 mm, each already compared by compare_lobovsky.py): a table row per run whose dx, impact
# time, peaks and 10 ms means of sensors 1-3, sensor 2's verdicts against the spread and its RMS
# distance from it / share inside are those of that run's lobovsky.json, a PNG; a JSON of an older compare_lobovsky (no
# rms_outside, no *_rel_outside) gives the same note against the spread and "-" for the series; exit
# 2 with a message on a run without lobovsky.json, an argument that is not LABEL=RUN, a LABEL with
# no RUN, runs compared with different windows, and a PNG in a directory that does not exist.
# usage: tools_lobovsky_convergence.sh SRC_DIR IMPACT_DIR OUT_DIR PYTHON
set -u
src=$1 runs=$2 out=$3 py=$4
fail() { echo "tools_lobovsky_convergence: $*" >&2; exit 1; }
mkdir -p "$out"
tool="$src/tools/plot_lobovsky_convergence.py"
. "$src/tests/tools_test_lib.sh"  # row, bad

"$py" "$tool" "$out/conv.png" "delta=$runs/lobovsky_2d/lobovsky.json" "riemann=$runs/lobovsky_2d_riemann/lobovsky.json" > "$out/conv.md" ||
  fail "exit $? on the two runs"
cat "$out/conv.md"
[ -s "$out/conv.png" ] || fail "no PNG"
for s in delta:lobovsky_2d riemann:lobovsky_2d_riemann; do
  label=${s%%:*} run=${s#*:}
  # dx | impact | peaks | means | sensor 2's peak and mean against the spread (from compare_lobovsky's
  # own verdicts, *_inside and *_rel_outside; the tool derives them from the values) | series
  want=$("$py" -c 'import json, sys
m = json.load(open(sys.argv[1])); s = m["sensors"]; sp = s["sensor2"]["spread"]
note = lambda q: "inside" if sp[q + "_inside"] else "x%.2f of the top" % (s["sensor2"][q] / sp["p97.5"][q]) \
    if sp[q + "_rel_outside"] > 0 else "%+.1f %%" % (100 * sp[q + "_rel_outside"])
print("%g|%.3f (%+.1f %%)|%s|%s|%s|%s|%.3f / %.0f %%" % (1e3 * m["dx"], m["rise"]["run"], 100 * m["rise"]["rel"],
      " / ".join("%.2f" % s[n]["peak"] for n in ("sensor1", "sensor2", "sensor3")),
      " / ".join("%.2f" % s[n]["peak_mean"] for n in ("sensor1", "sensor2", "sensor3")),
      note("peak"), note("peak_mean"), sp["rms_outside"], 100 * sp["inside_fraction"]))' "$runs/$run/lobovsky.json") ||
    fail "cannot read $run's lobovsky.json"
  got=$(row "$label" "$out/conv.md")
  [ "$got" = "$want" ] || fail "$label: the table's row '$got', lobovsky.json's '$want'"
done

# the JSON of an older compare_lobovsky: the notes against the spread from the values, no series cell
"$py" -c 'import json, sys
m = json.load(open(sys.argv[1])); sp = m["sensors"]["sensor2"]["spread"]
for k in ("rms_outside", "inside_fraction", "peak_rel_outside", "peak_mean_rel_outside", "peak_inside", "peak_mean_inside"):
    del sp[k]
json.dump(m, open(sys.argv[2], "w"))' "$runs/lobovsky_2d/lobovsky.json" "$out/old.json" || fail "cannot write old.json"
"$py" "$tool" "$out/old.png" "delta=$runs/lobovsky_2d/lobovsky.json" "old=$out/old.json" > "$out/old.md" ||
  fail "exit $? on an older lobovsky.json"
new=$(row delta "$out/old.md" | cut -d'|' -f5,6) old=$(row old "$out/old.md" | cut -d'|' -f5,6,7)
[ "$old" = "$new|-" ] || fail "older lobovsky.json: notes '$old', expected '$new|-'"

# bad input: exit 2 and a message saying what is wrong
bad no_json "no readable lobovsky.json" "$out/x.png" "a=$out/nothing"
bad no_label "expected LABEL=RUN" "$out/x.png" "$runs/lobovsky_2d/lobovsky.json"
bad no_run "expected LABEL=RUN" "$out/x.png" "a=,"
"$py" -c 'import json, sys
m = json.load(open(sys.argv[1])); m["window_ms"] = 5.0; json.dump(m, open(sys.argv[2], "w"))' \
  "$runs/lobovsky_2d/lobovsky.json" "$out/w5.json" || fail "cannot write w5.json"
bad windows "different --window" "$out/x.png" "a=$runs/lobovsky_2d/lobovsky.json,$out/w5.json"
bad png_dir "does not exist" "$out/nowhere/x.png" "a=$runs/lobovsky_2d/lobovsky.json"
echo "tools_lobovsky_convergence: ok"
