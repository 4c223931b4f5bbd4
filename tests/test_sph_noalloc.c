/* The SPH step allocates nothing in the steady state (sph_fluid.h: all storage at setup; the cell
 * table and the coupling's contact list grow by doubling only on a step that needs more than ever
 * before, which a warm-up covers).
 *
 * This binary is linked with -Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc,--wrap=free, so every
 * call the solver core (a static library linked into it) makes goes through the counters below;
 * calls inside libgomp (a shared library) are not seen (it keeps and reuses its thread team).
 * Run with OMP_NUM_THREADS=2 (tests/perf.cmake), so the parallel paths are the ones counted.
 *
 * Scenes (warm-up steps, then counted steps, half through sph_fluid_step and half through
 * sph_fluid_step_begin / _end as the SPH node does):
 *  A. 2D, 2400 particles (above SPH_OMP_MIN_HEAVY: the neighbour and body loops are parallel) in a
 *     tank of three fixed walls with a disc pushed into the water through body states, SPS on,
 *     Shepard filter every 5 steps: warm-up 10, counted 30; the disc must be in contact;
 *  B. 2D, 33856 particles (above SPH_OMP_MIN_LIGHT: the sort and the updates are parallel too)
 *     in a closed tank: warm-up 2, counted 4;
 *  C. 3D, 4000 particles in a box of five fixed walls with Tait EOS: warm-up 5, counted 10.
 * Each scene must have zero malloc/calloc/realloc/free calls in the counted steps. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "shape_build.h"
#include "sph_fluid.h"

#include "alloc_count.h"
#include "test_bodies.h"
#include "test_util.h"

/* nsteps steps of the solver's own dt, the disc (body `moving`, or -1) moved down at 0.5 m/s;
 * returns the allocation calls made inside them. */
static long steps(sph_fluid *f, int nsteps, lahar_body_state *states, int moving, int count)
{
    long before = alloc_nalloc + alloc_nfree;
    for (int k = 0; k < nsteps; k++) {
        double dt = sph_fluid_dt(f);
        if (moving >= 0) {
            states[moving].v[1] = -0.5;
            states[moving].x[1] -= 0.5 * dt;
        }
        alloc_counting = count;
        int64_t c;
        if (k % 2)
            c = sph_fluid_step(f, dt, states);
        else
            c = sph_fluid_step_begin(f, dt) == 0 ? sph_fluid_step_end(f, dt, states) : -1;
        alloc_counting = 0;
        CHECK(c == 0, "step %d: %lld (crossings, or -1 for an error)", k, (long long)c);
    }
    return alloc_nalloc + alloc_nfree - before;
}

/* Scene: water block [0, wlo..whi) of spacing dx in a tank [0, tank) of fixed walls (+ a disc in
 * 2D when `disc`). */
static void scene(const char *name, int dim, double dx, const double water[3], const double tank[3], int disc, int sps,
                  lahar_sph_eos eos, int nwarm, int ncount)
{
    sph_params prm;
    sph_params_default(&prm);
    prm.dim = dim;
    prm.dx = dx;
    snprintf(prm.opt.kernel, sizeof prm.opt.kernel, "%s", "wendland2");
    prm.opt.h_over_dx = 1.41;
    prm.rho0 = 1000.0;
    const double H = water[dim - 1];
    prm.opt.c0 = 10.0 * sqrt(9.81 * H);
    prm.opt.eos = eos;
    prm.opt.mu = 1e-3;
    prm.opt.alpha = 0.02;
    prm.opt.delta = 0.1;
    prm.body_force[dim - 1] = -9.81;
    prm.opt.sps = sps;
    prm.opt.shepard_interval = sps ? 5 : 0;
    int64_t cap = 1;
    for (int a = 0; a < dim; a++)
        cap *= (int64_t)floor(water[a] / dx + 1e-9);
    sph_fluid f;
    char err[256];
    if (sph_fluid_init(&f, &prm, cap, err, sizeof err) != 0) {
        CHECK(0, "%s: %s", name, err);
        return;
    }
    double lo[3] = {0, 0, 0}, hi[3] = {water[0], water[1], dim == 3 ? water[2] : 0}, v0[3] = {0, 0, 0};
    CHECK(sph_particles_add_box(&f.p, dim, dx, prm.rho0, lo, hi, v0) == cap, "%s: particles", name);
    if (sps) /* SPS needs a strain rate: a shear in the water */
        for (int64_t i = 0; i < f.p.n; i++)
            f.p.vx[i] = 0.5 * (f.p.y[i] - 0.5 * H);
    lahar_body bodies[6];
    const double T = 0.02, top = tank[dim - 1];
    int nb = 0;
    if (dim == 2) {
        double l[3][3] = {{-T, -T, 0}, {-T, 0, 0}, {tank[0], 0, 0}};
        double u[3][3] = {{tank[0] + T, 0, 0}, {0, top, 0}, {tank[0] + T, top, 0}};
        for (; nb < 3; nb++)
            test_fixed_box_lohi(&bodies[nb], 2, l[nb], u[nb], 0.002);
    } else {
        double l[5][3] = {{-T, -T, -T}, {-T, -T, 0}, {tank[0], -T, 0}, {-T, -T, 0}, {-T, tank[1], 0}};
        double u[5][3] = {{tank[0] + T, tank[1] + T, 0},
                          {0, tank[1] + T, top},
                          {tank[0] + T, tank[1] + T, top},
                          {tank[0] + T, 0, top},
                          {tank[0] + T, tank[1] + T, top}};
        for (; nb < 5; nb++)
            test_fixed_box_lohi(&bodies[nb], 3, l[nb], u[nb], 0.002);
    }
    int moving = -1;
    if (disc) {
        memset(&bodies[nb], 0, sizeof bodies[nb]);
        if (lahar_shape_make_sphere(&bodies[nb].shape, 0.03) != 0)
            abort();
        bodies[nb].motion = LAHAR_MOTION_FREE;
        bodies[nb].convex = 1;
        bodies[nb].mass = 1.0;
        bodies[nb].q[0] = 1.0;
        bodies[nb].x[0] = 0.5 * water[0];
        bodies[nb].x[1] = H + 0.034; /* in coupling range of the surface particles */
        moving = nb++;
    }
    lahar_body_state states[6];
    for (int b = 0; b < nb; b++) {
        memset(&states[b], 0, sizeof states[b]);
        memcpy(states[b].x, bodies[b].x, sizeof states[b].x);
        states[b].q[0] = 1.0;
    }
    if (sph_fluid_attach_bodies(&f, nb, bodies) != 0 || sph_cells_sort(&f.cells, &f.p) != 0 ||
        sph_fluid_rates(&f, states, 0.25 * f.k.h / prm.opt.c0) < 0) {
        CHECK(0, "%s: set-up", name);
    } else {
        long warm = steps(&f, nwarm, states, moving, 1);
        long calls = steps(&f, ncount, states, moving, 1);
        int64_t disc_contacts = moving >= 0 ? f.cpl.body_start[moving + 1] - f.cpl.body_start[moving] : -1;
        printf("%s: %lld particles, %d warm-up steps (%ld allocation calls), %d counted steps: %ld allocation "
               "calls; t = %.3g s, contacts %lld (disc %lld)\n",
               name, (long long)f.p.n, nwarm, warm, ncount, calls, f.t, (long long)f.cpl.ncontacts,
               (long long)disc_contacts);
        CHECK(calls == 0, "%s: %ld malloc/calloc/realloc/free calls in %d steps after a %d-step warm-up", name, calls,
              ncount, nwarm);
        CHECK(f.cpl.ncontacts > 0, "%s: the walls carry the water (contacts %lld)", name, (long long)f.cpl.ncontacts);
        if (moving >= 0)
            CHECK(disc_contacts > 0, "%s: the disc touches the water (%lld contacts)", name, (long long)disc_contacts);
    }
    sph_fluid_free(&f);
    for (int b = 0; b < nb; b++)
        lahar_shape_free(&bodies[b].shape);
}

int main(void)
{
    /* the counters see this binary's calls: check that the wrapping is really in place */
    volatile size_t sz = 16; /* volatile: keep the compiler from eliding the pair */
    alloc_counting = 1;
    void *volatile p = malloc(sz);
    free(p);
    alloc_counting = 0;
    CHECK(alloc_nalloc == 1 && alloc_nfree == 1, "malloc/free are counted (--wrap works): %ld, %ld", alloc_nalloc, alloc_nfree);
    const double wa[3] = {0.3, 0.2, 0}, ta[3] = {0.3, 0.4, 0};
    scene("A 2D disc SPS", 2, 0.005, wa, ta, 1, 1, LAHAR_SPH_EOS_LINEAR, 10, 30);
    const double wb[3] = {0.46, 0.46, 0}, tb[3] = {0.46, 0.6, 0};
    scene("B 2D 33856", 2, 0.0025, wb, tb, 0, 0, LAHAR_SPH_EOS_LINEAR, 2, 4);
    const double wc[3] = {0.2, 0.2, 0.1}, tc[3] = {0.2, 0.2, 0.3};
    scene("C 3D Tait", 3, 0.01, wc, tc, 0, 0, LAHAR_SPH_EOS_TAIT, 5, 10);
    return failures ? 1 : 0;
}
