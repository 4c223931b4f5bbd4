#!/usr/bin/env python3
"""Tables of tests/stress/liveness_load.sh's results.csv (markdown on stdout).

usage: liveness_report.py results.csv"""
import csv
import statistics
import sys


def num(v):
    try:
        return float(v)
    except ValueError:
        return None


def span(vals, fmt="%.2f"):
    vals = [v for v in vals if v is not None]
    if not vals:
        return "—"
    if len(vals) == 1:
        return fmt % vals[0]
    return (fmt + " / " + fmt + " / " + fmt) % (min(vals), statistics.median(vals), max(vals))


def main():
    rows = list(csv.DictReader(open(sys.argv[1])))
    kinds = []
    for r in rows:
        k = (r["phase"], r["kind"])
        if k not in kinds:
            kinds.append(k)
    fp = [k for k in kinds if k[0] == "fp"]
    if fp:
        print("False positives at load (short runs, --threads 2; silences in s, min / median / max):\n")
        print("| runs | kind | finished | lost (false positive) | other | longest silence heard, DEM node | SPH node "
              "| silences forgiven as starved (runs) | coordinator's longest scheduling gap | load average |")
        print("|---|---|---|---|---|---|---|---|---|---|")
        for k in fp:
            rs = [r for r in rows if (r["phase"], r["kind"]) == k]
            fin = sum(r["status"] == "finished" for r in rs)
            lost = sum("LOST" in r["note"] for r in rs)
            starved = sum(int(r["starved"] or 0) > 0 for r in rs)
            print("| %d | %s | %d | %d | %d | %s | %s | %d (%d) | %s | %s |" % (
                len(rs), k[1], fin, lost, len(rs) - fin - lost,
                span([num(r["max_silence_dem_s"]) for r in rs]), span([num(r["max_silence_sph_s"]) for r in rs]),
                sum(int(r["starved"] or 0) for r in rs), starved,
                span([num(r["coord_gap_max_s"]) for r in rs], "%.3f"), span([num(r["loadavg"]) for r in rs], "%.1f")))
        print()
    other = [k for k in kinds if k[0] != "fp"]
    if other:
        print("Injected faults (times in s from the fault, min / median / max):\n")
        print("| fault | runs | exit status | status | lost after | lahar exited after | run wall time | load average "
              "| notes (last run) |")
        print("|---|---|---|---|---|---|---|---|---|")
        for k in other:
            rs = [r for r in rows if (r["phase"], r["kind"]) == k]
            rcs = sorted(set(r["rc"] for r in rs))
            sts = sorted(set(r["status"] for r in rs))
            print("| %s | %d | %s | %s | %s | %s | %s | %s | %s |" % (
                k[1], len(rs), ", ".join(rcs), ", ".join(sts), span([num(r["detect_s"]) for r in rs]),
                span([num(r["exit_s"]) for r in rs]), span([num(r["wall_s"]) for r in rs]), span([num(r["loadavg"]) for r in rs], "%.1f"), rs[-1]["note"]))
        print()


if __name__ == "__main__":
    main()
