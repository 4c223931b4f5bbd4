#!/usr/bin/python3
"""Compare two (or more) runs of the same case, e.g. one per DEM engine: the free bodies' paths and
the force on one fixed body (the barrier).

  tools/compare_engines.py OUT_A OUT_B [OUT_C ...] [--out PNG] [--barrier NAME] [--window S]
                           [--json FILE] [--label NAME ...]

Every run after the first is compared with the first (OUT_A). Printed per pair:
  * per free body, the largest distance between its positions in the two runs over time
    (bodies.h5 snapshots; OUT_B's positions interpolated linearly to OUT_A's snapshot times, since
    runs with other time steps write their snapshots at slightly other times), and when;
  * the barrier's force (forces.h5, the body named --barrier, default `barrier`): the peak of its
    magnitude after a moving average over --window seconds (default 0.005 s; single-step rows of a
    penalty wall are spiky, cases/README.md "Wall force chatter"), the impulse |int F dt| over the
    common time span, and the largest difference of the two averaged force histories; each
    difference also relative to OUT_A's value (the history's to OUT_A's peak). Impulses sum each
    row's force times its step (t_i - t_{i-1}): exact when the force stream has a row every step
    (time.forces_interval: 0), otherwise an estimate.
--out draws the paths (x-y) of the free bodies of all runs and the averaged barrier force |F|
against t into one PNG. --json writes the numbers (for tests). Exit status: 0, 2 bad input."""
import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lahar_py  # noqa: E402

lahar_py.require("h5py", "numpy")
import h5py  # noqa: E402
import numpy as np  # noqa: E402


class InputError(Exception):
    pass


def load_run(out):
    """Snapshot times, names, motion kinds and positions (nsnap x nbody x 3) from bodies.h5, and
    the force stream (t, names, force) from forces.h5."""
    bpath, fpath = os.path.join(out, "bodies.h5"), os.path.join(out, "forces.h5")
    for p in (bpath, fpath):
        if not os.path.exists(p):
            raise InputError(f"{p}: no such file (is {out} the output directory of a finished lahar run?)")
    try:
        with h5py.File(bpath, "r") as f:
            names = lahar_py.text_names(f["header/body_name"][()])
            motion = np.asarray(f["header/motion"][()])
            dim = int(f["header"].attrs.get("dimensions", 3))
            snaps = f["snapshots"]
            keys = sorted(snaps.keys())
            if not keys:
                raise InputError(f"{bpath}: no snapshots")
            times = np.array([float(snaps[k].attrs["time"]) for k in keys])
            pos = np.array([snaps[k]["position"][()] for k in keys])
        with h5py.File(fpath, "r", libver="latest", swmr=True) as f:
            t = f["t"][()]
            n = len(t)
            force = f["force"][:n]
            fnames = lahar_py.text_names(f.attrs.get("body_names", []))
    except (OSError, KeyError) as e:
        raise InputError(f"{out}: cannot read the output: {e}") from e
    order = np.argsort(times, kind="stable")
    return {"out": out, "names": names, "motion": motion, "times": times[order], "pos": pos[order],
            "t": t, "force": force, "fnames": fnames, "dim": dim}


def averaged_force(run, barrier, window, grid):
    """The barrier's force averaged over `window` around each grid time (from the cumulative
    impulse, so runs with other steps are averaged alike), and its impulse up to grid[-1]."""
    if barrier not in run["fnames"]:
        raise InputError(f"{run['out']}/forces.h5: no body '{barrier}' (bodies: {', '.join(run['fnames'])}); "
                         "name the fixed body with --barrier")
    b = run["fnames"].index(barrier)
    t = run["t"]
    if len(t) < 2:
        raise InputError(f"{run['out']}/forces.h5: fewer than two rows")
    f = run["force"][:, b, :]
    dt = np.diff(np.concatenate(([0.0], t)))
    tc = np.concatenate(([0.0], t))
    cum = np.vstack((np.zeros(3), np.cumsum(f * dt[:, None], axis=0)))  # impulse J(t) at tc
    def J(s):
        s = np.clip(s, tc[0], tc[-1])
        return np.stack([np.interp(s, tc, cum[:, a]) for a in range(3)], axis=-1)
    lo, hi = np.clip(grid - 0.5 * window, 0.0, None), grid + 0.5 * window
    hi = np.minimum(hi, tc[-1])
    span = np.maximum(hi - lo, 1e-300)
    favg = (J(hi) - J(lo)) / span[:, None]
    impulse = J(np.array([grid[-1]]))[0]
    return favg, impulse


def relative(diff, ref):
    """diff / ref; a barrier no run loads (both 0) differs by 0; one loaded only by run b has no
    relative difference (None: null in the JSON, "n/a" printed)."""
    return diff / ref if ref > 0 else (0.0 if diff == 0 else None)


def percent(x, digits):
    return "n/a" if x is None else "%.*f %%" % (digits, 100 * x)


def compare(a, b, barrier, window):
    free = [n for n, m in zip(a["names"], a["motion"]) if m == 0]
    res = {"a": a["out"], "b": b["out"], "bodies": {}}
    for name in free:
        if name not in b["names"]:
            raise InputError(f"{b['out']}: no body '{name}' (the runs are not of the same case)")
        ia, ib = a["names"].index(name), b["names"].index(name)
        tb = b["times"]
        ts = a["times"][(a["times"] >= tb[0]) & (a["times"] <= tb[-1])]
        xa = np.stack([np.interp(ts, a["times"], a["pos"][:, ia, k]) for k in range(3)], axis=-1)
        xb = np.stack([np.interp(ts, tb, b["pos"][:, ib, k]) for k in range(3)], axis=-1)
        d = np.linalg.norm(xa - xb, axis=1)
        j = int(np.argmax(d))
        res["bodies"][name] = {"max_position_diff_m": float(d[j]), "at_s": float(ts[j]),
                               "final_position_diff_m": float(d[-1])}
    t_end = min(a["t"][-1], b["t"][-1])
    grid = np.linspace(0.0, t_end, max(2, int(round(t_end / 1e-4)) + 1))
    fa, ja = averaged_force(a, barrier, window, grid)
    fb, jb = averaged_force(b, barrier, window, grid)
    ma, mb = np.linalg.norm(fa, axis=1), np.linalg.norm(fb, axis=1)
    pa, pb = float(ma.max()), float(mb.max())
    hist = float(np.linalg.norm(fa - fb, axis=1).max())
    res["barrier"] = {
        "name": barrier, "window_s": window, "t_end_s": float(t_end),
        "peak_a_N": pa, "peak_b_N": pb, "peak_at_a_s": float(grid[int(np.argmax(ma))]),
        "peak_at_b_s": float(grid[int(np.argmax(mb))]),
        "peak_rel_diff": relative(abs(pa - pb), pa),
        "impulse_a_Ns": float(np.linalg.norm(ja)), "impulse_b_Ns": float(np.linalg.norm(jb)),
        "impulse_rel_diff": relative(float(np.linalg.norm(ja - jb)), float(np.linalg.norm(ja))),
        "history_max_diff_N": hist, "history_max_diff_rel_peak": relative(hist, pa),
    }
    res["max_position_diff_m"] = max((v["max_position_diff_m"] for v in res["bodies"].values()), default=0.0)
    return res, grid, ma, mb


def print_result(r, la, lb):
    print(f"{lb} against {la}:")
    for name, v in r["bodies"].items():
        print(f"  {name:12s} largest position difference {v['max_position_diff_m']*1e3:8.3f} mm at t = "
              f"{v['at_s']:.3f} s (at the end {v['final_position_diff_m']*1e3:.3f} mm)")
    c = r["barrier"]
    print(f"  {c['name']}: peak |F| ({c['window_s']*1e3:g} ms average) {c['peak_a_N']:.2f} N at {c['peak_at_a_s']:.3f} s "
          f"vs {c['peak_b_N']:.2f} N at {c['peak_at_b_s']:.3f} s ({percent(c['peak_rel_diff'], 1)})")
    print(f"  {c['name']}: impulse |J| over 0-{c['t_end_s']:.3f} s {c['impulse_a_Ns']:.4f} vs {c['impulse_b_Ns']:.4f} N s "
          f"(|J_a - J_b| / |J_a| = {percent(c['impulse_rel_diff'], 2)})")
    print(f"  {c['name']}: largest difference of the averaged force histories {c['history_max_diff_N']:.2f} N "
          f"({percent(c['history_max_diff_rel_peak'], 1)} of the peak)")


def plot(runs, labels, grid, forces, barrier, window, path):
    lahar_py.require("matplotlib")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(13, 4.8))
    styles = ["-", "--", ":", "-."]
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    a = runs[0]
    free = [n for n, m in zip(a["names"], a["motion"]) if m == 0]
    for r, (run, lab) in enumerate(zip(runs, labels)):
        for k, name in enumerate(free):
            i = run["names"].index(name)
            ax[0].plot(run["pos"][:, i, 0], run["pos"][:, i, 1], styles[r % 4], color=colors[k % len(colors)],
                       lw=1.2, label=f"{name} ({lab})")
        ax[1].plot(grid[r], forces[r], styles[r % 4], lw=1.0, label=lab)
    ax[0].set_xlabel("x [m]")
    ax[0].set_ylabel("y [m]")
    ax[0].set_title("free bodies: paths of the centres")
    ax[0].legend(fontsize=7, ncol=len(runs))
    ax[1].set_xlabel("t [s]")
    ax[1].set_ylabel("|F| [N/m]" if a["dim"] == 2 else "|F| [N]")
    ax[1].set_title(f"force on '{barrier}' ({window*1e3:g} ms moving average)")
    ax[1].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="+", help="output directories (OUT_A OUT_B ...): each later one against the first")
    ap.add_argument("--out", help="PNG to write (paths and barrier force of all runs)")
    ap.add_argument("--barrier", default="barrier", help="name of the fixed body whose force is compared")
    ap.add_argument("--window", type=float, default=0.005, help="moving average of the force [s] (default 0.005)")
    ap.add_argument("--json", help="write the numbers to this JSON file")
    ap.add_argument("--label", action="append", help="a label per run (default: the directory names)")
    args = ap.parse_args()
    if len(args.runs) < 2:
        print("compare_engines: give at least two output directories", file=sys.stderr)
        return 2
    if not args.window > 0:
        print("compare_engines: --window must be positive", file=sys.stderr)
        return 2
    labels = args.label or [os.path.basename(os.path.normpath(r)) for r in args.runs]
    if len(labels) != len(args.runs):
        print("compare_engines: give one --label per run", file=sys.stderr)
        return 2
    try:
        runs = [load_run(r) for r in args.runs]
        results, grids, forces = [], [], []
        for r in runs[1:]:
            res, grid, ma, mb = compare(runs[0], r, args.barrier, args.window)
            results.append(res)
            if not grids:
                grids.append(grid)
                forces.append(ma)
            grids.append(grid)
            forces.append(mb)
    except InputError as e:
        print(f"compare_engines: {e}", file=sys.stderr)
        return 2
    for res, lab in zip(results, labels[1:]):
        print_result(res, labels[0], lab)
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"labels": labels, "comparisons": results}, f, indent=1)
    if args.out:
        plot(runs, labels, grids, forces, args.barrier, args.window, args.out)
        print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
