#!/bin/sh
# Progress when stderr is not a terminal (a log file, a pipe, a batch job; coordinator/run/lockstep.c,
# coord_progress): whole lines "lahar: t = T / END s (P %) ... ETA ..." every --progress-every
# seconds, with the simulated time rising and ending at or below END, a set-up line while the nodes
# fill their particles, no carriage returns; none with -q, with --progress-every 0 or (default 60 s)
# in a run shorter than a minute; a bad value is refused with exit 2. The cases: the 3D dam break at
# dx = 2 cm to t = 0.01 s (1875 particles, well under a second), and for the lines into a file the
# case as it is (15000 particles) for 10 steps of about 50 ms each on one core: every step spans a
# 5 ms interval, so it writes about one line a step on a faster machine too. Its set-up can end
# within the coordinator's first 100 ms set-up poll, which prints no set-up line, so the set-up
# line is looked for in a run at dx 5 mm (120000 particles, ~0.5 s of set-up) for a step or two.
# Small enough for the sanitizer build (the 10-step run with 120000 particles reached the test's
# 120 s timeout there).
# usage: cli_progress.sh LAHAR CASE_OVERRIDE_PY CASES_DIR WORK_DIR
lahar=$1 override=$2 cases=$3 work=$4
fail=0 n=0
rm -rf "$work" && mkdir -p "$work" || exit 2
python3 "$override" "$cases/dam_break_3d.yaml" "$work/short.yaml" sph.dx=0.02 time.end=0.01 time.output_interval=0.01 >/dev/null || exit 2
python3 "$override" "$cases/dam_break_3d.yaml" "$work/fine.yaml" time.end=0.0015 \
    time.output_interval=0.0015 >/dev/null || exit 2
python3 "$override" "$cases/dam_break_3d.yaml" "$work/setup.yaml" sph.dx=0.005 time.end=0.0001 \
    time.output_interval=0.0001 >/dev/null || exit 2
result() { # name ok-condition-status message
    n=$((n + 1))
    if [ "$2" -eq 0 ]; then echo "ok   $1"; else echo "FAIL $1: $3"; fail=$((fail + 1)); fi
}
"$lahar" run "$work/fine.yaml" -o "$work/log" --threads 1 --progress-every 0.005 >/dev/null 2>"$work/log.err"
rc=$?
lines=$(grep -c '^lahar: t = [0-9.e+-]* / 0\.0015 s ([0-9]* %)   step [0-9]*   [0-9]* steps/s   .* elapsed   ETA ' "$work/log.err")
rising=$(sed -n 's/^lahar: t = \([0-9.e+-]*\) .*/\1/p' "$work/log.err" |
         awk 'NR > 1 && $1 < prev { bad = 1 } $1 > 0.0015 { bad = 1 } { prev = $1 } END { print bad ? "no" : "yes" }')
[ "$rc" -eq 0 ] && [ "$lines" -ge 3 ] && [ "$rising" = yes ]
result "--progress-every 0.005 into a file: $lines progress lines, times rising to <= 0.0015 s (exit $rc)" $? \
    "want exit 0, >= 3 lines, rising times; stderr: $(head -c 600 "$work/log.err")"
# the set-up line: a case whose set-up outlasts the coordinator's 100 ms set-up poll on a fast
# machine too (120,000 particles, about 0.5 s of filling on one core), for a step or two
"$lahar" run "$work/setup.yaml" -o "$work/setup" --threads 1 --progress-every 0.005 >/dev/null 2>"$work/setup.err"
grep -q '^lahar: setting up: waiting for the SPH node' "$work/setup.err"
result "a set-up line while the SPH node fills its particles" $? "none in: $(head -c 300 "$work/setup.err")"
! grep -q "$(printf '\r')" "$work/log.err"
result "no carriage return in the log" $? "found one"
for args in "-q --progress-every 0.1" "--progress-every 0" ""; do
    # shellcheck disable=SC2086 # the options are words
    "$lahar" run "$work/short.yaml" -o "$work/none" --overwrite --threads 1 $args >/dev/null 2>"$work/none.err"
    rc=$?
    [ "$rc" -eq 0 ] && ! grep -q '^lahar: \(t = \|setting up\)' "$work/none.err"
    result "no progress lines with '${args:-the default (60 s) in a 1 s run}' (exit $rc)" $? "$(head -c 300 "$work/none.err")"
done
"$lahar" run "$work/short.yaml" -o "$work/bad" --progress-every -1 >/dev/null 2>"$work/bad.err"
rc=$?
[ "$rc" -eq 2 ] && grep -q -- '--progress-every takes a number of seconds' "$work/bad.err"
result "--progress-every -1 refused (exit $rc)" $? "$(cat "$work/bad.err")"
echo "$((n - fail)) passed, $fail failed"
[ "$fail" -eq 0 ]
