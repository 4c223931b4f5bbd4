#!/usr/bin/env python3
"""SPHERIC Test 2: timing and the loads on the box of several runs against their spacing.

usage: plot_spheric2_convergence.py [--peaks] OUT.png "LABEL=RUN[,RUN...]" ["LABEL=RUN[,RUN...]" ...]

Each RUN is the output directory of a run of cases/dam_break_obstacle_3d.yaml or of its centre
plane (cases/dam_break_obstacle_plane_2d.yaml), any dx, any scheme, on which
tools/compare_spheric2.py has been run: the script reads only RUN/spheric2.json (a path to a .json
file works too), so every number is compare_spheric2's own. A LABEL names one series, e.g. the
scheme and the dimension: "3D delta-SPH=/tmp/d20,/tmp/d10" "plane Riemann=/tmp/r10,/tmp/r5".

Prints a Markdown table, one row per run: the first impact on P1 and the front's travel time
from H4's drop to it against the experiment (0.394 s, 0.260 s), the sustained loads on P1 and P3
(the mean over 50-150 ms after each series' own first impact; experiment 6.89 and 5.60 kPa) and
the mean distance of the levels H1 and H2 from the experiment's. For a series of three runs or
more, a row "LABEL: converged" gives, per quantity, the Richardson extrapolation from its three
finest runs with the observed order (tools/lahar_py.py richardson_extrapolate; any refinement
ratios), or why none can be read off them: "not monotone" (the differences change sign), "no
order in 0.25-4" (they shrink too slowly or too fast to be in the asymptotic range: ratio of the
coarser difference to the finer given), "no value in a run".
The PNG draws the four quantities against dx with the experiment and the converged values.
--peaks: the same table and PNG for the peaks instead: on P1 and P3 the largest sample and the
largest mean over compare_spheric2's window (10 ms unless it was given another), within 0.2 s of
each series' own first impact on P1 (the experiment's: 11.24 / 10.1 kPa on P1, 6.56 / 6.4 kPa on
P3). The level column is the same in both tables.
Exit 0, 2 on bad usage, a RUN without a readable spheric2.json or a PNG that cannot be written."""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lahar_py  # noqa: E402

lahar_py.require("matplotlib")
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

# (key, column title, value of a run, the experiment's, unit scale, unit): what the table and the
# panels show, in their order
TIMING_AND_SUSTAINED = (
    ("impact", "first impact on P1", lambda m: m["impact"]["run"], lambda m: m["impact"]["experiment"], 1.0, "s"),
    ("travel", "travel H4 drop to P1 impact", lambda m: m["travel"]["run"], lambda m: m["travel"]["experiment"],
     1.0, "s"),
    ("P1", "P1 sustained", lambda m: m["peaks"]["P1"]["plateau"], lambda m: m["peaks"]["P1"]["plateau_exp"],
     1e-3, "kPa"),
    ("P3", "P3 sustained", lambda m: m["peaks"]["P3"]["plateau"], lambda m: m["peaks"]["P3"]["plateau_exp"],
     1e-3, "kPa"),
)


def peak(probe, key, title):
    """A quantity of the --peaks table: compare_spheric2's peaks[probe][key] and the experiment's."""
    return ("%s_%s" % (probe, key), "%s %s" % (probe, title), lambda m: m["peaks"][probe][key],
            lambda m: m["peaks"][probe][key + "_exp"], 1e-3, "kPa")


PEAKS = (peak("P1", "peak", "peak (one sample)"), peak("P1", "peak_mean", "largest window mean"),
         peak("P3", "peak", "peak (one sample)"), peak("P3", "peak_mean", "largest window mean"))


fail = lahar_py.fail_usage


def load(run):
    path, m = lahar_py.read_compare_json(run, "spheric2.json", "compare_spheric2.py", fail)
    if not isinstance(m, dict) or any(k not in m for k in ("dx", "impact", "peaks", "levels")) or \
            any(p not in m["peaks"] for p in ("P1", "P3")):
        fail("%s: not the JSON of tools/compare_spheric2.py (no dx, impact, levels or P1 and P3)" % path)
    if "travel" not in m:  # an older compare_spheric2: no travel time
        m["travel"] = {"run": math.nan, "experiment": math.nan, "rel": math.nan}
    return m


def cell(value, exp, scale, unit):
    """A run's value with its deviation from the experiment, or "none" when the run has none."""
    if not math.isfinite(value):
        return "none"
    digits = 4 if unit == "s" else 2
    dev = " (%+.1f %%)" % (100 * (value / exp - 1)) if math.isfinite(exp) and exp != 0 else ""
    return "%.*f%s" % (digits, value * scale, dev)


def converged(ms, quantities):
    """{key: (q*, p), or the reason there is none as a string} from the three finest runs of a series."""
    three = ms[-3:]
    dxs = tuple(m["dx"] for m in three)
    out = {}
    for key, _, val, _, _, _ in quantities:
        q, why = lahar_py.richardson_extrapolate_or_why(dxs, tuple(val(m) for m in three))
        out[key] = q if q is not None else why
    return out


def main():
    quantities = TIMING_AND_SUSTAINED
    if "--peaks" in sys.argv[1:]:
        sys.argv.remove("--peaks")
        quantities = PEAKS
    png, series = lahar_py.convergence_args(__doc__, load, fail)
    for label, ms in series:
        dxs = [m["dx"] for m in ms]
        if len(set(dxs)) < len(dxs):
            fail("%s: two runs at the same dx (%s mm); a series is one run per spacing" % (
                label, ", ".join("%g" % (1e3 * d) for d in dxs)))

    # the experiment's values: from the first run that has them (an older JSON lacks the travel time)
    exps = {key: next((exp(m) for _, ms in series for m in ms if math.isfinite(exp(m))), math.nan)
            for key, _, _, exp, _, _ in quantities}
    print("| series | dx [mm] | %s | H1 / H2 mean \\|h - h_exp\\| [mm] |" % " | ".join(
        "%s [%s] (exp. %s)" % (title, unit, cell(exps[key], math.nan, scale, unit))
        for key, title, _, _, scale, unit in quantities))
    print("|---|---|%s---|" % ("---|" * len(quantities)))
    limits = {}
    for label, ms in series:
        for m in ms:
            print("| %s | %g | %s | %.0f / %.0f |" % (
                label, 1e3 * m["dx"],
                " | ".join(cell(val(m), exps[key], scale, unit) for key, _, val, _, scale, unit in quantities),
                1e3 * m["levels"]["H1"]["mean_abs_diff_m"], 1e3 * m["levels"]["H2"]["mean_abs_diff_m"]))
        if len(ms) >= 3:
            limits[label] = converged(ms, quantities)
            cells = []
            for key, _, _, _, scale, unit in quantities:
                q = limits[label][key]
                cells.append(q if isinstance(q, str) else "%s, order %.2f" % (cell(q[0], exps[key], scale, unit), q[1]))
            print("| %s: converged | dx %s → 0 | %s | |" % (
                label, ", ".join("%g" % (1e3 * m["dx"]) for m in ms[-3:]), " | ".join(cells)))

    fig, axes = plt.subplots(2, 2, figsize=(11, 8), sharex=True)
    dxs = [1e3 * m["dx"] for _, ms in series for m in ms]
    for ax, (key, title, val, _, scale, unit) in zip(axes.flat, quantities):
        if math.isfinite(exps[key]):
            ax.axhline(exps[key] * scale, color="k", lw=1.2, label="Kleefsman et al. 2005")
        for label, ms in series:
            line, = ax.plot([1e3 * m["dx"] for m in ms], [val(m) * scale for m in ms], "o-", label="lahar, " + label)
            q = limits.get(label, {}).get(key)
            if isinstance(q, tuple):
                ax.axhline(q[0] * scale, color=line.get_color(), ls="--", lw=1,
                           label="%s, Richardson (order %.2f)" % (label, q[1]))
        lahar_py.dx_axis(ax, dxs)
        ax.set_title(title, fontsize=10)
        ax.set_ylabel(unit)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7)
    for ax in axes[1]:
        ax.set_xlabel("dx [mm]")
    fig.tight_layout()
    lahar_py.save_png(fig, png, fail)
    return 0


if __name__ == "__main__":
    sys.exit(main())
