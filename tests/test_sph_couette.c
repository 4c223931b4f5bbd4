/* Transient plane Couette flow (Morris et al.
 * 1997 eq. 22): fluid at rest between two DEM plates H = 0.1 m apart, nu = 1e-4 (rho = 1000,
 * mu = 0.1), periodic in x; at t = 0 the upper plate starts moving along x at V0 = 1.25e-3 m/s.
 * The upper plate is a PRESCRIBED body whose pose and velocity are passed to the coupling as body
 * states every step (Trujillo-Vela et al. 2020 eq. 16: u_rel = u_i - v_body - w x r), the lower one is fixed.
 * Against the series at t = 5, 10, 20 s and 100 s (steady within 1e-4): max error <= 2 % of V0 at
 * every time (measured 0.52 % at most), steady L2 relative error <= 1 % (measured 0.56 %); the
 * shear force on each plate at steady state is mu V0 / H * l within 5 % (measured +2.7 % on the
 * fixed plate, -0.2 % on the moving one: the sheared lattice's pressure noise, the same that makes
 * the Poiseuille error peak at t = 20 s, still pushes the fluid a little). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "shape_build.h"
#include "sph_fluid.h"

#include "test_util.h"

static const double H = 0.1, V0 = 1.25e-3, RHO = 1000.0, MU = 0.1, NU = 1e-4, PERIOD = 0.04;

static double u_exact(double y, double t)
{
    double u = V0 * y / H;
    for (int n = 1; n < 400; n++)
        u += 2.0 * V0 / (n * M_PI) * (n % 2 ? -1.0 : 1.0) * sin(n * M_PI * y / H) * exp(-NU * n * n * M_PI * M_PI * t / (H * H));
    return u;
}

static void make_plate(lahar_body *b, double ysurf, int below)
{
    memset(b, 0, sizeof *b);
    const double R = 0.002, th = 0.004;
    double half[2] = {1.0, th};
    if (lahar_shape_make_box2d(&b->shape, half, R) != 0)
        abort();
    b->q[0] = 1.0;
    b->convex = 1;
    if (below) { /* fixed: world-frame vertices */
        double t[3] = {0.5 * PERIOD, ysurf - R - th, 0.0};
        lahar_shape_transform(&b->shape, NULL, t, 1.0);
        b->motion = LAHAR_MOTION_FIXED;
    } else { /* prescribed: body frame at its centre */
        b->motion = LAHAR_MOTION_PRESCRIBED;
        b->x[0] = 0.5 * PERIOD;
        b->x[1] = ysurf + R + th;
        b->v[0] = V0;
        b->mass = 1.0;
    }
}

int main(void)
{
    const int nrow = 20;
    const double dx = H / nrow;
    sph_params prm;
    sph_params_default(&prm);
    prm.opt.delta = 0.0;
    prm.dim = 2;
    prm.dx = dx;
    prm.rho0 = RHO;
    prm.opt.c0 = 0.05;
    prm.opt.mu = MU;
    prm.opt.periodic[0] = 1;
    prm.opt.hi[0] = PERIOD;
    sph_fluid f;
    char err[256];
    if (sph_fluid_init(&f, &prm, (int64_t)lround(PERIOD / dx) * nrow, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        return 1;
    }
    double lo[3] = {0, 0, 0}, hi[3] = {PERIOD, H, 0}, v0[3] = {0, 0, 0};
    sph_particles_add_box(&f.p, 2, dx, RHO, lo, hi, v0);
    lahar_body plates[2];
    make_plate(&plates[0], 0.0, 1);
    make_plate(&plates[1], H, 0);
    if (sph_fluid_attach_bodies(&f, 2, plates) != 0)
        return 1;
    lahar_body_state st[2];
    memset(st, 0, sizeof st);
    for (int b = 0; b < 2; b++) {
        memcpy(st[b].x, plates[b].x, sizeof st[b].x);
        memcpy(st[b].q, plates[b].q, sizeof st[b].q);
        memcpy(st[b].v, plates[b].v, sizeof st[b].v);
    }
    const double times[4] = {5.0, 10.0, 20.0, 100.0};
    double l2 = 0.0;
    int steps = 0;
    for (int k = 0; k < 4; k++) {
        while (f.t < times[k] - 1e-9) {
            double dt = f.primed ? sph_fluid_dt(&f) : 0.01;
            if (f.t + dt > times[k])
                dt = times[k] - f.t;
            st[1].x[0] = plates[1].x[0] + V0 * (f.t + dt); /* the lid at the end of the step */
            CHECK(sph_fluid_step(&f, dt, st) == 0, "crossing at t = %g", f.t);
            steps++;
        }
        double se = 0.0, sa = 0.0, mx = 0.0;
        for (int64_t i = 0; i < f.p.n; i++) {
            double ue = u_exact(f.p.y[i], f.t), e = f.p.vx[i] - ue;
            se += e * e;
            sa += ue * ue;
            mx = fmax(mx, fabs(e) / V0);
        }
        l2 = sqrt(se / sa);
        printf("couette t = %5.1f s: L2 %.3f %%, max error %.3f %% of V0; plate forces %.5g, %.5g N/m (steady %.5g)\n",
               f.t, 100 * l2, 100 * mx, f.cpl.force[0][0], f.cpl.force[1][0], MU * V0 / H * PERIOD);
        CHECK(mx <= 0.02, "t = %g: max error %.2f %% of V0 > 2 %%", f.t, 100 * mx);
    }
    const double fs = MU * V0 / H * PERIOD;
    CHECK(l2 <= 0.01, "steady L2 error %.3f %% > 1 %%", 100 * l2);
    CHECK(fabs(f.cpl.force[0][0] / fs - 1) <= 0.05 && fabs(-f.cpl.force[1][0] / fs - 1) <= 0.05,
          "steady plate forces %g, %g N/m, expected +-%g within 5 %%", f.cpl.force[0][0], f.cpl.force[1][0], fs);
    printf("%d steps\n", steps);
    sph_fluid_free(&f);
    lahar_shape_free(&plates[0].shape);
    lahar_shape_free(&plates[1].shape);
    if (failures)
        return 1;
    printf("PASS test_sph_couette\n");
    return 0;
}
