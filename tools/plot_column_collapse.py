#!/usr/bin/python3
"""Run-out of the dry-sand column collapses (cases/granular_column_*_2d.yaml) against the published
2D scalings, and against dx: reads the check.json of `lahar check` outputs, writes a CSV and a PNG.

usage: plot_column_collapse.py OUT.png OUT.csv RUN_DIR [RUN_DIR ...]
Each RUN_DIR is a `lahar check` output of a granular_collapse case (its check.json carries
aspect_ratio, runout_mass99_normalised, runout_normalised); dx is sph.dx of the case its check.json
names, else the directory name's last '_' field (e.g. OUT/a1_0.005). Scalings: docs/soil/column_collapse_scalings.md (Lube et al. 2005, Lajeunesse et
al. 2005, as quoted by Lagree, Staron & Popinet 2011, eq. 3.1)."""
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lahar_py  # noqa: E402

lahar_py.require("matplotlib", "numpy")

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def band(a):
    """[min, max] of the branches that apply at a (coordinator/check/check_soil_collapse.c, granular_collapse)."""
    br = []
    if a < 2.8:
        br.append(1.2 * a)
    if a > 1.8:
        br.append(1.9 * a ** (2 / 3))
    if a <= 3.0:
        br.append(1.8 * a)
    if a >= 3.0:
        br.append(2.3 * a ** (2 / 3))
    return min(br), max(br)


def run_dx(d, check):
    """sph.dx of the case the run's check.json names, else the directory name's last '_' field."""
    try:
        import yaml
        with open(check["case"]) as f:
            return float(yaml.safe_load(f)["sph"]["dx"])
    except Exception:
        return float(os.path.basename(os.path.normpath(d)).split("_")[-1])


def main():
    if len(sys.argv) > 1 and sys.argv[1] in ("-h", "--help"):
        print(__doc__)
        return
    if len(sys.argv) < 4:
        sys.stderr.write(__doc__ + "\n")
        sys.exit(2)
    png, csv, runs = sys.argv[1], sys.argv[2], sys.argv[3:]
    rows = []
    for d in runs:
        check = json.load(open(os.path.join(d, "check.json")))
        info = check["info"]
        dx = run_dx(d, check)
        rows.append((info["aspect_ratio"], dx, info["runout_mass99_normalised"], info["runout_normalised"]))
    rows.sort()
    with open(csv, "w") as f:
        f.write("aspect_ratio,dx_m,runout_mass99_normalised,runout_front_normalised\n")
        for r in rows:
            f.write("%.4g,%.4g,%.5f,%.5f\n" % r)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.5))
    aa = np.linspace(0.3, 5, 200)
    lo_hi = np.array([band(a) for a in aa])
    ax1.fill_between(aa, lo_hi[:, 0], lo_hi[:, 1], color="0.85", label="band of the two fits")
    ax1.plot(aa, [1.2 * a if a < 2.3 else 1.9 * a ** (2 / 3) for a in aa], "k--", lw=1,
             label="Lube et al. 2005: 1.2 a / 1.9 a^(2/3)")
    ax1.plot(aa, [1.8 * a if a < 3 else 2.3 * a ** (2 / 3) for a in aa], "k:", lw=1,
             label="Lajeunesse et al. 2005: 1.8 a / 2.3 a^(2/3)")
    dxs = sorted({r[1] for r in rows})
    marks = {dx: m for dx, m in zip(dxs, "os^D")}
    for dx in dxs:
        sel = [r for r in rows if r[1] == dx]
        ax1.plot([r[0] for r in sel], [r[2] for r in sel], marks[dx], ms=6, label="lahar L_99, dx = %g mm" % (dx * 1e3))
        ax1.plot([r[0] for r in sel], [r[3] for r in sel], marks[dx], ms=4, mfc="none", color="0.4")
    ax1.plot([], [], "o", mfc="none", color="0.4", label="lahar front particle (open)")
    ax1.set_xlabel("a = H0 / L0")
    ax1.set_ylabel("(L_inf - L0) / L0")
    ax1.set_title("dry sand, phi = 30 deg: run-out against the 2D scalings")
    ax1.legend(fontsize=7)
    for a in sorted({r[0] for r in rows}):
        sel = sorted([r for r in rows if r[0] == a], key=lambda r: r[1])
        ax2.plot([r[1] * 1e3 for r in sel], [r[2] for r in sel], "-o", label="a = %g, L_99" % a)
        ax2.plot([r[1] * 1e3 for r in sel], [r[3] for r in sel], ":", marker="o", mfc="none", color="0.5")
    ax2.plot([], [], ":o", mfc="none", color="0.5", label="front particle")
    ax2.set_xscale("log")
    ax2.set_xlabel("dx (mm)")
    ax2.set_ylabel("(L_inf - L0) / L0")
    ax2.set_title("run-out against the particle spacing")
    ax2.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(png, dpi=90)
    print("plot_column_collapse: wrote %s and %s" % (png, csv))


if __name__ == "__main__":
    main()
