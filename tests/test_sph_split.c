/* The split step (sph_fluid.h) integrates in time at second order: sph_fluid_step_begin(dt) (the
 * particle work before the body states arrive) then sph_fluid_step_end(dt, states) (the coupling
 * with the bodies at the end of the step) is a kick-drift-kick leapfrog, whose error at a fixed
 * time falls as dt^2. Scene: 2400 particles in a tank of three fixed walls with a disc pushed
 * down into the water at 1 m/s through prescribed body states (x(t) exact at every step end),
 * SPS off and on, no Shepard filter (it acts every N steps, not at fixed times). Run to
 * T = 4 ms at dt, dt/2 and dt/4 (dt = 8e-5 s, below the acoustic limit); the observed order
 * p = log2(|x_dt - x_dt/2| / |x_dt/2 - x_dt/4|) (particle positions by id, RMS) must lie in
 * [1.6, 2.6]: a begin that read stale body states, an end that skipped its half kick or a drift
 * from the wrong velocity drops it to 1 or below. Also: the disc is pushed up, no particle crosses
 * it, and an end without a begin is refused (-1). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "shape_build.h"
#include "sph_fluid.h"

#include "test_bodies.h"
#include "test_util.h"

#define NP 2400

static int setup(sph_fluid *f, int sps, lahar_body *bodies)
{
    const double dx = 0.005, W = 0.3, H = 0.2, g = 9.81;
    sph_params prm;
    sph_params_default(&prm);
    prm.dim = 2;
    prm.dx = dx;
    prm.rho0 = 1000.0;
    prm.opt.c0 = 10.0 * sqrt(g * H);
    prm.opt.mu = 1e-3;
    prm.opt.alpha = 0.02;
    prm.opt.delta = 0.1;
    prm.body_force[1] = -g;
    prm.opt.sps = sps;
    prm.opt.penalty_stiffness = LAHAR_SPH_PENALTY_ACOUSTIC; /* K_n from the acoustic step, not from dt: the same model at every dt */
    char err[256];
    if (sph_fluid_init(f, &prm, NP, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        return -1;
    }
    double lo[3] = {0, 0, 0}, hi[3] = {W, H, 0}, v0[3] = {0, 0, 0};
    if (sph_particles_add_box(&f->p, 2, dx, prm.rho0, lo, hi, v0) != NP)
        return -1;
    if (sps) /* SPS needs a strain rate from the start: a shear in the water */
        for (int64_t i = 0; i < f->p.n; i++)
            f->p.vx[i] = 0.5 * (f->p.y[i] - 0.5 * H);
    return sph_fluid_attach_bodies(f, 4, bodies);
}

/* Run to T with nstep split steps of T / nstep; positions by particle id into xy[2 * id]. */
static int run_to(int sps, int nstep, double T, double *xy, double *fy, int64_t *crossed, int *refused)
{
    lahar_body bodies[4];
    test_fixed_box2d(&bodies[0], 0.15, -0.05, 0.35, 0.05, 0.005);
    test_fixed_box2d(&bodies[1], -0.05, 0.2, 0.05, 0.3, 0.005);
    test_fixed_box2d(&bodies[2], 0.35, 0.2, 0.05, 0.3, 0.005);
    memset(&bodies[3], 0, sizeof bodies[3]);
    if (lahar_shape_make_sphere(&bodies[3].shape, 0.03) != 0)
        abort();
    bodies[3].motion = LAHAR_MOTION_FREE;
    bodies[3].convex = 1;
    bodies[3].mass = 1.0;
    bodies[3].q[0] = 1.0;
    bodies[3].x[0] = 0.15;
    bodies[3].x[1] = 0.234; /* 2.4 dx above the surface particles: in coupling range */
    lahar_body_state states[4];
    for (int b = 0; b < 4; b++) {
        memset(&states[b], 0, sizeof states[b]);
        memcpy(states[b].x, bodies[b].x, sizeof states[b].x);
        states[b].q[0] = 1.0;
    }
    sph_fluid f;
    if (setup(&f, sps, bodies) != 0)
        return -1;
    *refused = sph_fluid_step_end(&f, 1e-5, states) == -1;
    const double dt = T / nstep, y0 = bodies[3].x[1];
    sph_cells_sort(&f.cells, &f.p);
    sph_fluid_rates(&f, states, dt); /* the node evaluates the rates at t_0 before the first step */
    *crossed = 0;
    int rc = 0;
    for (int k = 0; k < nstep && rc == 0; k++) {
        /* the disc moves down into the water at 1 m/s (bodies at the end of the step) */
        states[3].v[1] = -1.0;
        states[3].x[1] = y0 - 1.0 * (k + 1) * dt;
        if (sph_fluid_step_begin(&f, dt) != 0)
            rc = -1;
        int64_t c = sph_fluid_step_end(&f, dt, states);
        if (c < 0)
            rc = -1;
        else
            *crossed += c;
    }
    for (int64_t i = 0; i < f.p.n; i++) {
        int64_t id = f.p.id[i];
        if (id < 0 || id >= NP)
            rc = -1;
        else
            xy[2 * id] = f.p.x[i], xy[2 * id + 1] = f.p.y[i];
    }
    *fy = f.cpl.force[3][1];
    sph_fluid_free(&f);
    for (int b = 0; b < 4; b++)
        lahar_shape_free(&bodies[b].shape);
    return rc;
}

static double rms_diff(const double *a, const double *b)
{
    double s = 0.0;
    for (int i = 0; i < 2 * NP; i++)
        s += (a[i] - b[i]) * (a[i] - b[i]);
    return sqrt(s / NP);
}

static void run(int sps)
{
    static double xy[3][2 * NP];
    const double T = 4e-3;
    const int n0 = 50;
    double fy[3];
    int64_t crossed[3];
    int refused[3];
    for (int r = 0; r < 3; r++)
        if (run_to(sps, n0 << r, T, xy[r], &fy[r], &crossed[r], &refused[r]) != 0) {
            CHECK(0, "SPS %d: the run with %d steps failed", sps, n0 << r);
            return;
        }
    double e1 = rms_diff(xy[0], xy[1]), e2 = rms_diff(xy[1], xy[2]);
    double order = e2 > 0.0 ? log2(e1 / e2) : 0.0;
    printf("SPS %s: t = %.3f s at dt = %.1e, %.1e, %.1e s: |x_dt - x_dt/2| = %.3e m, |x_dt/2 - x_dt/4| = %.3e m, "
           "observed order %.2f; force on the disc %.4f N/m, crossings %lld\n",
           sps ? "on" : "off", T, T / n0, T / (2 * n0), T / (4 * n0), e1, e2, order, fy[2],
           (long long)(crossed[0] + crossed[1] + crossed[2]));
    CHECK(order >= 1.6 && order <= 2.6, "SPS %d: observed order in time %.2f, want 2 (1.6-2.6)", sps, order);
    CHECK(crossed[0] + crossed[1] + crossed[2] == 0, "SPS %d: particles crossed the disc", sps);
    CHECK(fy[2] > 0.0, "SPS %d: the water does not push the disc up (%.4g): the coupling was not exercised", sps,
          fy[2]);
    CHECK(refused[0], "step_end without step_begin accepted");
}

int main(void)
{
    run(0);
    run(1);
    if (failures) {
        fprintf(stderr, "%d failure(s)\n", failures);
        return 1;
    }
    printf("split step checks passed\n");
    return 0;
}
