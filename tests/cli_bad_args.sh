#!/bin/sh
# The coordinator's command line refuses bad arguments with exit status 2 and a message naming the
# option or the case file, line and key (coordinator/main.c), before anything runs.
# usage: cli_bad_args.sh LAHAR FIXTURES_DIR WORK_DIR
lahar=$1 fixtures=$2 work=$3
fail=0 pass=0
rm -rf "$work" && mkdir -p "$work"
good=$fixtures/../../cases/dem_bounce_3d.yaml
expect() { # expect STATUS PATTERN -- ARGS...
    want=$1 pattern=$2
    shift 3
    "$lahar" "$@" >"$work/out" 2>"$work/err"
    got=$?
    if [ "$got" -ne "$want" ] || { [ -n "$pattern" ] && ! grep -q -E -e "$pattern" "$work/err"; }; then
        echo "FAIL lahar $*: exit $got (want $want), stderr:"; sed 's/^/    /' "$work/err"
        echo "     (wanted a line matching: $pattern)"
        fail=$((fail + 1))
    else
        pass=$((pass + 1)); echo "ok   lahar $*: exit $got, $(head -n 1 "$work/err")"
    fi
}
expect 2 "unknown_engine.yaml:5: dem.engine: unknown DEM engine 'nosuch'; engines in this build: spheropoly" -- \
    validate "$fixtures/unknown_engine.yaml"
expect 2 "unknown_engine.yaml:5: dem.engine" -- run "$fixtures/unknown_engine.yaml" -o "$work/run" --in-process
# each engine validates what is its own: the lammps engine refuses a free box at validation, naming it
if "$lahar" validate "$fixtures/lammps_box.yaml" 2>&1 | grep -q "unknown DEM engine 'lammps'"; then
    echo "skip lammps_box.yaml: this build has no lammps engine"
else
    expect 2 "lammps_box.yaml:5: dem.engine: lammps cannot run this case: .*body 'crate'.*spheres \(3D\) and discs \(2D\)" -- \
        validate "$fixtures/lammps_box.yaml"
fi
expect 2 "--threads takes a whole number from 1 to 1024 \(got 'abc'\)" -- run "$good" -o "$work/run" --threads abc
expect 2 "--threads takes a whole number" -- run "$good" -o "$work/run" --threads 0
expect 2 "--threads takes a whole number" -- check "$good" -o "$work/run" --threads 2x
expect 2 "--wait takes a number of seconds" -- run "$good" -o "$work/run" --wait soon
expect 2 "--wait takes a number of seconds" -- run "$good" -o "$work/run" --wait 0
expect 2 "-o is empty; give the output directory's name" -- run "$good" -o "" --in-process
[ ! -e "$work/run" ] || { echo "FAIL an output directory was created for a refused command"; fail=$((fail + 1)); }
expect 0 "" -- validate "$good"
# validate says what the case costs; a case over the machine's memory is refused unless --allow-large
"$lahar" validate "$fixtures/../../cases/dam_break_2d.yaml" > "$work/validate.txt" 2>&1
if grep -q "^  3200 particles (0 soil), 3 bodies$" "$work/validate.txt" && grep -q "^  memory: about [0-9.]* MB" "$work/validate.txt" &&
   grep -q "^  cost: at least [0-9.e+]* steps to t = 1 s" "$work/validate.txt"; then
    pass=$((pass + 1)); echo "ok   validate dam_break_2d.yaml: $(sed -n 2p "$work/validate.txt")"
else
    echo "FAIL validate dam_break_2d.yaml does not state its 3200 particles, memory and cost:"; sed 's/^/    /' "$work/validate.txt"
    fail=$((fail + 1))
fi
# a terrain case: 907200 lattice points, of which the two blocks between the terrain and the
# debris surface hold 108496 (the count, not the lattice's bound, drives memory and cost)
"$lahar" validate "$fixtures/../../cases/debris_flow_3d.yaml" > "$work/validate3d.txt" 2>&1
if grep -q "^  108496 particles (54248 soil), 6 bodies$" "$work/validate3d.txt"; then
    pass=$((pass + 1)); echo "ok   validate debris_flow_3d.yaml: $(sed -n 2p "$work/validate3d.txt")"
else
    echo "FAIL validate debris_flow_3d.yaml does not count its 108496 particles:"; sed 's/^/    /' "$work/validate3d.txt"
    fail=$((fail + 1))
fi
python3 "$fixtures/../../tools/case_override.py" "$fixtures/../../cases/dam_break_3d.yaml" "$work/giant.yaml" sph.dx=0.0002 >/dev/null
expect 2 "giant.yaml needs about [0-9.]* [GT]B of memory \(at most 1875000000 particles\) but this machine has .*--allow-large" -- \
    run "$work/giant.yaml" -o "$work/giant" --in-process
[ ! -e "$work/giant" ] || { echo "FAIL an output directory was created for a refused case"; fail=$((fail + 1)); }
# an OUT with an earlier run's files is refused; --overwrite removes them first (a water run's
# particles.h5 must not stay beside a DEM-only run)
mkdir -p "$work/reuse" && echo stale > "$work/reuse/particles.h5" && echo '{}' > "$work/reuse/summary.json"
expect 2 "holds the output of an earlier run \(summary.json, particles.h5\); add --overwrite" -- \
    run "$good" -o "$work/reuse" --in-process -q
expect 0 "" -- run "$good" -o "$work/reuse" --in-process -q --overwrite
if [ -e "$work/reuse/particles.h5" ] || grep -q particles "$work/reuse/lahar.xmf"; then
    echo "FAIL --overwrite left the earlier run's particles.h5 (or lahar.xmf still points at it)"; fail=$((fail + 1))
else
    pass=$((pass + 1)); echo "ok   --overwrite removed the earlier run's particles.h5; lahar.xmf has the bodies only"
fi
# an output directory another run holds (OUT/.lahar.lock, flock) is refused, naming the holder
mkdir -p "$work/busy" && printf 'pid 4242\nhost testhost\nstarted then\ncase other.yaml\n' > "$work/busy/.lahar.lock"
sh -c 'exec 9<>"$1"; flock 9; exec sleep 30' sh "$work/busy/.lahar.lock" & holder=$!  # the lock dies with it
i=0; while flock -n "$work/busy/.lahar.lock" true 2>/dev/null && [ $i -lt 50 ]; do sleep 0.1; i=$((i + 1)); done
expect 2 "is in use by another lahar run \(pid 4242, host testhost, started then, case other.yaml\)" -- \
    run "$good" -o "$work/busy" --in-process -q
[ ! -e "$work/busy/summary.json" ] || { echo "FAIL the refused run wrote into the busy directory"; fail=$((fail + 1)); }
kill $holder 2>/dev/null; wait $holder 2>/dev/null
expect 0 "" -- run "$good" -o "$work/busy" --in-process -q
grep -q "^pid [0-9]" "$work/busy/.lahar.lock" && ! grep -q 4242 "$work/busy/.lahar.lock" ||
    { echo "FAIL the run did not write its own pid into the lock file"; fail=$((fail + 1)); }
# a key that cannot be found or reached is named with the reason, before any node starts
expect 2 "auth key $work/no.key: No such file or directory \(make one with \`lahar keygen FILE\`\)" -- \
    run "$good" -o "$work/auth" --auth-key "$work/no.key"
expect 2 "auth key $good/run.key: Not a directory \(check the path and its permissions\)" -- run "$good" -o "$work/auth" --auth-key "$good/run.key"
# lahar resume given the case instead of the run's output directory, or a directory that is not there
expect 2 "lahar resume: .*dem_bounce_3d.yaml: not a directory; resume takes the output directory of a run \(lahar resume OUT\), not its case" -- \
    resume "$good"
expect 2 "lahar resume: $work/no_such_run: No such file or directory; resume takes the output directory of a run" -- resume "$work/no_such_run"
# lahar keys takes a section as a case writes it (bodies, materials, sph.blocks) or as the table does
# (bodies[]); an unknown one is an error on stderr
for section in bodies materials sph.blocks 'bodies[]'; do
    if "$lahar" keys "$section" > "$work/keys.txt" 2>&1 && grep -q "^$(echo "$section" | sed 's/\[\]//')" "$work/keys.txt"; then
        pass=$((pass + 1)); echo "ok   lahar keys $section: $(head -c 60 "$work/keys.txt")"
    else
        echo "FAIL lahar keys $section:"; sed 's/^/    /' "$work/keys.txt"; fail=$((fail + 1))
    fi
done
expect 2 "lahar keys: unknown section 'nosuch'; the sections are: '' time materials.NAME" -- keys nosuch
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
