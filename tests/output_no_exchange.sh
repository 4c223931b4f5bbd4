#!/bin/sh
# On a file system that cannot swap two names (renameat2 RENAME_EXCHANGE fails: simulated by the
# LD_PRELOAD shim tests/renameat2_unsupported.c) the snapshot writers fall back to writing in
# place: the run finishes, says so once per file, leaves no twin, and its bodies.h5, particles.h5
# and contacts.h5 are bitwise those of a run on a file system with the exchange. With
# `output: {twins: false}` (carried to the nodes in the scene message) they write in place from
# the start: under the same shim, no note (no exchange is ever tried), and the same bytes.
#   output_no_exchange.sh LAHAR SHIM SOURCE_DIR WORK PYTHON
set -u
lahar=$1 shim=$2 src=$3 work=$4 python=$5
fail() { echo "FAIL: $*" >&2; exit 1; }
rm -rf "$work" && mkdir -p "$work" && cd "$work" || exit 2
"$python" "$src/tools/case_override.py" "$src/cases/debris_2d.yaml" case.yaml time.end=0.02 time.output_interval=0.005 ||
    fail "cannot write the case"
"$python" "$src/tools/case_override.py" case.yaml in_place.yaml output.twins=false || fail "cannot write the case"
"$lahar" run case.yaml -o ref -q --in-process || fail "the reference run failed"
LD_PRELOAD=$shim "$lahar" run case.yaml -o fb -q --in-process 2> fb.stderr || { cat fb.stderr; fail "the run without the exchange failed"; }
cat fb.stderr
for f in bodies.h5 particles.h5 contacts.h5; do
    [ "$(grep -c "fb/$f: this file system cannot swap two files in one step" fb.stderr)" -eq 1 ] ||
        fail "no single note for $f"
    [ ! -e "fb/.$f.twin" ] || fail "fb/.$f.twin is left"
    "$python" "$src/tools/h5_compare.py" --quiet "ref/$f" "fb/$f" || fail "fb/$f differs from ref/$f"
done
# output.twins: false, as processes (the nodes learn it from the scene message)
LD_PRELOAD=$shim "$lahar" run in_place.yaml -o ip -q 2> ip.stderr || { cat ip.stderr; fail "the run with twins: false failed"; }
! grep -q "cannot swap two files" ip.stderr || { cat ip.stderr; fail "twins: false still tried the exchange"; }
for f in bodies.h5 particles.h5 contacts.h5; do
    "$python" "$src/tools/h5_compare.py" --quiet "ref/$f" "ip/$f" || fail "ip/$f (twins: false) differs from ref/$f"
done
echo "output_no_exchange: written in place after one note per file, bitwise those of the run with the exchange; twins: false writes in place from the start"
