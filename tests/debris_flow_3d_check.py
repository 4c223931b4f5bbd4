#!/usr/bin/python3
"""The 3D debris flow on a heightmap against a check dam (cases/debris_flow_3d.yaml) after a run:
what `lahar check` (reference dam_break: count kept, nothing inside a body) does not assert.

  debris_flow_3d_check.py RUN [--window S] [--momentum-tol F] [--joukowsky-hi F]

RUN is the output folder of the run (its case: particles.h5's header case_path). Asserts:
  - nothing through the heightmap: at every snapshot every particle above the terrain's
    triangulated surface (the .asc nodes, two triangles per cell split along the (i, j)-(i+1, j+1)
    diagonal, as common/io/terrain.c builds it) at its (x, y); bound 0 particles;
  - mass balance: no particle left the domain box (flow_removed_* 0), the particle count of each
    phase and the domain's mass (flow_domain_mass) unchanged at every snapshot, to round-off (1e-12);
  - the dam is loaded: the force on the body `dam` along the flow (+x, forces.h5, every step) is
    positive after the front arrives;
  - momentum balance along x (gravity is along -z): the x-momentum of the particles and the boulders
    at each snapshot equals minus the impulse of the fixed bodies' forces (dam + terrain; forces.h5,
    the trapezoidal rule over every step) within --momentum-tol (default 0.02) of the largest
    |P_x|: the dam's force is the force the flow feels (Newton's third law through the coupling);
  - the impact pressure: the largest pressure on the dam's lowest probe lies between the
    incompressible stagnation pressure rho_w u^2 / 2 + rho_w g h_p (h_p: the flow's depth above the
    probe when the force peaks, from the snapshot nearest to it) and --joukowsky-hi (default 2)
    x the acoustic (Joukowsky) pressure rho_w c0 u of a weakly compressible fluid stopped by a
    rigid wall; u the arriving flow's mean speed sqrt(2 E_K / M) in the control volume at its
    largest momentum flux. The peak is of the order of rho_w c0 u (measured 0.96, 0.82, 1.35, 0.37 x
    at dx = 0.4, 0.3, 0.2, 0.1 m; the front's local speed exceeds the mean), 10-45 x the
    incompressible rho_w u^2: a dam the flow never reaches, or a pressure far above the acoustic
    one, fails it.
Also printed (information): the dam's peak force (averaged over --window, default 0.02 s) against
the momentum flux rho u^2 A = 2 E_K / L of the control volume just upstream of the dam (L its length
along x; the hydrodynamic impact model F = alpha rho u^2 A) and against the hydrostatic thrust of
the material in the control volume, (M / L) g (eta - z_G) (eta: its top + dx/2, z_G: its centre of
mass) at the snapshots; the front (99 % of x) per snapshot, the trackers' peak speeds, the probes'
peaks.
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


def read_asc(path):
    head, rows = {}, []
    with open(path) as f:
        for line in f:
            w = line.split()
            if not w:
                continue
            if len(head) < 6 and w[0][0].isalpha():
                head[w[0].lower()] = float(w[1])
            else:
                rows.append([float(v) for v in w])
    z = np.array(rows[::-1])  # row 0 = the southern row
    cs = head["cellsize"]
    x0 = head["xllcenter"] if "xllcenter" in head else head["xllcorner"] + 0.5 * cs
    y0 = head["yllcenter"] if "yllcenter" in head else head["yllcorner"] + 0.5 * cs
    return x0, y0, cs, z


def terrain_z(grid, x, y):
    """Elevation of the triangulated heightmap at (x, y): cells split along (i, j)-(i+1, j+1)."""
    x0, y0, cs, z = grid
    nr, nc = z.shape
    u, v = (x - x0) / cs, (y - y0) / cs
    j = np.clip(np.floor(u).astype(int), 0, nc - 2)
    i = np.clip(np.floor(v).astype(int), 0, nr - 2)
    fu, fv = u - j, v - i
    za, zb, zc, zd = z[i, j], z[i, j + 1], z[i + 1, j + 1], z[i + 1, j]
    lower = fu >= fv  # triangle (a, b, c): below the diagonal
    return np.where(lower, za + fu * (zb - za) + fv * (zc - zb), za + fv * (zd - za) + fu * (zc - zd))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run")
    ap.add_argument("--window", type=float, default=0.02)
    ap.add_argument("--momentum-tol", type=float, default=0.02)
    ap.add_argument("--joukowsky-hi", type=float, default=2.0)
    a = ap.parse_args()
    fails = []
    with h5py.File(os.path.join(a.run, "particles.h5"), "r") as f:
        case_path = f["header"].attrs["case_path"]
        case_path = case_path.decode() if isinstance(case_path, bytes) else str(case_path)
        with open(case_path) as cf:
            case = yaml.safe_load(cf)
        asc = case["terrain"]["file"]
        if not os.path.isabs(asc):
            asc = os.path.join(os.path.dirname(case_path), asc)
        grid = read_asc(asc)
        dx = float(f["header"].attrs["dx"])
        rho_w = float(f["header"].attrs["rest_density"])
        rho_s = float(case["materials"][case["sph"]["blocks"][0]["material"]]["density"])
        c0 = float(case["sph"]["c0"])
        cvd = case["control_volumes"][0]["box"]
        cv_lo, cv_hi = np.array(cvd["lo"], float), np.array(cvd["hi"], float)
        snaps = f["snapshots"]
        keys = sorted(snaps.keys())
        s0 = snaps[keys[0]]
        ph0 = s0["phase"][:]
        n0 = [int(np.sum(ph0 == 0)), int(np.sum(ph0 == 1))]
        m0 = float(s0.attrs["flow_domain_mass"])
        through, worst_mass, lowest = 0, 0.0, np.inf
        fronts, px, thrust = [], [], []
        for k in keys:
            g = snaps[k]
            x, y, zz, ph = g["x"][:], g["y"][:], g["z"][:], g["phase"][:]
            gap = zz - terrain_z(grid, x, y)
            through = max(through, int(np.sum(gap < 0.0)))
            lowest = min(lowest, float(gap.min()))
            at = g.attrs
            n = [int(np.sum(ph == 0)), int(np.sum(ph == 1))]
            if n != n0 or at["flow_removed_water"] or at["flow_removed_soil"]:
                fails.append("snapshot %s: particles water/soil %s (start %s), removed %d/%d"
                             % (k, n, n0, at["flow_removed_water"], at["flow_removed_soil"]))
            worst_mass = max(worst_mass, abs(float(at["flow_domain_mass"]) - m0) / m0)
            fronts.append((float(at["time"]), float(np.quantile(x, 0.99))))
            m = np.where(ph == 1, rho_s, rho_w) * dx ** 3  # every block particle: rho0 dx^3
            px.append(float(np.sum(m * g["vx"][:])))
            inb = np.all([(c >= cv_lo[d]) & (c < cv_hi[d]) for d, c in enumerate((x, y, zz))], axis=0)
            M = float(np.sum(m[inb]))
            thrust.append(M / (cv_hi[0] - cv_lo[0]) * 9.81 * (zz[inb].max() + 0.5 * dx - np.sum(m[inb] * zz[inb]) / M)
                          if M > 0 else 0.0)
        times = np.array([fr[0] for fr in fronts])
        print("debris_flow_3d_check: %d snapshots, %d water + %d soil particles, t = %g .. %g s"
              % (len(keys), n0[0], n0[1], times[0], times[-1]))
        print("debris_flow_3d_check: particles below the heightmap's surface: %d (bound 0); the lowest particle "
              "%.4f m above it" % (through, lowest))
        if through:
            fails.append("%d particles through the terrain" % through)
        print("debris_flow_3d_check: domain mass change |M - M0| / M0 = %.3g (bound 1e-12)" % worst_mass)
        if worst_mass > 1e-12:
            fails.append("mass change %.3g > 1e-12" % worst_mass)
        print("debris_flow_3d_check: front (99 %% of x) %s"
              % ", ".join("%.1f s %.2f m" % fr for fr in fronts[:: max(1, len(fronts) // 8)] + [fronts[-1]]))
    with h5py.File(os.path.join(a.run, "forces.h5"), "r") as f:
        names = [n.decode() if isinstance(n, bytes) else str(n) for n in f.attrs["body_names"]]
        t = f["t"][:]
        force = f["force"][:]
    with h5py.File(os.path.join(a.run, "bodies.h5"), "r") as b:
        mass_b = b["header"]["mass"][:]
        bs = b["snapshots"]
        bt = {round(float(bs[k].attrs["time"]), 9): float(np.sum(mass_b * bs[k]["velocity"][:, 0])) for k in bs}
    fx = force[:, names.index("dam"), 0]
    fixed = [j for j, n in enumerate(names) if mass_b[j] == 0.0]
    cum_fixed = np.concatenate(([0.0], np.cumsum(0.5 * (force[1:, fixed, 0] + force[:-1, fixed, 0]).sum(axis=1)
                                                 * np.diff(t))))
    worst_p, pscale = 0.0, max(abs(v) for v in px) or 1.0
    for tk, pk in zip(times, px):
        pb = bt.get(round(float(tk), 9), np.nan)
        imp = float(np.interp(tk, np.concatenate(([0.0], t)), np.concatenate(([0.0], cum_fixed))))
        worst_p = max(worst_p, abs(pk + pb + imp) / pscale)
    print("debris_flow_3d_check: x-momentum of particles + boulders against minus the impulse of the fixed bodies' "
          "(%s) forces: worst difference %.3g of max |P_x| = %.4g N s (bound %g)"
          % (", ".join(names[j] for j in fixed), worst_p, pscale, a.momentum_tol))
    if not worst_p <= a.momentum_tol:
        fails.append("momentum balance %.3g > %g" % (worst_p, a.momentum_tol))
    # moving average over the window (the force of every step; steps are not equally spaced)
    tw = np.arange(t[0], t[-1], 0.25 * a.window)
    cum = np.concatenate(([0.0], np.cumsum(0.5 * (fx[1:] + fx[:-1]) * np.diff(t))))
    lo_t, hi_t = np.clip(tw - 0.5 * a.window, t[0], t[-1]), np.clip(tw + 0.5 * a.window, t[0], t[-1])
    favg = (np.interp(hi_t, t, cum) - np.interp(lo_t, t, cum)) / np.maximum(hi_t - lo_t, 1e-12)
    kp = int(np.argmax(favg))
    f_peak, t_peak = float(favg[kp]), float(tw[kp])
    hit = np.nonzero(favg > 0.05 * f_peak)[0]
    t_arrive = float(tw[hit[0]]) if len(hit) and f_peak > 0 else np.nan
    print("debris_flow_3d_check: dam force along x: peak %.4g N at %.3f s (%.3g s average), raw peak %.4g N, "
          "first load (> 5 %% of the peak) at %.3f s, at the end %.4g N"
          % (f_peak, t_peak, a.window, fx.max(), t_arrive, favg[-1]))
    if not (f_peak > 0.0) or not np.isfinite(t_arrive):
        fails.append("the dam is not loaded (peak %.4g N)" % f_peak)
    with h5py.File(os.path.join(a.run, "gauges.h5"), "r") as f:
        cvg = f["control_volumes"][case["control_volumes"][0]["name"]]
        L = float(cv_hi[0] - cv_lo[0])
        tc, ek = cvg["t"][:], cvg["ek"][:]
        mcv = cvg["mass_water"][:] + cvg["mass_soil"][:]
        flux = 2.0 * ek / L
        kf = int(np.argmax(flux))
        u = float(np.sqrt(2.0 * ek[kf] / mcv[kf])) if mcv[kf] > 0 else 0.0
        print("debris_flow_3d_check: momentum flux rho u^2 A = 2 E_K / L of the control volume (L = %.3g m): peak "
              "%.4g N at %.3f s (mass in it %.4g kg, u = %.3g m/s); F_peak / max(rho u^2 A) = %.3g (information)"
              % (L, flux[kf], tc[kf], mcv[kf], u, f_peak / flux[kf] if flux[kf] > 0 else np.inf))
        ks = int(np.argmin(np.abs(times - t_peak)))
        print("debris_flow_3d_check: hydrostatic thrust of the material in the control volume at %.2f s: %.4g N; "
              "F_peak / it = %.3g; at the end (%.2f s) %.4g N against the dam's %.4g N (information)"
              % (times[ks], thrust[ks], f_peak / thrust[ks] if thrust[ks] > 0 else np.inf, times[-1], thrust[-1],
                 favg[-1]))
        # the probes, lowest first; the flow's depth above the lowest one when it arrives
        pr = sorted(case.get("probes", []), key=lambda q: q["position"][2])
        for q in pr:
            g = f["probes"][q["name"]]
            tp, p = g["t"][:], g["p"][:]
            i = int(np.argmax(p))
            print("debris_flow_3d_check: probe %s (z = %.3f m): peak %.4g Pa at %.3f s" % (q["name"], q["position"][2],
                                                                                       p[i], tp[i]))
        if pr:
            q = pr[0]
            p = f["probes"][q["name"]]["p"][:]
            depth = max(thrust[ks] and 0.0, 0.0)
            with h5py.File(os.path.join(a.run, "particles.h5"), "r") as pf:
                g = pf["snapshots"][keys[ks]]
                x, y, zz = g["x"][:], g["y"][:], g["z"][:]
                near = (x >= cv_lo[0]) & (x < cv_hi[0]) & (np.abs(y - q["position"][1]) < 2 * dx)
                depth = float(zz[near].max() + 0.5 * dx - q["position"][2]) if near.any() else 0.0
            p_lo = 0.5 * rho_w * u * u + rho_w * 9.81 * max(depth, 0.0)
            p_hi = a.joukowsky_hi * rho_w * c0 * u
            print("debris_flow_3d_check: probe %s peak %.4g Pa: stagnation + hydrostatic rho u^2/2 + rho g h = %.4g Pa "
                  "(h = %.2f m), Joukowsky rho c0 u = %.4g Pa (peak / it = %.3f); bound [%.4g, %.4g] Pa"
                  % (q["name"], p.max(), p_lo, depth, rho_w * c0 * u, p.max() / (rho_w * c0 * u) if u > 0 else np.inf,
                     p_lo, p_hi))
            if not (p_lo <= p.max() <= p_hi):
                fails.append("probe %s peak %.4g Pa outside [%.4g, %.4g]" % (q["name"], p.max(), p_lo, p_hi))
        for n in sorted(f.get("trackers", {}).keys()):
            tr = f["trackers"][n]
            sp = np.sqrt(tr["vx"][:] ** 2 + tr["vy"][:] ** 2 + tr["vz"][:] ** 2)
            i = int(np.nanargmax(sp))
            print("debris_flow_3d_check: tracker %s: peak speed %.2f m/s at %.2f s" % (n, sp[i], tr["t"][i]))
    for msg in fails:
        print("debris_flow_3d_check: FAIL " + msg)
    print("debris_flow_3d_check: %s" % ("PASS" if not fails else "FAIL"))
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
