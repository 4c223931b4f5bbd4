/* The split step (sph_fluid.h): sph_fluid_step_begin(dt) then sph_fluid_step_end(dt, states) gives
 * bitwise the state of the one-call sph_fluid_step(dt, states), so the SPH node can do the
 * particle work before the body states arrive without changing any result. Scene: 2400 particles
 * (the parallel loops are active) in a tank of three fixed walls with a disc pushed into the water
 * through prescribed body states; 80 steps, with SPS off and on. Compared after every step: every
 * particle array, the coupling forces and torques on the bodies, t, vmax, amax. The end without a
 * begin is refused (-1). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "shape_build.h"
#include "sph_fluid.h"

#include "test_util.h"

static void wall(lahar_body *b, double cx, double cy, double hx, double hy)
{
    memset(b, 0, sizeof *b);
    const double R = 0.005;
    double half[2] = {hx - R, hy - R}, t[3] = {cx, cy, 0};
    if (lahar_shape_make_box2d(&b->shape, half, R) != 0)
        abort();
    lahar_shape_transform(&b->shape, NULL, t, 1.0);
    b->motion = LAHAR_MOTION_FIXED;
    b->convex = 1;
    b->q[0] = 1.0;
}

static int setup(sph_fluid *f, int sps, lahar_body *bodies)
{
    const double dx = 0.005, W = 0.3, H = 0.2, g = 9.81;
    sph_params prm;
    memset(&prm, 0, sizeof prm);
    prm.dim = 2;
    prm.dx = dx;
    prm.rho0 = 1000.0;
    prm.c0 = 10.0 * sqrt(g * H);
    prm.mu = 1e-3;
    prm.alpha = 0.02;
    prm.delta = 0.1;
    prm.body_force[1] = -g;
    prm.sps = sps;
    prm.shepard_every = 30;
    char err[256];
    if (sph_fluid_init(f, &prm, 2400, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        return -1;
    }
    double lo[3] = {0, 0, 0}, hi[3] = {W, H, 0}, v0[3] = {0, 0, 0};
    if (sph_particles_add_box(&f->p, 2, dx, prm.rho0, lo, hi, v0) != 2400)
        return -1;
    if (sps) /* SPS needs a strain rate from the start: a shear in the water */
        for (int64_t i = 0; i < f->p.n; i++)
            f->p.vx[i] = 0.5 * (f->p.y[i] - 0.5 * H);
    return sph_fluid_attach_bodies(f, 4, bodies);
}

static int same(const double *a, const double *b, int64_t n) { return memcmp(a, b, (size_t)n * sizeof(double)) == 0; }

static void run(int sps)
{
    lahar_body bodies[4];
    wall(&bodies[0], 0.15, -0.05, 0.35, 0.05);
    wall(&bodies[1], -0.05, 0.2, 0.05, 0.3);
    wall(&bodies[2], 0.35, 0.2, 0.05, 0.3);
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
    sph_fluid a, s;
    if (setup(&a, sps, bodies) != 0 || setup(&s, sps, bodies) != 0) {
        CHECK(0, "setup failed");
        return;
    }
    CHECK(sph_fluid_step_end(&s, 1e-5, states) == -1, "step_end without step_begin accepted");
    /* both primed the same way (the node evaluates the rates at t_0 before the first step) */
    double dt = 1e-4;
    sph_cells_sort(&a.cells, &a.p);
    sph_cells_sort(&s.cells, &s.p);
    sph_fluid_rates(&a, states, dt);
    sph_fluid_rates(&s, states, dt);
    int first_bad = -1;
    const int nstep = 80;
    int64_t cross_total = 0;
    for (int k = 0; k < nstep && first_bad < 0; k++) {
        dt = sph_fluid_dt(&a);
        /* the disc moves down into the water at 1 m/s (bodies at the end of the step) */
        states[3].v[1] = -1.0;
        states[3].x[1] -= 1.0 * dt;
        int64_t ca = sph_fluid_step(&a, dt, states);
        int rb = sph_fluid_step_begin(&s, dt);
        int64_t cs = sph_fluid_step_end(&s, dt, states);
        cross_total += ca;
        const sph_particles *p = &a.p, *q = &s.p;
        int64_t n = p->n;
        int ok = rb == 0 && ca == cs && n == q->n && a.t == s.t && a.vmax == s.vmax && a.amax == s.amax &&
                 same(p->x, q->x, n) && same(p->y, q->y, n) && same(p->z, q->z, n) && same(p->vx, q->vx, n) &&
                 same(p->vy, q->vy, n) && same(p->vz, q->vz, n) && same(p->rho, q->rho, n) &&
                 same(p->p, q->p, n) && same(p->ax, q->ax, n) && same(p->ay, q->ay, n) &&
                 same(p->drho, q->drho, n) && memcmp(p->id, q->id, (size_t)n * sizeof *p->id) == 0 &&
                 memcmp(a.cpl.force, s.cpl.force, 4 * sizeof a.cpl.force[0]) == 0 &&
                 memcmp(a.cpl.torque, s.cpl.torque, 4 * sizeof a.cpl.torque[0]) == 0;
        if (!ok)
            first_bad = k;
    }
    double fy = a.cpl.force[3][1];
    printf("SPS %s: %d steps to t = %.4f s, split vs one-call %s (first difference at step %d); "
           "force on the disc %.4f N/m, crossings %lld\n",
           sps ? "on" : "off", nstep, a.t, first_bad < 0 ? "bitwise identical" : "DIFFERENT", first_bad, fy,
           (long long)cross_total);
    CHECK(first_bad < 0, "SPS %d: split step differs from the one-call step at step %d", sps, first_bad);
    CHECK(cross_total == 0, "SPS %d: %lld particles crossed the disc", sps, (long long)cross_total);
    CHECK(fy > 0.0, "SPS %d: the water does not push the disc up (%.4g): the coupling was not exercised", sps, fy);
    sph_fluid_free(&a);
    sph_fluid_free(&s);
    for (int b = 0; b < 4; b++)
        lahar_shape_free(&bodies[b].shape);
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
