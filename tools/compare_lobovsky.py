#!/usr/bin/python3
"""Compare a run of cases/dam_break_lobovsky_2d.yaml with Lobovsky et al. 2014 (H = 300 mm).

  tools/compare_lobovsky.py OUT [--window MS] [-o FILE.png] [--json FILE] [--check]
                                [--rise-tol F] [--peak-band LO HI] [--level-tol F] [--spread-tol F]

Reads OUT/gauges.h5 (pressure probes sensor1..sensor4, level gauges H1..H4) and
the experiment in docs/references-data/ (lobovsky_2014_pressure.csv: Fig. 18, peak event 5;
lobovsky_2014_levels.csv: Fig. 16, runs ETSIN 01 and 02; lobovsky_2014_sensor2_percentiles.csv:
sensor 2's repeat spread, the 2.5 / 50 / 97.5 % percentiles over the test runs at each instant).
All in the paper's units: t* = t sqrt(g/H), p/(rho g H), h/H, H = 0.3 m.

Metrics (printed, and written to --json):
  rise        t* of the first sample of sensor 1 at or above 0.5 rho g H (the impact), run and
              experiment (2.446), relative difference
  peak        per sensor 1-3, the largest sample within 0.3 t* (52 ms) after sensor 1's rise
  peak_mean   per sensor 1-3, the largest mean pressure over a window of --window ms (default 10)
              starting within that interval: (1/tau) * the pressure impulse over tau (Cooker &
              Peregrine 1995, J. Fluid Mech. 297:193: the impulse of an impact is set by the
              incompressible flow; the peak of a pulse shorter than tau is not)
  spread      sensor 2: the same peak and peak_mean of the experiment's 2.5 %, 50 % and 97.5 %
              percentile series (the repeat spread; the mean of a percentile series stands in
              for the percentile of the runs' means), and whether the run's lie between the
              2.5 % and 97.5 % values; and the whole series over the same 0.3 t* (run and spread
              aligned on their impact): the RMS distance of the run's samples from the band (0 for
              a sample inside it) and the fraction of samples inside it
  levels      per gauge H1-H4 (x = 0.300, 0.865, 1.114, 1.3625 m), the mean |h_run - h_exp| / H
              over the run's level-gauge samples with t* <= min(run end, --level-tmax, default 5.5:
              before the bore reflected from the wall reaches H4), against the experiment's mean
              of its runs; beside it the difference between the two experimental runs (their
              repeat spread) where both exist. h_run: the case's level gauges (kind: level, 1 kHz;
              the highest point of the vertical line where the water's kernel fraction is 1/2,
              sph_node/probes/sph_probes.h). For H2-H4 also the arrival of the front, the first t* with
              h >= 0.05 H, reported only.
With --check: exit 1 unless |rise - 2.446| / 2.446 <= --rise-tol (default 0.05), every sensor 1-3
sensor in --sensors (default sensor1 sensor2) peak_mean / experiment within --peak-band (default
0.5 2), every gauge's level difference <= --level-tol (default 0.05 H) and, with --spread-tol F,
sensor 2's peak_mean within the experiment's spread widened by the fraction F:
[p2.5 (1 - F), p97.5 (1 + F)]. The PNG shows pressure and levels against the experiment."""
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

H, G, RHO = 0.3, 9.81, 1000.0
TS = np.sqrt(H / G)  # time scale, s
PS = RHO * G * H  # pressure scale, Pa
GAUGES = [("H1", 0.300), ("H2", 0.865), ("H3", 1.114), ("H4", 1.3625)]
SENSORS = ["sensor1", "sensor2", "sensor3", "sensor4"]
RISE_LEVEL = 0.5  # rho g H
PEAK_SPAN = 0.3  # t* after the rise in which peaks are sought (52 ms: the sensor 2, 3 maxima)
DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "docs", "references-data")


def read_csv(name):
    with open(os.path.join(DATA, name)) as fh:
        lines = [ln for ln in fh if not ln.startswith("#")]
    head = lines[0].strip().split(",")
    return head, np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])


def rise_time(t, p):
    i = np.flatnonzero(p >= RISE_LEVEL)
    return t[i[0]] if len(i) else float("nan")


def peak(t, p, t0):
    sel = (t >= t0) & (t <= t0 + PEAK_SPAN)
    return float(p[sel].max()) if sel.any() else float("nan")


def peak_mean(t, p, t0, tau):
    return lahar_py.window_mean_peak(t, p, t0, tau, PEAK_SPAN)


def rel_outside(v, lo, hi):
    """How far v lies outside [lo, hi], relative to the edge it passes: (v - hi) / hi above,
    (v - lo) / lo below, 0 inside; None when v has no value (a run without an impact)."""
    if not np.isfinite(v):
        return None
    return (v - hi) / hi if v > hi else (v - lo) / lo if v < lo else 0.0


def band_fit(t, p, t0, te, lo, hi, t0_exp):
    """The run's series against the percentile series over the PEAK_SPAN after each one's impact
    (aligned on the rise, as the peaks are): the RMS distance of p from the band between the 2.5 %
    and 97.5 % series (0 inside it) and the fraction of samples inside it."""
    sel = (t >= t0) & (t <= t0 + PEAK_SPAN)
    if not sel.any():
        return float("nan"), float("nan")
    s = t0_exp + (t[sel] - t0)
    q, qlo, qhi = p[sel], np.interp(s, te, lo), np.interp(s, te, hi)
    out = np.maximum(q - qhi, 0.0) + np.maximum(qlo - q, 0.0)
    return float(np.sqrt(np.mean(out ** 2))), float(np.mean(out == 0.0))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--window", type=float, default=10.0, help="window of the mean peak, ms")
    ap.add_argument("--level-tmax", type=float, default=5.5, help="last t* of the level comparison")
    ap.add_argument("--dx", type=float, help="particle spacing of the run, m (default: from the case in summary.json)")
    ap.add_argument("-o", "--output", help="PNG (default OUT/lobovsky.png)")
    ap.add_argument("--json", help="metrics as JSON (default OUT/lobovsky.json)")
    ap.add_argument("--check", action="store_true")
    ap.add_argument("--rise-tol", type=float, default=0.05)
    ap.add_argument("--peak-band", type=float, nargs=2, default=[0.5, 2.0])
    ap.add_argument("--level-tol", type=float, default=0.05)
    ap.add_argument("--spread-tol", type=float, help="check sensor 2's peak_mean against the spread, widened by F")
    ap.add_argument("--sensors", nargs="+", default=["sensor1", "sensor2"], help="sensors whose peak_mean is checked")
    ap.add_argument("--no-plot", action="store_true")
    a = ap.parse_args()
    tau = a.window * 1e-3 / TS

    dx = a.dx
    if dx is None:
        case = lahar_py.run_case(a.out)
        lahar_py.require("yaml")
        import yaml
        with open(case) as fh:
            dx = float(yaml.safe_load(fh)["sph"]["dx"])

    ph, pe = read_csv("lobovsky_2014_pressure.csv")
    exp_p = {"sensor1": pe[:, ph.index("sensor1")], "sensor2": pe[:, ph.index("sensor2")],
             "sensor3": pe[:, ph.index("sensor3")], "sensor4": pe[:, ph.index("sensor4")]}
    te = pe[:, 0]
    lh, le = read_csv("lobovsky_2014_levels.csv")

    with h5py.File(os.path.join(a.out, "gauges.h5"), "r") as f:
        run_p = {n: (f["probes"][n]["t"][:] / TS, f["probes"][n]["p"][:] / PS) for n in SENSORS}

    m = {"window_ms": a.window, "dx": dx}
    r_run = rise_time(*run_p["sensor1"])
    r_exp = rise_time(te, exp_p["sensor1"])
    m["rise"] = {"run": r_run, "experiment": r_exp, "rel": (r_run - r_exp) / r_exp}
    m["sensors"] = {}
    for n in SENSORS[:3]:
        t, p = run_p[n]
        m["sensors"][n] = {
            "peak": peak(t, p, r_run), "peak_exp": peak(te, exp_p[n], r_exp),
            "peak_mean": peak_mean(t, p, r_run, tau), "peak_mean_exp": peak_mean(te, exp_p[n], r_exp, tau)}
        s = m["sensors"][n]
        s["ratio"] = s["peak"] / s["peak_exp"]
        s["ratio_mean"] = s["peak_mean"] / s["peak_mean_exp"]

    # sensor 2's repeat spread: the percentile series, read as the run's sensor 2 is
    sh, se = read_csv("lobovsky_2014_sensor2_percentiles.csv")
    s2 = m["sensors"]["sensor2"]
    spread = {}
    for c, key in (("p2_5", "p2.5"), ("median", "median"), ("p97_5", "p97.5")):
        y = se[:, sh.index(c)]
        spread[key] = {"peak": peak(se[:, 0], y, r_exp), "peak_mean": peak_mean(se[:, 0], y, r_exp, tau)}
    for q in ("peak", "peak_mean"):
        lo, hi, v = spread["p2.5"][q], spread["p97.5"][q], s2[q]
        spread[q + "_inside"] = bool(lo <= v <= hi)
        spread[q + "_rel_outside"] = rel_outside(v, lo, hi)
    t2, p2 = run_p["sensor2"]
    spread["rms_outside"], spread["inside_fraction"] = band_fit(
        t2, p2, r_run, se[:, 0], se[:, sh.index("p2_5")], se[:, sh.index("p97_5")], r_exp)
    s2["spread"] = spread

    # levels: the level gauges H1-H4 of the case (kind: level, gauges.h5)
    hs, tls = {}, {}
    with h5py.File(os.path.join(a.out, "gauges.h5"), "r") as f:
        for g, _ in GAUGES:
            if g not in f["probes"] or "h" not in f["probes"][g]:
                sys.stderr.write("compare_lobovsky: %s/gauges.h5 has no level gauge %s (kind: level); run "
                                 "cases/dam_break_lobovsky_2d.yaml as it is\n" % (a.out, g))
                return 2
            tls[g] = f["probes"][g]["t"][:] / TS
            hs[g] = f["probes"][g]["h"][:] / H
    m["levels"] = {}
    for g, _ in GAUGES:
        tl = tls[g]
        tmax = min(tl[-1], a.level_tmax)
        runs = [c for c in lh if c.startswith(g + "_")]
        cols = [le[:, lh.index(c)] for c in runs]
        mean_exp = np.mean(cols, axis=0)
        sel = tl <= tmax
        he = np.interp(tl[sel], le[:, 0], mean_exp)
        hr = hs[g][sel]
        d = {"mean_abs_diff": float(np.mean(np.abs(hr - he))), "t_star_max": float(tmax)}
        # arrival of the front: first h/H >= 0.05 (H1 stands in the column: skipped)
        if g != "H1":
            i_r, i_e = np.flatnonzero(hs[g] >= 0.05), np.flatnonzero(mean_exp >= 0.05)
            if len(i_r) and len(i_e):
                d["arrival"], d["arrival_exp"] = float(tl[i_r[0]]), float(le[i_e[0], 0])
                d["arrival_rel"] = (d["arrival"] - d["arrival_exp"]) / d["arrival_exp"]
        if len(cols) == 2:
            both = le[:, 0] <= tmax
            d["runs_mean_abs_diff"] = float(np.mean(np.abs(cols[0][both] - cols[1][both])))
        m["levels"][g] = d

    ok = True
    msgs = []
    if not abs(m["rise"]["rel"]) <= a.rise_tol:  # (a run without an impact fails too)
        ok = False
        msgs.append("rise")
    for n, s in m["sensors"].items():
        if n in a.sensors and not (a.peak_band[0] <= s["ratio_mean"] <= a.peak_band[1]):
            ok = False
            msgs.append(n + ".peak_mean")
    if a.spread_tol is not None:
        sp = m["sensors"]["sensor2"]["spread"]
        if not (sp["p2.5"]["peak_mean"] * (1 - a.spread_tol) <= m["sensors"]["sensor2"]["peak_mean"] <=
                sp["p97.5"]["peak_mean"] * (1 + a.spread_tol)):
            ok = False
            msgs.append("sensor2.peak_mean.spread")
    for g, d in m["levels"].items():
        if d["mean_abs_diff"] > a.level_tol:
            ok = False
            msgs.append(g + ".level")
    m["bounds"] = {"rise_tol": a.rise_tol, "peak_band": a.peak_band, "level_tol": a.level_tol,
                   "sensors_checked": a.sensors, "spread_tol": a.spread_tol}
    m["pass"] = ok
    m["failed"] = msgs

    print("impact at sensor 1: t* %.3f (experiment %.3f, %+.2f %%)" % (r_run, r_exp, 100 * m["rise"]["rel"]))
    for n, s in m["sensors"].items():
        print("%s: peak %.2f (exp %.2f, x%.2f); %g ms mean %.2f (exp %.2f, x%.2f)" % (
            n, s["peak"], s["peak_exp"], s["ratio"], a.window, s["peak_mean"], s["peak_mean_exp"], s["ratio_mean"]))
        if "spread" in s:
            sp = s["spread"]
            def where(q):
                r = sp[q + "_rel_outside"]
                return "no value" if r is None else "inside" if sp[q + "_inside"] else "outside by %+.1f %%" % (100 * r)
            print("%s against the experiment's repeat spread (2.5-97.5 %%, median): peak %.2f-%.2f (%.2f): %s; "
                  "%g ms mean %.2f-%.2f (%.2f): %s" % (
                      n, sp["p2.5"]["peak"], sp["p97.5"]["peak"], sp["median"]["peak"], where("peak"),
                      a.window, sp["p2.5"]["peak_mean"], sp["p97.5"]["peak_mean"], sp["median"]["peak_mean"],
                      where("peak_mean")))
            print("%s against the spread over %.2f t* after the impact: %s" % (
                n, PEAK_SPAN, "RMS distance from the band %.3f, %.0f %% of the samples inside it" % (
                    sp["rms_outside"], 100 * sp["inside_fraction"]) if np.isfinite(sp["rms_outside"]) else "no value"))
    for g, d in m["levels"].items():
        print("%s: mean |h - h_exp| / H = %.3f over t* <= %.2f%s%s" % (
            g, d["mean_abs_diff"], d["t_star_max"],
            " (runs 01/02 differ by %.3f)" % d["runs_mean_abs_diff"] if "runs_mean_abs_diff" in d else "",
            "; front (h >= 0.05 H) at t* %.2f (experiment %.2f, %+.1f %%)" % (
                d["arrival"], d["arrival_exp"], 100 * d["arrival_rel"]) if "arrival" in d else ""))
    with open(a.json or os.path.join(a.out, "lobovsky.json"), "w") as fh:
        lahar_py.dump_json(m, fh)

    if not a.no_plot:
        fig, axes = plt.subplots(4, 2, figsize=(12, 10), sharex="col")
        for k, n in enumerate(SENSORS):
            ax = axes[k, 0]
            t, p = run_p[n]
            ax.plot(te, exp_p[n], "k", lw=1.2, label="Lobovsky 2014, peak event 5")
            if n == "sensor2":
                ax.fill_between(se[:, 0], se[:, sh.index("p2_5")], se[:, sh.index("p97_5")], color="0.75",
                                label="Lobovsky 2014, 2.5-97.5 % of the runs")
            ax.plot(t, p, lw=0.7, label="lahar, dx %g mm" % (1e3 * dx))
            w = max(1, int(round(tau / np.median(np.diff(t)))))
            ax.plot(t, np.convolve(p, np.ones(w) / w, mode="same"), lw=1.0,
                    label="lahar, %g ms running mean" % a.window)
            ax.set_xlim(2.2, min(7.0, t[-1]))
            ax.set_ylabel("p/ρgH, " + n)
            ax.grid(alpha=0.3)
            if k <= 1:
                ax.legend(fontsize=7)
        axes[-1, 0].set_xlabel("t √(g/H)")
        for k, (g, xg) in enumerate(GAUGES):
            ax = axes[k, 1]
            for c in [c for c in lh if c.startswith(g + "_")]:
                ax.plot(le[:, 0], le[:, lh.index(c)], "k" if c.endswith("run1") else "0.5", lw=1.0,
                        label="Lobovsky 2014, " + ("ETSIN 01" if c.endswith("run1") else "ETSIN 02"))
            ax.plot(tls[g], hs[g], lw=0.8, label="lahar, level gauge")
            ax.set_xlim(0, min(7.0, tls[g][-1]))
            ax.set_ylabel("h/H, %s (x = %g m)" % (g, xg))
            ax.grid(alpha=0.3)
            if k == 0:
                ax.legend(fontsize=7)
        axes[-1, 1].set_xlabel("t √(g/H)")
        fig.tight_layout()
        png = a.output or os.path.join(a.out, "lobovsky.png")
        fig.savefig(png, dpi=90)
        print("wrote", png)
    if a.check and not ok:
        print("FAIL:", ", ".join(msgs))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
