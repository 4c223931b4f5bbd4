#!/bin/sh
# Trackers, control volumes and body energies across `lahar resume`: gauges_uniform_2d.yaml with
# checkpoints run to 0.05 s and resumed to 0.08 s must write gauges.h5 and forces.h5 bitwise as
# one run to 0.08 s (the tracker's particle id comes back from the checkpoint).
# usage: resume_check.sh LAHAR PYTHON SRC_DIR OUT
set -eu
lahar=$1 py=$2 src=$3 out=$4
rm -rf "$out" && mkdir -p "$out"
sed 's/^time: {end: 0.05, \(.*\)}$/time: {end: 0.05, \1}\ncheckpoint: {interval: 0.02}/' \
    "$src/tests/terrain/gauges_uniform_2d.yaml" > "$out/a.yaml"
grep -q '^checkpoint:' "$out/a.yaml"
sed 's/^time: {end: 0.05,/time: {end: 0.08,/' "$out/a.yaml" > "$out/b.yaml"
"$lahar" run "$out/a.yaml" -o "$out/a" --in-process -q
"$lahar" resume "$out/a" --time-end 0.08 --in-process -q
"$lahar" run "$out/b.yaml" -o "$out/b" --in-process -q
"$py" "$src/tools/h5_compare.py" "$out/a/gauges.h5" "$out/b/gauges.h5"
"$py" "$src/tools/h5_compare.py" "$out/a/forces.h5" "$out/b/forces.h5"
