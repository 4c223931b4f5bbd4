/* Transient plane Poiseuille flow between two fixed DEM plates (Trujillo-Vela et al. 2020 section 5.1), solved by
 * the SPH core alone (no processes): H = 0.1 m, body force a = 1e-4 m/s^2 along x, rho = 1000,
 * mu = 0.1 (nu = 1e-4), periodic in x. The plates are 2D sphero-rectangles whose swept surfaces
 * lie at y = 0 and y = H; the fluid feels them only through the coupling of Trujillo-Vela et al. 2020 section 4.
 *
 * Reference: the series of Morris et al.
 * 1997 eq. 21, Trujillo-Vela et al. 2020, eq. 28) at t = 2, 5, 10, 20 s and at t = 100 s (steady within 1e-4), and the
 * plate force of Trujillo-Vela et al. 2020, eq. 31 at y = 0 (steady: eq. 32, F = rho a H/2 l per plate, l = the period).
 * Bounds: steady L2 relative velocity error <= 1 % with 20 particles across H, <= 0.5 %
 * with 40; plate force within 1 % at steady state; transient profiles within 2 % (of u_max) and the
 * error falls with resolution. Also bitwise the same plate force with 1 and 2 threads. */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "shape_build.h"
#include "sph_fluid.h"

#include "test_util.h"

static const double H = 0.1, A = 1e-4, RHO = 1000.0, MU = 0.1, NU = 1e-4, PERIOD = 0.04;

/* 05_analytic_fluid_checks.txt 5.1 */
static double u_exact(double y, double t)
{
    double u = A / (2.0 * NU) * y * (H - y);
    for (int n = 0; n < 200; n++) {
        double k = 2.0 * n + 1.0;
        u -= 4.0 * A * H * H / (NU * M_PI * M_PI * M_PI * k * k * k) * sin(k * M_PI * y / H) *
             exp(-k * k * M_PI * M_PI * NU * t / (H * H));
    }
    return u;
}

/* Trujillo-Vela et al. 2020, eq. 31 at y = 0, times the period l: force of the fluid on the lower plate along x. */
static double plate_force_exact(double t)
{
    double f = RHO * A * H / 2.0;
    for (int n = 0; n < 200; n++) {
        double k = 2.0 * n + 1.0;
        f -= 4.0 * RHO * A * H * H / (M_PI * M_PI * M_PI * k * k * k) * (M_PI * k / H) *
             exp(-k * k * M_PI * M_PI * NU * t / (H * H));
    }
    return f * PERIOD;
}

static void make_plate(lahar_body *b, double ysurf, int below)
{
    memset(b, 0, sizeof *b);
    const double R = 0.002, th = 0.004;
    double half[2] = {0.1, th};
    if (lahar_shape_make_box2d(&b->shape, half, R) != 0)
        abort();
    double t[3] = {0.5 * PERIOD, below ? ysurf - R - th : ysurf + R + th, 0.0};
    lahar_shape_transform(&b->shape, NULL, t, 1.0);
    b->motion = LAHAR_MOTION_FIXED;
    b->convex = 1;
    b->q[0] = 1.0;
    snprintf(b->name, sizeof b->name, below ? "floor" : "lid");
}

#define NTIMES 5
static const double times[NTIMES] = {2.0, 5.0, 10.0, 20.0, 100.0};

typedef struct {
    double l2[NTIMES];       /* relative L2 velocity error */
    double linf[NTIMES];     /* max |u - u_exact| / u_max */
    double force_err[NTIMES];/* lower plate, relative to the steady value */
    double force_lower, force_upper;
    int64_t crossings;
    int steps;
} poiseuille_result;

static void run(int nrow, const char *kern, lahar_sph_wall_viscous wv, int threads, poiseuille_result *res)
{
    omp_set_num_threads(threads);
    memset(res, 0, sizeof *res);
    double dx = H / nrow;
    sph_params prm;
    sph_params_default(&prm);
    prm.opt.delta = 0.0;
    prm.dim = 2;
    snprintf(prm.opt.kernel, sizeof prm.opt.kernel, "%s", kern);
    prm.dx = dx;
    prm.rho0 = RHO;
    prm.opt.c0 = 0.0125 * 4; /* 40 u_max: density variations ~ (u/c)^2 stay tiny */
    prm.opt.mu = MU;
    prm.body_force[0] = A;
    prm.opt.periodic[0] = 1;
    prm.opt.lo[0] = 0.0;
    prm.opt.hi[0] = PERIOD;
    prm.opt.wall_viscous = wv;
    sph_fluid f;
    char err[256];
    int ncol = (int)lround(PERIOD / dx);
    if (sph_fluid_init(&f, &prm, (int64_t)ncol * nrow, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        abort();
    }
    double lo[3] = {0, 0, 0}, hi[3] = {PERIOD, H, 0}, v0[3] = {0, 0, 0};
    sph_particles_add_box(&f.p, 2, dx, RHO, lo, hi, v0);
    lahar_body plates[2];
    make_plate(&plates[0], 0.0, 1);
    make_plate(&plates[1], H, 0);
    if (sph_fluid_attach_bodies(&f, 2, plates) != 0)
        abort();
    double u_max = A * H * H / (8.0 * NU), f_steady = RHO * A * H / 2.0 * PERIOD;
    double dt = 0.0;
    for (int k = 0; k < NTIMES; k++) {
        while (f.t < times[k] - 1e-9) {
            dt = f.primed ? sph_fluid_dt(&f) : 0.01;
            if (f.t + dt > times[k])
                dt = times[k] - f.t;
            int64_t c = sph_fluid_step(&f, dt, NULL);
            res->crossings += c;
            res->steps++;
        }
        double se = 0.0, sa = 0.0, mx = 0.0;
        for (int64_t i = 0; i < f.p.n; i++) {
            double ue = u_exact(f.p.y[i], f.t), e = f.p.vx[i] - ue;
            se += e * e;
            sa += ue * ue;
            mx = fmax(mx, fabs(e) / u_max);
        }
        res->l2[k] = sqrt(se / sa);
        res->linf[k] = mx;
        res->force_err[k] = (f.cpl.force[0][0] - plate_force_exact(f.t)) / f_steady;
        res->force_lower = f.cpl.force[0][0];
        res->force_upper = f.cpl.force[1][0];
    }
    sph_fluid_free(&f);
    lahar_shape_free(&plates[0].shape);
    lahar_shape_free(&plates[1].shape);
}

static void report(const char *label, int nrow, const poiseuille_result *r)
{
    printf("%-22s %2d across H, %5d steps:", label, nrow, r->steps);
    for (int k = 0; k < NTIMES; k++)
        printf(" t=%g L2 %.3f%% F %+.2f%%;", times[k], 100 * r->l2[k], 100 * r->force_err[k]);
    printf(" crossings %lld\n", (long long)r->crossings);
}

int main(void)
{
    const double f_steady = RHO * A * H / 2.0 * PERIOD;
    poiseuille_result r20, r40, r20b, paper;
    run(20, "cubic", LAHAR_SPH_WALL_HALFSPACE, 2, &r20);
    report("cubic, half-space wall", 20, &r20);
    run(40, "cubic", LAHAR_SPH_WALL_HALFSPACE, 2, &r40);
    report("cubic, half-space wall", 40, &r40);
    run(20, "cubic", LAHAR_SPH_WALL_PAPER, 2, &paper);
    report("cubic, eq. 17 as printed", 20, &paper);

    CHECK(r20.l2[NTIMES - 1] <= 0.01, "20 across: steady L2 error %.3f%% > 1%%", 100 * r20.l2[NTIMES - 1]);
    CHECK(r40.l2[NTIMES - 1] <= 0.005, "40 across: steady L2 error %.3f%% > 0.5%%", 100 * r40.l2[NTIMES - 1]);
    CHECK(r40.l2[NTIMES - 1] < r20.l2[NTIMES - 1], "error does not fall with resolution (%.3f%% -> %.3f%%)",
          100 * r20.l2[NTIMES - 1], 100 * r40.l2[NTIMES - 1]);
    for (int k = 0; k < NTIMES - 1; k++) {
        CHECK(r20.linf[k] <= 0.02, "20 across, t = %g: max error %.2f%% of u_max > 2%%", times[k], 100 * r20.linf[k]);
        CHECK(r40.linf[k] <= 0.02, "40 across, t = %g: max error %.2f%% of u_max > 2%%", times[k], 100 * r40.linf[k]);
    }
    CHECK(fabs(r20.force_lower / f_steady - 1.0) <= 0.01 && fabs(r20.force_upper / f_steady - 1.0) <= 0.01,
          "20 across: steady plate forces %.6g, %.6g N/m, expected %.6g (eq. 32) within 1%%", r20.force_lower,
          r20.force_upper, f_steady);
    CHECK(fabs(r40.force_lower / f_steady - 1.0) <= 0.01 && fabs(r40.force_upper / f_steady - 1.0) <= 0.01,
          "40 across: steady plate forces %.6g, %.6g N/m, expected %.6g (eq. 32) within 1%%", r40.force_lower,
          r40.force_upper, f_steady);
    for (int k = 1; k < NTIMES; k++)
        CHECK(fabs(r40.force_err[k]) <= 0.02, "40 across, t = %g: plate force off eq. 31 by %.2f%% of steady > 2%%",
              times[k], 100 * r40.force_err[k]);
    CHECK(r20.crossings == 0 && r40.crossings == 0, "particles crossed a plate");

    /* determinism: the same run on one thread gives the same bits */
    run(20, "cubic", LAHAR_SPH_WALL_HALFSPACE, 1, &r20b);
    CHECK(memcmp(&r20b, &r20, sizeof r20) == 0, "1 vs 2 threads differ: plate force %.17g vs %.17g",
          r20b.force_lower, r20.force_lower);
    if (failures)
        return 1;
    printf("PASS test_sph_poiseuille\n");
    return 0;
}
