#!/usr/bin/python3
"""Plot the comparison `lahar check` made (OUT/check.json) to OUT/check.png.

  tools/plot_check.py OUT [-o FILE.png]

check.json carries the metrics and either one measured/reference series over t ("plot": t,
measured, reference; drawn with the residual below it) or panels of labelled curves ("plot":
panels: [{title, xlabel, ylabel, ylog, curves: [{label, kind: measured|reference, x, y}]}], one
subplot each: e.g. velocity profiles at several times next to the analytic ones, a force history
next to its reference line). `lahar check` runs this script itself after writing check.json.
Exit 3 when matplotlib is missing (lahar check then says so and keeps check.json)."""
import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lahar_py  # noqa: E402

lahar_py.require("matplotlib")
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def fmt(v):
    """A metric value; cJSON writes NaN as null."""
    return "nan" if v is None else f"{v:.4g}"


def plot_series(plot, summary):
    """One measured/reference series over t, the residual below."""
    fig, (ax, axr) = plt.subplots(2, 1, sharex=True, figsize=(8, 7), gridspec_kw={"height_ratios": [3, 1]})
    t, meas, ref = plot["t"], plot["measured"], plot["reference"]
    ax.plot(t, meas, "o", ms=3, label="lahar")
    ax.plot(t, ref, "-", label="reference")
    ax.set_ylabel(plot.get("ylabel", ""))
    ax.legend(loc="best")
    ax.set_title(summary, fontsize=9)
    axr.plot(t, [m - r for m, r in zip(meas, ref)], ".", ms=3)
    axr.set_ylabel("lahar - reference")
    axr.set_xlabel(plot.get("xlabel", ""))
    fig.tight_layout()
    return fig


def plot_panels(panels, summary):
    """One subplot per panel; measured curves as markers, reference curves as lines. A reference
    curve right after a single measured one shares its colour (profile at t_i vs series at t_i);
    one after several measured curves (e.g. both plates vs one reference) is black."""
    fig, axes = plt.subplots(len(panels), 1, figsize=(8, 4.2 * len(panels)), squeeze=False)
    colours = plt.rcParams["axes.prop_cycle"].by_key().get("color", ["C0"])
    for ax, panel in zip(axes[:, 0], panels):
        ci, run = -1, 0
        for curve in panel.get("curves", []):
            measured = curve.get("kind") == "measured"
            if measured:
                ci, run = ci + 1, run + 1
                colour = colours[ci % len(colours)]
            else:
                colour = colours[ci % len(colours)] if run == 1 else "k"
                run = 0
            if measured:
                ax.plot(curve["x"], curve["y"], "o", ms=3, color=colour, label=curve.get("label", "lahar"))
            else:
                ax.plot(curve["x"], curve["y"], "-", lw=1.2, color=colour, label=curve.get("label", "reference"))
        if panel.get("ylog"):
            ax.set_yscale("log")
        ax.set_xlabel(panel.get("xlabel", ""))
        ax.set_ylabel(panel.get("ylabel", ""))
        ax.set_title(panel.get("title", ""), fontsize=9)
        if len(panel.get("curves", [])) <= 14:
            ax.legend(loc="best", fontsize=7)
    fig.suptitle(summary, fontsize=9)
    fig.tight_layout()
    return fig


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", help="run output directory (holds check.json)")
    ap.add_argument("-o", "--output", help="PNG to write (default OUT/check.png)")
    args = ap.parse_args()
    path = os.path.join(args.out, "check.json")
    try:
        with open(path) as fh:
            check = json.load(fh)
    except (OSError, ValueError) as e:
        print(f"plot_check: {path}: {e}", file=sys.stderr)
        return 2
    plot = check.get("plot") or {}
    lines = [f"{name} = {fmt(m.get('value'))} (bound {fmt(m.get('bound'))}) {'pass' if m.get('pass') else 'FAIL'}"
             for name, m in check.get("metrics", {}).items()]
    summary = (plot.get("title") or check.get("reference", "")) + "\n" + "; ".join(lines)
    if plot.get("panels"):
        fig = plot_panels(plot["panels"], summary)
    elif plot.get("t"):
        fig = plot_series(plot, summary)
    else:
        print(f"plot_check: {path}: nothing to plot ({check.get('error', 'no series')})", file=sys.stderr)
        return 2
    out = args.output or os.path.join(args.out, "check.png")
    fig.savefig(out, dpi=120)
    print(f"plot_check: wrote {out} ({'PASS' if check.get('pass') else 'FAIL'})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
