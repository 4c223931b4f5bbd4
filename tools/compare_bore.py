#!/usr/bin/python3
"""Compare a run of cases/bore_reflection_2d.yaml with the shallow-water bore a wall reflects.

  tools/compare_bore.py OUT [--wall NAME] [--window T0 T1] [-o FILE.png] [--json FILE] [--no-plot]
                        [--check [--speed-tol F] [--force-tol F] [--depth-tol F]]

A supercritical stream (depth h1, velocity u1 from the case's inlet: `level` and a constant
`velocity`, the inlet's normal along +x) runs into a wall (the body --wall, default `wall`, a box
whose upstream face ends the channel). The reference is the shallow-water shock across the bore that travels back upstream,
with the water at rest behind it (mass and momentum conserved; e.g. Stoker 1957, Water Waves,
ch. 10): with r = h2/h1 and F^2 = u1^2/(g h1), 2 r F^2 = (r - 1)^2 (r + 1), the bore speed
w = h1 u1 / (h2 - h1), and the force on the wall rho g h2^2 / 2 per metre (2D).

Reads OUT/particles.h5 (every snapshot), OUT/forces.h5 and the case (OUT/summary.json). Metrics
(printed, and written to --json, default OUT/bore.json), over the window T0-T1 (default 1.5 5.5 s,
after the first impact's run-up on the wall has fallen back):
  speed   the bore's speed: the slope of a least-squares line through the front's position in
          the window's snapshots. The front: the most upstream point where the water depth,
          measured as the particles' volume (m/rho) per column of the channel, averaged over
          0.1 m, exceeds (h1 + h2) / 2; depth by volume, so that air pockets under a breaking
          roller do not count as water. Also the rms of the positions about that line.
  force   the mean horizontal force on the wall over the window, and its rms about that mean
  depth   the mean water depth (volume per column) over the last metre before the wall in the
          window's snapshots whose front is at least 0.3 m upstream of that reach
  stream_at_bore  the stream's mean velocity and depth 0.2-0.5 m ahead of the front (reported,
          not checked: the floor's friction slows it between the inlet and the bore)
Each against its reference, with the relative difference.
With --check: exit 1 unless |speed / w - 1| <= --speed-tol (default 0.05), |force / (rho g h2^2
/ 2) - 1| <= --force-tol (default 0.05) and |depth / h2 - 1| <= --depth-tol (default 0.05).
The PNG shows the front against the bore's path, the force on the wall against rho g h2^2 / 2,
and the depth along the channel at four instants against h1 and h2. Exit 2 on a run or case this
tool cannot read (what is missing and what to do is printed)."""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lahar_py  # noqa: E402

lahar_py.require("h5py", "numpy", "matplotlib", "yaml")
import h5py  # noqa: E402
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import yaml  # noqa: E402

SMOOTH = 0.1  # m, the length the depth is averaged over to find the front
REACH = 1.0  # m before the wall where the depth behind the bore is measured
CLEAR = 0.3  # m the front must be upstream of that reach
ARRIVE = (0.2, 0.5)  # m ahead of the front where the arriving stream is measured


InputError = lahar_py.InputError


def bore_reference(h1, u1, g):
    """h2 and the bore speed w of the shock a wall reflects into a stream (h1, u1): the real root
    r > 1 of (r - 1)^2 (r + 1) - 2 r F^2 = r^3 - r^2 - (1 + 2 F^2) r + 1."""
    f2 = u1 * u1 / (g * h1)
    roots = np.roots([1.0, -1.0, -1.0 - 2.0 * f2, 1.0])
    r = max(x.real for x in roots if abs(x.imag) < 1e-9)
    h2 = r * h1
    return h2, h1 * u1 / (h2 - h1)


def read_case(out, wall):
    """The stream (h1, u1), gravity, rest density, the channel's ends (inlet, wall face)."""
    path = lahar_py.run_case(out)
    with open(path) as fh:
        case = yaml.safe_load(fh)
    if case.get("dimensions") != 2:
        raise InputError(f"{path}: dimensions {case.get('dimensions')}: this tool reads a 2D channel")
    inlets = [i for i in case.get("inlets") or [] if "level" in i and "velocity" in i]
    if not inlets:
        raise InputError(f"{path}: inlets: none with `level` and a constant `velocity`: the reference needs "
                         "the stream's depth and speed (cases/bore_reflection_2d.yaml)")
    normal = inlets[0].get("normal", [0.0, 0.0])
    if not float(normal[0]) > 0.0:
        raise InputError(f"{path}: inlets: normal {normal}: this tool reads a stream that runs towards +x, "
                         "into a wall downstream of the inlet")
    bodies = {b.get("name"): b for b in case.get("bodies") or []}
    if wall not in bodies or bodies[wall].get("shape") != "box":
        raise InputError(f"{path}: bodies: no box named '{wall}' (bodies: {', '.join(map(str, bodies))}); "
                         "give the wall with --wall NAME")
    b = bodies[wall]
    face = float(b["position"][0]) - 0.5 * float(b["size"][0])  # a box's size is its outer size
    sph = case["sph"]
    return {"h1": float(inlets[0]["level"]), "u1": float(inlets[0]["velocity"]),
            "g": abs(float(case["gravity"][1])), "rho": float(sph["density"]),
            "x0": float(inlets[0]["position"][0]), "face": face}


def depth_profiles(out, c):
    """(t, column centres, volume depth per column, the column's mean horizontal velocity, dx) of
    every snapshot: the water's volume m/rho (m = rho0 dx^2 per particle, dx the run's from
    particles.h5) per column of width 2 dx, the columns laid back from the wall's face towards the
    inlet; the velocity volume-weighted, nan without the velocity field or water in the column."""
    path = os.path.join(out, "particles.h5")
    ts, depths, speeds = [], [], []
    try:
        with h5py.File(path, "r") as f:
            dx = float(f["header"].attrs["dx"])
            width = 2.0 * dx
            n = int((c["face"] - c["x0"]) / width)
            edges = c["face"] - width * np.arange(n, -1, -1)  # whole columns back from the wall's face
            for key in sorted(f["snapshots"]):
                s = f["snapshots"][key]
                x = s["x"][()]
                keep = s["inlet"][()] < 0 if "inlet" in s else np.ones(len(x), bool)  # not the inlet's buffer
                vol = dx * dx * (c["rho"] / s["density"][()] if "density" in s else np.ones(len(x)))
                n, _ = np.histogram(x[keep], edges, weights=vol[keep])
                if "vx" in s:
                    q, _ = np.histogram(x[keep], edges, weights=(vol * s["vx"][()])[keep])
                    with np.errstate(invalid="ignore", divide="ignore"):
                        speeds.append(q / n)
                else:
                    speeds.append(np.full(len(n), np.nan))
                ts.append(float(s.attrs["time"]))
                depths.append(n / width)
    except (OSError, KeyError) as e:
        raise InputError(f"{path}: {e}; give the output directory of a run of cases/bore_reflection_2d.yaml")
    return np.array(ts), 0.5 * (edges[1:] + edges[:-1]), np.array(depths), np.array(speeds), dx


def front_positions(centres, depths, level, dx):
    """The most upstream column whose depth, averaged over SMOOTH, exceeds level (the wall's x when
    none does)."""
    k = max(1, int(round(SMOOTH / (2.0 * dx))))
    xs = []
    for d in depths:
        smooth = np.convolve(d, np.ones(k) / k, mode="same")
        above = np.flatnonzero(smooth > level)
        xs.append(centres[above[0]] if len(above) else centres[-1])
    return np.array(xs)


def wall_force(out, wall):
    t, force = lahar_py.body_force(out, wall, "--wall NAME")
    return t, force[:, 0]


def measure(out, wall, window):
    c = read_case(out, wall)
    h2, w = bore_reference(c["h1"], c["u1"], c["g"])
    f_ref = 0.5 * c["rho"] * c["g"] * h2 * h2
    ts, centres, depths, speeds, c["dx"] = depth_profiles(out, c)
    t0, t1 = window
    sel = (ts >= t0 - 1e-9) & (ts <= t1 + 1e-9)
    if sel.sum() < 5:
        raise InputError(f"{out}: {sel.sum()} snapshots in the window {t0:g}-{t1:g} s (run to "
                         f"{ts[-1] if len(ts) else 0:g} s); need at least 5: run the case to {t1:g} s or give --window")
    xf = front_positions(centres, depths, 0.5 * (c["h1"] + h2), c["dx"])
    slope, icpt = np.polyfit(ts[sel], xf[sel], 1)
    resid = xf[sel] - (slope * ts[sel] + icpt)
    reach = centres >= c["face"] - REACH
    clear = sel & (xf <= c["face"] - REACH - CLEAR)
    depth = float(depths[clear][:, reach].mean()) if clear.any() else float("nan")
    # the stream as it meets the bore: ARRIVE m ahead of the front (the floor slows it on its way)
    ahead = [(centres >= x - ARRIVE[1]) & (centres <= x - ARRIVE[0]) for x in xf[sel]]
    h_arr = float(np.mean([d[a].mean() for d, a in zip(depths[sel], ahead) if a.any()] or [np.nan]))
    u_snap = [np.nanmean(u[a]) for u, a in zip(speeds[sel], ahead) if np.isfinite(u[a]).any()]
    u_arr = float(np.mean(u_snap)) if u_snap else float("nan")
    tf, fx = wall_force(out, wall)
    fsel = (tf >= t0) & (tf <= t1)
    force = float(fx[fsel].mean())
    m = {"case": {k: c[k] for k in ("h1", "u1", "dx", "face")}, "froude": c["u1"] / np.sqrt(c["g"] * c["h1"]),
         "window": [t0, t1], "stream_at_bore": {"u": u_arr, "h": h_arr},
         "speed": {"run": -slope, "reference": w, "rel": -slope / w - 1.0, "rms_m": float(resid.std())},
         "force": {"run": force, "reference": f_ref, "rel": force / f_ref - 1.0, "rms": float(fx[fsel].std())},
         "depth": {"run": depth, "reference": h2, "rel": depth / h2 - 1.0, "snapshots": int(clear.sum())}}
    series = {"t": ts, "front": xf, "line": (slope, icpt), "centres": centres, "depths": depths,
              "tf": tf, "fx": fx, "h2": h2, "w": w, "f_ref": f_ref, "c": c}
    return m, series


def plot(m, s, png):
    c = s["c"]
    fig, ax = plt.subplots(3, 1, figsize=(8, 10))
    t = s["t"]
    ax[0].plot(t, s["front"], ".", label="front (depth by volume > (h1 + h2)/2)")
    slope, icpt = s["line"]
    t0, t1 = m["window"]
    tw = np.array([t0, t1])
    ax[0].plot(tw, slope * tw + icpt, "k-", label=f"fit {m['window'][0]:g}-{m['window'][1]:g} s: "
               f"{-slope:.3f} m/s")
    ax[0].plot(t, c["face"] - s["w"] * t, "r--", label=f"shallow-water bore from the wall: {s['w']:.3f} m/s")
    ax[0].set_xlabel("t [s]")
    ax[0].set_ylabel("front x [m]")
    ax[0].legend(loc="best", fontsize=8)
    tf, fx = s["tf"], s["fx"]
    ax[1].plot(tf, fx, color="0.8", lw=0.5, label="force on the wall, each step")
    ax[1].plot(tf, lahar_py.running_mean(tf, fx, 0.1), "b", lw=1, label="its 0.1 s running mean")
    ax[1].axhline(s["f_ref"], color="r", ls="--", label=f"rho g h2^2 / 2 = {s['f_ref']:.1f} N/m")
    ax[1].axvspan(t0, t1, color="y", alpha=0.15, label=f"window: mean {m['force']['run']:.1f} N/m")
    ax[1].set_ylim(0, 3 * s["f_ref"])
    ax[1].set_xlabel("t [s]")
    ax[1].set_ylabel("F_x [N/m]")
    ax[1].legend(loc="best", fontsize=8)
    for tt in np.linspace(t0, t1, 4):
        i = int(np.argmin(abs(t - tt)))
        ax[2].plot(s["centres"], s["depths"][i], lw=0.8, label=f"t = {t[i]:.1f} s")
    ax[2].axhline(c["h1"], color="k", ls=":", label="h1")
    ax[2].axhline(s["h2"], color="r", ls="--", label=f"h2 = {s['h2']:.4f} m")
    ax[2].set_xlabel("x [m]")
    ax[2].set_ylabel("depth by volume [m]")
    ax[2].legend(loc="best", fontsize=8)
    fig.suptitle(f"bore reflected by a wall: h1 = {c['h1']:g} m, u1 = {c['u1']:g} m/s (Froude {m['froude']:.2f}), "
                 f"dx = {c['dx']:g} m", fontsize=10)
    fig.tight_layout()
    lahar_py.save_png(fig, png, lahar_py.fail_usage)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    lahar_py.compare_cli(ap, "bore")
    ap.add_argument("--wall", default="wall", help="the wall body's name (default wall)")
    ap.add_argument("--window", type=float, nargs=2, default=[1.5, 5.5], metavar=("T0", "T1"),
                    help="time window of the comparison, s (default 1.5 5.5)")
    ap.add_argument("--speed-tol", type=float, default=0.05, help="bound on |speed / w - 1|")
    ap.add_argument("--force-tol", type=float, default=0.05, help="bound on |force / (rho g h2^2/2) - 1|")
    ap.add_argument("--depth-tol", type=float, default=0.05, help="bound on |depth / h2 - 1|")
    a = ap.parse_args()
    if not a.window[0] < a.window[1]:
        lahar_py.fail_usage(f"--window {a.window[0]:g} {a.window[1]:g}: T0 must be below T1")
    try:
        m, s = measure(a.out, a.wall, a.window)
    except InputError as e:
        sys.stderr.write(f"compare_bore: {e}\n")
        return 2
    print(f"stream h1 = {m['case']['h1']:g} m, u1 = {m['case']['u1']:g} m/s (Froude {m['froude']:.3f}), "
          f"dx = {m['case']['dx']:g} m; window {a.window[0]:g}-{a.window[1]:g} s")
    print(f"  bore speed    {m['speed']['run']:.4f} m/s   shallow water {m['speed']['reference']:.4f} m/s   "
          f"{100 * m['speed']['rel']:+.1f} %   (front rms about the line {100 * m['speed']['rms_m']:.1f} cm)")
    print(f"  wall force    {m['force']['run']:.2f} N/m    rho g h2^2/2  {m['force']['reference']:.2f} N/m    "
          f"{100 * m['force']['rel']:+.1f} %   (rms {m['force']['rms']:.1f} N/m)")
    print(f"  depth at wall {m['depth']['run']:.4f} m     h2            {m['depth']['reference']:.4f} m     "
          f"{100 * m['depth']['rel']:+.1f} %   (last {REACH:g} m, {m['depth']['snapshots']} snapshots)")
    print(f"  the stream {ARRIVE[0]:g}-{ARRIVE[1]:g} m ahead of the bore: u {m['stream_at_bore']['u']:.3f} m/s, "
          f"h {m['stream_at_bore']['h']:.4f} m (at the inlet {m['case']['u1']:g} m/s, {m['case']['h1']:g} m)")
    with open(a.json or os.path.join(a.out, "bore.json"), "w") as fh:
        lahar_py.dump_json(m, fh)
    if not a.no_plot:
        plot(m, s, a.output or os.path.join(a.out, "bore.png"))
    if a.check:
        return lahar_py.check_verdict("compare_bore", [
            f"{k} {100 * m[k]['rel']:+.1f} % outside +-{100 * tol:g} %"
            for k, tol in (("speed", a.speed_tol), ("force", a.force_tol), ("depth", a.depth_tol))
            if not abs(m[k]["rel"]) <= tol])
    return 0


if __name__ == "__main__":
    sys.exit(main())
