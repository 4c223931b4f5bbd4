#!/usr/bin/env python3
"""K of the sphere_array check (cases/sphere_array_3d.yaml) against Zick & Homsy (1982).

usage: plot_sphere_array.py OUT.png RUN [RUN ...]
RUN: an output directory of `lahar check` on a sphere_array case (its check.json), optionally
followed by ':a_over_dx' (the resolution to plot it at) and ':LABEL' (a series name added to
"c = ...", e.g. the speed of sound). Left: K / K_ref against a/dx for the
runs at each solid fraction (at the run's end, and at the peak of U_s, where K is lowest).
Right: K against c, the reference curve and the runs' end values.
"""
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lahar_py  # noqa: E402

lahar_py.require("matplotlib")

import matplotlib  # noqa: E402
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(argv):
    if len(argv) > 1 and argv[1] in ("-h", "--help"):
        print(__doc__)
        return 0
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    runs = []
    for arg in argv[2:]:
        path, _, rest = arg.partition(":")
        res, _, tag = rest.partition(":")
        d = json.load(open(path.rstrip("/") + "/check.json"))
        i = d["info"]
        u = d["plot"]["panels"][0]["curves"][0]["y"]
        k_peak = i["K_measured"] * i["U_superficial"] / max(u)
        runs.append((i["solid_fraction"], float(res) if res else float("nan"), i["K_measured"], k_peak,
                     i["K_reference"], d, tag))
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(10, 4))
    for c, tag in sorted({(round(r[0], 4), r[6]) for r in runs}):
        rs = sorted((r for r in runs if round(r[0], 4) == c and r[6] == tag and r[1] == r[1]), key=lambda r: r[1])
        if not rs:
            continue
        name = f"c = {c:.3g}" + (f", {tag}" if tag else "")
        ax.plot([r[1] for r in rs], [r[2] / r[4] for r in rs], "o-", label=f"{name}, end of run")
        if not tag:
            ax.plot([r[1] for r in rs], [r[3] / r[4] for r in rs], "x--", label=f"{name}, peak of U_s")
    ax.axhline(1.0, color="k", lw=0.8)
    ax.axhspan(0.95, 1.05, color="0.9")
    ax.set_xlabel("a / dx")
    ax.set_ylabel("K / K_Zick-Homsy")
    ax.set_title("sphere array: K against resolution")
    ax.legend(fontsize=7)
    ref = runs[0][5]["plot"]["panels"][1]["curves"][0]
    bx.plot(ref["x"], ref["y"], "k-", label="Zick & Homsy 1982 / dilute series")
    bx.plot([r[0] for r in runs], [r[2] for r in runs], "o", label="lahar (end of run)")
    bx.set_yscale("log")
    bx.set_xlabel("solid fraction c")
    bx.set_ylabel("K = rho a_x L^3 / (6 pi mu a U_s)")
    bx.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(argv[1], dpi=80)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
