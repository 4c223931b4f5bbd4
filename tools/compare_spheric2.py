#!/usr/bin/python3
"""Compare a run of cases/dam_break_obstacle_3d.yaml with SPHERIC Test 2 (Kleefsman et al. 2005).

  tools/compare_spheric2.py OUT [--window MS] [-o FILE.png] [--json FILE] [--no-plot] [--depths]
                            [--check [--impact-tol F] [--travel-tol F] [--level-tol M]
                                     [--p1-mean-band LO HI]]

Reads OUT/gauges.h5 (probes P1..P8 on the obstacle, level gauges H1..H4) and
docs/references-data/kleefsman_2005_test2.csv (t in s, P1-P8 in Pa, H1-H4 in m). Metrics
(printed, and written to --json, default OUT/spheric2.json):
  impact     t of the first sample of P1 at or above 1 kPa, run and experiment (0.394 s), relative
             difference
  peak       P1 and P3: the largest sample, and the largest mean over --window ms (default 10),
             within 0.2 s of P1's impact
  plateau    P1 and P3: the mean over 50-150 ms after P1's first impact (the run's and the
             experiment's each from its own impact), the sustained load; nan when the run ends earlier
  noise      P1 and P3: the rms of p about its --window running mean over that same window: how
             far the signal swings about the load a structure feels
  travel     the time from H4's first 20 mm drop to P1's first impact, run and experiment: the
             front's travel time from the column to the box, which does not depend on when the
             clock was started (H4 stands in the column, 0.646 m behind its face, and is the first
             gauge the release reaches; the experiment's t = 0 is not documented)
  levels     H1-H4 at (x, y) = (1.488, 0.5), (0.992, 0.5), (0.496, 0.5), (2.638, 0.5) m: the time
             the level first changes by 20 mm, and the mean |h_run - h_exp| over the run (m);
             h_run: the case's level gauges (kind: level, 1 kHz; the top of the water column on
             the floor, where the water's kernel fraction falls to 1/2, sph_node/probes/sph_probes.h)
  profile    every probe the run has (P1-P4 up the face, P5-P8 along the top): the mean over the
             sustained-load window above against the experiment's: how the load is spread up the
             face, and whether water rests on the top (the experiment's P5-P8 read within 0.01 kPa
             of zero there); with P1-P4, the face's line load (N/m: the profile piecewise linear
             between the probes, constant below P1 and above P4 to the top, z = 0.161 m) and the
             height of its resultant, the two numbers a barrier's sliding and overturning take
  depths     (--depths) H1 and H2 every 50 ms from 0.25 s: the run, the experiment and Ritter's
             (1892) shallow-water dam-break depth h = (4/9g) (sqrt(g H0) - x/2t)^2 for the
             instantaneous release of the case's column (H0 its height, x the distance from its
             downstream face): how much water arrives in front of the box
The PNG shows P1, P3, P5, P7 and H1-H4 against the experiment (and Ritter's depth at the gauges
before the box); when the run has P1-P4 and covers the sustained-load window, a second PNG
(the first's name with _face) the load up the face with the line loads. Runs of the 2D centre plane
(cases/dam_break_obstacle_plane_2d.yaml) are read the same way (its probes and gauges have the
3D case's names).
With --check: exit 1 unless |impact - 0.394 s| / 0.394 s <= --impact-tol (default 0.05), every
gauge's mean |h_run - h_exp| <= --level-tol (default 0.02 m) and, when given, |travel - 0.260 s| /
0.260 s <= --travel-tol and P1's largest 10 ms mean within [LO, HI] x the experiment's (10.1 kPa)
(--p1-mean-band LO HI)."""
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

GAUGES = [("H1", 1.488, 0.5), ("H2", 0.992, 0.5), ("H3", 0.496, 0.5), ("H4", 2.638, 0.5)]
BOX_FACE_X = 0.8245  # the obstacle's face towards the water: Ritter's depth is drawn for the gauges before it
# SPHERIC's pressure probes: on the box's face (height z, m) and on its top (x, m)
PROBES = {"P1": ("face", 0.021), "P2": ("face", 0.061), "P3": ("face", 0.101), "P4": ("face", 0.141),
          "P5": ("top", 0.8035), "P6": ("top", 0.7635), "P7": ("top", 0.7235), "P8": ("top", 0.6835)}
BOX_TOP_Z = 0.161
IMPACT_PA = 1000.0
SPAN = 0.2
PLATEAU = (0.05, 0.15)  # s after the first impact on P1: the window of the sustained load
DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "docs", "references-data",
                    "kleefsman_2005_test2.csv")


def first_at_or_above(t, p, level):
    i = np.flatnonzero(p >= level)
    return float(t[i[0]]) if len(i) else float("nan")


def window_peak(t, p, t0, tau):
    return lahar_py.window_mean_peak(t, p, t0, tau, SPAN)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--window", type=float, default=10.0, help="window of the mean peak, ms")
    ap.add_argument("-o", "--output")
    ap.add_argument("--json")
    ap.add_argument("--no-plot", action="store_true", help="write no PNG")
    ap.add_argument("--depths", action="store_true",
                    help="print H1 and H2 every 50 ms against the experiment and Ritter's solution")
    ap.add_argument("--check", action="store_true", help="exit 1 when a bound below is not met")
    ap.add_argument("--impact-tol", type=float, default=0.05, help="bound on |impact - experiment| / experiment")
    ap.add_argument("--travel-tol", type=float,
                    help="bound on |travel - experiment| / experiment (not checked unless given)")
    ap.add_argument("--level-tol", type=float, default=0.02, help="bound on each gauge's mean |h - h_exp|, m")
    ap.add_argument("--p1-mean-band", type=float, nargs=2, metavar=("LO", "HI"),
                    help="bounds on P1's largest window mean / the experiment's (not checked unless given)")
    a = ap.parse_args()
    tau = a.window * 1e-3
    case = lahar_py.run_case(a.out)
    with open(case) as fh:
        sph = yaml.safe_load(fh)["sph"]
    dx = float(sph["dx"])
    column = sph["blocks"][0]["box"]  # the water column: x from its downstream face, height on the last axis
    with open(DATA) as fh:
        lines = [ln for ln in fh if not ln.startswith("#")]
    head = lines[0].strip().split(",")
    e = np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])
    te = e[:, 0]
    with h5py.File(os.path.join(a.out, "gauges.h5"), "r") as f:
        run_p = {n: (f["probes"][n]["t"][:], f["probes"][n]["p"][:]) for n in PROBES if n in f["probes"]}
    m = {"dx": dx, "window_ms": a.window}
    ti_run = first_at_or_above(*run_p["P1"], IMPACT_PA)
    if np.isnan(ti_run):
        t1 = run_p["P1"][0]
        sys.stderr.write("compare_spheric2: %s: P1 never reaches %g Pa (samples to t = %.3g s): the water has not "
                         "hit the box yet; run the case longer\n" % (a.out, IMPACT_PA, t1[-1] if len(t1) else 0.0))
        return 2
    ti_exp = first_at_or_above(te, e[:, head.index("P1")], IMPACT_PA)
    m["impact"] = {"run": ti_run, "experiment": ti_exp, "rel": (ti_run - ti_exp) / ti_exp}
    m["profile"] = profile(run_p, te, e, head, ti_run, ti_exp)
    m["peaks"] = {}
    for n in ["P1", "P3"]:
        t, p = run_p[n]
        pe = e[:, head.index(n)]
        sel, sele = (t >= ti_run) & (t <= ti_run + SPAN), (te >= ti_exp) & (te <= ti_exp + SPAN)
        m["peaks"][n] = {"peak": float(p[sel].max()), "peak_exp": float(pe[sele].max()),
                         "peak_mean": window_peak(t, p, ti_run, tau), "peak_mean_exp": window_peak(te, pe, ti_exp, tau)}
        m["peaks"][n]["plateau"], m["peaks"][n]["plateau_exp"] = m["profile"][n]["run"], m["profile"][n]["exp"]
        w, we, covered = plateau_window(t, te, ti_run, ti_exp)
        # how smooth the load is: rms of p about its running mean over --window, in that window
        m["peaks"][n]["noise_rms"] = float(np.sqrt(np.mean((p - lahar_py.running_mean(t, p, tau))[w] ** 2))) if covered \
            else float("nan")
        m["peaks"][n]["noise_rms_exp"] = float(np.sqrt(np.mean((pe - lahar_py.running_mean(te, pe, tau))[we] ** 2)))
    with h5py.File(os.path.join(a.out, "gauges.h5"), "r") as f:
        missing = [g for g, _, _ in GAUGES if g not in f["probes"] or "h" not in f["probes"][g]]
        if missing:
            sys.stderr.write("compare_spheric2: %s/gauges.h5 has no level gauge %s (kind: level); run "
                             "cases/dam_break_obstacle_3d.yaml as it is\n" % (a.out, ", ".join(missing)))
            return 2
        tls = {g: f["probes"][g]["t"][:] for g, _, _ in GAUGES}
        hs = {g: f["probes"][g]["h"][:] for g, _, _ in GAUGES}
    tl = tls["H1"]
    m["levels"] = {}
    for g, _, _ in GAUGES:
        he = e[:, head.index(g)]
        hr, tg = hs[g], tls[g]
        arr_run = next((tg[i] for i in range(len(tg)) if abs(hr[i] - hr[0]) >= 0.02), float("nan"))
        arr_exp = next((te[i] for i in range(len(te)) if abs(he[i] - he[0]) >= 0.02), float("nan"))
        m["levels"][g] = {"change_run": float(arr_run), "change_exp": float(arr_exp),
                          "mean_abs_diff_m": float(np.mean(np.abs(hr - np.interp(tg, te, he))))}
    # the same event pair in both series, so a different time origin cancels
    h4 = m["levels"]["H4"]
    tr_run, tr_exp = ti_run - h4["change_run"], ti_exp - h4["change_exp"]
    m["travel"] = {"run": tr_run, "experiment": tr_exp, "rel": (tr_run - tr_exp) / tr_exp}
    print("first impact on P1 (>= 1 kPa): t = %.4f s (experiment %.4f s, %+.2f %%)" % (
        ti_run, ti_exp, 100 * m["impact"]["rel"]))
    print("from H4's first 20 mm drop to P1's first impact: %.4f s (experiment %.4f s, %+.2f %%)" % (
        tr_run, tr_exp, 100 * m["travel"]["rel"]))
    for n, s in m["peaks"].items():
        print("%s: peak %.0f Pa (exp %.0f), %g ms mean %.0f Pa (exp %.0f), mean 50-150 ms after the impact %.0f Pa "
              "(exp %.0f), rms about the %g ms running mean there %.0f Pa (exp %.0f)" % (
                  n, s["peak"], s["peak_exp"], a.window, s["peak_mean"], s["peak_mean_exp"], s["plateau"],
                  s["plateau_exp"], a.window, s["noise_rms"], s["noise_rms_exp"]))
    print("sustained load (mean %g-%g ms after P1's first impact), kPa%s:" % (
        1e3 * PLATEAU[0], 1e3 * PLATEAU[1], "" if np.isfinite(m["peaks"]["P1"]["plateau"]) else
        " (run: nan, it ends before the window does)"))
    for n, d in m["profile"].items():
        if n in PROBES:
            print("  %s (%s = %3.0f mm): run %5.2f, experiment %5.2f" % (
                n, "face, z" if d["where"] == "face" else "top, x", 1e3 * d["at"], 1e-3 * d["run"], 1e-3 * d["exp"]))
    if "face_run" in m["profile"]:
        r, x = m["profile"]["face_run"], m["profile"]["face_exp"]
        print("  face from P1-P4: line load %.0f N/m (experiment %.0f, %+.1f %%), resultant at z = %.0f mm "
              "(experiment %.0f mm)" % (r["line_load"], x["line_load"], 100 * (r["line_load"] / x["line_load"] - 1),
                                        1e3 * r["resultant_z"], 1e3 * x["resultant_z"]))
    for g, d in m["levels"].items():
        print("%s: level changes by 20 mm at %.3f s (exp %.3f s); mean |h - h_exp| = %.3f m over 0-%.2f s" % (
            g, d["change_run"], d["change_exp"], d["mean_abs_diff_m"], tl[-1]))
    if a.depths:
        m["depths"] = depths(te, e, head, tls, hs, float(column["lo"][0]), float(column["hi"][-1]))
    ok, failed = check(m, a)
    with open(a.json or os.path.join(a.out, "spheric2.json"), "w") as fh:
        lahar_py.dump_json(m, fh)
    if not a.no_plot:
        plot(a, te, e, head, run_p, tls, hs, dx, tau, column)
        if "face_run" in m["profile"] and np.isfinite(m["profile"]["face_run"]["line_load"]):
            plot_face(a, m["profile"], dx)
    if a.check and not ok:
        print("FAIL:", ", ".join(failed))
        return 1
    return 0


def plateau_window(t, te, ti_run, ti_exp):
    """The sustained-load window, PLATEAU after each series' own first impact on P1 (so that the
    run's timing error does not enter): the run's and the experiment's masks, and whether the run
    lasts to the window's end."""
    lo, hi = PLATEAU
    w, we = (t >= ti_run + lo) & (t <= ti_run + hi), (te >= ti_exp + lo) & (te <= ti_exp + hi)
    return w, we, bool(len(t)) and t[-1] >= ti_run + hi


def profile(probes, te, e, head, ti_run, ti_exp):
    """Per probe the run has: the mean over the sustained-load window, run and experiment (Pa);
    the run's nan when it ends before the window does."""
    out = {}
    for n, (t, p) in probes.items():
        w, we, covered = plateau_window(t, te, ti_run, ti_exp)
        where, at = PROBES[n]
        out[n] = {"where": where, "at": at, "run": float(p[w].mean()) if covered else float("nan"),
                  "exp": float(e[we, head.index(n)].mean())}
    face = ["P1", "P2", "P3", "P4"]
    if all(n in out for n in face):
        for k in ("run", "exp"):
            load, z = face_load([PROBES[n][1] for n in face], [out[n][k] for n in face])
            out["face_" + k] = {"line_load": load, "resultant_z": z}
    return out


def face_load(z, p, top=BOX_TOP_Z):
    """Line load (N/m) and the height of its resultant (m) of the pressures p at the heights z up a
    face from 0 to top: p piecewise linear between the probes and constant below the lowest and
    above the highest; both integrals exact for that profile."""
    z = np.concatenate([[0.0], z, [top]])
    p = np.concatenate([p[:1], p, p[-1:]])
    h = np.diff(z)
    load = float(np.sum(0.5 * h * (p[:-1] + p[1:])))
    moment = float(np.sum(h / 6.0 * (p[:-1] * (2 * z[:-1] + z[1:]) + p[1:] * (z[:-1] + 2 * z[1:]))))
    return load, moment / load if load != 0.0 else float("nan")


def ritter_depth(distance, t, h0, g=9.81):
    """Depth at `distance` downstream (negative: upstream, in the reservoir) of an instantaneously
    released column of height h0 at time t (Ritter 1892, shallow water on a dry bed; until the
    rarefaction comes back from the reservoir's end wall)."""
    c = np.sqrt(g * h0)
    s = distance / t if t > 0.0 else (np.inf if distance > 0.0 else -np.inf)
    if s >= 2.0 * c:
        return 0.0
    if s <= -c:
        return h0
    return 4.0 / (9.0 * g) * (c - 0.5 * s) ** 2


def depths(te, e, head, tls, hs, gate_x, h0):
    """H1 and H2 every 50 ms from 0.25 s to the run's end: run, experiment, Ritter (m)."""
    rows = []
    print("depth (mm)   t:  H1 run / exp / Ritter    H2 run / exp / Ritter")
    for t in np.arange(0.25, tls["H1"][-1] + 1e-9, 0.05):
        row = {"t": float(t)}
        for g, x, _ in GAUGES[:2]:
            row[g] = {"run": float(np.interp(t, tls[g], hs[g])), "exp": float(np.interp(t, te, e[:, head.index(g)])),
                      "ritter": float(ritter_depth(gate_x - x, t, h0))}
        rows.append(row)
        print("         %.2f s:  %4.0f / %4.0f / %4.0f          %4.0f / %4.0f / %4.0f" % (
            t, *(1e3 * row[g][k] for g in ("H1", "H2") for k in ("run", "exp", "ritter"))))
    return rows


def check(m, a):
    """Fills m["bounds"], m["pass"], m["failed"]; returns (pass, failed names)."""
    failed = []
    if not abs(m["impact"]["rel"]) <= a.impact_tol:  # a run that never hits P1 has rel nan: fails
        failed.append("impact")
    if a.travel_tol is not None and not abs(m["travel"]["rel"]) <= a.travel_tol:
        failed.append("travel")
    for g, d in m["levels"].items():
        if not d["mean_abs_diff_m"] <= a.level_tol:
            failed.append(g + ".level")
    if a.p1_mean_band:
        s = m["peaks"]["P1"]
        ratio = s["peak_mean"] / s["peak_mean_exp"]
        s["ratio_mean"] = ratio
        if not a.p1_mean_band[0] <= ratio <= a.p1_mean_band[1]:
            failed.append("P1.peak_mean")
    m["bounds"] = {"impact_tol": a.impact_tol, "travel_tol": a.travel_tol, "level_tol_m": a.level_tol,
                   "p1_mean_band": a.p1_mean_band}
    m["pass"] = not failed
    m["failed"] = failed
    return not failed, failed


def plot(a, te, e, head, run_p, tls, hs, dx, tau, column):
    tl = tls["H1"]
    fig, axes = plt.subplots(4, 2, figsize=(12, 10), sharex=True)
    for k, n in enumerate(["P1", "P3", "P5", "P7"]):
        ax = axes[k, 0]
        ax.plot(te, e[:, head.index(n)] / 1e3, "k", lw=1.0, label="Kleefsman et al. 2005 (SPHERIC Test 2)")
        t, p = run_p[n]
        ax.plot(t, p / 1e3, lw=0.7, label="lahar, dx %g mm" % (1e3 * dx))
        ax.plot(t, lahar_py.running_mean(t, p, tau) / 1e3, lw=1.0, label="lahar, %g ms running mean" % a.window)
        ax.set_ylabel(n + ", kPa")
        ax.grid(alpha=0.3)
        if k == 0:
            ax.legend(fontsize=7)
    for k, (g, xg, yg) in enumerate(GAUGES):
        ax = axes[k, 1]
        ax.plot(te, e[:, head.index(g)], "k", lw=1.0, label="experiment")
        ax.plot(tls[g], hs[g], lw=0.8, label="lahar, level gauge")
        # Ritter's depth, for the gauges before the box, until the rarefaction reflected at the
        # reservoir's end wall arrives
        gate, back, h0 = float(column["lo"][0]), float(column["hi"][0]), float(column["hi"][-1])
        t_end = min(tls[g][-1], (back - gate + back - xg) / np.sqrt(9.81 * h0))
        if xg > BOX_FACE_X:
            tr = np.linspace(1e-3, t_end, 400)
            ax.plot(tr, [ritter_depth(gate - xg, t, h0) for t in tr], "--", color="0.5", lw=0.8,
                    label="Ritter 1892 (instantaneous release, shallow water)")
        ax.set_ylabel("%s (x = %g m), m" % (g, xg))
        ax.grid(alpha=0.3)
        if k == 0:
            ax.legend(fontsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("t (s)")
        ax.set_xlim(0, tl[-1])
    fig.tight_layout()
    png = a.output or os.path.join(a.out, "spheric2.png")
    fig.savefig(png, dpi=90)
    print("wrote", png)


def plot_face(a, prof, dx):
    """The sustained load up the face (P1-P4) against the experiment's, beside the PNG of plot()."""
    fig, ax = plt.subplots(figsize=(5, 4.5))
    face = ["P1", "P2", "P3", "P4"]
    z = [1e3 * PROBES[n][1] for n in face]
    for k, style, label in (("exp", "ko-", "Kleefsman et al. 2005 (SPHERIC Test 2)"),
                            ("run", "s-", "lahar, dx %g mm" % (1e3 * dx))):
        f = prof["face_" + k]
        ax.plot([1e-3 * prof[n][k] for n in face], z, style,
                label="%s: %.0f N/m at z = %.0f mm" % (label, f["line_load"], 1e3 * f["resultant_z"]))
    ax.axhline(1e3 * BOX_TOP_Z, color="0.5", lw=0.8, ls="--", label="the box's top")
    ax.set_xlabel("mean pressure %g-%g ms after the first impact on P1, kPa" % (1e3 * PLATEAU[0], 1e3 * PLATEAU[1]))
    ax.set_ylabel("height on the face, mm")
    ax.set_xlim(left=0)
    ax.set_ylim(0, 1.1e3 * BOX_TOP_Z)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="lower left")
    fig.tight_layout()
    png = os.path.splitext(a.output or os.path.join(a.out, "spheric2.png"))[0] + "_face.png"
    fig.savefig(png, dpi=90)
    print("wrote", png)


if __name__ == "__main__":
    sys.exit(main())
