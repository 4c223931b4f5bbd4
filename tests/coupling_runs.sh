#!/usr/bin/env bash
# Co-simulation over LCM: the same DEM scene run in every way lahar can run it must give bitwise
# the same trajectories (the in-process run over memq:// is the reference), and faults must end a
# run cleanly. Every multicast run happens inside a private network namespace: `lahar run`'s own,
# or one this script makes with `unshare --user --map-root-user --net` (lo up, multicast on, route
# 224.0.0.0/4 via lo, ttl=0 or ttl=1 on an isolated veth link). Nothing leaves the host.
#
#   coupling_runs.sh TEST BIN_DIR TOOLS_DIR WORK_DIR
#   TEST: inprocess_both | processes | packet_loss | node_killed | node_stopped | coordinator_killed | concurrent |
#         cross_host | cross_host_auth | no_namespace | engine_error | cli | disk_full | disk_full_start |
#         busy_machine
set -u
test_name=$1 bin=$2 tools=$3 work=$4
here=$(cd "$(dirname "$0")" && pwd) # tests/: two_hosts.sh
python=/usr/bin/python3
[ -x "$python" ] || python=python3
rm -rf "$work"
mkdir -p "$work"
cd "$work" || exit 2
URL_LO='udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608'
URL_LINK='udpm://239.255.76.67:7667?ttl=1&recv_buf_size=8388608'

fail() { echo "FAIL: $*" >&2; exit 1; }

# pid of the child of $1 whose command is $2 (from /proc: no procps needed)
child_pid() {
    local stat pid comm state ppid rest
    for stat in /proc/[0-9]*/stat; do
        read -r pid comm state ppid rest < "$stat" 2>/dev/null || continue
        [ "$ppid" = "$1" ] && [ "$comm" = "($2)" ] && echo "$pid"
    done
}

# A few spheres and a box falling on a fixed plate; collisions within the first 0.3 s.
write_case() { # file t_end
    cat > "$1" <<YAML
dimensions: 3
gravity: [0, 0, -9.81]
time: {end: $2, dt_max: 1e-3, output_interval: 0.05}
materials:
  rock: {density: 2650, model: hertz, young: 1e7, poisson: 0.25, restitution: 0.5, friction: 0.5}
bodies:
  - {name: ball, shape: sphere, radius: 0.05, material: rock, position: [0, 0, 0.2]}
  - {name: crate, shape: box, size: [0.2, 0.1, 0.1], radius: 0.02, material: rock, position: [0.3, 0, 0.15]}
  - {name: ball2, shape: sphere, radius: 0.04, material: rock, position: [0.02, 0.01, 0.4], velocity: [0, 0, -1]}
  - {name: floor, shape: plane, motion: fixed, normal: [0, 0, 1], size: [2, 2], radius: 0.02, material: rock, position: [0, 0, 0]}
YAML
}

# The same bodies with a block of SPH particles beside them: both nodes, LOADS and BODY_STATE
# every step. The water block falls freely, far from every body; the SPH node chooses dt (CFL).
write_case_both() { # file
    write_case "$1" 0.2
    cat >> "$1" <<YAML
sph:
  dx: 0.02
  density: 1000
  blocks:
    - {name: water, box: {lo: [-1, -1, 0.5], hi: [-0.8, -0.9, 0.6]}, velocity: [0.5, 0, 1]}
YAML
}

# Bitwise comparison of every dataset of bodies.h5 and forces.h5 with the reference run.
same_as_reference() { # outdir
    for f in bodies.h5 forces.h5; do
        "$python" "$tools/h5_compare.py" --quiet ref/$f "$1/$f" || fail "$1/$f differs from the in-process reference"
    done
}

summary() { # outdir python-expression on s
    "$python" -c "import json,sys; s=json.load(open('$1/summary.json')); print($2)"
}

reference() {
    write_case case.yaml 0.3
    "$bin/lahar" run case.yaml -o ref --in-process -q || fail "in-process reference run failed"
    [ "$(summary ref "s['status'], s['steps'], s['sim_time']")" = "finished 300 0.3" ] ||
        fail "reference run: unexpected summary $(summary ref "s['status'], s['steps'], s['sim_time']")"
}

# Run a shell snippet inside a fresh private user + network namespace with multicast on lo.
in_private_netns() {
    unshare --user --map-root-user --net bash -c "
        set -e
        ip link set lo up; ip link set lo multicast on; ip route add 224.0.0.0/4 dev lo
        $1"
}

case $test_name in
inprocess_both)
    # DEM and SPH nodes as threads. References: the particle block's centre of mass moves with
    # v0 + g t at every snapshot (time is consistent between coordinator and node: the steps sum
    # to t; the SPH forces inside the block cancel in pairs), the
    # snapshot times are exactly j * output_interval, one LOADS and one BODY_STATE per step.
    write_case_both both.yaml
    "$bin/lahar" run both.yaml -o both -q --in-process || fail "in-process DEM + SPH run failed"
    "$python" - both <<'PY' || fail "in-process DEM + SPH run: wrong results"
import json, sys
import h5py, numpy as np
out = sys.argv[1]
s = json.load(open(out + "/summary.json"))
steps = s["steps"]
assert s["status"] == "finished" and s["sim_time"] == 0.2, (s["status"], s["sim_time"])
assert set(s["nodes"]) == {"dem", "sph"}, s["nodes"].keys()
# the wall time split: start-up + steps + end = the whole run, each part positive
parts = (s["setup_s"], s["stepping_s"], s["finish_s"])
assert min(parts) > 0 and abs(sum(parts) - s["wall_time_s"]) < 1e-3, (parts, s["wall_time_s"])
for ch in ("LAHAR_LOADS", "LAHAR_BODY_STATE", "LAHAR_STEP"):
    assert s["channels"][ch]["messages"] == steps, (ch, s["channels"][ch]["messages"], steps)
with h5py.File(out + "/particles.h5", "r") as f:
    names = sorted(f["snapshots"])
    assert len(names) == 5, names  # t = 0, 0.05, ..., 0.2
    worst = 0.0
    for j, name in enumerate(names):
        g = f["snapshots"][name]
        t = float(g.attrs["time"])
        assert t == j * 0.05, (name, t, j * 0.05)
        vz, vx = np.asarray(g["vz"]), np.asarray(g["vx"])
        # the block's internal SPH forces are pairwise opposite: its centre of mass falls freely
        # (equal particle masses: the mean velocity)
        worst = max(worst, abs(float(vz.mean()) - (1.0 - 9.81 * t)), abs(float(vx.mean()) - 0.5))
    assert worst < 1e-12, worst
print("inprocess_both: %d steps, %d particle snapshots, centre of mass: max |v - (v0 + g t)| = %.2e m/s" % (steps, len(names), worst))
PY
    ;;
processes)
    # `lahar run` (own namespace, nodes as processes) == `lahar run --in-process`
    reference
    "$bin/lahar" run case.yaml -o proc -q || fail "multi-process run failed"
    same_as_reference proc
    [ "$(summary proc "s['mode']")" = processes ] || fail "mode is not processes"
    # both nodes, with LOADS / BODY_STATE between them
    write_case_both both.yaml
    "$bin/lahar" run both.yaml -o both_ip -q --in-process || fail "in-process DEM + SPH run failed"
    "$bin/lahar" run both.yaml -o both_proc -q || fail "multi-process DEM + SPH run failed"
    for f in bodies.h5 forces.h5 particles.h5; do
        "$python" "$tools/h5_compare.py" --quiet both_ip/$f both_proc/$f || fail "DEM + SPH: $f differs between modes"
    done
    ;;
packet_loss)
    # 2 % of all UDP datagrams dropped by nft: NACKs repair, the result stays bitwise the same.
    reference
    in_private_netns "
        nft add table inet lahar_test
        nft add chain inet lahar_test out '{ type filter hook output priority 0; }'
        nft add rule inet lahar_test out meta l4proto udp numgen random mod 100 '<' 2 drop
        '$bin/lahar' run case.yaml -o lossy -q --lcm-url '$URL_LO'" || fail "run with 2 % packet loss failed"
    same_as_reference lossy
    resent=$(summary lossy "s['resent_frames']")
    # STEP and STATUS are only ever re-sent to repair a loss (a loss-free run re-sends none of them)
    resent_lockstep=$(summary lossy "s['channels']['LAHAR_STEP']['resent_frames'] + s['channels']['LAHAR_STATUS']['resent_frames']")
    nacks=$(summary lossy "sum(c['nacks_sent'] for c in s['channels'].values())")
    echo "packet loss: $resent frames re-sent ($resent_lockstep STEP/STATUS), $nacks NACKs sent by the coordinator"
    [ "$resent_lockstep" -gt 0 ] || fail "no STEP/STATUS re-sent although 2 % of the datagrams were dropped"
    ;;
node_killed)
    # kill -9 the DEM node mid-run: the coordinator stops within ~2-3 s, names the node and the
    # last completed step, exits 3, and what was written so far opens.
    write_case long.yaml 30
    "$bin/lahar" run long.yaml -o killed -q 2> stderr.txt &
    lahar_pid=$!
    dem_pid=""
    for _ in $(seq 100); do
        dem_pid=$(child_pid "$lahar_pid" lahar-dem)
        [ -n "$dem_pid" ] && [ -e killed/bodies.h5 ] && break
        sleep 0.05
    done
    [ -n "$dem_pid" ] || { kill -9 "$lahar_pid"; fail "no lahar-dem child found"; }
    sleep 0.5
    kill -9 "$dem_pid"
    t0=$(date +%s.%N)
    wait "$lahar_pid"
    rc=$?
    t1=$(date +%s.%N) # before python starts: its start-up takes seconds on a loaded machine
    elapsed=$("$python" -c "print(round($t1 - $t0, 2))")
    cat stderr.txt
    echo "coordinator exited with $rc after ${elapsed} s"
    [ "$rc" -eq 3 ] || fail "exit status $rc, expected 3 (node lost)"
    # a dead node is reaped at once (every 50 ms while a STATUS is missing): far below the 2 s of
    # silence that would otherwise end the run
    gap=$(summary killed "s['coordinator_sched_gap_sum_s']")
    "$python" -c "import sys; sys.exit(0 if $elapsed < 4.0 + $gap else 1)" ||
        fail "took ${elapsed} s to notice (limit 4 s + the coordinator's own scheduling gaps ${gap} s)"
    grep -q "silent for [01]\.[0-9] s (killed by signal 9)" stderr.txt ||
        fail "the killed node was not noticed before its silence reached 2 s"
    grep -q "DEM node" stderr.txt || fail "message does not name the DEM node"
    grep -q "last completed step [0-9]" stderr.txt || fail "message does not give the last completed step"
    h5dump -H killed/bodies.h5 > /dev/null || fail "bodies.h5 written so far does not open"
    # the twin the killed writer left (common/io/output_snapfile.c) is removed by the coordinator
    [ ! -e killed/.bodies.h5.twin ] || fail "the killed node's killed/.bodies.h5.twin is left"
    # the force stream of the killed SWMR writer: every row it flushed reads (h5dump reads the data)
    h5dump killed/forces.h5 > /dev/null || fail "forces.h5 of the killed node does not read"
    [ "$(summary killed "s['status']")" = "node lost" ] || fail "summary.json status is not 'node lost'"
    ;;
node_stopped)
    # SIGSTOP the DEM node mid-run: a node that is alive but hung (its CPU time does not advance)
    # is still lost after 2 s; only a silent node that keeps computing is waited for (starved by
    # an overloaded machine). Exit 3, the node named, "hangs" in the reason. With --node-timeout 4
    # the same hung node is lost after 4 s of silence, not 2.
    write_case long.yaml 30
    stop_dem_run() { # out [lahar options]: run, SIGSTOP the DEM node, set rc and elapsed
        local out=$1 dem_pid="" lahar_pid t0 t1
        shift
        "$bin/lahar" run long.yaml -o "$out" -q "$@" 2> "$out.stderr" &
        lahar_pid=$!
        for _ in $(seq 100); do
            dem_pid=$(child_pid "$lahar_pid" lahar-dem)
            [ -n "$dem_pid" ] && [ -e "$out/bodies.h5" ] && break
            sleep 0.05
        done
        [ -n "$dem_pid" ] || { kill -9 "$lahar_pid"; fail "no lahar-dem child found ($out)"; }
        sleep 0.5
        kill -STOP "$dem_pid"
        t0=$(date +%s.%N)
        wait "$lahar_pid"
        rc=$?
        t1=$(date +%s.%N) # before python starts: its start-up takes seconds on a loaded machine
    elapsed=$("$python" -c "print(round($t1 - $t0, 2))")
        kill -9 "$dem_pid" 2>/dev/null
        cat "$out.stderr"
        echo "$out: coordinator exited with $rc after ${elapsed} s"
    }
    # Detection counts from the signal to the end of the lockstep (lahar's exit less summary.json
    # finish_s: STOP, the 3 s the stopped node gets before it is killed, the summary): the silence
    # (up to one 0.25 s heartbeat period of it may precede the signal), the 0.5 s probe and 1 s of
    # slack, plus the time the coordinator itself was not running while it waited (summary.json
    # coordinator_sched_gap_sum_s, not counted as the node's silence): on a loaded machine the
    # judge may be starved too, and only its own measured gaps widen the limit.
    detected() { # out: sets det and lim_extra
        det=$("$python" -c "import json; print(round($elapsed - json.load(open('$1/summary.json'))['finish_s'], 2))")
        lim_extra=$(summary "$1" "s['coordinator_sched_gap_sum_s']")
    }
    stop_dem_run stopped
    [ "$rc" -eq 3 ] || fail "exit status $rc, expected 3 (node lost)"
    detected stopped
    echo "stopped: detected after $det s (coordinator's own scheduling gaps $lim_extra s)"
    "$python" -c "import sys; sys.exit(0 if 1.7 <= $det < 3.5 + $lim_extra else 1)" ||
        fail "detected after $det s (want 1.7-3.5 s + the coordinator's own scheduling gaps $lim_extra s)"
    grep -q "DEM node.*hangs" stopped.stderr || fail "message does not name the DEM node as hung"
    stop_dem_run stopped4 --node-timeout 4
    [ "$rc" -eq 3 ] || fail "--node-timeout 4: exit status $rc, expected 3"
    detected stopped4
    echo "stopped4: detected after $det s (coordinator's own scheduling gaps $lim_extra s)"
    "$python" -c "import sys; sys.exit(0 if 3.7 <= $det < 5.5 + $lim_extra else 1)" ||
        fail "--node-timeout 4: detected after $det s (want 3.7-5.5 s + the coordinator's own scheduling gaps $lim_extra s)"
    grep -q "silent for 4.0 s" stopped4.stderr || fail "--node-timeout 4: the message does not give the 4 s"
    ;;
coordinator_killed)
    # A node started by hand (--no-spawn: no PR_SET_PDEATHSIG) gives up 5 s after the coordinator
    # went silent, with exit status 3.
    write_case long.yaml 30
    in_private_netns "
        '$bin/lahar-dem' --lcm-url '$URL_LO' 2> dem_stderr.txt & dem=\$!
        '$bin/lahar' run long.yaml -o orphan -q --no-spawn --lcm-url '$URL_LO' & coord=\$!
        for _ in \$(seq 100); do [ -e orphan/bodies.h5 ] && break; sleep 0.05; done
        sleep 0.5
        kill -9 \$coord
        t0=\$(date +%s.%N)
        set +e
        wait \$dem
        echo \$? > dem_rc.txt
        '$python' -c \"import time; print(round(time.time() - \$t0, 2))\" > dem_elapsed.txt" || fail "setup failed"
    cat dem_stderr.txt
    rc=$(cat dem_rc.txt) elapsed=$(cat dem_elapsed.txt)
    echo "lahar-dem exited with $rc, ${elapsed} s after the coordinator was killed"
    [ "$rc" -eq 3 ] || fail "lahar-dem exit status $rc, expected 3"
    "$python" -c "import sys; sys.exit(0 if 4.5 < $elapsed < 7.5 else 1)" || fail "gave up after ${elapsed} s (expected ~5 s)"
    grep -q "coordinator has been silent" dem_stderr.txt || fail "lahar-dem does not say why it stopped"
    ;;
concurrent)
    # Two runs at the same time, each in its own namespace, and two more sharing one namespace
    # (different run ids on the same multicast group): all equal the reference.
    reference
    "$bin/lahar" run case.yaml -o a -q & pa=$!
    "$bin/lahar" run case.yaml -o b -q & pb=$!
    in_private_netns "
        '$bin/lahar' run case.yaml -o c -q --lcm-url '$URL_LO' & pc=\$!
        '$bin/lahar' run case.yaml -o d -q --lcm-url '$URL_LO' & pd=\$!
        wait \$pc; wait \$pd" || fail "runs sharing one namespace failed"
    wait $pa || fail "run a failed"
    wait $pb || fail "run b failed"
    for o in a b c d; do same_as_reference $o; done
    ;;
cross_host)
    # Two "hosts": network namespaces joined by a veth pair inside a private namespace; the
    # coordinator on one, the DEM node (started by hand, ttl=1) on the other.
    reference
    unshare --user --map-root-user --net bash -c "
        set -e
        . '$here/two_hosts.sh'
        nsenter --net=\$host_b_ns '$bin/lahar-dem' --lcm-url '$URL_LINK' & dem=\$!
        '$bin/lahar' run case.yaml -o xhost -q --no-spawn --lcm-url '$URL_LINK'
        wait \$dem" || fail "cross-host run failed"
    same_as_reference xhost
    [ "$(summary xhost "s['mode']")" = no-spawn ] || fail "mode is not no-spawn"
    ;;
cross_host_auth)
    # An authenticated run across two "hosts" (--auth-key on the coordinator and the DEM node)
    # with a hostile peer on the coordinator's host (tests/lahar_attack.c) that re-publishes every
    # small frame it hears altered, with its MAC zeroed, and verbatim: the run's bodies are
    # bitwise those of the in-process reference, and summary.json counts the rejected and the
    # replayed frames. Then a DEM node without the key cannot join the keyed run (exit 2).
    write_case case.yaml 2   # 2000 steps: the attack runs through most of the run
    "$bin/lahar" run case.yaml -o ref --in-process -q || fail "in-process reference run failed"
    "$bin/lahar" keygen run.key > /dev/null || fail "lahar keygen failed"
    [ "$(stat -c %a run.key)" = 600 ] || fail "the key file is not mode 0600"
    hosts=". '$here/two_hosts.sh'"
    unshare --user --map-root-user --net bash -c "
        set -e
        $hosts
        nsenter --net=\$host_b_ns '$bin/lahar-dem' --lcm-url '$URL_LINK' --auth-key run.key & dem=\$!
        '$LAHAR_ATTACK' '$URL_LINK' 3 > attack.txt & attacker=\$!
        '$bin/lahar' run case.yaml -o auth -q --no-spawn --lcm-url '$URL_LINK' --auth-key run.key
        wait \$dem
        wait \$attacker" || fail "authenticated cross-host run failed"
    cat attack.txt
    same_as_reference auth
    [ "$(summary auth "s['auth']['enabled']")" = True ] || fail "summary.json: auth not enabled"
    rejected=$(summary auth "s['auth']['frames_rejected']")
    replayed=$(summary auth "s['auth']['frames_replayed']")
    echo "dropped (coordinator + nodes): $rejected altered or forged frames, $replayed replayed ones"
    [ "$rejected" -gt 0 ] && [ "$replayed" -gt 0 ] || fail "the hostile frames were not counted (rejected $rejected, replayed $replayed)"
    unshare --user --map-root-user --net bash -c "
        $hosts
        nsenter --net=\$host_b_ns '$bin/lahar-dem' --lcm-url '$URL_LINK' --wait 5 > /dev/null 2>&1 & dem=\$!
        set +e
        '$bin/lahar' run case.yaml -o keyless -q --no-spawn --lcm-url '$URL_LINK' --auth-key run.key --wait 3 2> keyless.txt
        echo \$? > keyless_rc.txt
        kill \$dem 2>/dev/null; wait \$dem 2>/dev/null; true"
    cat keyless.txt
    [ "$(cat keyless_rc.txt)" = 2 ] || fail "a DEM node without the key joined the keyed run (exit $(cat keyless_rc.txt), want 2)"
    ;;
engine_error)
    # An engine failure (here: a 6 m/s impact overlapping two balls by more than a tight
    # stability.max_overlap, 5 % of the smaller sweep radius; a DEM step beyond the contact's
    # stability limit is refused by the case loader) stops the run with the engine's message
    # (which bodies, which step), exit 1, and a last snapshot at the failed step.
    write_case base.yaml 0.3
    "$python" "$tools/case_override.py" base.yaml bad.yaml time.dt_max=1e-2 'dem={engine: spheropoly, dt_safety: 0.2}' \
        'stability={max_overlap: 0.05}' 'bodies.ball2.velocity=[0, 0, -6]' || fail "cannot make bad.yaml"
    "$bin/lahar" run bad.yaml -o bad -q --in-process 2> stderr.txt
    rc=$?
    cat stderr.txt
    [ "$rc" -eq 1 ] || fail "exit status $rc, expected 1"
    grep -q "the DEM node reports at step [0-9]*: body [0-9] '[a-z0-9]*' overlaps body [0-9] '[a-z0-9]*' by" stderr.txt ||
        fail "no engine message"
    "$python" - bad <<'PY' || fail "summary or last snapshot wrong"
import json, sys
import h5py
s = json.load(open(sys.argv[1] + "/summary.json"))
assert s["status"] == "unstable" and s["exit_status"] == 1, s["status"]
assert s["instability"]["what"] == "overlap" and s["instability"]["where"]["kind"] == "body", s["instability"]
failed_step = s["steps"]  # steps completed before the failing one
with h5py.File(sys.argv[1] + "/bodies.h5", "r") as f:
    last = sorted(f["snapshots"])[-1]
    g = f["snapshots"][last]
    t = float(g.attrs["time"])
# the last snapshot is the state at the end of the failed step k = steps: t_{k+1} = 0.01 (k + 1)
assert abs(t - 0.01 * (failed_step + 1)) < 1e-12, (last, t, failed_step)
print("engine_error: failed at step %d, last snapshot %s at t = %.3f s" % (failed_step, last, t))
PY
    ;;
cli)
    # The user's commands: every program documents every option in --help; validate exits 0 / 2;
    # `lahar check` on the bounce case runs (own namespace, processes) and its restitution metric
    # passes against the analytic reference (cases/README.md), exit 0.
    cases=$(cd "$tools/../cases" && pwd)
    "$bin/lahar" --help > help.txt || fail "lahar --help failed"
    for opt in --output --threads --in-process --no-spawn --lcm-url --wait --quiet; do
        grep -q -- "$opt" help.txt || fail "lahar --help does not document $opt"
    done
    for prog in lahar-dem lahar-sph; do
        "$bin/$prog" --help > help.txt || fail "$prog --help failed"
        for opt in --lcm-url --run-id --threads --wait; do
            grep -q -- "$opt" help.txt || fail "$prog --help does not document $opt"
        done
    done
    "$bin/lahar" validate "$cases/dem_bounce_3d.yaml" || fail "validate rejects a good case"
    "$bin/lahar" validate "$tools/../tests/bad_cases/dt_max_zero.yaml" 2> bad.txt
    [ $? -eq 2 ] || fail "validate accepts a bad case"
    "$bin/lahar" run "$tools/../tests/bad_cases/dt_max_zero.yaml" -o never -q 2> bad.txt
    [ $? -eq 2 ] && [ ! -e never ] || fail "run of a bad case: not exit 2 before anything ran"
    "$bin/lahar" check "$cases/dem_bounce_3d.yaml" -o bounce -q || fail "lahar check on dem_bounce_3d failed"
    "$python" -c "import json; c = json.load(open('bounce/check.json')); assert c['pass'] is True, c" ||
        fail "check.json does not say pass"
    ;;
busy_machine)
    # More OpenMP threads per node than cores: lahar notes it, and the nodes it starts run with
    # OMP_WAIT_POLICY=passive (a spinning wait takes the CPU from the threads it waits for),
    # which changes no result: bitwise the same as the user's OMP_WAIT_POLICY=active. A policy
    # the user set is kept; one thread per node is never busy. --in-process nodes share lahar's
    # OpenMP, which reads the policy before main: lahar runs itself again with it, same results.
    unset OMP_WAIT_POLICY # the suite's own (tests/CMakeLists.txt): this test is about lahar's
    cores=$(nproc)
    threads=$((2 * cores + 1))
    write_case_both both.yaml
    "$bin/lahar" run both.yaml -o busy --threads $threads 2> busy.txt || fail "run with $threads threads failed"
    grep -q "lahar: note: $threads OpenMP threads per node on $cores cores" busy.txt || fail "no note: $(cat busy.txt)"
    grep -q "The nodes run with OMP_WAIT_POLICY=passive (set by lahar" busy.txt || fail "note: $(cat busy.txt)"
    [ "$(summary busy "s['machine']['busy'], s['machine']['omp_wait_policy'], s['machine']['omp_wait_policy_set_by_lahar'], s['machine']['threads_per_node']")" = "True passive True $threads" ] ||
        fail "summary.json machine: $(summary busy "s['machine']")"
    OMP_WAIT_POLICY=active "$bin/lahar" run both.yaml -o active --threads $threads -q || fail "run with the user's policy failed"
    [ "$(summary active "s['machine']['omp_wait_policy'], s['machine']['omp_wait_policy_set_by_lahar']")" = "active False" ] ||
        fail "the user's OMP_WAIT_POLICY was not kept: $(summary active "s['machine']")"
    "$bin/lahar" run both.yaml -o inproc --threads $threads --in-process 2> inproc.txt || fail "in-process run failed"
    grep -q "The nodes run with OMP_WAIT_POLICY=passive (set by lahar" inproc.txt || fail "in-process note: $(cat inproc.txt)"
    [ "$(summary inproc "s['machine']['omp_wait_policy'], s['machine']['omp_wait_policy_set_by_lahar']")" = "passive True" ] ||
        fail "in-process: lahar did not run itself with the passive policy: $(summary inproc "s['machine']")"
    for f in bodies.h5 forces.h5 particles.h5; do
        "$python" "$tools/h5_compare.py" --quiet busy/$f active/$f || fail "$f differs between wait policies"
        "$python" "$tools/h5_compare.py" --quiet inproc/$f active/$f || fail "$f differs in-process"
    done
    # the node lahar started has the policy in its environment
    write_case long.yaml 30
    "$bin/lahar" run long.yaml -o long --threads $threads -q &
    lahar_pid=$!
    env_seen=
    for i in $(seq 1 100); do
        for p in $(child_pid $lahar_pid lahar-dem); do
            env_seen=$(tr '\0' '\n' < /proc/$p/environ | grep '^OMP_WAIT_POLICY=')
        done
        [ -n "$env_seen" ] && break
        sleep 0.1
    done
    kill -INT $lahar_pid; wait $lahar_pid
    [ "$env_seen" = "OMP_WAIT_POLICY=passive" ] || fail "lahar-dem's environment: '$env_seen'"
    # beside another lahar run that has only just started (no load to read yet): busy all the
    # same, from the other run's process; one thread per core each
    if [ "$cores" -ge 2 ]; then
        "$bin/lahar" run long.yaml -o first --threads $cores -q &
        first_pid=$!
        for i in $(seq 1 100); do
            tr '\0' ' ' < /proc/$first_pid/cmdline 2>/dev/null | grep -q "run long.yaml" && break
            sleep 0.05
        done
        "$bin/lahar" run both.yaml -o beside --threads $cores --in-process 2> beside.txt
        rc=$?
        kill -INT $first_pid; wait $first_pid
        [ $rc -eq 0 ] || fail "run beside another one failed: $(cat beside.txt)"
        grep -q "other lahar run.* on this machine's $cores cores" beside.txt || fail "no note beside another run: $(cat beside.txt)"
        [ "$(summary beside "s['machine']['other_lahar_runs'] >= 1, s['machine']['busy'], s['machine']['omp_wait_policy_set_by_lahar']")" = "True True True" ] ||
            fail "beside another run: summary.json machine: $(summary beside "s['machine']")"
    fi
    "$bin/lahar" run both.yaml -o one --threads 1 2> one.txt || fail "run with one thread failed"
    ! grep -q "note:" one.txt || fail "a note for one thread per node: $(cat one.txt)"
    [ "$(summary one "s['machine']['busy'], s['machine']['threads_per_node']")" = "False 1" ] ||
        fail "summary.json machine: $(summary one "s['machine']")"
    echo "busy_machine: $threads threads on $cores cores, and beside another run: note, passive set (processes and in-process), same results as active; user's policy kept"
    ;;
disk_full)
    # OUT on a small file system (a 5 MB tmpfs in a private user + mount namespace) that the run
    # fills: the node that cannot write says which file, "no space left on device" and the step
    # and time; the run stops with exit 1 and status "error" (no hang, no crash); every HDF5 file
    # opens with h5py and every dataset reads; the particle snapshots written before the failure
    # are bitwise those of the same run on a roomy disk; summary.json is written; no node process
    # is left.
    cases=$(cd "$tools/../cases" && pwd)
    "$python" "$tools/case_override.py" "$cases/debris_2d.yaml" full.yaml time.end=0.03 time.output_interval=0.001 ||
        fail "cannot write the case"
    "$bin/lahar" run full.yaml -o ref -q --in-process || fail "reference run failed"
    mkdir -p mnt
    unshare --user --map-root-user --mount bash -c "
        mount -t tmpfs -o size=5m tmpfs mnt || exit 9
        '$bin/lahar' run full.yaml -o mnt/out -q 2> full.stderr & lahar=\$!
        nodes=''
        while kill -0 \$lahar 2>/dev/null; do
            for stat in /proc/[0-9]*/stat; do
                read -r pid comm state ppid rest < \$stat 2>/dev/null || continue
                [ \"\$ppid\" = \$lahar ] && case \$comm in '(lahar-sph)'|'(lahar-dem)') case \" \$nodes \" in *\" \$pid \"*) ;; *) nodes=\"\$nodes \$pid\" ;; esac ;; esac
            done
            sleep 0.05
        done
        wait \$lahar; echo \$? > full_rc.txt
        echo \$nodes > full_nodes.txt
        df -k mnt | tail -1 > full_df.txt
        cp -r mnt/out full_out"
    [ -s full_rc.txt ] || fail "the tmpfs could not be mounted in a private mount namespace"
    cat full.stderr
    rc=$(cat full_rc.txt)
    echo "exit status $rc; tmpfs: $(cat full_df.txt); node pids seen: $(cat full_nodes.txt)"
    [ "$rc" -eq 1 ] || fail "exit status $rc, expected 1"
    grep -q "no space left on device" full.stderr || fail "the message does not say 'no space left on device'"
    grep -q "\.h5: no space left on device.* at step [0-9]* (t = " full.stderr || fail "the message does not name the file, step and time"
    for p in $(cat full_nodes.txt); do [ ! -e "/proc/$p" ] || fail "node process $p is left"; done
    [ -n "$(cat full_nodes.txt)" ] || fail "no node process was seen"
    "$python" - full_out ref <<'PY' || fail "files after the full disk"
import glob, json, sys
import h5py, numpy as np
out, ref = sys.argv[1], sys.argv[2]
s = json.load(open(out + "/summary.json"))
assert s["status"] == "error" and s["exit_status"] == 1, (s["status"], s["exit_status"])
assert "no space left on device" in s["message"], s["message"]
for p in sorted(glob.glob(out + "/*.h5")):
    with h5py.File(p, "r") as f:  # opens, and every dataset reads
        f.visititems(lambda n, o: o[()] if isinstance(o, h5py.Dataset) else None)
with h5py.File(out + "/particles.h5", "r") as f, h5py.File(ref + "/particles.h5", "r") as g:
    names = sorted(f["snapshots"])
    assert len(names) >= 2, names
    for name in names:
        a, b = f["snapshots"][name], g["snapshots"][name]
        assert a.attrs["time"] == b.attrs["time"], name
        for d in a:
            assert np.array_equal(a[d][()], b[d][()]), (name, d)
    t_last = float(f["snapshots"][names[-1]].attrs["time"])
print("disk_full: stopped at step %d (t = %.4g s); %d particle snapshots kept, to t = %.4g s, bitwise those of the "
      "run on a roomy disk; every HDF5 file opens" % (s["steps"], s["sim_time"], len(names), t_last))
PY
    ;;
disk_full_start)
    # OUT on a file system without room for the first snapshots: exit 2 before anything runs,
    # saying so; nothing written but the lock file.
    write_case case.yaml 0.3
    mkdir -p mnt
    unshare --user --map-root-user --mount bash -c "
        mount -t tmpfs -o size=192k tmpfs mnt || exit 9
        '$bin/lahar' run case.yaml -o mnt/out -q 2> start.stderr; echo \$? > start_rc.txt
        ls -A mnt/out > start_ls.txt"
    [ -s start_rc.txt ] || fail "the tmpfs could not be mounted in a private mount namespace"
    cat start.stderr
    rc=$(cat start_rc.txt)
    [ "$rc" -eq 2 ] || fail "exit status $rc, expected 2"
    grep -q "no space left on device" start.stderr || fail "the message does not say 'no space left on device'"
    [ "$(cat start_ls.txt)" = .lahar.lock ] || fail "files were written: $(cat start_ls.txt)"
    ;;
no_namespace)
    # When no user namespace can be created (here: nested to the kernel's limit), lahar run exits 2
    # before anything runs and says why and what to use instead.
    write_case case.yaml 0.3
    cat > nest.sh <<'SH'
if unshare --user --map-root-user true 2>/dev/null; then exec unshare --user --map-root-user bash "$0" "$@"; fi
"$@"
SH
    bash nest.sh "$bin/lahar" run case.yaml -o nons -q 2> stderr.txt
    rc=$?
    cat stderr.txt
    [ "$rc" -eq 2 ] || fail "exit status $rc, expected 2"
    grep -q "cannot create a private network namespace" stderr.txt || fail "no explanation"
    grep -q -- "--in-process" stderr.txt || fail "no alternative offered"
    [ ! -e nons/summary.json ] || fail "a run started without a namespace"
    ;;
*)
    echo "unknown test $test_name" >&2
    exit 2
    ;;
esac
echo "PASS: $test_name"
