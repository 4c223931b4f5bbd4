/* 2D hydrostatic water column in a tank of three fixed DEM walls (the hydrostatic closed form): width W, water depth H = N dx, rho0 = 1000,
 * g = 9.81, linear EOS with c0 = 20 sqrt(g H), particles start on the lattice with the
 * hydrostatic density, Monaghan artificial viscosity damps the start-up waves.
 * After settling (t = 2 s), against p = rho0 g (H - y) and the force per unit width
 * F = rho0 g H^2 / 2 on a side wall (exact hydrostatics):
 *   - each side wall's horizontal force within 1 %;
 *   - the floor carries the weight of the water within 0.5 %;
 *   - the pressure profile at gauges on the centre line (kernel support above the floor to h
 *     below the surface; with "ghost" the rows of particles from dx/2, each particle against
 *     rho0 g (H - y) at its own height) within 1 % of rho0 g H (RMS) and 1.5 % (max);
 *   - no particle crossed a wall, the free surface stays level and at the depth H (level gauges,
 *     sph_probes_level, at every dx a kernel support away from the side walls: spread < dx/2,
 *     each within dx/4 of H) and the kinetic energy has decayed (|v|max < 1 % of sqrt(g H)).
 * usage: test_sph_hydrostatic [NY [T [ghost [riemann [ETA]]]]] (riemann: sph.scheme riemann, Zhang et al.
 * 2017, instead of the artificial viscosity, with the limiter eta = ETA, default 3; the same bounds). With "ghost" the walls carry the pressure of ghost
 * layers (LAHAR_SPH_WALL_PRESSURE_GHOST, sph_coupling.h) and the gauges start at dx/2 above the floor,
 * where the penalty wall alone reads +13 % of rho0 g H at 1.5 dx: the same bounds hold there; the
 * side walls then carry part of the weight (the ghosts beside a particle complete its vertical
 * pressure gradient), so the floor plus the side walls' vertical forces must carry it (0.5 %).
 * Environment: SPH_ROWS=1 prints each pressure gauge, SPH_LEVELS=1 each level gauge. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "shape_build.h"
#include "sph_fluid.h"
#include "sph_probes.h"

#include "test_bodies.h"
#include "test_util.h"

int main(int argc, char **argv)
{
    const int NX = 20, NY = argc > 1 ? atoi(argv[1]) : 20;
    const double dx = 0.01, W = NX * dx, H = NY * dx, g = 9.81, rho0 = 1000, T = argc > 2 ? atof(argv[2]) : 2.0;
    sph_params prm;
    sph_params_default(&prm);
    prm.dim = 2;
    prm.dx = dx;
    prm.rho0 = rho0;
    prm.opt.c0 = 20.0 * sqrt(g * H);
    prm.opt.alpha = 0.1;
    prm.opt.delta = getenv("SPH_DELTA") ? atof(getenv("SPH_DELTA")) : 0.0;
    prm.opt.shepard_interval = getenv("SPH_SHEPARD") ? atoi(getenv("SPH_SHEPARD")) : 0;
    prm.opt.mu = 1e-3;
    prm.body_force[1] = -g;
    const int ghost = argc > 3 && strcmp(argv[3], "ghost") == 0;
    if (argc > 4 && strcmp(argv[4], "riemann") == 0) { /* the Riemann scheme (sph_riemann.h): its own dissipation */
        prm.opt.scheme = LAHAR_SPH_SCHEME_RIEMANN;
        prm.opt.riemann_limiter = argc > 5 ? atof(argv[5]) : 3.0; /* 0: the full acoustic dissipation */
        prm.opt.alpha = 0.0;
    }
    if (ghost)
        prm.opt.wall_pressure = LAHAR_SPH_WALL_PRESSURE_GHOST;
    sph_fluid f;
    char err[256];
    if (sph_fluid_init(&f, &prm, NX * NY, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        return 1;
    }
    double lo[3] = {0, 0, 0}, hi[3] = {W, H, 0}, v0[3] = {0, 0, 0};
    sph_particles_add_box(&f.p, 2, dx, rho0, lo, hi, v0);
    for (int64_t i = 0; i < f.p.n; i++) { /* hydrostatic start: p = rho0 g (H - y), mass rho dx^2 */
        f.p.rho[i] = rho0 + rho0 * g * (H - f.p.y[i]) / (prm.opt.c0 * prm.opt.c0);
        f.p.m[i] = f.p.rho[i] * dx * dx;
    }
    lahar_body walls[3];
    test_fixed_box2d(&walls[0], W / 2, -0.05, W / 2 + 0.2, 0.05, 0.005);  /* floor, surface y = 0 */
    test_fixed_box2d(&walls[1], -0.05, H, 0.05, H + 0.1, 0.005);         /* left, surface x = 0 */
    test_fixed_box2d(&walls[2], W + 0.05, H, 0.05, H + 0.1, 0.005);      /* right, surface x = W */
    if (sph_fluid_attach_bodies(&f, 3, walls) != 0)
        return 1;
    int64_t crossings = 0;
    int steps = 0;
    double fsum[3][2] = {{0}};
    int nsum = 0;
    while (f.t < T) {
        double dt = f.primed ? sph_fluid_dt(&f) : 1e-5;
        int64_t c = sph_fluid_step(&f, dt, NULL);
        crossings += c > 0 ? c : 0;
        steps++;
        if (f.t > T - 0.1) { /* average the wall forces over the last 0.1 s (acoustic ringing) */
            for (int b = 0; b < 3; b++)
                for (int a = 0; a < 2; a++)
                    fsum[b][a] += f.cpl.force[b][a];
            nsum++;
        }
    }
    double mass = 0.0;
    for (int64_t i = 0; i < f.p.n; i++)
        mass += f.p.m[i];
    const double f_wall = rho0 * g * H * H / 2.0, weight = mass * g;
    /* the water pushes the left wall to -x, the right one to +x, the floor down */
    double fl = -fsum[1][0] / nsum, fr = fsum[2][0] / nsum, ff = -fsum[0][1] / nsum;
    double fside = -(fsum[1][1] + fsum[2][1]) / nsum; /* vertical, on the side walls */
    if (ghost)
        ff += fside;
    /* pressure gauges on the centre line every dx from one kernel support above the floor to one
     * h below the surface (as DualSPHysics' MeasureTool): Shepard-normalised kernel interpolation
     * sum p_j V_j W / sum V_j W. Closer to the floor the particles pressed against the penalty
     * wall read high (+13 % of rho g H at 1.5 dx): no wall particles complete their kernel. */
    double rms = 0.0, worst = 0.0, vmax = 0.0, level_min = 1e9, level_max = -1e9;
    int rows = 0;
    for (double gy = ghost ? 0.5 * dx : f.k.support; gy <= H - f.k.h; gy += dx) {
        double num = 0.0, den = 0.0, ref = 0.0;
        for (int64_t i = 0; i < f.p.n; i++) {
            double w = kernel_w(&f.k, hypot(f.p.x[i] - W / 2, f.p.y[i] - gy)) * f.p.m[i] / f.p.rho[i];
            /* the row of particles at gy across the middle half of the tank, each against the
             * hydrostatic pressure at its own height: once the particles leave the lattice a row
             * spans +-dx/2, +-2.5 % of rho g H at this depth */
            if (ghost)
                w = fabs(f.p.y[i] - gy) < 0.5 * dx && fabs(f.p.x[i] - W / 2) < W / 4 ? 1.0 : 0.0;
            num += w * f.p.p[i];
            den += w;
            ref += w * rho0 * g * (H - (ghost ? f.p.y[i] : gy));
        }
        double e = (num - ref) / den / (rho0 * g * H);
        if (getenv("SPH_ROWS"))
            printf("gauge y %.4f: p %.2f, hydrostatic %.2f (%+.2f %% of rho g H)\n", gy, num / den, ref / den,
                   100 * e);
        rms += e * e;
        worst = fmax(worst, fabs(e));
        rows++;
    }
    rms = sqrt(rms / rows);
    /* the free surface: the level gauge of the case's `kind: level` probes (sph_probes_level: where
     * the water's kernel fraction falls to 1/2 going up from the floor) at every dx across the
     * middle of the tank, a kernel support away from the side walls (whose ghosts it does not
     * count). Not the top particle per dx-wide bin: when the surface row shifts sideways a bin
     * loses its top particle and reads a dip of a whole dx on a level surface. */
    const double lstep = dx / 8.0;
    const int lnpt = (int)(1.5 * H / lstep) + 1;
    double *phi = malloc((size_t)lnpt * sizeof *phi);
    if (!phi)
        abort();
    for (double gx = f.k.support; gx <= W - f.k.support + 1e-12; gx += dx) {
        const double foot[3] = {gx, 0.0, 0.0};
        const double level = sph_probes_level(&f, foot, lnpt, lstep, phi);
        if (getenv("SPH_LEVELS"))
            printf("level at x %.4f: %.5f m (%+.3f dx from H)\n", gx, level, (level - H) / dx);
        level_min = fmin(level_min, level);
        level_max = fmax(level_max, level);
    }
    free(phi);
    for (int64_t i = 0; i < f.p.n; i++)
        vmax = fmax(vmax, hypot(f.p.vx[i], f.p.vy[i]));
    printf("hydrostatic 2D, %d x %d particles, %d steps to t = %.2f s (dt %.3g s):\n", NX, NY, steps, f.t,
           sph_fluid_dt(&f));
    printf("  side walls %.5g, %.5g N/m vs rho g H^2/2 = %.5g (%+.3f %%, %+.3f %%)\n", fl, fr, f_wall,
           100 * (fl / f_wall - 1), 100 * (fr / f_wall - 1));
    printf("  floor%s %.5g N/m vs weight %.5g (%+.3f %%; side walls %.3g N/m); pressure gauges from %.2g dx: RMS %.3f %%, "
           "max %.3f %% of rho g H\n", ghost ? " + side walls" : "", ff, weight, 100 * (ff / weight - 1), fside,
           ghost ? 0.5 : f.k.support / dx, 100 * rms, 100 * worst);
    printf("  |v|max %.3g m/s, free surface spread %.3g m (level gauges), crossings %lld\n", vmax, level_max - level_min,
           (long long)crossings);
    CHECK(fabs(fl / f_wall - 1) <= 0.01 && fabs(fr / f_wall - 1) <= 0.01, "side wall force off rho g H^2/2 by > 1 %%");
    CHECK(fabs(ff / weight - 1) <= 0.005, "floor force off the weight by > 0.5 %%");
    CHECK(rms <= 0.01 && worst <= 0.015, "pressure profile off hydrostatic (RMS %.3f %%, max %.3f %%)", 100 * rms,
          100 * worst);
    CHECK(crossings == 0, "%lld wall crossings", (long long)crossings);
    CHECK(level_max - level_min < 0.5 * dx, "free surface not level (spread %g m)", level_max - level_min);
    CHECK(fabs(level_min - H) < 0.25 * dx && fabs(level_max - H) < 0.25 * dx,
          "free surface moved off the water's depth H = %g m (levels %g to %g m; bound dx/4)", H, level_min, level_max);
    CHECK(vmax < 0.01 * sqrt(g * H), "not settled: |v|max %g m/s", vmax);
    sph_fluid_free(&f);
    for (int b = 0; b < 3; b++)
        lahar_shape_free(&walls[b].shape);
    if (failures)
        return 1;
    printf("PASS test_sph_hydrostatic%s\n", ghost ? " (ghost wall pressure)" : "");
    return 0;
}
