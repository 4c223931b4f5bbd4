#!/usr/bin/env bash
# Liveness under load and what a fault costs, measured (docs/reliability.md, docs/bench/liveness.md).
#
#   tests/stress/liveness_load.sh BIN_DIR WORK_DIR [options]
#     --load N        busy processes put on the machine for the loaded phases (default 8)
#     --runs N        short two-thread coupled water + DEM runs (debris_2d to 6 ms, every 4th
#                     floating_box_2d to 10 ms; about 100 steps each) (default 40)
#     --soil-runs N   short 3200-particle soil runs (granular_collapse_2d at dx 2.5 mm to 4 ms) (default 12)
#     --detect N      repetitions of each injected fault and of SIGTERM (default 3)
#     --loss-reps N   runs per packet-loss rate (default 2)
#     --phases LIST   comma-separated subset of fp,detect,xhost,sigterm,loss (default: all)
#     --parallel P    fp phase: P runs at a time (default 1; more runs in the same wall time on a
#                     machine others load too, and more load)
#
# Phases:
#   fp       at load N: the short runs above, each with --threads 2; a run that stops with "lost" is
#            a false positive (nothing was killed). Per run: exit status, the longest silence the
#            coordinator heard from each node (summary.json nodes.*.max_silence_s), silences
#            forgiven as starvation, the coordinator's own longest scheduling gap.
#   detect   at load N: kill -9 and SIGSTOP of the DEM node and of the SPH node during a debris_2d
#            run (--threads 2): time from the signal to the "lost" message and to lahar's exit,
#            exit status, summary.json node statuses, every HDF5 file opened by h5py.
#   xhost    at load N: the DEM node on another network-namespace "host" (--no-spawn: heartbeat
#            only) killed with kill -9.
#   sigterm  idle: SIGTERM to lahar during a run: time to exit, status, files, no node left.
#   loss     idle: 0 %, 2 % and 10 % of all UDP datagrams dropped (nft in a private namespace):
#            wall time and bitwise equality with the in-process run.
# The busy processes and every run inherit this script's niceness (run it with `nice -n 10` on a
# shared machine: the load is relative). Results: WORK_DIR/results.csv (one line per run) and
# WORK_DIR/results.md (the tables of docs/bench/liveness.md). Every multicast run happens inside
# a private network namespace (lahar's own, or one made here with unshare). Only Debian tools.
set -u
bin=$(cd "$1" && pwd) work=$2
shift 2
here=$(cd "$(dirname "$0")" && pwd)
tools=$(cd "$here/../../tools" && pwd)
cases=$(cd "$here/../../cases" && pwd)
python=/usr/bin/python3
[ -x "$python" ] || python=python3
load=8 runs=40 soil_runs=12 detect=3 loss_reps=2 parallel=1 phases=fp,detect,xhost,sigterm,loss
while [ $# -gt 0 ]; do
    case $1 in
    --load) load=$2; shift 2 ;;
    --runs) runs=$2; shift 2 ;;
    --soil-runs) soil_runs=$2; shift 2 ;;
    --detect) detect=$2; shift 2 ;;
    --loss-reps) loss_reps=$2; shift 2 ;;
    --parallel) parallel=$2; shift 2 ;;
    --phases) phases=$2; shift 2 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
    esac
done
mkdir -p "$work"
work=$(cd "$work" && pwd)
cd "$work" || exit 2
csv=$work/results.csv
echo "phase,kind,run,rc,status,wall_s,detect_s,exit_s,max_silence_dem_s,max_silence_sph_s,starved,coord_gap_max_s,loadavg,note" > "$csv"
URL_LO='udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608'
URL_LINK='udpm://239.255.76.67:7667?ttl=1&recv_buf_size=8388608'

has_phase() { case ",$phases," in *",$1,"*) return 0 ;; esac; return 1; }
now() { date +%s.%N; }
sub() { "$python" -c "print('%.2f' % ($1 - $2))"; }
loadavg() { cut -d' ' -f1 /proc/loadavg; }

# ---- load: N busy shell loops, ended by pid on exit -----------------------------------------
busy_pids=()
load_on() {
    for _ in $(seq "$load"); do
        sh -c 'while :; do :; done' &
        busy_pids+=($!)
    done
    sleep 5 # let the load average and the scheduler settle
}
load_off() {
    for p in "${busy_pids[@]}"; do kill "$p" 2>/dev/null; done
    for p in "${busy_pids[@]}"; do wait "$p" 2>/dev/null; done
    busy_pids=()
}
trap load_off EXIT
trap 'load_off; exit 1' INT TERM HUP

# ---- cases: shortened copies (tools/case_override.py) ----------------------------------------
"$python" "$tools/case_override.py" "$cases/debris_2d.yaml" debris_short.yaml time.end=0.006 time.output_interval=0.002 || exit 2
"$python" "$tools/case_override.py" "$cases/floating_box_2d.yaml" box_short.yaml time.end=0.01 time.output_interval=0.005 || exit 2
"$python" "$tools/case_override.py" "$cases/granular_collapse_2d.yaml" soil_short.yaml time.end=0.004 time.output_interval=0.002 sph.dx=0.0025 || exit 2
"$python" "$tools/case_override.py" "$cases/debris_2d.yaml" debris_long.yaml time.end=1.5 || exit 2

# summary.json fields for the CSV line: status, max silences, starved silences, coordinator gap
summary_fields() { # outdir
    "$python" - "$1" <<'PY'
import json, sys
try:
    s = json.load(open(sys.argv[1] + "/summary.json"))
except Exception:
    print("no-summary,,,,,"); sys.exit()
n = s.get("nodes", {})
ms = lambda k: "%.3f" % n[k]["max_silence_s"] if k in n else ""
starved = sum(v.get("starved_silences", 0) for v in n.values())
print("%s,%.2f,%s,%s,%d,%.3f" % (s["status"].replace(" ", "_"), s["wall_time_s"], ms("dem"), ms("sph"), starved,
                                  s.get("coordinator_sched_gap_max_s", 0)))
PY
}

# every HDF5 file of OUT opens with h5py and every dataset reads; prints "ok" or what failed
files_ok() { # outdir
    "$python" - "$1" <<'PY'
import glob, sys
import h5py
bad = []
for p in sorted(glob.glob(sys.argv[1] + "/*.h5")):
    try:
        with h5py.File(p, "r") as f:
            f.visititems(lambda n, o: o[()] if isinstance(o, h5py.Dataset) else None)
    except Exception as e:
        bad.append("%s: %s" % (p.split("/")[-1], e))
print("ok" if not bad else "; ".join(bad).replace(",", " "))
PY
}

# pid of the child of $1 whose command is $2 (from /proc)
child_pid() {
    local stat pid comm state ppid rest
    for stat in /proc/[0-9]*/stat; do
        read -r pid comm state ppid rest < "$stat" 2>/dev/null || continue
        [ "$ppid" = "$1" ] && [ "$comm" = "($2)" ] && echo "$pid"
    done
}

# ---- fp: short runs at load, none may stop as "lost" -----------------------------------------
fp_run() { # kind case index
    local kind=$1 case=$2 i=$3 out="fp_$1_$3" t0 rc
    t0=$(now)
    "$bin/lahar" run "$case" -o "$out" --overwrite --threads 2 -q 2> "$out.stderr"
    rc=$?
    local note=""
    grep -q "lost the" "$out.stderr" && note="LOST: $(grep -o 'lost the [A-Z]* node[^;]*' "$out.stderr" | head -1 | tr ',' ' ')"
    grep -q "still running" "$out.stderr" && note="$note starved-warning"
    local f
    f=$(summary_fields "$out")
    IFS=, read -r st wall msd mss starved gap <<< "$f"
    echo "fp,$kind,$i,$rc,$st,$wall,,,$msd,$mss,$starved,$gap,$(loadavg),$note" >> "$csv"
    echo "fp $kind $i: rc $rc $st wall $wall s, max silence dem $msd sph $mss, starved $starved, coordinator gap $gap $note"
    rm -rf "$out" # keep the stderr only (the disk is shared)
}
if has_phase fp; then
    load_on
    fp_start() { # kind case index: start a run, at most $parallel at a time
        while [ "$(jobs -rp | wc -l)" -ge $((parallel + ${#busy_pids[@]})) ]; do wait -n; done
        fp_run "$@" &
    }
    for i in $(seq "$runs"); do
        if [ $((i % 4)) -eq 0 ]; then fp_start floating_box box_short.yaml "$i"; else fp_start debris debris_short.yaml "$i"; fi
    done
    for i in $(seq "$soil_runs"); do fp_start soil soil_short.yaml "$i"; done
    while [ "$(jobs -rp | wc -l)" -gt "${#busy_pids[@]}" ]; do wait -n; done
    load_off
fi

# ---- detect: a node killed or stopped during a run at load ----------------------------------
# Runs debris_long, waits until it steps (bodies.h5 exists, then 1 s), signals the node, and
# measures the time to the "lost" line on stderr and to lahar's exit.
fault_run() { # kind signal node-exe index
    local kind=$1 sig=$2 exe=$3 i=$4 out="det_$1_$4" lahar_pid node_pid="" t0 t_det="" t_exit rc
    "$bin/lahar" run debris_long.yaml -o "$out" --overwrite --threads 2 -q 2> "$out.stderr" &
    lahar_pid=$!
    for _ in $(seq 600); do
        node_pid=$(child_pid "$lahar_pid" "$exe")
        [ -n "$node_pid" ] && [ -e "$out/bodies.h5" ] && break
        sleep 0.05
    done
    sleep 1
    kill "-$sig" "$node_pid"
    t0=$(now)
    while kill -0 "$lahar_pid" 2>/dev/null; do
        [ -z "$t_det" ] && grep -q "lost the" "$out.stderr" && t_det=$(now)
        sleep 0.01
    done
    wait "$lahar_pid"
    rc=$?
    t_exit=$(now)
    [ -z "$t_det" ] && grep -q "lost the" "$out.stderr" && t_det=$t_exit
    kill -9 "$node_pid" 2>/dev/null
    local f files nodes
    f=$(summary_fields "$out")
    IFS=, read -r st wall msd mss starved gap <<< "$f"
    files=$(files_ok "$out")
    nodes=$("$python" -c "import json; s=json.load(open('$out/summary.json')); print(' '.join('%s:%s' % (k, v['exit_status']) for k, v in s['nodes'].items()))" 2>/dev/null)
    # detected: lahar's exit less summary.json finish_s (STOP, the nodes' exit, the summary: after
    # the lockstep ended on the loss); the "lost" line itself is printed only after that
    local ddet="" fin
    fin=$("$python" -c "import json; print(json.load(open('$out/summary.json'))['finish_s'])" 2>/dev/null)
    [ -n "$fin" ] && ddet=$("$python" -c "print('%.2f' % ($t_exit - $t0 - $fin))")
    echo "detect,$kind,$i,$rc,$st,$wall,$ddet,$(sub "$t_exit" "$t0"),$msd,$mss,$starved,$gap,$(loadavg),nodes $nodes; files $files" >> "$csv"
    echo "detect $kind $i: rc $rc $st, lost after $ddet s, exit after $(sub "$t_exit" "$t0") s, nodes $nodes, files $files"
    rm -rf "$out"
}
if has_phase detect; then
    load_on
    for i in $(seq "$detect"); do
        fault_run kill_dem KILL lahar-dem "$i"
        fault_run kill_sph KILL lahar-sph "$i"
        fault_run stop_dem STOP lahar-dem "$i"
        fault_run stop_sph STOP lahar-sph "$i"
    done
    load_off
fi

# ---- xhost: the DEM node on another namespace "host", heartbeat only -------------------------
if has_phase xhost; then
    load_on
    for i in $(seq "$detect"); do
        out="xhost_$i"
        unshare --user --map-root-user --net bash -c "
            set -e
            . '$here/../two_hosts.sh'
            nsenter --net=\$host_b_ns '$bin/lahar-dem' --lcm-url '$URL_LINK' --threads 2 2> $out.dem.stderr & dem=\$!
            '$bin/lahar-sph' --lcm-url '$URL_LINK' --threads 2 2> $out.sph.stderr & sph=\$!
            '$bin/lahar' run debris_long.yaml -o $out --overwrite -q --no-spawn --lcm-url '$URL_LINK' 2> $out.stderr & coord=\$!
            for _ in \$(seq 600); do [ -e $out/bodies.h5 ] && break; sleep 0.05; done
            sleep 1
            kill -9 \$dem
            t0=\$(date +%s.%N); t_det=''
            while kill -0 \$coord 2>/dev/null; do
                [ -z \"\$t_det\" ] && grep -q 'lost the' $out.stderr && t_det=\$(date +%s.%N)
                sleep 0.01
            done
            set +e
            wait \$coord; rc=\$?
            t_exit=\$(date +%s.%N)
            [ -z \"\$t_det\" ] && t_det=\$t_exit
            wait \$sph; sph_rc=\$?
            echo \$rc \$t0 \$t_det \$t_exit \$sph_rc > $out.times"
        read -r rc t0 t_det t_exit sph_rc < "$out.times"
        f=$(summary_fields "$out")
        IFS=, read -r st wall msd mss starved gap <<< "$f"
        files=$(files_ok "$out")
        fin=$("$python" -c "import json; print(json.load(open('$out/summary.json'))['finish_s'])" 2>/dev/null)
        t_det=$("$python" -c "print($t_exit - ${fin:-0})")
        echo "xhost,kill_dem_remote,$i,$rc,$st,$wall,$(sub "$t_det" "$t0"),$(sub "$t_exit" "$t0"),$msd,$mss,$starved,$gap,$(loadavg),sph node exit $sph_rc; files $files" >> "$csv"
        echo "xhost $i: rc $rc $st, lost after $(sub "$t_det" "$t0") s, exit after $(sub "$t_exit" "$t0") s, SPH node (by hand) exit $sph_rc, files $files"
        rm -rf "$out"
    done
    load_off
fi

# ---- sigterm: SIGTERM to lahar during a run (idle machine) -----------------------------------
if has_phase sigterm; then
    for i in $(seq "$detect"); do
        out="term_$i"
        "$bin/lahar" run debris_long.yaml -o "$out" --overwrite --threads 2 -q 2> "$out.stderr" &
        lahar_pid=$!
        for _ in $(seq 600); do [ -e "$out/bodies.h5" ] && break; sleep 0.05; done
        sleep 1
        dem=$(child_pid "$lahar_pid" lahar-dem) sph=$(child_pid "$lahar_pid" lahar-sph)
        kill -TERM "$lahar_pid"
        t0=$(now)
        wait "$lahar_pid"
        rc=$?
        t_exit=$(now)
        left=""
        for p in $dem $sph; do [ -e "/proc/$p" ] && left="$left $p"; done
        f=$(summary_fields "$out")
        IFS=, read -r st wall msd mss starved gap <<< "$f"
        files=$(files_ok "$out")
        kept=$("$python" -c "import json; s=json.load(open('$out/summary.json')); fs=s.get('final_snapshot',{}); print('steps %d; ' % s['steps'] + ' '.join('%s %s t=%.4g' % (k, v['group'], v['time']) for k, v in fs.items()))" 2>/dev/null)
        echo "sigterm,term_coordinator,$i,$rc,$st,$wall,,$(sub "$t_exit" "$t0"),$msd,$mss,$starved,$gap,$(loadavg),$kept; nodes left:${left:- none}; files $files" >> "$csv"
        echo "sigterm $i: rc $rc $st, exit after $(sub "$t_exit" "$t0") s, $kept, nodes left:${left:- none}, files $files"
        rm -rf "$out"
    done
fi

# ---- loss: 0 / 2 / 10 % of the datagrams dropped (idle machine) ------------------------------
if has_phase loss; then
    "$python" "$tools/case_override.py" "$cases/debris_2d.yaml" debris_loss.yaml time.end=0.03 || exit 2
    "$bin/lahar" run debris_loss.yaml -o loss_ref --overwrite --in-process -q || echo "in-process reference failed"
    for pct in 0 2 10; do
        for i in $(seq "$loss_reps"); do
            out="loss_${pct}_$i"
            t0=$(now)
            unshare --user --map-root-user --net bash -c "
                set -e
                ip link set lo up; ip link set lo multicast on; ip route add 224.0.0.0/4 dev lo
                if [ $pct -gt 0 ]; then
                    nft add table inet lahar_loss
                    nft add chain inet lahar_loss out '{ type filter hook output priority 0; }'
                    nft add rule inet lahar_loss out meta l4proto udp numgen random mod 100 '<' $pct drop
                fi
                '$bin/lahar' run debris_loss.yaml -o $out --overwrite -q --lcm-url '$URL_LO'" 2> "$out.stderr"
            rc=$?
            t_exit=$(now)
            same=yes
            for fl in bodies.h5 forces.h5 particles.h5 contacts.h5; do
                "$python" "$tools/h5_compare.py" --quiet "loss_ref/$fl" "$out/$fl" > /dev/null 2>&1 || same=no
            done
            f=$(summary_fields "$out")
            IFS=, read -r st wall msd mss starved gap <<< "$f"
            resent=$("$python" -c "import json; s=json.load(open('$out/summary.json')); print(s['resent_frames'])" 2>/dev/null)
            echo "loss,loss_$pct,$i,$rc,$st,$wall,,$(sub "$t_exit" "$t0"),$msd,$mss,$starved,$gap,$(loadavg),bitwise $same; resent $resent" >> "$csv"
            echo "loss $pct % $i: rc $rc $st wall $wall s, bitwise same as in-process: $same, resent frames $resent"
            rm -rf "$out"
        done
    done
fi

"$python" "$here/liveness_report.py" "$csv" > "$work/results.md" && cat "$work/results.md"
