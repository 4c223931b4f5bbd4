#!/bin/sh
# The open-boundary example (cases/inflow_channel_2d.yaml) end to end: `lahar check` in-process
# (discharge against the CSV hydrograph, mass balance, outflow = inflow, steady depth = the inlet
# level: the case's check: bounds), the XDMF sidecars name datasets that exist with their
# declared shapes although the particle count changes from snapshot to snapshot, the snapshot
# viewer draws the last snapshot, and summary.json carries the flow counters.
# usage: inflow_example.sh LAHAR CASE OUT PYTHON
set -u
lahar=$1 case=$2 out=$3 python=$4
rm -rf "$out"
"$lahar" check "$case" -o "$out" --in-process --threads 1 -q || { echo "inflow_example: lahar check failed"; exit 1; }
"$python" "$(dirname "$0")/test_output_xdmf.py" "$out" || exit 1
"$python" "$(dirname "$0")/../tools/plot_snapshot.py" "$out" -o "$out/last.png" || exit 1
"$python" - "$out" <<'PY' || exit 1
import json, sys
import h5py
out = sys.argv[1]
flow = json.load(open(out + "/summary.json"))["flow"]
with h5py.File(out + "/particles.h5", "r") as f:
    snaps = sorted(f["snapshots"])
    counts = {int(f["snapshots"][s].attrs["n"]) for s in snaps}
    last = f["snapshots"][snaps[-1]].attrs
    assert len(counts) > 1, f"the particle count never changed: {counts}"
    assert flow["entered"] == last["flow_entered"] and flow["removed_water"] == last["flow_removed_water"], \
        f"summary.json flow {flow} is not the last snapshot's counters"
    assert flow["entered"] > 500 and flow["removed_water"] > 500, f"little went through: {flow}"
    # ids: unique in every snapshot, the created ones never reuse an id seen before
    first = set(f["snapshots"][snaps[0]]["id"][()].tolist())
    seen = set(first)
    for s in snaps:
        ids = f["snapshots"][s]["id"][()]
        assert len(set(ids.tolist())) == len(ids), f"snapshot {s}: an id twice"
        seen.update(ids.tolist())
    # every id handed out shows up in some snapshot here (a particle needs 0.6 s to cross the channel)
    assert max(seen) - min(seen) + 1 == len(seen), "ids are not the contiguous 0 .. created - 1"
    # the ids handed out: the blocks' 0 .. nb - 1, then one per created particle
    nb = int(sum(v < 0 for v in f["snapshots"][snaps[0]]["inlet"][()]))
    assert max(seen) < nb + flow["created"], f"id {max(seen)} beyond the {nb} + {flow['created']} handed out"
print(f"inflow_example: {len(snaps)} snapshots, counts {min(counts)}..{max(counts)}, flow {flow}")
PY
