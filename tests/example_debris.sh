#!/bin/sh
# The README's default example (cases/debris_2d.yaml) end to end at a shorter end time: the
# surge reaches the check dam at 0.6 s, so 0.95 s covers its arrival, the impact (0.1 s) and the
# quasi-steady window after it (0.2 s).
# Passes when
#   - `lahar check` runs it and exits 0: the case's own bounds hold (no fluid particle inside a
#     body, boulders included, or out of the channel; particle count constant);
#   - tests/example_debris_check.py holds: no boulder through the bed, barrier or walls; the
#     barrier's force in forces.h5 becomes positive (downstream) when the water arrives; its mean
#     over the quasi-steady window is within a factor 2 of rho u^2 h + rho g h_b^2 / 2 (reasoning there);
#   - tools/plot_snapshot.py writes a PNG of a snapshot.
# usage: example_debris.sh LAHAR CASE OUT PYTHON
set -u
[ $# -eq 4 ] || { echo "usage: $0 LAHAR CASE OUT PYTHON" >&2; exit 2; }
lahar=$1 case=$2 out=$3 py=$4
here=$(cd "$(dirname "$0")" && pwd)
rm -rf "$out" && mkdir -p "$out" || exit 2
# a copy of the case with time.end = 0.95 (tools/case_override.py)
"$py" "$here/../tools/case_override.py" "$case" "$out/case.yaml" time.end=0.95 ||
    { echo "example_debris: cannot set time.end in $case" >&2; exit 2; }
start=$(date +%s)
"$lahar" check "$out/case.yaml" -o "$out/run" --in-process -q --overwrite
rc=$?
echo "example_debris: lahar check exit $rc, $(( $(date +%s) - start )) s wall"
[ $rc -eq 0 ] || { cat "$out/run/check.json" 2>/dev/null; exit 1; }
"$py" "$here/example_debris_check.py" "$out/run" || exit 1
rm -f "$out/snap.png"
"$py" "$here/../tools/plot_snapshot.py" "$out/run" --time 0.5 -o "$out/snap.png" || exit 1
# a PNG: the 8-byte signature and more than a header
[ "$(head -c 8 "$out/snap.png" | od -An -tx1 | tr -d ' \n')" = "89504e470d0a1a0a" ] &&
    [ "$(wc -c < "$out/snap.png")" -gt 10000 ] || { echo "example_debris: $out/snap.png is not a PNG of a scene"; exit 1; }
echo "example_debris: $out/snap.png written"
