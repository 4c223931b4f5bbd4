# Helpers of the tests of tools/*.py (sourced by tests/tools_*.sh, which set py, tool and out and
# define fail() first).

# row LABEL FILE: the cells after the label of LABEL's row in the Markdown table FILE, '|'-separated
row() { awk -F'|' -v l="$1" '{ for (i = 2; i < NF; i++) { gsub(/^ +| +$/, "", $i) } }
  $2 == l { s = $3; for (i = 4; i < NF; i++) s = s "|" $i; print s }' "$2"; }

# bad NAME MESSAGE ARGS...: the tool on ARGS exits 2 with MESSAGE on stderr (kept in $out/NAME.err)
bad() {
  name=$1 msg=$2; shift 2
  "$py" "$tool" "$@" > /dev/null 2> "$out/$name.err"
  rc=$?
  [ $rc -eq 2 ] && grep -q "$msg" "$out/$name.err" || fail "$name: exit $rc, $(cat "$out/$name.err")"
}
