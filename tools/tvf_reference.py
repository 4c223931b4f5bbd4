#!/usr/bin/env python3
"""An independent implementation of the transport-velocity formulation (Adami, Hu & Adams 2013,
J. Comput. Phys. 241:292-307) for the 2D periodic Taylor-Green vortex, to check lahar's against.

usage: tvf_reference.py OUT [--check TOL] [--json FILE] [--png FILE]

OUT is a lahar run of a Taylor-Green case with the transport velocity (cases/taylor_green_2d.yaml
or a tools/case_override.py variant of it). The tool reads the run's case (dx, L from sph.periodic,
kernel, h_over_dx, c0, density, viscosity, background_pressure) and U from the run's first snapshot (U^2 = 2 <|v|^2>), runs the same vortex
with the formulation written out here in numpy, and compares the kinetic energy E(t)/E(0) of the
two at the run's snapshot times (the reference's energy interpolated between its steps).

Why: the energy of the vortex collapses by half at coarse resolution (25^2 or 50^2) around
t = 0.1-0.3 s while the particles rearrange near the hyperbolic stagnation points
(docs/bench/validation.md "Taylor-Green vortex"). Whether that is lahar's code or the formulation
is what this reference answers: it shares no code with lahar, and if the two histories agree
through the collapse, the collapse is the method's.

The reference, per Adami et al. 2013 (section 2, eqs. 7-8, 13-17), with V_i = 1/sum_j W_ij:
  rho_i = m sum_j W_ij (j includes i), p = rho0 c0^2 (rho/rho0 - 1),
  dv_i/dt = 1/m sum_j (V_i^2 + V_j^2) [-p~_ij grad_i W_ij + (A_i + A_j)/2 . grad_i W_ij
                                      + mu F_ij v_ij],  p~_ij = (rho_j p_i + rho_i p_j)/(rho_i + rho_j),
  A = rho v (x) (v~ - v), F_ij = W'(r)/r (so x_ij.grad W / r^2),
  b_i = -p_b/m sum_j (V_i^2 + V_j^2) grad_i W_ij,
  kick-drift-kick: v += dt/2 a; v~ = v + dt/2 b; x += dt v~; evaluate a, b; v += dt/2 a,
the case's kernel (Adami et al. use the quintic spline with h = dx; `kernel` below),
dt = min(0.25 h/(c0 + U), 0.125 h^2/nu) fixed.
lahar differs in two details it documents (sph_node/fluid/sph_fluid.h): its steps adapt to the
largest speed, and it evaluates the rates with the predicted velocity instead of v(t + dt/2).

--check TOL: exit 1 if |E_lahar/E_reference - 1| > TOL at any snapshot (a verdict line per
failure). --json FILE: the two histories and the largest deviation. --png FILE: both over the exact
decay exp(-16 pi^2 nu t / L^2) against t. Exit 2, with what to do, on a run that is not
such a case: no transport velocity, not a periodic square, or a first snapshot that
is not the vortex u = -U cos(2 pi x/L) sin(2 pi y/L), v = U sin cos (to 1e-6 U)."""
import argparse
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lahar_py  # noqa: E402

lahar_py.require("numpy", "h5py", "yaml")
import h5py  # noqa: E402
import numpy as np  # noqa: E402
import yaml  # noqa: E402

TOOL = "tvf_reference.py"


def fail(msg):
    sys.stderr.write(f"{TOOL}: {msg}\n")
    sys.exit(2)


def kernel(name, h):
    """W(r), W'(r) and the support of a 2D kernel lahar offers (sph.kernel), from its published
    form: cubic spline (Monaghan & Lattanzio 1985, 10/(7 pi h^2), support 2h), quintic spline
    (Morris et al. 1997, 7/(478 pi h^2), 3h), Wendland C2 (Wendland 1995, 7/(4 pi h^2), 2h)."""
    if name == "quintic":
        sig = 7.0 / (478.0 * math.pi * h * h)
        return (lambda q: sig * (np.where(q < 3, (3 - q) ** 5, 0) - 6 * np.where(q < 2, (2 - q) ** 5, 0)
                                 + 15 * np.where(q < 1, (1 - q) ** 5, 0)),
                lambda q: sig / h * (-5 * np.where(q < 3, (3 - q) ** 4, 0) + 30 * np.where(q < 2, (2 - q) ** 4, 0)
                                     - 75 * np.where(q < 1, (1 - q) ** 4, 0)), 3.0 * h)
    if name == "cubic":
        sig = 10.0 / (7.0 * math.pi * h * h)
        return (lambda q: sig * np.where(q < 1, 1 - 1.5 * q * q + 0.75 * q ** 3, np.where(q < 2, 0.25 * (2 - q) ** 3, 0)),
                lambda q: sig / h * np.where(q < 1, -3 * q + 2.25 * q * q, np.where(q < 2, -0.75 * (2 - q) ** 2, 0)),
                2.0 * h)
    if name == "wendland2":
        sig = 7.0 / (4.0 * math.pi * h * h)
        return (lambda q: sig * np.where(q < 2, (1 - 0.5 * q) ** 4 * (2 * q + 1), 0),
                lambda q: sig / h * np.where(q < 2, -5 * q * (1 - 0.5 * q) ** 3, 0), 2.0 * h)
    fail(f"kernel {name!r}: the reference knows cubic, quintic and wendland2")


def pairs(x, y, L, support):
    """Ordered pairs (i, j), i itself included, within `support` in the periodic square of side L,
    with x_ij = x_i - x_j by the nearest image: from a cell list of cells >= support."""
    nc = max(3, int(L // support))
    cs = L / nc
    cell = (np.floor(x / cs).astype(int) % nc) * nc + np.floor(y / cs).astype(int) % nc
    order = np.argsort(cell, kind="stable")
    start = np.searchsorted(cell[order], np.arange(nc * nc))
    end = np.searchsorted(cell[order], np.arange(nc * nc), side="right")
    I, J = [], []
    for a in range(nc):
        for b in range(nc):
            pi = order[start[a * nc + b]:end[a * nc + b]]
            for da in (-1, 0, 1):
                for db in (-1, 0, 1):
                    c2 = ((a + da) % nc) * nc + (b + db) % nc
                    pj = order[start[c2]:end[c2]]
                    I.append(np.repeat(pi, len(pj)))
                    J.append(np.tile(pj, len(pi)))
    I, J = np.concatenate(I), np.concatenate(J)
    rx, ry = x[I] - x[J], y[I] - y[J]
    rx -= L * np.round(rx / L)
    ry -= L * np.round(ry / L)
    r = np.hypot(rx, ry)
    keep = r < support
    return I[keep], J[keep], rx[keep], ry[keep], r[keep]


def taylor_green(n, L, U, rho0, mu, c0, pb, hdx, kern, t_end):
    """Times and E/E0 of the reference run: n x n particles, one entry per step."""
    dx = L / n
    h = hdx * dx
    w, dw, support = kernel(kern, h)
    nu = mu / rho0
    p0 = rho0 * c0 * c0
    xs = (np.arange(n) + 0.5) * dx
    X, Y = np.meshgrid(xs, xs, indexing="ij")
    x, y = X.ravel().copy(), Y.ravel().copy()
    k = 2 * math.pi / L
    u = -U * np.cos(k * x) * np.sin(k * y)
    v = U * np.sin(k * x) * np.cos(k * y)
    m, N = rho0 * dx * dx, n * n

    def rates(uh, vh):
        I, J, rx, ry, r = pairs(x, y, L, support)
        vinv = np.bincount(I, w(r / h), N)
        rho, V = m * vinv, 1.0 / vinv
        p = p0 * (rho / rho0 - 1.0)
        nz = r > 0
        I, J, rx, ry, r = I[nz], J[nz], rx[nz], ry[nz], r[nz]
        F = dw(r / h) / r
        gx, gy = F * rx, F * ry
        vv = V[I] ** 2 + V[J] ** 2
        pij = (rho[J] * p[I] + rho[I] * p[J]) / (rho[I] + rho[J])
        axx, axy = rho * u * (uh - u), rho * u * (vh - v)
        ayx, ayy = rho * v * (uh - u), rho * v * (vh - v)
        ax = vv * (-pij * gx + 0.5 * ((axx[I] + axx[J]) * gx + (axy[I] + axy[J]) * gy) + mu * F * (u[I] - u[J]))
        ay = vv * (-pij * gy + 0.5 * ((ayx[I] + ayx[J]) * gx + (ayy[I] + ayy[J]) * gy) + mu * F * (v[I] - v[J]))
        return (np.bincount(I, ax, N) / m, np.bincount(I, ay, N) / m,
                np.bincount(I, -pb * vv * gx, N) / m, np.bincount(I, -pb * vv * gy, N) / m)

    dt = min(0.25 * h / (c0 + U), 0.125 * h * h / nu)
    ax, ay, bx, by = rates(u, v)
    e0 = np.sum(u * u + v * v)
    ts, es = [0.0], [1.0]
    t = 0.0
    while t < t_end:
        u += 0.5 * dt * ax
        v += 0.5 * dt * ay
        uh, vh = u + 0.5 * dt * bx, v + 0.5 * dt * by
        x = (x + dt * uh) % L
        y = (y + dt * vh) % L
        ax, ay, bx, by = rates(uh, vh)
        u += 0.5 * dt * ax
        v += 0.5 * dt * ay
        t += dt
        ts.append(t)
        es.append(float(np.sum(u * u + v * v) / e0))
    return np.array(ts), np.array(es)


def lahar_history(out):
    """Snapshot times and E/E0 (E = sum |v|^2, equal masses) of the run, and U of its first snapshot."""
    path = os.path.join(out, "particles.h5")
    try:
        with h5py.File(path, "r") as f:
            snaps = f["snapshots"]
            ts, es = [], []
            for key in sorted(snaps):
                g = snaps[key]
                ts.append(float(g.attrs["time"]))
                es.append(float(np.sum(g["vx"][:] ** 2 + g["vy"][:] ** 2)))
            first = snaps[sorted(snaps)[0]]
            x0, y0, u0, v0 = first["x"][:], first["y"][:], first["vx"][:], first["vy"][:]
    except (OSError, KeyError) as exc:
        fail(f"{path}: {exc}; give the output directory of a finished lahar run")
    if len(ts) < 2:
        fail(f"{path}: {len(ts)} snapshot(s); the comparison needs the run's history (time.output_interval)")
    U = math.sqrt(2.0 * es[0] / len(u0))
    return np.array(ts), np.array(es) / es[0], U, (x0, y0, u0, v0)


def require_taylor_green(first, U, L, path):
    """Exit 2 unless the run started from the vortex the reference runs, u = -U cos kx sin ky,
    v = U sin kx cos ky (k = 2 pi / L, x from 0), at its own particle positions."""
    x, y, u, v = first
    k = 2 * math.pi / L
    err = max(np.max(np.abs(u + U * np.cos(k * x) * np.sin(k * y))), np.max(np.abs(v - U * np.sin(k * x) * np.cos(k * y))))
    if not err <= 1e-6 * U:
        fail(f"{path}: the first snapshot is not the Taylor-Green vortex u = -U cos(2 pi x/L) sin(2 pi y/L), "
             f"v = U sin cos (off by {err:.3g} m/s at U = {U:.4g} m/s); run a variant of cases/taylor_green_2d.yaml")


def exact_decay(t, prm):
    """E(t)/E0 of the exact vortex, exp(-16 pi^2 nu t / L^2)."""
    return np.exp(-16 * math.pi ** 2 * prm["mu"] / prm["rho0"] * t / prm["L"] ** 2)


def case_parameters(out):
    """The reference's parameters from the run's case; a key the case leaves out takes lahar's
    default (`lahar keys sph`: kernel cubic, h_over_dx 1.3, background_pressure rho0 c0^2)."""
    path = lahar_py.run_case(out)
    try:
        with open(path) as fh:
            case = yaml.safe_load(fh)
        sph = case["sph"]
        per = sph["periodic"]
        L = per["x"][1] - per["x"][0]
        if abs((per["y"][1] - per["y"][0]) - L) > 1e-12 * L or case.get("dimensions") != 2:
            fail(f"{path}: the reference is the 2D vortex on a periodic square")
        if not sph.get("transport_velocity"):
            fail(f"{path}: the reference is Adami et al.'s transport-velocity formulation: set "
                 "sph.transport_velocity: true (as cases/taylor_green_2d.yaml does)")
        n = int(round(L / sph["dx"]))
        return dict(n=n, L=L, rho0=float(sph["density"]), mu=float(sph["viscosity"]), c0=float(sph["c0"]),
                    pb=float(sph.get("background_pressure", float(sph["density"]) * float(sph["c0"]) ** 2)),
                    hdx=float(sph.get("h_over_dx", 1.3)), kern=sph.get("kernel", "cubic"), t_end=float(case["time"]["end"]))
    except (OSError, KeyError, TypeError, ValueError, yaml.YAMLError) as exc:
        fail(f"{path}: not a periodic Taylor-Green case ({exc!r})")


def main():
    ap = argparse.ArgumentParser(prog=TOOL, description=__doc__.split("\n\n")[0])
    ap.add_argument("out", help="output directory of the lahar run")
    ap.add_argument("--check", type=float, metavar="TOL", help="exit 1 if |E_lahar/E_ref - 1| > TOL")
    ap.add_argument("--json", metavar="FILE", help="write both histories and the largest deviation")
    ap.add_argument("--png", metavar="FILE", help="plot both over the exact decay against t")
    a = ap.parse_args()
    prm = case_parameters(a.out)
    t_run, e_run, U, first = lahar_history(a.out)
    require_taylor_green(first, U, prm["L"], os.path.join(a.out, "particles.h5"))
    t_ref, e_ref = taylor_green(U=U, **prm)
    keep = t_run <= t_ref[-1]
    t_run, e_run = t_run[keep], e_run[keep]
    e_at = np.interp(t_run, t_ref, e_ref)
    dev = e_run / e_at - 1.0
    decay = exact_decay(t_run, prm)
    print(f"Taylor-Green, {prm['n']}^2, {prm['kern']} h = {prm['hdx']} dx, c0 {prm['c0']}, p_b {prm['pb']}: "
          "E/E0 (and over the exact decay)")
    print("t [s]    lahar            reference        lahar/ref - 1")
    for t, er, ef, d, ex in zip(t_run, e_run, e_at, dev, decay):
        print(f"{t:6.3f}   {er:.4f} ({er / ex:.3f})   {ef:.4f} ({ef / ex:.3f})   {d:+.4f}")
    worst = int(np.argmax(np.abs(dev)))
    print(f"largest |lahar/ref - 1|: {abs(dev[worst]):.4f} at t = {t_run[worst]:.3f} s")
    if a.json:
        with open(a.json, "w") as fh:
            lahar_py.dump_json({"t": t_run.tolist(), "lahar": e_run.tolist(), "reference": e_at.tolist(),
                                "max_rel_deviation": float(abs(dev[worst])), "at": float(t_run[worst]),
                                "parameters": prm}, fh)
    if a.png:
        lahar_py.require("matplotlib")
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(6.4, 4.0))
        stride = max(1, len(t_ref) // 2000)  # a line of at most ~2000 points
        t_all, e_all = t_ref[::stride], e_ref[::stride]
        ax.plot(t_all, e_all / exact_decay(t_all, prm),
                "k-", lw=1, label="independent TVF (tools/tvf_reference.py)")
        ax.plot(t_run, e_run / decay, "o", ms=4, mfc="none", label="lahar")
        ax.axhline(1.0, color="0.6", lw=0.8, ls="--")
        ax.set_xlabel("t (s)")
        ax.set_ylabel("E/E0 over the exact decay")
        ax.set_title(f"Taylor-Green, Re 100, {prm['n']}$^2$, {prm['kern']} h = {prm['hdx']:g} dx, p_b = {prm['pb']:g} Pa")
        ax.legend()
        lahar_py.save_png(fig, a.png, fail)
    if a.check is not None:
        return lahar_py.check_verdict(TOOL, [f"E/E0 at t = {t:.3f} s: lahar {er:.4f}, reference {ef:.4f} "
                                             f"({d:+.4f}, bound {a.check})"
                                             for t, er, ef, d in zip(t_run, e_run, e_at, dev) if abs(d) > a.check])
    return 0


if __name__ == "__main__":
    sys.exit(main())
