#!/usr/bin/python3
"""Plot the probes of a run (OUT/gauges.h5, case section probes:) to a PNG.

  tools/plot_probes.py OUT [--probe NAME ...] [--csv FILE [--csv-label TEXT]] [--scale-p PA]
                           [--scale-h M] [--scale-t S] [--t0 S] [--tmax S] [-o FILE.png]

One panel per probe: p(t) in Pa (or p / scale-p and t / scale-t, e.g. rho g H and sqrt(H/g) for
dimensionless axes); a level gauge (kind: level) h(t) in m (or h / scale-h, e.g. H). --csv FILE adds an experiment beside the runs: a CSV (or whitespace)
table whose first column is t and whose next columns are the probes in the order plotted
(columns named like the probes in a header row are matched by name instead); its values are in
the same units as the plot (pass them already scaled when --scale-* are given). --t0 shifts the
run's time (t - t0; e.g. the gate opening). Default output OUT/probes.png. Works on a running
job (the file is written in SWMR mode)."""
import argparse
import csv
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lahar_py  # noqa: E402

lahar_py.require("h5py", "numpy", "matplotlib")
import h5py  # noqa: E402
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def read_table(path):
    """(header or None, 2D float array) of a CSV / whitespace table; lines starting with # skipped."""
    with open(path, newline="") as fh:
        lines = [ln for ln in fh if ln.strip() and not ln.lstrip().startswith("#")]
    delim = "," if "," in lines[0] else None
    rows = list(csv.reader(lines, delimiter=",")) if delim else [ln.split() for ln in lines]
    header = None
    try:
        float(rows[0][0])
    except ValueError:
        header, rows = [h.strip() for h in rows[0]], rows[1:]
    return header, np.array([[float(v) for v in r] for r in rows])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", help="run output directory (holds gauges.h5)")
    ap.add_argument("--probe", action="append", help="probe name (repeat; default: all)")
    ap.add_argument("--csv", help="experiment table: t, then one column per probe")
    ap.add_argument("--csv-label", default="experiment")
    ap.add_argument("--scale-p", type=float, default=1.0, help="divide p by this (Pa)")
    ap.add_argument("--scale-h", type=float, default=1.0, help="divide level gauges' h by this (m)")
    ap.add_argument("--scale-t", type=float, default=1.0, help="divide t by this (s)")
    ap.add_argument("--t0", type=float, default=0.0, help="subtract from the run's t before scaling (s)")
    ap.add_argument("--tmax", type=float, help="last time shown (scaled units)")
    ap.add_argument("-o", "--output", help="PNG to write")
    a = ap.parse_args()
    path = os.path.join(a.out, "gauges.h5")
    try:
        f = h5py.File(path, "r", libver="latest", swmr=True)
    except OSError as e:
        sys.stderr.write(f"plot_probes: cannot open {path}: {e}\n")
        return 2
    names = [n.decode() if isinstance(n, bytes) else str(n) for n in f.attrs.get("probe_names", [])]
    want = a.probe or names
    for n in want:
        if n not in names:
            sys.stderr.write(f"plot_probes: no probe '{n}' in {path} (probes: {', '.join(names)})\n")
            return 2
    exp = read_table(a.csv) if a.csv else None
    fig, axes = plt.subplots(len(want), 1, figsize=(9, 2.6 * len(want)), sharex=True, squeeze=False)
    for k, (n, ax) in enumerate(zip(want, axes[:, 0])):
        g = f["probes"][n]
        t = (g["t"][:] - a.t0) / a.scale_t
        level = "h" in g
        p = g["h"][:] / a.scale_h if level else g["p"][:] / a.scale_p
        pos = ", ".join(f"{v:g}" for v in g.attrs["position"])
        body = g.attrs.get("body", "")
        body = body.decode() if isinstance(body, bytes) else body
        size = float(g.attrs.get("size", 0.0))
        ax.plot(t, p, lw=0.7, label=f"lahar ({len(t)} samples)")
        if exp is not None:
            header, tab = exp
            col = header.index(n) if header and n in header else k + 1
            if col < tab.shape[1]:
                ax.plot(tab[:, 0], tab[:, col], "k", lw=1.2, alpha=0.7, label=a.csv_label)
        if level:
            ax.set_title(f"{n}: water level on the vertical line from ({pos}) m", fontsize=9)
            ax.set_ylabel("h / " + (f"{a.scale_h:g} m" if a.scale_h != 1.0 else "m"))
        else:
            ax.set_title(f"{n}: ({pos}) m" + (f" on {body}" if body else " in the fluid") +
                         (f", sensor {1000 * size:g} mm" if size > 0 else ""), fontsize=9)
            ax.set_ylabel("p / " + (f"{a.scale_p:g} Pa" if a.scale_p != 1.0 else "Pa"))
        ax.grid(alpha=0.3)
        if a.tmax is not None:
            ax.set_xlim(right=a.tmax)
        ax.legend(fontsize=8, loc="upper right")
    axes[-1, 0].set_xlabel("t" + (f" / {a.scale_t:g} s" if a.scale_t != 1.0 else " (s)") +
                           (f", from t0 = {a.t0:g} s" if a.t0 else ""))
    fig.tight_layout()
    out = a.output or os.path.join(a.out, "probes.png")
    fig.savefig(out, dpi=100)
    print(f"plot_probes: wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
