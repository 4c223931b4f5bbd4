#!/usr/bin/python3
"""Plot the force stream of a run (OUT/forces.h5) to a PNG.

  tools/plot_forces.py OUT [--body NAME] [-o FILE.png]

With --body: force and torque components and the contact count of that body over time.
Without: the magnitude of the force on every body (one line each; fixed bodies carry the
contact force they receive: walls, barriers). Default output OUT/forces.png or
OUT/forces_NAME.png. Works on a running job (the file is written in SWMR mode)."""
import argparse
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


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", help="run output directory (holds forces.h5)")
    ap.add_argument("--body", help="body name (default: |F| of all bodies)")
    ap.add_argument("-o", "--output", help="PNG to write")
    args = ap.parse_args()
    path = os.path.join(args.out, "forces.h5")
    try:
        f = h5py.File(path, "r", libver="latest", swmr=True)
    except OSError as e:
        print(f"plot_forces: {path}: {e}", file=sys.stderr)
        return 2
    with f:
        names = lahar_py.text_names(f.attrs.get("body_names", []))
        t = f["t"][()]
        n = len(t)  # /t grows last: the other datasets hold at least these rows
        force, torque, ncont = f["force"][:n], f["torque"][:n], f["ncontacts"][:n]
        funit = f["force"].attrs.get("units", "N")
        tunit = f["torque"].attrs.get("units", "N m")
    funit = funit.decode() if isinstance(funit, bytes) else funit
    tunit = tunit.decode() if isinstance(tunit, bytes) else tunit
    if len(t) == 0:
        print(f"plot_forces: {path}: no rows yet", file=sys.stderr)
        return 2
    if args.body:
        if args.body not in names:
            print(f"plot_forces: no body '{args.body}'; bodies: {', '.join(names)}", file=sys.stderr)
            return 2
        b = names.index(args.body)
        fig, ax = plt.subplots(3, 1, sharex=True, figsize=(8, 8))
        for k, c in enumerate("xyz"):
            ax[0].plot(t, force[:, b, k], label=f"F{c}")
            ax[1].plot(t, torque[:, b, k], label=f"M{c}")
        ax[0].plot(t, np.linalg.norm(force[:, b, :], axis=1), "k", lw=0.8, label="|F|")
        ax[2].step(t, ncont[:, b], where="post")
        ax[0].set_ylabel(f"force [{funit}]")
        ax[1].set_ylabel(f"torque [{tunit}]")
        ax[2].set_ylabel("contacts")
        ax[0].legend(loc="best")
        ax[1].legend(loc="best")
        ax[0].set_title(f"{args.body}: force and torque about its centre of mass")
        out = args.output or os.path.join(args.out, f"forces_{args.body}.png")
    else:
        fig, ax = plt.subplots(figsize=(8, 5))
        for b, n in enumerate(names):
            ax.plot(t, np.linalg.norm(force[:, b, :], axis=1), label=n)
        ax.set_ylabel(f"|force| [{funit}]")
        if len(names) <= 12:
            ax.legend(loc="best")
        ax.set_title("force on each body")
        ax = [ax]
        out = args.output or os.path.join(args.out, "forces.png")
    ax[-1].set_xlabel("t [s]")
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print(f"plot_forces: wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
