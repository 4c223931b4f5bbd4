#!/usr/bin/python3
"""The debris flow of Trujillo-Vela et al. 2020 §6 (cases/debris_flow_2d.yaml) after a run: what
`lahar check` (reference landslide) does not assert.

  debris_flow_check.py RUN [--pore-lo F] [--pore-hi F]

RUN is the output folder of the run (its case: the header's case_path). Asserts:
  - no water particle below the terrain's polyline at any snapshot (the soil: `lahar check`);
  - mass balance of the open boundaries at every snapshot: the domain's mass changed by
    entered - removed (water and soil) within 1e-12 of the domain's mass (round-off), and the
    domain's particle count by the entered - removed counts exactly;
  - the inlet delivered water (entered > 0) and the soil's particle count is kept;
  - pore pressure in the soil: at the last snapshot the water particles in the columns (dx wide) that
    hold soil carry pressure; least squares p = a rho_w g d, d the depth below the column's highest
    water particle + dx/2, with a in [pore-lo, pore-hi] (default 0.4 .. 1.2: on the 20-25 deg slope
    the slope-normal hydrostatic part is cos^2 = 0.82-0.88 of the vertical one; measured 0.67 at
    dx = 1 m, t = 5 s), and more than 80 % of them with p > 0;
  - boulders' potential energy (forces.h5 /energy E_P, eq. 37): for a boulder whose centre stays
    on the flat (x > 193.1 m + 2 R) over the last 2 s of the run, E_P constant within 1 % of m g R
    (the paper's Fig. 26a); a boulder not there yet is reported, not asserted.
  - particle count against the paper's (Trujillo-Vela et al. 2020 §6: 7662 SPH points at the start,
    8216 at the end of the 30 s with its three boulders, dx = 0.5 m), scaled by (0.5 m / dx)^2 for
    another dx and, for a scene with fewer boulders, raised by the lattice points of the missing
    discs (2 phases x pi R_B^2 / dx^2 each): all particles (the inlet's buffer included) at the
    first snapshot within --count-tol (default 5 %) of the start count, and, when the run reaches
    30 s, at the last snapshot within --count-tol of the end count;
  - the inlet's volume: the particles that entered x dx^2 against 5 m x the integral of eq. 36
    (a_G [G(t) - G(t0)], G the Gumbel CDF, up to t and the inlet's end) within one row (5 m x dx)
    + 2 %.
Also printed (information, docs/bench/debris_flow.md): the front (99 % quantile of the soil's and
the water's x) per snapshot, its largest speed between snapshots and where it ends; the trackers'
peak speeds; the control volumes' peak E_K (total and the bodies' part) and when, and per passage
of a body through a control volume its peak E_K, the body's part and which boulder it was.
Exit 0 when all hold, 1 otherwise."""
import argparse
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tools"))
import lahar_py  # noqa: E402

lahar_py.require("h5py", "numpy", "yaml")
import h5py  # noqa: E402
import numpy as np  # noqa: E402
import yaml  # noqa: E402

FOOT_X, R_B = 193.1, 2.0
# Trujillo-Vela et al. 2020 §6: SPH points at the start and at the end (30 s), dx = 0.5 m, 3 boulders
PAPER_DX, PAPER_N0, PAPER_N1, PAPER_T1, PAPER_BOULDERS = 0.5, 7662, 8216, 30.0, 3


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run")
    ap.add_argument("--pore-lo", type=float, default=0.4)
    ap.add_argument("--pore-hi", type=float, default=1.2)
    ap.add_argument("--count-tol", type=float, default=0.05)
    a = ap.parse_args()
    fails = []
    with h5py.File(os.path.join(a.run, "particles.h5"), "r") as f:
        dx = float(f["header"].attrs["dx"])
        rho_w = float(f["header"].attrs["rest_density"])
        snaps = f["snapshots"]
        keys = sorted(snaps.keys())
        with open(f["header"].attrs["case_path"]) as cf:
            case = yaml.safe_load(cf)
        tp = np.array(case["terrain"]["points"], dtype=float)
        through = 0
        for k in keys:
            g = snaps[k]
            w = (g["phase"][:] == 0) & (g["inlet"][:] < 0)
            xw, yw = g["x"][:][w], g["y"][:][w]
            inside = (xw >= tp[0, 0]) & (xw <= tp[-1, 0])
            through = max(through, int(np.sum(yw[inside] < np.interp(xw[inside], tp[:, 0], tp[:, 1]))))
        print("debris_flow_check: water particles below the terrain's line: %d (bound 0)" % through)
        if through:
            fails.append("%d water particles through the terrain" % through)
        s0 = snaps[keys[0]]
        m0 = s0.attrs["flow_domain_mass"]
        n0 = int(np.sum(s0["inlet"][:] < 0))
        soil0 = int(np.sum(s0["phase"][:] == 1))
        worst = 0.0
        for k in keys:
            g = snaps[k]
            at = g.attrs
            dm = at["flow_domain_mass"] - m0
            flow = at["flow_entered_mass"] - at["flow_removed_water_mass"] - at["flow_removed_soil_mass"]
            worst = max(worst, abs(dm - flow) / at["flow_domain_mass"])
            dn = int(np.sum(g["inlet"][:] < 0)) - n0
            dflow = int(at["flow_entered"] - at["flow_removed_water"] - at["flow_removed_soil"])
            if dn != dflow:
                fails.append("snapshot %s: domain count changed by %d, entered - removed = %d" % (k, dn, dflow))
        print("debris_flow_check: mass balance worst |dM - (in - out)| / M = %.3g (bound 1e-12)" % worst)
        if worst > 1e-12:
            fails.append("mass balance %.3g > 1e-12" % worst)
        fronts = []
        for k in keys:
            g = snaps[k]
            dom = g["inlet"][:] < 0
            fronts.append((g.attrs["time"], float(np.quantile(g["x"][:][dom], 0.99))))
        fr = np.array(fronts)
        vf = np.diff(fr[:, 1]) / np.diff(fr[:, 0])
        kmax = int(np.argmax(vf))
        print("debris_flow_check: front (99 %% of x) %.1f -> %.1f m (run-out %.1f m), fastest %.1f m/s at t = %.1f-%.1f s"
              % (fr[0, 1], fr[-1, 1], fr[-1, 1] - fr[0, 1], vf[kmax], fr[kmax, 0], fr[kmax + 1, 0]))
        g = snaps[keys[-1]]
        if g.attrs["flow_entered"] <= 0:
            fails.append("the inlet delivered no water")
        ph, inl, p = g["phase"][:], g["inlet"][:], g["pressure"][:]
        x, y = g["x"][:], g["y"][:]
        soil1 = int(np.sum(ph == 1))
        print("debris_flow_check: particles %d -> %d (soil %d -> %d), entered %d, removed water %d soil %d, t = %g s"
              % (len(s0["x"]), len(x), soil0, soil1, g.attrs["flow_entered"], g.attrs["flow_removed_water"],
                 g.attrs["flow_removed_soil"], g.attrs["time"]))
        # the paper's counts, scaled to this dx and this number of boulders
        nb = sum(1 for b in case.get("bodies", []) if str(b.get("name", "")).startswith("boulder"))
        holes = (PAPER_BOULDERS - nb) * 2 * np.pi * R_B ** 2 / PAPER_DX ** 2
        scale = (PAPER_DX / dx) ** 2
        ref0, ref1 = (PAPER_N0 + holes) * scale, (PAPER_N1 + holes) * scale
        n_start, n_end, t1 = len(s0["x"]), len(x), float(g.attrs["time"])
        print("debris_flow_check: particle count at the start %d, paper's %.0f (scaled to dx = %g m, %d boulders): %+.1f %% "
              "(bound %g %%)" % (n_start, ref0, dx, nb, 100 * (n_start / ref0 - 1), 100 * a.count_tol))
        if abs(n_start / ref0 - 1) > a.count_tol:
            fails.append("start count %d vs paper's %.0f" % (n_start, ref0))
        if t1 >= PAPER_T1 - 1e-9:
            print("debris_flow_check: particle count at %g s %d, paper's %.0f: %+.1f %% (bound %g %%)"
                  % (t1, n_end, ref1, 100 * (n_end / ref1 - 1), 100 * a.count_tol))
            if abs(n_end / ref1 - 1) > a.count_tol:
                fails.append("end count %d vs paper's %.0f" % (n_end, ref1))
        else:
            print("debris_flow_check: run ends at %g s before the paper's %g s: end count %d (paper's %.0f) not asserted"
                  % (t1, PAPER_T1, n_end, ref1))
        for ild in case.get("inlets", []):
            if "gumbel" not in ild:
                continue
            aG, bG, mG = (float(v) for v in ild["gumbel"])
            t0, te = float(ild.get("start", 0.0)), min(t1, float(ild.get("end", t1)))
            cdf = lambda tt: np.exp(-np.exp(-(tt - mG) / bG))  # noqa: E731
            level = float(ild["level"])
            vref = level * aG * (cdf(te) - cdf(t0)) if te > t0 else 0.0
            vin = float(g.attrs["flow_entered"]) * dx * dx
            bound = level * dx + 0.02 * vref
            print("debris_flow_check: inlet %s: %.1f m^2 entered by %g s, eq. 36: %.1f m^2 (bound %.2g)"
                  % (ild.get("name", "?"), vin, t1, vref, bound))
            if abs(vin - vref) > bound:
                fails.append("inlet volume %.1f vs eq. 36 %.1f m^2" % (vin, vref))
        if soil1 + g.attrs["flow_removed_soil"] != soil0:
            fails.append("soil count %d + removed %d != %d" % (soil1, g.attrs["flow_removed_soil"], soil0))
        w = (ph == 0) & (inl < 0)
        col = np.floor(x / dx).astype(np.int64)
        top = {}
        for c, yy in zip(col[w], y[w]):
            top[c] = max(top.get(c, -np.inf), yy)
        soilcols = set(col[ph == 1].tolist())
        sel = w & np.isin(col, list(soilcols))
        d = np.array([top[c] - yy + 0.5 * dx for c, yy in zip(col[sel], y[sel])])
        ph_ = rho_w * 9.81 * d
        pw = p[sel]
        ratio = float(np.sum(pw * ph_) / np.sum(ph_ * ph_)) if sel.any() else 0.0
        pos = float(np.mean(pw > 0)) if sel.any() else 0.0
        print("debris_flow_check: pore pressure in the soil: %d water particles, p = %.3f rho_w g d "
              "(bound [%g, %g]), %.1f %% positive, median %.4g Pa" % (sel.sum(), ratio, a.pore_lo, a.pore_hi,
                                                                      100 * pos, np.median(pw) if sel.any() else 0))
        if not (a.pore_lo <= ratio <= a.pore_hi) or pos < 0.8:
            fails.append("pore pressure: ratio %.3f, %.1f %% positive" % (ratio, 100 * pos))
    with h5py.File(os.path.join(a.run, "forces.h5"), "r") as f:
        names = [n.decode() if isinstance(n, bytes) else str(n) for n in f.attrs["body_names"]]
        t = f["t"][:]
        ep = f["energy"][:, :, 0]
    with h5py.File(os.path.join(a.run, "bodies.h5"), "r") as b:
        snaps = b["snapshots"]
        bk = sorted(snaps.keys())
        bt = np.array([snaps[k].attrs["time"] for k in bk]) if "time" in snaps[bk[0]].attrs else None
        pos = np.array([snaps[k]["position"][:, 0] for k in bk])
    t_end = t[-1]
    for i, n in enumerate(names):
        if not n.startswith("boulder"):
            continue
        late = (bt >= t_end - 2.0) if bt is not None else np.arange(len(bk)) >= len(bk) - 5
        on_flat = bool(np.all(pos[late, i] > FOOT_X + 2 * R_B))
        if not on_flat:
            print("debris_flow_check: %s not on the flat over the last 2 s (x = %.1f m): E_P not asserted" % (n, pos[-1, i]))
            continue
        e = ep[t >= t_end - 2.0, i]
        m = np.pi * R_B ** 2 * 2200.0
        spread = float(e.max() - e.min()) / (m * 9.81 * R_B)
        print("debris_flow_check: %s on the flat: E_P spread over the last 2 s = %.3g m g R (bound 0.01)" % (n, spread))
        if spread > 0.01:
            fails.append("%s E_P varies by %.3g m g R on the flat" % (n, spread))
    with h5py.File(os.path.join(a.run, "gauges.h5"), "r") as f:
        for n in sorted(f.get("trackers", {}).keys()):
            tr = f["trackers"][n]
            sp = np.hypot(tr["vx"][:], tr["vy"][:])
            i = int(np.nanargmax(sp))  # NaN once the tracked particle has left the domain
            print("debris_flow_check: tracker %s: peak speed %.1f m/s at %.1f s" % (n, sp[i], tr["t"][i]))
        for n in sorted(f.get("control_volumes", {}).keys()):
            cv = f["control_volumes"][n]
            ek, eb, tc = cv["ek"][:], cv["ek_bodies"][:], cv["t"][:]
            i, j = int(np.argmax(ek)), int(np.argmax(eb))
            print("debris_flow_check: control volume %s: peak E_K %.3g J/m at %.2f s; bodies' part peak %.3g J/m at %.2f s"
                  % (n, ek[i], tc[i], eb[j], tc[j]))
            # each passage of a body (a run of samples with a body in the box): its peak E_K, the
            # body's part then, which boulder (nearest centre, x interpolated between body snapshots)
            on = eb > 0
            starts = np.flatnonzero(on & ~np.concatenate([[False], on[:-1]]))
            ends = np.flatnonzero(on & ~np.concatenate([on[1:], [False]]))
            xc = 0.5 * (cv.attrs["lo"][0] + cv.attrs["hi"][0])
            for s0_, e0_ in zip(starts, ends):
                k = s0_ + int(np.argmax(ek[s0_:e0_ + 1]))
                who = "?"
                if bt is not None:
                    d = [abs(np.interp(tc[k], bt, pos[:, bi]) - xc) if nm.startswith("boulder") else np.inf
                         for bi, nm in enumerate(names)]
                    who = names[int(np.argmin(d))]
                print("debris_flow_check: control volume %s: %s passes %.2f-%.2f s: peak E_K %.3g J/m at %.2f s "
                      "(the body's part %.3g, the particles' %.3g)"
                      % (n, who, tc[s0_], tc[e0_], ek[k], tc[k], eb[k], ek[k] - eb[k]))
    for msg in fails:
        print("debris_flow_check: FAIL " + msg)
    print("debris_flow_check: %s" % ("PASS" if not fails else "FAIL"))
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
