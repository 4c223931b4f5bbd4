#!/bin/sh
# tools/plot_lobovsky_convergence.py on the two Lobovsky ctests' runs (delta-SPH and Riemann at
# dx 10 mm, each already compared by compare_lobovsky.py): a table row per run whose sensor 2 peak
# is the one in that run's lobovsky.json, a PNG, and exit 2 with a message on a run without
# lobovsky.json and on an argument that is not LABEL=RUN.
# usage: tools_lobovsky_convergence.sh SRC_DIR IMPACT_DIR OUT_DIR PYTHON
set -u
src=$1 runs=$2 out=$3 py=$4
fail() { echo "tools_lobovsky_convergence: $*" >&2; exit 1; }
mkdir -p "$out"
tool="$src/tools/plot_lobovsky_convergence.py"
"$py" "$tool" "$out/conv.png" "delta=$runs/lobovsky_2d/lobovsky.json" "riemann=$runs/lobovsky_2d_riemann/lobovsky.json" > "$out/conv.md" ||
  fail "exit $? on the two runs"
cat "$out/conv.md"
[ -s "$out/conv.png" ] || fail "no PNG"
for s in delta:lobovsky_2d riemann:lobovsky_2d_riemann; do
  label=${s%%:*} run=${s#*:}
  want=$("$py" -c 'import json,sys; print("%.2f" % json.load(open(sys.argv[1]))["sensors"]["sensor2"]["peak"])' \
         "$runs/$run/lobovsky.json") || fail "cannot read $run's lobovsky.json"
  # the row: | label | dx | impact | s1 / s2 / s3 peaks | ...
  got=$(awk -F'|' -v l=" $label " '$2 == l { split($5, p, " / "); gsub(/ /, "", p[2]); print p[2] }' "$out/conv.md")
  [ "$got" = "$want" ] || fail "$label: sensor 2 peak in the table '$got', in lobovsky.json $want"
done
"$py" "$tool" "$out/x.png" "a=$out/nothing" 2> "$out/err1"
rc=$?
[ $rc -eq 2 ] && grep -q "no readable lobovsky.json" "$out/err1" || fail "run without lobovsky.json: exit $rc, $(cat "$out/err1")"
"$py" "$tool" "$out/x.png" "$runs/lobovsky_2d/lobovsky.json" 2> "$out/err2"
rc=$?
[ $rc -eq 2 ] && grep -q "expected LABEL=RUN" "$out/err2" || fail "argument without LABEL=: exit $rc, $(cat "$out/err2")"
echo "tools_lobovsky_convergence: ok"
