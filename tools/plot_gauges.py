#!/usr/bin/python3
"""Plot the trackers, the body energies and the control volumes of a run to PNGs.

  tools/plot_gauges.py OUT [--tmax S] [--prefix NAME]

Writes, for what the run has (OUT/gauges.h5, OUT/forces.h5):
  OUT/trackers.png         per tracker (one row each) its velocity in x (left) and y (right; z in
                           3D) over t, as Trujillo-Vela et al. 2020 Fig. 18 and 25, and their paths
                           over the initial and final particles in an extra panel (x-z in 3D)
  OUT/body_energy.png      per moving body its potential energy E_P (eq. 37; m g y_B, 0 at y = 0)
                           and kinetic energy E_K (eq. 38) over t, as Fig. 26
  OUT/control_volumes.png  per control volume its kinetic energy (eq. 39: particles and bodies
                           inside; log scale, as Fig. 28) and its mass flux per phase
Works on a running job (the files are read in SWMR mode). Exit 0, 2 on bad input."""
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


def open_swmr(path):
    try:
        return h5py.File(path, "r", libver="latest", swmr=True)
    except OSError:
        return None


def units(ds):
    u = ds.attrs.get("units", b"")
    return u.decode() if isinstance(u, bytes) else u


def clip(t, tmax):
    return np.ones(len(t), bool) if tmax is None else t <= tmax


def save(fig, out, name):
    """Lay out, write OUT/name at 110 dpi, close; the path."""
    fig.tight_layout()
    path = os.path.join(out, name)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_trackers(out, g, tmax):
    names = list(g.keys())
    # 3D (z up): the velocity along the flow and the vertical one, paths in the x-z plane
    up = "z" if any("vz" in g[n] for n in names) else "y"
    fig, ax = plt.subplots(len(names) + 1, 2, figsize=(10, 2.6 * (len(names) + 1)), squeeze=False)
    for k, n in enumerate(names):
        tr = g[n]
        t = tr["t"][:]
        m = clip(t, tmax)
        for c, comp in enumerate(("vx", "v" + up)):
            ax[k][c].plot(t[m], tr[comp][:][m], "b-")
            ax[k][c].set_ylabel("%s %s (%s)" % (n, comp, units(tr[comp])))
            ax[k][c].grid(alpha=0.3)
        if len(t):
            ax[k][0].set_title("tracker %s (particle id %d)" % (n, int(tr["id"][0])))
    for c in range(2):
        ax[len(names) - 1][c].set_xlabel("t (s)")
    # paths over the first and last particle snapshots
    pa = ax[len(names)][0]
    pf = open_swmr(os.path.join(out, "particles.h5"))
    if pf is not None and "snapshots" in pf and len(pf["snapshots"]):
        snaps = sorted(pf["snapshots"].keys())
        for s, col, lab in ((snaps[0], "0.75", "initial"), (snaps[-1], "tab:purple", "last snapshot")):
            sg = pf["snapshots"][s]
            pa.plot(sg["x"][:], sg[up][:], ".", ms=1, color=col, label="%s (t = %.3g s)" % (lab, sg.attrs["time"]))
        pf.close()
    for n in names:
        tr = g[n]
        m = clip(tr["t"][:], tmax)
        pa.plot(tr["x"][:][m], tr[up][:][m], "r--", lw=1)
        if m.any():
            pa.plot(tr["x"][0], tr[up][0], "go")
            pa.annotate(n, (tr["x"][0], tr[up][0]))
    pa.set_aspect("equal", adjustable="datalim")
    pa.set_xlabel("x (m)")
    pa.set_ylabel("%s (m)" % up)
    pa.set_title("tracker paths (red), start points (green)")
    pa.legend(fontsize=7, markerscale=8)
    ax[len(names)][1].axis("off")
    return save(fig, out, "trackers.png")


def plot_body_energy(out, f, tmax):
    if "energy" not in f:
        return None
    t = f["t"][:]
    m = clip(t, tmax)
    e = f["energy"][:]
    names = lahar_py.text_names(f.attrs.get("body_names", []))
    moving = [b for b in range(e.shape[1]) if np.any(e[:, b, 1] != 0) or np.any(e[:, b, 0] != 0)]
    if not moving:
        return None
    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    for b in moving:
        lab = names[b] if b < len(names) else "body %d" % b
        ax[0].plot(t[m], e[m, b, 0], label=lab)
        ax[1].plot(t[m], e[m, b, 1], label=lab)
    ax[0].set_title("potential energy E_P = m g y_B (Trujillo-Vela et al. 2020 eq. 37)")
    ax[1].set_title("kinetic energy E_K = m |u_B|^2 / 2 (eq. 38)")
    for a, lab in zip(ax, ("E_P", "E_K")):
        a.set_xlabel("t (s)")
        a.set_ylabel("%s (%s)" % (lab, units(f["energy"])))
        a.grid(alpha=0.3)
        a.legend(fontsize=8)
    return save(fig, out, "body_energy.png")


def plot_control_volumes(out, g, tmax):
    names = list(g.keys())
    fig, ax = plt.subplots(len(names), 2, figsize=(11, 3.2 * len(names)), squeeze=False)
    for k, n in enumerate(names):
        cv = g[n]
        t = cv["t"][:]
        m = clip(t, tmax)
        a = ax[k][0]
        for key, style in (("ek", "k-"), ("ek_water", "b:"), ("ek_soil", "y--"), ("ek_bodies", "m-.")):
            y = cv[key][:][m]
            if np.any(y > 0):
                a.semilogy(t[m], np.where(y > 0, y, np.nan), style, label=key)
        a.set_title("%s: kinetic energy inside (eq. 39)" % n)
        a.set_ylabel("E_K (%s)" % units(cv["ek"]))
        a.grid(alpha=0.3)
        a.legend(fontsize=8)
        a = ax[k][1]
        for key, style in (("flux_water", "b-"), ("flux_soil", "y-")):
            a.plot(t[m], cv[key][:][m], style, label=key)
        a.set_title("%s: mass flux along %s" % (n, cv.attrs.get("axis", b"x").decode()
                                                 if isinstance(cv.attrs.get("axis", b"x"), bytes)
                                                 else cv.attrs.get("axis", "x")))
        a.set_ylabel("q (%s)" % units(cv["flux_water"]))
        a.grid(alpha=0.3)
        a.legend(fontsize=8)
    for c in range(2):
        ax[-1][c].set_xlabel("t (s)")
    return save(fig, out, "control_volumes.png")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", help="run output directory")
    ap.add_argument("--tmax", type=float, help="last time shown (s)")
    a = ap.parse_args()
    if not os.path.isdir(a.out):
        print("plot_gauges: %s is not a directory; give a run's output directory" % a.out, file=sys.stderr)
        return 2
    wrote = []
    gf = open_swmr(os.path.join(a.out, "gauges.h5"))
    if gf is not None:
        if "trackers" in gf and len(gf["trackers"]):
            wrote.append(plot_trackers(a.out, gf["trackers"], a.tmax))
        if "control_volumes" in gf and len(gf["control_volumes"]):
            wrote.append(plot_control_volumes(a.out, gf["control_volumes"], a.tmax))
        gf.close()
    ff = open_swmr(os.path.join(a.out, "forces.h5"))
    if ff is not None:
        p = plot_body_energy(a.out, ff, a.tmax)
        if p:
            wrote.append(p)
        ff.close()
    if not wrote:
        print("plot_gauges: %s has no trackers, control volumes or moving bodies (gauges.h5 / forces.h5)" % a.out,
              file=sys.stderr)
        return 2
    for p in wrote:
        print("plot_gauges: wrote %s" % p)
    return 0


if __name__ == "__main__":
    sys.exit(main())
