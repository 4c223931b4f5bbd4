#!/bin/sh
# Runs `lahar check` on a validation case at a CI resolution: copies CASE to OUT/case.yaml with the
# overrides applied (the case's check: bounds are left as they are), runs the check in-process and
# exits with its status (0 = every metric within its bound). The main cases stay the single source
# of the set-up; only the resolution, the duration and the cylinder radius change.
# After a passing run, `lahar check --evaluate-only` on OUT/run must write the same check.json.
# usage: validation_check.sh LAHAR CASE OUT [dx=M] [end=S] [layers=N] [c=SOLID_FRACTION] [threads=N] [paraview=1]
#   dx=M   sph.dx (particle spacing)             end=S  time.end
#   layers=N  sph.body_layers (the case must set the key; particle layers fitted to a sphere or disc)
#   c=F    cylinder_array: disc radius r = L sqrt(F / pi); sphere_array (a body `name: sphere`):
#          sphere radius a = L (3 F / (4 pi))^(1/3); L = 0.2 m (the cases' cell)
#   bound.NAME=V  the case's check: bound of metric NAME becomes V in the copy, for a metric the
#          solver does not yet meet at the issue's bound: the test then guards what holds
#          (say why next to the test and in cases/README.md)
#   NAME<=V, NAME>=V  also: the value NAME of check.json (a metric or an information value)
#          within that bound, for what the issue asks beyond the case's metrics (a disc that
#          "moves, rotates and stops" has lower bounds, which check: metrics cannot state)
#   paraview=1  also: OUT/run/lahar.xmf shows particles and bodies together and every *.xmf
#          names datasets that exist with their declared shapes (tests/test_output_xdmf.py)
set -u
[ $# -ge 3 ] || { echo "usage: $0 LAHAR CASE OUT [dx=M] [end=S] [layers=N] [c=F] [threads=N] [paraview=1]" >&2; exit 2; }
lahar=$1 case=$2 out=$3
shift 3
# an OUT such as "dx=0.004" is an option given in OUT's place: refuse it rather than create a
# directory of that name wherever the script was started
case $out in
    *=*) echo "validation_check: OUT '$out' looks like an option; usage: $0 LAHAR CASE OUT [options]" >&2; exit 2 ;;
esac
[ -f "$case" ] || { echo "validation_check: case file '$case' not found" >&2; exit 2; }
mkdir -p "$out" || exit 2
py=${LAHAR_PYTHON:-python3}
tools=$(cd "$(dirname "$0")/../tools" && pwd)
threads="" paraview="" asserts="" overrides=""
for kv in "$@"; do
    case $kv in
        *'<='*|*'>='*) asserts="$asserts $kv"; continue ;;
    esac
    k=${kv%%=*} v=${kv#*=}
    case $k in
        dx) overrides="$overrides sph.dx=$v" ;;
        layers) grep -qE "^  body_layers:" "$case" && overrides="$overrides sph.body_layers=$v" ;;
        end) overrides="$overrides time.end=$v" ;;
        c) if grep -qE "name: sphere,.*shape: sphere" "$case"; then
               r=$(awk -v c="$v" 'BEGIN { printf "%.7f", 0.2 * (3 * c / (4 * atan2(0, -1)))^(1 / 3) }')
               overrides="$overrides bodies.sphere.radius=$r"
           else
               r=$(awk -v c="$v" 'BEGIN { printf "%.7f", 0.2 * sqrt(c / atan2(0, -1)) }')
               overrides="$overrides bodies.cylinder.radius=$r"
           fi ;;
        bound.*) overrides="$overrides check.metrics.${k#bound.}=$v" ;;
        threads) threads="--threads $v"; true ;;
        paraview) paraview=$v; true ;;
        *) false ;;
    esac || { echo "validation_check: cannot apply $kv to $case" >&2; exit 2; }
done
# the one way to make a variant of a case (tools/case_override.py): it names the original and
# the overrides in the copy's first line
# shellcheck disable=SC2086
"$py" "$tools/case_override.py" "$case" "$out/case.yaml" $overrides ||
    { echo "validation_check: cannot apply$overrides to $case" >&2; exit 2; }
start=$(date +%s)
# shellcheck disable=SC2086
"$lahar" check "$out/case.yaml" -o "$out/run" --in-process -q --overwrite $threads
rc=$?
echo "validation_check: $(basename "$case") $* -> exit $rc, $(( $(date +%s) - start )) s wall"
if [ $rc -eq 0 ]; then
    # `lahar check --evaluate-only` on the same output must give the same check.json
    cp "$out/run/check.json" "$out/check.run.json" &&
        "$lahar" check "$out/case.yaml" -o "$out/run" --evaluate-only -q > "$out/evaluate.log" 2>&1 &&
        cmp -s "$out/run/check.json" "$out/check.run.json" ||
        { echo "validation_check: lahar check --evaluate-only did not reproduce check.json (see $out/evaluate.log)"; exit 1; }
fi
if [ $rc -eq 0 ] && [ -n "$paraview" ]; then
    grep -q "particles.h5:" "$out/run/lahar.xmf" && grep -q "bodies.h5:" "$out/run/lahar.xmf" ||
        { echo "validation_check: $out/run/lahar.xmf does not show both particles and bodies"; exit 1; }
    "$py" "$(dirname "$0")/test_output_xdmf.py" "$out/run" || exit 1
fi
if [ $rc -eq 0 ] && [ -n "$asserts" ]; then
    # shellcheck disable=SC2086
    "$py" - "$out/run/check.json" $asserts <<'PY' || exit 1
import json, re, sys
chk = json.load(open(sys.argv[1]))
values = {k: v["value"] for k, v in chk["metrics"].items()}
values.update({k: v for k, v in chk["info"].items() if isinstance(v, (int, float))})
ok = True
for a in sys.argv[2:]:
    name, op, bound = re.fullmatch(r"(\w+)(<=|>=)(.+)", a).groups()
    v = values.get(name)
    good = v is not None and (v <= float(bound) if op == "<=" else v >= float(bound))
    print("validation_check: %s = %s (%s %s) %s" % (name, v, op, bound, "pass" if good else "FAIL"))
    ok = ok and good
sys.exit(0 if ok else 1)
PY
fi
exit $rc
