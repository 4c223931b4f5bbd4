#!/usr/bin/env bash
# Coordinated checkpoints and `lahar resume` (coordinator/README.md "Checkpoints and resume"):
# a run that is interrupted (a node killed with SIGKILL, SIGTERM, a crash right after a
# checkpoint) or that ended early and is resumed must end with output files bitwise equal to those
# of the uninterrupted run (tools/h5_compare.py: every dataset and every attribute outside
# /header). Cases are shortened copies of cases/ made by tools/case_override.py. Every run is in
# lahar's own private network namespace or in-process.
#
#   checkpoint_runs.sh TEST BIN_DIR TOOLS_DIR CASES_DIR WORK_DIR
#   TEST: water | dem | coupled_killed | soil | sigterm | group_signals | disk_full | coordinator_killed |
#         sigusr1 | errors | inflow
set -u
test_name=$1 bin=$2 tools=$3 cases=$4 work=$5
python=/usr/bin/python3
[ -x "$python" ] || python=python3
rm -rf "$work"
mkdir -p "$work"
cd "$work" || exit 2
lahar="$bin/lahar"

fail() { echo "FAIL: $*" >&2; exit 1; }

override() { "$python" "$tools/case_override.py" "$@" || fail "case_override.py $*"; }

# pid of the child of $1 whose command is $2 (from /proc)
child_pid() {
    local stat pid comm state ppid rest
    for stat in /proc/[0-9]*/stat; do
        read -r pid comm state ppid rest < "$stat" 2>/dev/null || continue
        [ "$ppid" = "$1" ] && [ "$comm" = "($2)" ] && echo "$pid"
    done
}

# the output files of run A and run B are equal bit for bit (datasets and attributes; /header
# names the case file and its end time, which legitimately differ for a resume with --time-end)
same_output() { # A B files...
    local a=$1 b=$2 f
    shift 2
    for f in "$@"; do
        [ -f "$a/$f" ] || fail "$a/$f missing"
        "$python" "$tools/h5_compare.py" "$a/$f" "$b/$f" --attrs --exclude '^/header' --quiet ||
            fail "$b/$f differs from the uninterrupted run's $a/$f"
    done
    echo "bitwise equal: $*"
}

# summary.json field (python expression on d)
summary() { "$python" -c "import json,sys; d=json.load(open('$1/summary.json')); print($2)"; }

# wait until OUT/checkpoints holds a complete checkpoint (a directory NNNNNN with coord.h5)
wait_checkpoint() { # OUT pid
    local i
    for i in $(seq 1 3000); do
        compgen -G "$1/checkpoints/[0-9]*[0-9]/coord.h5" > /dev/null && return 0
        kill -0 "$2" 2>/dev/null || return 1
        sleep 0.01
    done
    return 1
}

case "$test_name" in
water)
    # dam break (fixed walls: the SPH node writes the body files, contacts.h5 of the right wall)
    # with a pressure probe; run to 0.15 s, then `lahar resume --time-end 0.2` (a finished run
    # extended; 0.15 is 3 x 0.05 only up to round-off, the clock's end is the grid time)
    # against a run to 0.2 s
    override "$cases/dam_break_2d.yaml" water.yaml sph.dx=0.005 time.end=0.2 time.output_interval=0.05 \
        'checkpoint={interval: 0.05}' 'probes=[{name: p1, position: [0.1, 0.01], rate: 200}]'
    override water.yaml water_01.yaml time.end=0.15
    nice -n 10 "$lahar" run water.yaml -o full --threads 1 -q || fail "full run"
    nice -n 10 "$lahar" run water_01.yaml -o part --threads 1 -q || fail "run to 0.15 s"
    nice -n 10 "$lahar" resume part --threads 1 -q > resume0.txt || fail "resume of a finished run without --time-end"
    grep -q "at its end time already" resume0.txt || fail "resume of a finished run: $(cat resume0.txt)"
    nice -n 10 "$lahar" resume part --time-end 0.2 --threads 1 -q || fail "resume --time-end 0.2"
    same_output full part particles.h5 bodies.h5 forces.h5 contacts.h5 gauges.h5
    w_full=$(summary full "d['work']['sph_passes'], d['work']['pairs_fluid_fluid'], d['work']['particle_body']")
    w_part=$(summary part "d['work']['sph_passes'], d['work']['pairs_fluid_fluid'], d['work']['particle_body']")
    [ "$w_full" = "$w_part" ] || fail "summary.json work: resumed $w_part, uninterrupted $w_full"
    [ "$(summary part "d['steps']")" = "$(summary full "d['steps']")" ] ||
        fail "summary.json: the resumed run counts $(summary part "d['steps']") steps, the uninterrupted one $(summary full "d['steps']")"
    [ "$(summary part "round(d['resumed_from']['time'], 9)")" = 0.15 ] || fail "summary.json resumed_from: $(summary part "d.get('resumed_from')")"
    [ "$(summary part "d['status']")" = finished ] || fail "resumed run not finished"
    # the sidecars list every snapshot once
    n_full=$(grep -c '<Time ' full/particles.xmf) n_part=$(grep -c '<Time ' part/particles.xmf)
    [ "$n_full" = "$n_part" ] || fail "particles.xmf: $n_part time steps, the uninterrupted run has $n_full"
    ;;
inflow)
    # open boundaries (cases/inflow_channel_2d: inlet with a CSV hydrograph, outlet, domain box):
    # the particle count varies; run to 0.25 s, resume with --time-end 0.4 against a run to 0.4 s
    override "$cases/inflow_channel_2d.yaml" flow.yaml time.end=0.4 time.output_interval=0.05 'outlets.downstream.position=[0.3, -0.5]' \
        'checkpoint={interval: 0.1}'
    override flow.yaml flow_part.yaml time.end=0.25
    nice -n 10 "$lahar" run flow.yaml -o full --threads 1 -q || fail "full run"
    nice -n 10 "$lahar" run flow_part.yaml -o part --threads 1 -q || fail "run to 0.25 s"
    nice -n 10 "$lahar" resume part --time-end 0.4 --threads 1 -q || fail "resume --time-end 0.4"
    same_output full part particles.h5
    f_full=$(summary full "d['flow']")
    f_part=$(summary part "d['flow']")
    [ "$f_full" = "$f_part" ] || fail "summary.json flow: resumed $f_part, uninterrupted $f_full"
    [ "$(summary full "d['flow']['removed_water'] > 0 and d['flow']['entered'] > 0")" = True ] ||
        fail "the shortened run moved no water through the boundaries: $f_full"
    ;;
dem)
    # DEM only (dem_drop_3d shortened): a crash right after a checkpoint, before the next one is
    # complete: the newest checkpoint is gone and a half-written one (*.tmp) is left behind
    override "$cases/dem_drop_3d.yaml" dem.yaml time.end=0.2 time.output_interval=0.05 'checkpoint={interval: 0.05, keep: 3}'
    nice -n 10 "$lahar" run dem.yaml -o full --threads 1 -q || fail "full run"
    cp -a full crash
    newest=$(ls -d crash/checkpoints/[0-9]*[0-9] | tail -1)
    mv "$newest" "$newest.tmp"
    rm -f "$newest.tmp/coord.h5"
    nice -n 10 "$lahar" resume crash --threads 1 -q || fail "resume"
    [ ! -e "$newest.tmp" ] || fail "the stale $newest.tmp was not removed"
    same_output full crash bodies.h5 forces.h5
    # the work counters of summary.json continue across the resume
    w_full=$(summary full "d['work']['body_body'], d['dem_substeps'], d['steps']")
    w_crash=$(summary crash "d['work']['body_body'], d['dem_substeps'], d['steps']")
    [ "$w_full" = "$w_crash" ] || fail "summary.json work/substeps/steps: resumed $w_crash, uninterrupted $w_full"
    [ "$(ls -d crash/checkpoints/[0-9]*[0-9] | wc -l)" = 3 ] || fail "keep: 3 not honoured: $(ls crash/checkpoints)"
    ;;
coupled_killed)
    # debris flow (water, free boulders, record_contacts) as processes: the DEM node is killed
    # with SIGKILL after the first checkpoint; the run ends with exit 3, resume continues from the
    # last complete checkpoint (and is itself killed and resumed, below)
    override "$cases/debris_2d.yaml" cpl.yaml sph.dx=0.01 time.end=0.4 time.output_interval=0.05 \
        'checkpoint={interval: 0.1}'
    nice -n 10 "$lahar" run cpl.yaml -o full --threads 1 -q || fail "full run"
    nice -n 10 "$lahar" run cpl.yaml -o killed --threads 1 -q 2> killed.err &
    pid=$!
    wait_checkpoint killed "$pid" || fail "no checkpoint appeared"
    sleep 0.3 # into the interval before the next checkpoint
    dem=$(child_pid "$pid" lahar-dem)
    [ -n "$dem" ] || fail "no lahar-dem child of $pid"
    kill -KILL "$dem"
    wait "$pid"
    rc=$?
    [ "$rc" = 3 ] || fail "the run with a killed node exited $rc, expected 3: $(cat killed.err)"
    echo "killed at t = $(summary killed "d['sim_time']") s; checkpoints: $(ls killed/checkpoints | tr '\n' ' ')"
    # the resumed run loses its SPH node (SIGKILL) after its own first checkpoint, and is resumed again
    first=$(ls -d killed/checkpoints/[0-9]*[0-9] | tail -1)
    nice -n 10 "$lahar" resume killed --threads 1 -q 2> killed2.err &
    pid=$!
    for i in $(seq 1 3000); do
        newest=$(ls -d killed/checkpoints/[0-9]*[0-9] 2>/dev/null | tail -1)
        [ "$newest" != "$first" ] && [ -f "$newest/coord.h5" ] && break
        kill -0 "$pid" 2>/dev/null || break
        sleep 0.01
    done
    sleep 0.2
    sph=$(child_pid "$pid" lahar-sph)
    [ -n "$sph" ] || fail "no lahar-sph child of the resumed run $pid"
    kill -KILL "$sph"
    wait "$pid"
    rc=$?
    [ "$rc" = 3 ] || fail "the resumed run with a killed node exited $rc, expected 3: $(cat killed2.err)"
    echo "killed again at t = $(summary killed "d['sim_time']") s; checkpoints: $(ls killed/checkpoints | tr '\n' ' ')"
    nice -n 10 "$lahar" resume killed --threads 1 -q || fail "second resume"
    same_output full killed particles.h5 bodies.h5 forces.h5 contacts.h5
    [ "$(summary killed "d['steps']")" = "$(summary full "d['steps']")" ] || fail "steps in summary.json"
    ;;
soil)
    # granular column collapse (Drucker-Prager soil on fixed DEM walls), resumed in-process from
    # its first checkpoint (the later ones removed: a crash after the first)
    override "$cases/granular_collapse_2d.yaml" soil.yaml sph.dx=0.01 time.end=0.2 time.output_interval=0.05 \
        'checkpoint={interval: 0.05, keep: 4}'
    nice -n 10 "$lahar" run soil.yaml -o full --threads 1 -q || fail "full run"
    cp -a full crash
    for d in $(ls -d crash/checkpoints/[0-9]*[0-9] | tail -n +2); do rm -rf "$d"; done
    nice -n 10 "$lahar" resume crash --in-process --threads 1 -q || fail "resume"
    same_output full crash particles.h5 bodies.h5 forces.h5
    ;;
sigterm)
    # SIGTERM: a checkpoint, then a clean stop (status "stopped", exit 1); resume finishes it
    override "$cases/debris_2d.yaml" cpl.yaml sph.dx=0.01 time.end=0.4 time.output_interval=0.05 \
        'checkpoint={interval: 1.0}'
    nice -n 10 "$lahar" run cpl.yaml -o full --threads 1 -q || fail "full run"
    nice -n 10 "$lahar" run cpl.yaml -o term --threads 1 -q 2> term.err &
    pid=$!
    for i in $(seq 1 500); do [ -f term/particles.h5 ] && break; sleep 0.01; done
    sleep 0.5
    kill -TERM "$pid"
    wait "$pid"
    rc=$?
    [ "$rc" = 1 ] || fail "SIGTERM: exit $rc, expected 1: $(cat term.err)"
    [ "$(summary term "d['status']")" = stopped ] || fail "SIGTERM: status $(summary term "d['status']")"
    echo "stopped at t = $(summary term "d['sim_time']") s: $(summary term "d['message']")"
    nice -n 10 "$lahar" resume term --threads 1 -q || fail "resume"
    same_output full term particles.h5 bodies.h5 forces.h5 contacts.h5
    ;;
group_signals)
    # A terminal (Ctrl-C, SIGHUP when it closes), a batch system (Slurm signals every process of
    # the job) or `kill -- -PGID` signal the nodes with lahar. SIGTERM and SIGHUP to lahar's whole
    # process group: a checkpoint and a clean stop as for SIGTERM to lahar alone (exit 1, status
    # "stopped", both nodes exit 0, not killed by the signal: the run ended "node lost" with exit 3,
    # or died of SIGHUP leaving summary.json "running"); resume finishes it bitwise. Ctrl-C
    # (SIGINT to the group) after the first checkpoint: status "interrupted", the nodes write their
    # final snapshot, and resume goes on from that checkpoint, cutting the snapshot back.
    override "$cases/debris_2d.yaml" cpl.yaml sph.dx=0.01 time.end=0.4 time.output_interval=0.05 \
        'checkpoint={interval: 1.0}'
    override "$cases/debris_2d.yaml" cpl_int.yaml sph.dx=0.01 time.end=0.4 time.output_interval=0.05 \
        'checkpoint={interval: 0.1}'
    nice -n 10 "$lahar" run cpl.yaml -o full --threads 1 -q || fail "full run"
    setsid nice -n 10 "$lahar" run cpl_int.yaml -o group_INT --threads 1 -q 2> group_INT.err &
    pid=$!
    wait_checkpoint group_INT "$pid" || fail "no checkpoint appeared"
    sleep 0.3
    kill -INT -- -"$pid"
    wait "$pid"
    rc=$?
    [ "$rc" = 1 ] || fail "SIGINT to the process group: exit $rc, expected 1: $(cat group_INT.err)"
    [ "$(summary group_INT "d['status']")" = interrupted ] || fail "SIGINT: status $(summary group_INT "d['status'], d['message']")"
    nodes=$(summary group_INT "sorted((k, v['exit_status']) for k, v in d['nodes'].items())")
    [ "$nodes" = "[('dem', 0), ('sph', 0)]" ] || fail "SIGINT to the process group: nodes' exit statuses $nodes"
    echo "SIGINT to the process group: $(summary group_INT "d['message']"); checkpoints: $(ls group_INT/checkpoints | tr '\n' ' ')"
    nice -n 10 "$lahar" resume group_INT --threads 1 -q || fail "resume after SIGINT"
    same_output full group_INT particles.h5 bodies.h5 forces.h5 contacts.h5
    for sig in TERM HUP; do
        out=group_$sig
        setsid nice -n 10 "$lahar" run cpl.yaml -o $out --threads 1 -q 2> $out.err &
        pid=$!
        for i in $(seq 1 500); do [ -f $out/particles.h5 ] && break; sleep 0.01; done
        sleep 0.5
        kill -0 "$pid" 2>/dev/null || fail "the run ended before SIG$sig was sent: nothing tested"
        read -r _ _ _ _ pgid _ < /proc/$pid/stat
        [ "$pgid" = "$pid" ] || fail "setsid did not make lahar ($pid) a process group leader ($pgid)"
        kill -$sig -- -"$pid"
        wait "$pid"
        rc=$?
        [ "$rc" = 1 ] || fail "SIG$sig to the process group: exit $rc, expected 1: $(cat $out.err)"
        [ "$(summary $out "d['status']")" = stopped ] || fail "SIG$sig to the process group: status $(summary $out "d['status'], d['message']")"
        summary $out "d['message']" | grep -q "stopped by SIG$sig after the checkpoint" ||
            fail "SIG$sig: message $(summary $out "d['message']")"
        nodes=$(summary $out "sorted((k, v['exit_status']) for k, v in d['nodes'].items())")
        [ "$nodes" = "[('dem', 0), ('sph', 0)]" ] || fail "SIG$sig to the process group: nodes' exit statuses $nodes"
        echo "SIG$sig to the process group: $(summary $out "d['message']")"
        nice -n 10 "$lahar" resume $out --threads 1 -q || fail "resume after SIG$sig"
        same_output full $out particles.h5 bodies.h5 forces.h5 contacts.h5
    done
    # started with nohup (SIGHUP ignored): the terminal's SIGHUP leaves the run going to its end
    setsid nohup nice -n 10 "$lahar" run cpl.yaml -o nohup --threads 1 -q > /dev/null 2> nohup.err &
    pid=$!
    for i in $(seq 1 500); do [ -f nohup/particles.h5 ] && break; sleep 0.01; done
    sleep 0.5
    kill -0 "$pid" 2>/dev/null || fail "the nohup run ended before its SIGHUP was sent: nothing tested"
    kill -HUP -- -"$pid"
    wait "$pid"
    rc=$?
    [ "$rc" = 0 ] || fail "nohup lahar run: exit $rc after SIGHUP, expected 0 (the run goes on): $(cat nohup.err)"
    same_output full nohup particles.h5 bodies.h5 forces.h5 contacts.h5
    # SIGUSR1 and SIGUSR2 to the whole group (a batch system's --signal=USR1 before its time
    # limit, or by hand): lahar writes a checkpoint on USR1 and goes on; the nodes neither die of
    # USR1 (its default action) nor take USR2 for the signal that lahar has died (they ended the
    # run "node lost" before)
    setsid nice -n 10 "$lahar" run cpl.yaml -o group_USR --threads 1 -q 2> group_USR.err &
    pid=$!
    for i in $(seq 1 500); do [ -f group_USR/particles.h5 ] && break; sleep 0.01; done
    sleep 0.5
    kill -0 "$pid" 2>/dev/null || fail "the run ended before SIGUSR1 was sent: nothing tested"
    kill -USR1 -- -"$pid"
    sleep 0.3
    kill -USR2 -- -"$pid"
    wait "$pid"
    rc=$?
    [ "$rc" = 0 ] || fail "SIGUSR1, SIGUSR2 to the process group: exit $rc, expected 0: $(cat group_USR.err)"
    written=$(summary group_USR "d['checkpoints']['written']")
    [ "$written" -ge 2 ] || fail "SIGUSR1 to the process group: $written checkpoints written, expected the end's and one more"
    echo "SIGUSR1, SIGUSR2 to the process group: finished, $written checkpoints"
    same_output full group_USR particles.h5 bodies.h5 forces.h5 contacts.h5
    # the log lahar writes to goes away (`lahar run ... | tee log`, tee ended with the terminal):
    # the run goes on to its end (it died of SIGPIPE at its next progress line)
    { nice -n 10 "$lahar" run cpl.yaml -o piped --threads 1 --progress-every 0.05 2>&1; echo $? > piped.rc; } | head -n 1
    [ "$(cat piped.rc)" = 0 ] || fail "the run whose log reader ended: exit $(cat piped.rc)"
    [ "$(summary piped "d['status']")" = finished ] || fail "the run whose log reader ended: status $(summary piped "d['status']")"
    same_output full piped particles.h5 bodies.h5 forces.h5 contacts.h5
    ;;
disk_full)
    # The disk fills up (another job's file) between two checkpoints of a particle-only case (no
    # force stream: the checkpoint is the next thing written): the SPH node says which checkpoint
    # file, "no space left on device" and the bytes free (it said only "cannot write 'x' (N
    # values) into the checkpoint"); exit 1, status "error"; the previous checkpoint is complete,
    # and once the space is freed `lahar resume` ends bitwise as the run on a roomy disk. OUT is a
    # 8 MB tmpfs in a private user + mount namespace.
    override "$cases/taylor_green_2d.yaml" tg.yaml sph.dx=0.02 time.end=1.0 time.output_interval=1.0 \
        'checkpoint={interval: 0.1, keep: 1}'
    nice -n 10 "$lahar" run tg.yaml -o full --threads 1 -q || fail "full run"
    mkdir -p mnt
    unshare --user --map-root-user --mount bash -c "
        mount -t tmpfs -o size=8m tmpfs mnt || exit 9
        nice -n 10 '$lahar' run tg.yaml -o mnt/out --threads 1 -q 2> full.stderr & pid=\$!
        until compgen -G 'mnt/out/checkpoints/[0-9]*[0-9]/coord.h5' > /dev/null; do
            kill -0 \$pid 2>/dev/null || break
            sleep 0.01
        done
        free=\$(df -k --output=avail mnt | tail -n 1)
        dd if=/dev/zero of=mnt/filler bs=1k count=\$((free - 200)) 2> /dev/null
        wait \$pid; echo \$? > full_rc.txt
        rm mnt/filler
        nice -n 10 '$lahar' resume mnt/out --threads 1 -q 2> resume.stderr; echo \$? > resume_rc.txt
        cp -r mnt/out out"
    [ -s full_rc.txt ] || fail "the tmpfs could not be mounted in a private mount namespace"
    cat full.stderr
    [ "$(cat full_rc.txt)" = 1 ] || fail "the run on the full disk: exit $(cat full_rc.txt), expected 1"
    msg=$(summary out "d.get('resumed_from') and 'resumed' or ''")
    grep -q "checkpoints/[0-9]*\.tmp/sph\.h5: no space left on device ([0-9]* bytes free): the checkpoint's" full.stderr ||
        fail "the message does not name the checkpoint file and say the disk is full"
    [ "$(cat resume_rc.txt)" = 0 ] || fail "resume after freeing the space: exit $(cat resume_rc.txt): $(cat resume.stderr)"
    [ "$msg" = resumed ] || fail "summary.json of the resumed run has no resumed_from"
    same_output full out particles.h5
    ;;
coordinator_killed)
    # lahar itself killed with SIGKILL (or crashed, or taken by the OOM killer) mid-run: the nodes
    # it started close their files and exit within a second (they were killed with it and left
    # forces.h5 and gauges.h5 flagged open for writing: h5py and h5dump refused both until
    # `h5clear -s`); every HDF5 file reads; resume goes on from the newest checkpoint, bitwise.
    override "$cases/debris_2d.yaml" cpl.yaml sph.dx=0.01 time.end=0.6 time.output_interval=0.05 \
        'checkpoint={interval: 0.1}' 'probes=[{name: p1, position: [1.1, 0.02], rate: 1000}]'
    nice -n 10 "$lahar" run cpl.yaml -o full --threads 1 -q || fail "full run"
    nice -n 10 "$lahar" run cpl.yaml -o killed --threads 1 -q 2> killed.err &
    pid=$!
    wait_checkpoint killed "$pid" || fail "no checkpoint appeared"
    sleep 0.3
    nodes="$(child_pid "$pid" lahar-dem) $(child_pid "$pid" lahar-sph)"
    [ "$(echo $nodes | wc -w)" = 2 ] || fail "the nodes of $pid: '$nodes'"
    kill -KILL "$pid"
    wait "$pid"
    # gone, or a zombie that the process that inherited it has not reaped yet
    alive() { local st; read -r _ _ st _ < /proc/$1/stat 2>/dev/null && [ "$st" != Z ]; }
    for i in $(seq 1 300); do
        left=""
        for n in $nodes; do alive "$n" && left="$left $n"; done
        [ -z "$left" ] && break
        sleep 0.01
    done
    [ -z "$left" ] || fail "node processes$left still running 3 s after lahar was killed"
    cat killed.err
    "$python" - killed <<'PY' || fail "the files of the run whose lahar was killed"
import sys, h5py
for name in ("particles", "bodies", "forces", "contacts", "gauges"):
    with h5py.File("%s/%s.h5" % (sys.argv[1], name), "r") as f:  # opens, and every dataset reads
        f.visititems(lambda n, o: o[()] if isinstance(o, h5py.Dataset) else None)
with h5py.File(sys.argv[1] + "/forces.h5", "r") as f, h5py.File(sys.argv[1] + "/gauges.h5", "r") as g:
    print("lahar killed: forces.h5 to t = %.4f s, gauges.h5 to t = %.4f s, both read" % (f["t"][-1], g["probes/p1/t"][-1]))
PY
    grep -q "lahar-dem: lahar, which started this node, has ended" killed.err || fail "the DEM node did not say why it stopped"
    nice -n 10 "$lahar" resume killed --threads 1 -q || fail "resume"
    same_output full killed particles.h5 bodies.h5 forces.h5 contacts.h5 gauges.h5
    ;;
sigusr1)
    # SIGUSR1: a checkpoint after the next step, in a case whose interval would write none
    override "$cases/dam_break_2d.yaml" water.yaml sph.dx=0.005 time.end=0.3 'checkpoint={interval: 10.0}'
    nice -n 10 "$lahar" run water.yaml -o usr --threads 1 -q &
    pid=$!
    for i in $(seq 1 500); do [ -f usr/particles.h5 ] && break; sleep 0.01; done
    sleep 0.3
    kill -USR1 "$pid"
    wait "$pid" || fail "run with SIGUSR1"
    n=$(summary usr "d['checkpoints']['written']")
    [ "$n" = 2 ] || fail "SIGUSR1: $n checkpoints written, expected 2 (SIGUSR1 and the last step)"
    ;;
errors)
    # what a user can meet: clear message, exit 2
    override "$cases/dam_break_2d.yaml" water.yaml sph.dx=0.01 time.end=0.05 'checkpoint={interval: 0.02}'
    override "$cases/dam_break_2d.yaml" nockpt.yaml sph.dx=0.01 time.end=0.05
    nice -n 10 "$lahar" run nockpt.yaml -o nockpt --threads 1 -q || fail "run without checkpoints"
    "$lahar" resume nockpt 2> e1.txt
    [ $? = 2 ] && grep -q "has no checkpoints" e1.txt || fail "resume without checkpoints: $(cat e1.txt)"
    "$lahar" resume nowhere 2> e2.txt
    [ $? = 2 ] || fail "resume of a missing directory: $(cat e2.txt)"
    nice -n 10 "$lahar" run water.yaml -o run --threads 1 -q || fail "run"
    # the directory of a finished run with checkpoints: refused without --overwrite, naming resume
    "$lahar" run water.yaml -o run -q 2> e3.txt
    [ $? = 2 ] && grep -q "lahar resume" e3.txt || fail "reuse of OUT: $(cat e3.txt)"
    # a checkpoint of another format / build
    cp -a run other
    for f in other/checkpoints/[0-9]*[0-9]/coord.h5; do
        "$python" -c "import h5py,sys; f=h5py.File(sys.argv[1],'r+'); f.attrs['format']=99" "$f"
    done
    "$lahar" resume other --time-end 0.1 2> e4.txt
    [ $? = 2 ] && grep -q "format 99" e4.txt || fail "incompatible checkpoint: $(cat e4.txt)"
    # locked by a running run
    exec 9> run/.lahar.lock
    flock -x 9
    "$lahar" resume run --time-end 0.1 2> e5.txt
    rc=$?
    exec 9>&-
    [ $rc = 2 ] && grep -q "in use by another lahar run" e5.txt || fail "locked OUT: $(cat e5.txt)"
    # bad keys: file, line, key
    override "$cases/dam_break_2d.yaml" bad1.yaml 'checkpoint={interval: -1}'
    "$lahar" validate bad1.yaml 2> e6.txt
    [ $? = 2 ] && grep -q "checkpoint.interval: must be > 0" e6.txt || fail "checkpoint.interval -1: $(cat e6.txt)"
    override "$cases/dam_break_2d.yaml" bad2.yaml 'checkpoint={interval: 0.1, keep: 0}'
    "$lahar" validate bad2.yaml 2> e7.txt
    [ $? = 2 ] && grep -q "checkpoint.keep: must be a whole number" e7.txt || fail "checkpoint.keep 0: $(cat e7.txt)"
    override "$cases/dam_break_2d.yaml" bad3.yaml 'checkpoint={every: 0.1}'
    "$lahar" validate bad3.yaml 2> e8.txt
    [ $? = 2 ] && grep -q "unknown key" e8.txt || fail "checkpoint.every: $(cat e8.txt)"
    "$lahar" run water.yaml -o run2 --time-end 1 2> e9.txt
    [ $? = 2 ] || fail "--time-end on run: $(cat e9.txt)"
    cat e1.txt e3.txt e4.txt e5.txt e6.txt
    ;;
*)
    fail "unknown test $test_name"
    ;;
esac
echo "PASS: $test_name"
