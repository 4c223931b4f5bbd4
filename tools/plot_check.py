#!/usr/bin/python3
"""Plot the comparison `lahar check` made (OUT/check.json) to OUT/check.png.

  tools/plot_check.py OUT [-o FILE.png]

check.json carries the measured and reference series ("plot": t, measured, reference) and the
metrics; `lahar check` runs this script itself after writing check.json. Exit 3 when matplotlib
is missing (lahar check then says so and keeps check.json)."""
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
    plot = check.get("plot")
    if not plot or not plot.get("t"):
        print(f"plot_check: {path}: nothing to plot ({check.get('error', 'no series')})", file=sys.stderr)
        return 2
    fig, (ax, axr) = plt.subplots(2, 1, sharex=True, figsize=(8, 7), gridspec_kw={"height_ratios": [3, 1]})
    t, meas, ref = plot["t"], plot["measured"], plot["reference"]
    ax.plot(t, meas, "o", ms=3, label="lahar")
    ax.plot(t, ref, "-", label="reference")
    ax.set_ylabel(plot.get("ylabel", ""))
    ax.legend(loc="best")
    lines = [f"{name} = {m['value']:.4g} (bound {m['bound']:.4g}) {'pass' if m['pass'] else 'FAIL'}"
             for name, m in check.get("metrics", {}).items()]
    ax.set_title(plot.get("title", check.get("reference", "")) + "\n" + "; ".join(lines), fontsize=9)
    axr.plot(t, [m - r for m, r in zip(meas, ref)], ".", ms=3)
    axr.set_ylabel("lahar - reference")
    axr.set_xlabel(plot.get("xlabel", ""))
    fig.tight_layout()
    out = args.output or os.path.join(args.out, "check.png")
    fig.savefig(out, dpi=120)
    print(f"plot_check: wrote {out} ({'PASS' if check.get('pass') else 'FAIL'})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
