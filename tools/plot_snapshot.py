#!/usr/bin/python3
"""Draw one snapshot of a run: fluid particles coloured by speed (or pressure) and the outlines of
the bodies (display meshes of OUT/bodies.h5), to a PNG.

  tools/plot_snapshot.py OUT [--time T | --step K | --index I] [--color speed|pressure]
                             [--view xy|xz|yz] [-o FILE.png]
  tools/plot_snapshot.py OUT --all [-o DIR]

Without --time/--step/--index: the last snapshot. --time T picks the snapshot nearest to T s,
--step K the one nearest to solver step K, --index I snapshot number I (negative counts from the
end). --all writes every snapshot to DIR (default OUT/frames/snapshot_NNNNNN.png) with one
colour scale for the whole series. Default output: OUT/snapshot_NNNNNN.png.
2D runs are drawn in the x-y plane; 3D runs are projected onto --view (default xz: a side view
with z up). Moving bodies are drawn at their snapshot pose, fixed bodies (walls, terrain) in grey.
Runs with open boundaries (inlets:, outlets:, domain:): each snapshot has its own particle count;
the inlets' buffer particles (dataset `inlet` >= 0) are drawn in light grey and the title adds
the particles that entered and left so far (attributes flow_*).
Works on runs with only bodies or only particles, and on a run still going (last complete
snapshot)."""
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
from matplotlib.collections import LineCollection, PolyCollection  # noqa: E402

AXES = {"xy": (0, 1), "xz": (0, 2), "yz": (1, 2)}


def snapshot_list(f):
    """[(name, time, step)] of the complete snapshots of an open bodies/particles file, in order."""
    out = []
    if "snapshots" not in f:
        return out
    for name in sorted(f["snapshots"].keys()):
        g = f["snapshots"][name]
        if "time" not in g.attrs:  # being written
            continue
        out.append((name, float(g.attrs["time"]), int(g.attrs.get("step", -1))))
    return out


def open_h5(path):
    if not os.path.exists(path):
        return None
    try:
        return h5py.File(path, "r")
    except OSError as e:
        print(f"plot_snapshot: {path}: {e}", file=sys.stderr)
        return None


def particle_data(pf, name, color):
    """(positions n x 3, scalar per particle or None, label) of particle snapshot `name`."""
    s = pf["snapshots"][name]
    x = np.stack([s[k][()] if k in s else np.zeros(int(s.attrs.get("n", 0))) for k in ("x", "y", "z")], axis=1)
    if color == "pressure":
        if "pressure" in s:
            return x, s["pressure"][()], "pressure [Pa]"
        return x, None, "no pressure field in the output"
    if "vx" in s:
        v = np.stack([s[k][()] if k in s else np.zeros(len(x)) for k in ("vx", "vy", "vz")], axis=1)
        return x, np.linalg.norm(v, axis=1), "speed [m/s]"
    return x, None, "no velocity field in the output"


def body_segments(bf, name, dim, ax2):
    """(fixed, moving) lists of 2D polygons / segments (in the view plane) of body snapshot `name`."""
    geo = bf["geometry"]
    fixed, moving = [], []
    if "fixed" in geo and "vertices" in geo["fixed"] and len(geo["fixed"]["vertices"]):
        v = geo["fixed"]["vertices"][()][:, ax2]
        fixed = v[geo["fixed"]["cells"][()]]
    if name is not None and "moving" in geo and "cells" in geo["moving"]:
        s = bf["snapshots"][name]
        if "vertices" in s and len(s["vertices"]):
            v = s["vertices"][()].astype(np.float64)[:, ax2]
            moving = v[geo["moving"]["cells"][()]]
    return fixed, moving


def nearest(snaps, args):
    if not snaps:
        return None
    if args.index is not None:
        return args.index if args.index >= 0 else len(snaps) + args.index
    if args.time is not None:
        return int(np.argmin([abs(t - args.time) for _, t, _ in snaps]))
    if args.step is not None:
        return int(np.argmin([abs(k - args.step) for _, _, k in snaps]))
    return len(snaps) - 1


def draw(out_png, pf, psnap, bf, bsnap, dim, view, color, clim, limits, dx):
    ax2 = AXES["xy" if dim == 2 else view]
    # figure height from the scene's aspect ratio (axes about 8.5 in wide), so tall or flat scenes
    # fill the picture
    aspect = (limits[3] - limits[2]) / max(limits[1] - limits[0], 1e-12)
    fig, ax = plt.subplots(figsize=(11, min(max(8.5 * aspect + 1.2, 3.5), 10.0)), dpi=110)
    ax.set_aspect("equal")
    ax.set_xlim(limits[0], limits[1])
    ax.set_ylim(limits[2], limits[3])
    ax.set_xlabel("xyz"[ax2[0]] + " [m]")
    ax.set_ylabel("xyz"[ax2[1]] + " [m]")
    title = []
    if bf is not None:
        fixed, moving = body_segments(bf, bsnap[0] if bsnap else None, dim, ax2)
        if dim == 2:  # line segments (convex outlines; thin quads for segments and polylines)
            if len(fixed):
                ax.add_collection(LineCollection(fixed, colors="0.35", linewidths=1.2, zorder=3))
            if len(moving):
                ax.add_collection(LineCollection(moving, colors="saddlebrown", linewidths=1.5, zorder=4))
        else:  # triangles projected onto the view plane
            if len(fixed):
                ax.add_collection(PolyCollection(fixed, facecolors="0.8", edgecolors="0.6", linewidths=0.2,
                                                 alpha=0.35, zorder=1))
            if len(moving):
                ax.add_collection(PolyCollection(moving, facecolors="peru", edgecolors="saddlebrown",
                                                 linewidths=0.2, alpha=0.8, zorder=4))
        if bsnap and not pf:
            title.append(f"t = {bsnap[1]:.4g} s, step {bsnap[2]}")
    if pf is not None and psnap is not None:
        x, val, label = particle_data(pf, psnap[0], color)
        # marker diameter = dx in data units (points^2 for scatter)
        fig.canvas.draw()
        p0 = ax.transData.transform((0.0, 0.0))
        p1 = ax.transData.transform((dx, 0.0))
        size = max((abs(p1[0] - p0[0]) * 72.0 / fig.dpi) ** 2, 0.5)
        if dim == 3:  # far particles first so that the near side shows
            depth = 3 - ax2[0] - ax2[1]
            order = np.argsort(x[:, depth] if view != "xz" else -x[:, depth])
            x = x[order]
            val = val[order] if val is not None else None
        snap = pf["snapshots"][psnap[0]]
        if "inlet" in snap:  # open boundaries: the buffer particles apart, in grey
            buf = snap["inlet"][()] >= 0
            if dim == 3:
                buf = buf[order]
            ax.scatter(x[buf, ax2[0]], x[buf, ax2[1]], s=size, color="0.75", linewidths=0, zorder=2)
            x = x[~buf]
            val = val[~buf] if val is not None else None
            title.append(f"entered {int(snap.attrs.get('flow_entered', 0))}, "
                         f"removed {int(snap.attrs.get('flow_removed_water', 0) + snap.attrs.get('flow_removed_soil', 0))}")
        if val is not None:
            if color == "pressure" and clim == (None, None) and len(val):
                # one impact spike would wash out the rest: scale to the 1st..99th percentile
                clim = tuple(np.percentile(val, [1.0, 99.0]))
            sc = ax.scatter(x[:, ax2[0]], x[:, ax2[1]], c=val, s=size, cmap="viridis" if color == "speed" else "coolwarm",
                            vmin=clim[0], vmax=clim[1], linewidths=0, zorder=2)
            fig.colorbar(sc, ax=ax, label=label, shrink=0.8)
        else:
            ax.scatter(x[:, ax2[0]], x[:, ax2[1]], s=size, color="tab:blue", linewidths=0, zorder=2)
        title.append(f"t = {psnap[1]:.4g} s, step {psnap[2]}, {len(x)} particles")
        if val is not None and len(val):
            title.append(f"max {label.split(' ')[0]} {np.max(val):.3g} {label.split(' ')[-1].strip('[]')}")
    ax.set_title(", ".join(title))
    fig.tight_layout()
    fig.savefig(out_png)
    plt.close(fig)


def scene_limits(pf, psnaps, bf, dim, view):
    """Axis limits covering the fixed bodies and the first particle snapshot (all of them with --all)."""
    ax2 = AXES["xy" if dim == 2 else view]
    pts = []
    if bf is not None:
        geo = bf["geometry"]
        if "fixed" in geo and "vertices" in geo["fixed"] and len(geo["fixed"]["vertices"]):
            pts.append(geo["fixed"]["vertices"][()][:, ax2])
        for name, _, _ in snapshot_list(bf)[:1]:
            s = bf["snapshots"][name]
            if "vertices" in s and len(s["vertices"]):
                pts.append(s["vertices"][()].astype(np.float64)[:, ax2])
    if pf is not None and psnaps:
        x, _, _ = particle_data(pf, psnaps[0][0], "speed")
        pts.append(x[:, ax2])
    if not pts:
        return (-1, 1, -1, 1)
    p = np.concatenate(pts)
    lo, hi = p.min(axis=0), p.max(axis=0)
    pad = 0.03 * max(hi - lo) + 1e-9
    return (lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", help="run output directory (holds particles.h5 and/or bodies.h5)")
    sel = ap.add_mutually_exclusive_group()
    sel.add_argument("--time", type=float, help="snapshot nearest to this time [s]")
    sel.add_argument("--step", type=int, help="snapshot nearest to this solver step")
    sel.add_argument("--index", type=int, help="snapshot number (negative: from the end)")
    sel.add_argument("--all", action="store_true", help="every snapshot, one PNG each")
    ap.add_argument("--color", choices=("speed", "pressure"), default="speed", help="particle colour (default speed)")
    ap.add_argument("--view", choices=tuple(AXES), default="xz", help="3D: projection plane (default xz)")
    ap.add_argument("-o", "--output", help="PNG to write (with --all: a directory)")
    args = ap.parse_args()

    pf = open_h5(os.path.join(args.out, "particles.h5"))
    bf = open_h5(os.path.join(args.out, "bodies.h5"))
    if pf is None and bf is None:
        print(f"plot_snapshot: {args.out}: no particles.h5 or bodies.h5", file=sys.stderr)
        return 2
    try:
        head = (pf if pf is not None else bf)["header"].attrs
        dim = int(head.get("dimensions", 3))
        dx = float(pf["header"].attrs.get("dx", 0.0)) if pf is not None else 0.0
        psnaps = snapshot_list(pf) if pf is not None else []
        bsnaps = snapshot_list(bf) if bf is not None else []
        # the particle snapshots drive the selection when there are particles
        snaps = psnaps if psnaps else bsnaps
        if not snaps:
            print(f"plot_snapshot: {args.out}: no snapshots yet", file=sys.stderr)
            return 2
        limits = scene_limits(pf, psnaps, bf, dim, args.view)

        def body_at(t):
            if not bsnaps:
                return None
            return bsnaps[int(np.argmin([abs(tb - t) for _, tb, _ in bsnaps]))]

        if args.all:
            outdir = args.output or os.path.join(args.out, "frames")
            os.makedirs(outdir, exist_ok=True)
            clim = (None, None)
            if psnaps:  # one colour scale for the whole series
                lows, highs = [], []
                for name, _, _ in psnaps:
                    _, v, _ = particle_data(pf, name, args.color)
                    if v is not None and len(v):
                        lows.append(np.min(v) if args.color == "speed" else np.percentile(v, 1.0))
                        highs.append(np.max(v) if args.color == "speed" else np.percentile(v, 99.0))
                if highs:
                    # speed: 0 to the fastest particle of the run; pressure: the median frame's 1st..99th
                    # percentile (impact spikes and the first frames would wash out the scale)
                    clim = (0.0, max(highs)) if args.color == "speed" else (np.median(lows), np.median(highs))
            for i, s in enumerate(snaps):
                png = os.path.join(outdir, f"snapshot_{i:06d}.png")
                draw(png, pf, s if psnaps else None, bf, body_at(s[1]), dim, args.view, args.color, clim, limits, dx)
            print(f"plot_snapshot: {len(snaps)} frames in {outdir}")
            return 0
        i = nearest(snaps, args)
        if i is None or not 0 <= i < len(snaps):
            print(f"plot_snapshot: snapshot {args.index} out of range (0..{len(snaps) - 1})", file=sys.stderr)
            return 2
        s = snaps[i]
        png = args.output or os.path.join(args.out, f"snapshot_{i:06d}.png")
        clim = (0.0, None) if args.color == "speed" else (None, None)
        draw(png, pf, s if psnaps else None, bf, body_at(s[1]), dim, args.view, args.color, clim, limits, dx)
        print(f"plot_snapshot: t = {s[1]:.6g} s (snapshot {i}) -> {png}")
        return 0
    except (KeyError, OSError) as e:
        print(f"plot_snapshot: {args.out}: unexpected layout: {e}", file=sys.stderr)
        return 2
    finally:
        for f in (pf, bf):
            if f is not None:
                f.close()


if __name__ == "__main__":
    sys.exit(main())
