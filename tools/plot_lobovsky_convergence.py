#!/usr/bin/env python3
"""Lobovsky dam break: the wall pressures of several runs against their particle spacing.

usage: plot_lobovsky_convergence.py OUT.png "LABEL=RUN[,RUN...]" ["LABEL=RUN[,RUN...]" ...]

Each RUN is the output directory of a run of cases/dam_break_lobovsky_2d.yaml (any dx, any
scheme) on which tools/compare_lobovsky.py has been run: the script reads only RUN/lobovsky.json
(a path to a .json file works too), so every number is compare_lobovsky's own. A LABEL names one
series, e.g. the scheme: "delta-SPH=/tmp/d10,/tmp/d5" "Riemann=/tmp/r10,/tmp/r5".

Draws, per sensor 1-3, the peak (largest sample within 52 ms of the impact) and the largest
10 ms mean (the window compare_lobovsky was run with) against dx, with the experiment: peak
event 5 (Lobovsky et al. 2014, Fig. 18) for every sensor, and for sensor 2 the repeat spread
(2.5-97.5 % percentile series over the test runs) as a band; below, sensor 2's whole series
against that band (RMS distance from it, fraction of samples inside). Prints a Markdown table:
series, dx, impact t*, peaks and means of sensors 1-3, sensor 2 against the spread.
Exit 0, 2 on bad usage, a RUN without a readable lobovsky.json, runs compared with different
windows (--window of compare_lobovsky) or a PNG that cannot be written."""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lahar_py  # noqa: E402

lahar_py.require("matplotlib")
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from compare_lobovsky import rel_outside  # noqa: E402

SENSORS = ("sensor1", "sensor2", "sensor3")


fail = lahar_py.fail_usage


def load(run):
    path, m = lahar_py.read_compare_json(run, "lobovsky.json", "compare_lobovsky.py", fail)
    if not isinstance(m, dict) or any(k not in m for k in ("dx", "rise", "sensors")) or \
            any(s not in m["sensors"] for s in SENSORS):
        fail("%s: not the JSON of tools/compare_lobovsky.py (no dx, rise or sensors 1-3)" % path)
    return m


def spread_note(s2):
    """Sensor 2's peak and 10 ms mean against the spread, and its series against the band (from the
    values themselves: a JSON of an older compare_lobovsky lacks the derived keys)."""
    sp = s2.get("spread")
    if sp is None:
        return "-", "-", "-"
    out = []
    for q in ("peak", "peak_mean"):
        r = rel_outside(s2[q], sp["p2.5"][q], sp["p97.5"][q])
        out.append("no value" if r is None else "inside" if r == 0 else
                   "x%.2f of the top" % (1 + r) if r > 0 else "%+.1f %%" % (100 * r))
    if "rms_outside" not in sp:
        out.append("-")
    elif not math.isfinite(sp["rms_outside"]):
        out.append("no value")
    else:
        out.append("%.3f / %.0f %%" % (sp["rms_outside"], 100 * sp["inside_fraction"]))
    return out


def main():
    png, series = lahar_py.convergence_args(__doc__, load, fail)

    first = series[0][1][0]
    window = first.get("window_ms", 10)
    # the means, the experiment's means and the spread's depend on the window: one for all runs
    windows = sorted({m.get("window_ms", 10) for _, ms in series for m in ms})
    if len(windows) > 1:
        fail("the runs were compared with different --window (%s ms); run tools/compare_lobovsky.py on "
             "them all with one" % ", ".join("%g" % w for w in windows))
    # the experiment's values and the band: from a run whose JSON has sensor 2's spread
    ref = next((m for _, ms in series for m in ms if "spread" in m["sensors"]["sensor2"]), first)
    print("| series | dx [mm] | impact t* (exp. %.3f) | peak s1 / s2 / s3 (exp. %s) | %g ms mean s1 / s2 / s3 "
          "(exp. %s) | s2 peak against the spread | s2 mean against the spread | s2 series: RMS distance from the "
          "spread / inside |" % (
              ref["rise"]["experiment"], " / ".join("%.2f" % ref["sensors"][s]["peak_exp"] for s in SENSORS),
              window, " / ".join("%.2f" % ref["sensors"][s]["peak_mean_exp"] for s in SENSORS)))
    print("|---|---|---|---|---|---|---|---|")
    for label, ms in series:
        for m in ms:
            s = m["sensors"]
            n_peak, n_mean, n_series = spread_note(s["sensor2"])
            rise = "%.3f (%+.1f %%)" % (m["rise"]["run"], 100 * m["rise"]["rel"]) \
                if math.isfinite(m["rise"]["run"]) else "none (no impact in the run)"
            print("| %s | %g | %s | %s | %s | %s | %s | %s |" % (
                label, 1e3 * m["dx"], rise,
                " / ".join("%.2f" % s[n]["peak"] for n in SENSORS),
                " / ".join("%.2f" % s[n]["peak_mean"] for n in SENSORS), n_peak, n_mean, n_series))

    fig, axes = plt.subplots(3, 3, figsize=(13, 10), sharex=True)
    dxs = [1e3 * m["dx"] for _, ms in series for m in ms]
    for k, n in enumerate(SENSORS):
        for row, (q, name) in enumerate((("peak", "peak"), ("peak_mean", "%g ms mean" % window))):
            ax = axes[row, k]
            ax.axhline(ref["sensors"][n][q + "_exp"], color="k", lw=1.2, label="Lobovsky 2014, peak event 5")
            sp = ref["sensors"][n].get("spread")
            if sp is not None:
                ax.axhspan(sp["p2.5"][q], sp["p97.5"][q], color="0.8", label="Lobovsky 2014, 2.5-97.5 % of the runs")
            for label, ms in series:
                ax.plot([1e3 * m["dx"] for m in ms], [m["sensors"][n][q] for m in ms], "o-", label="lahar, " + label)
            lahar_py.dx_axis(ax, dxs)
            if q == "peak":
                ax.set_yscale("log")
            ax.set_title("%s: %s" % (n, name), fontsize=10)
            ax.grid(alpha=0.3, which="both")
            if k == 0:
                ax.set_ylabel("p/ρgH")
    for k, (q, name) in enumerate((("rms_outside", "RMS distance from the spread [ρgH]"),
                                   ("inside_fraction", "fraction of samples inside the spread"))):
        ax = axes[2, k]
        drawn = []
        for label, ms in series:
            # runs without the value (an older compare_lobovsky) or without an impact (NaN) left out
            pts = [(1e3 * m["dx"], m["sensors"]["sensor2"]["spread"][q]) for m in ms
                   if math.isfinite(m["sensors"]["sensor2"].get("spread", {}).get(q, math.nan))]
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", label="lahar, " + label)
            drawn += [p[1] for p in pts]
        lahar_py.dx_axis(ax, dxs)
        if q == "rms_outside" and any(v > 0 for v in drawn):
            ax.set_yscale("log")
        else:
            ax.set_ylim(0, 1)
        ax.set_title("sensor 2, series over 52 ms: " + name, fontsize=9)
        ax.grid(alpha=0.3, which="both")
        ax.set_xlabel("dx [mm]")
    axes[2, 2].axis("off")
    axes[0, 1].legend(fontsize=7)
    fig.tight_layout()
    lahar_py.save_png(fig, png, fail)
    return 0


if __name__ == "__main__":
    sys.exit(main())
