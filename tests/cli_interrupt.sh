#!/bin/sh
# Ctrl-C (SIGINT) and SIGTERM during a long set-up end the run at once (coordinator/run/nodes.c,
# coord_setup_wait): lahar exits 1 within 2 s (it took 23 s, the whole set-up, before), summary.json
# says "interrupted during set-up", and no node process is left. The case: the 3D dam break at
# dx 2 mm (1.87 million particles, 3.4 times dx 3 mm's, whose set-up took 2.4 s on one thread of a
# quiet machine, so that the signal came after it), interrupted 2.5 s in.
# usage: cli_interrupt.sh LAHAR CASE_OVERRIDE_PY CASES_DIR WORK_DIR
lahar=$1 override=$2 cases=$3 work=$4
fail=0 n=0
rm -rf "$work" && mkdir -p "$work" || exit 2
python3 "$override" "$cases/dam_break_3d.yaml" "$work/big.yaml" sph.dx=0.002 time.end=0.01 time.output_interval=0.01 >/dev/null || exit 2
now() { date +%s.%N; }
for mode in in-process processes; do
    for sig in INT TERM; do
        out=$work/$mode-$sig
        if [ "$mode" = processes ]; then set -- -q --threads 1; else set -- -q --threads 1 --in-process; fi
        "$lahar" run "$work/big.yaml" -o "$out" "$@" 2>"$out.err" & pid=$!
        sleep 2.5
        t0=$(now)
        kill -"$sig" $pid
        wait $pid; rc=$?
        dt=$(awk -v a="$t0" -v b="$(now)" 'BEGIN { printf "%.3f", b - a }')
        n=$((n + 1))
        if [ "$rc" -eq 1 ] && awk -v d="$dt" 'BEGIN { exit !(d < 2.0) }' &&
           grep -q '"message":.*"interrupted during set-up' "$out/summary.json"; then
            echo "ok   $mode, SIG$sig 2.5 s into set-up: exit $rc after ${dt} s, summary.json: interrupted during set-up"
        else
            echo "FAIL $mode, SIG$sig 2.5 s into set-up: exit $rc after ${dt} s (want 1 within 2 s); stderr:"
            sed 's/^/    /' "$out.err"; fail=$((fail + 1))
        fi
    done
done
# the SPH node processes those runs started (pid from summary.json) are gone
sleep 0.2
for sig in INT TERM; do
    pid=$(grep -A20 '"sph"' "$work/processes-$sig/summary.json" | sed -n 's/.*"pid":[^0-9]*\([0-9]*\).*/\1/p' | head -n 1)
    n=$((n + 1))
    if [ -z "$pid" ]; then
        echo "FAIL processes-$sig: no SPH node pid in summary.json"; fail=$((fail + 1))
    elif [ -d "/proc/$pid" ] && tr '\0' ' ' < "/proc/$pid/cmdline" | grep -q lahar-sph; then
        echo "FAIL processes-$sig: the SPH node (pid $pid) outlived its interrupted run"; fail=$((fail + 1))
    else
        echo "ok   processes-$sig: the SPH node (pid $pid) is gone"
    fi
done
echo "$((n - fail)) passed, $fail failed"
[ "$fail" -eq 0 ]
