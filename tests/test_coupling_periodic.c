/* Periodic images of bodies in the SPH-DEM coupling (sph_coupling_set_periodic, sph_coupling.h).
 *
 * A body across a periodic boundary must act on the fluid exactly as the same body does in the
 * middle of the period, with the whole fluid shifted along: the coupling is invariant under a
 * translation of everything by any vector when the fluid is periodic. Each check shifts a jittered,
 * moving particle lattice and a body by the same vector (particles wrapped back into the period)
 * and compares with the unshifted set-up:
 *   - every particle's coupling acceleration (eq. 19), the body's force (eq. 20) and torque
 *     (eq. 21), and the number of contacts, to round-off (1e-9 of the largest value);
 * for
 *   1. a fixed 2D disc (world-frame core: the world-box range of images) moved onto a corner of
 *      the period (it straddles both periodic axes), onto an edge and across two edges; and
 *      outside the period (ten periods away) it touches nothing (0 contacts);
 *   2. a free, translating and rotating 2D disc (body states, sphere range of images) on an edge:
 *      u_rel of eq. 16 and the torque about its centre;
 *   3. a fixed 3D box across the x and z boundaries of a domain periodic in x and z only;
 *   4. a fixed plate longer than the period (a periodic channel's wall) spans it: the same
 *      contacts and forces as without images (none counted twice);
 *   5. and that the check can fail: with the periodic axes not given to the coupling, the disc on
 *      the corner keeps less than half of its contacts (23 of 98) and its force is off by more
 *      than half of the reference (0.8 measured).
 * Tolerances: the shifted positions differ from the reference ones by rounding (1e-17 m), which
 * the normal force K_n delta (K_n = 0.1 m/dt^2) turns into relative differences of about 1e-13. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "shape_build.h"
#include "sph_fluid.h"

#include "test_util.h"

static const double DX = 0.01, RHO = 1000, MU = 0.01, DT = 1e-4, L = 0.2;

typedef struct {
    int64_t n, ncontacts;
    double *a; /* 3 per particle */
    double force[3], torque[3];
} result;

/* The particle lattice: nx x ny x nz points of spacing DX in [0, L)^2 (y in [0, ny DX) in 3D) with
 * a deterministic jitter and velocity, minus those within `clear` of the body (core and sweep). */
static int keep(int dim, const double x[3], const lahar_body *b, const double c[3])
{
    const lahar_shape *s = &b->shape;
    if (s->nv == 1) /* disc / sphere around c */
        return hypot(hypot(x[0] - c[0], x[1] - c[1]), dim == 3 ? x[2] - c[2] : 0.0) > s->radius + 0.2 * DX;
    for (int a = 0; a < dim; a++) /* box: its half extent is the core's |vertex| along the axis */
        if (fabs(x[a] - c[a]) > fabs(s->v[0][a] - c[a]) + s->radius + 0.2 * DX)
            return 1;
    return 0;
}

/* Evaluate the coupling on the lattice shifted by `shift` (wrapped into the periodic axes), with
 * the body whose centre (before the shift) is c0. periodic[a]: the axes the fluid repeats along;
 * images: 1 to tell the coupling (as sph_fluid_attach_bodies does), 0 to take them back from it.
 * The torque is reported about the body's centre c0 + shift (a fixed body's own is about the
 * origin of the world frame its core is given in). */
static void evaluate(int dim, const int periodic[3], int images, const lahar_body *body, const lahar_body_state *state,
                     const double c0[3], const double shift[3], int nx, int ny, int nz, result *r)
{
    sph_params prm;
    sph_params_default(&prm);
    prm.opt.delta = 0.0;
    prm.dim = dim;
    prm.dx = DX;
    prm.rho0 = RHO;
    prm.opt.c0 = 10;
    prm.opt.mu = MU;
    for (int a = 0; a < 3; a++) {
        prm.opt.periodic[a] = periodic ? periodic[a] : 0;
        prm.opt.lo[a] = 0.0;
        prm.opt.hi[a] = L;
    }
    int64_t cap = (int64_t)nx * ny * nz;
    sph_fluid f;
    char err[256];
    if (sph_fluid_init(&f, &prm, cap, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        abort();
    }
    unsigned long long s = 987654321;
    const double m = RHO * pow(DX, dim);
    for (int k = 0; k < nz; k++)
        for (int j = 0; j < ny; j++)
            for (int i = 0; i < nx; i++) {
                double jit[3];
                for (int a = 0; a < 3; a++) {
                    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
                    jit[a] = (double)(s >> 11) / 9007199254740992.0 - 0.5;
                }
                double x[3] = {(i + 0.5 + 0.3 * jit[0]) * DX, (j + 0.5 + 0.3 * jit[1]) * DX,
                               dim == 3 ? (k + 0.5 + 0.3 * jit[2]) * DX : 0.0};
                double v[3] = {0.02 + 0.01 * jit[1], -0.01 + 0.01 * jit[2], dim == 3 ? 0.005 * jit[0] : 0.0};
                if (!keep(dim, x, body, c0))
                    continue;
                for (int a = 0; a < dim; a++) {
                    x[a] += shift[a];
                    if (periodic && periodic[a]) { /* back into [0, L) */
                        x[a] = fmod(x[a], L);
                        if (x[a] < 0.0)
                            x[a] += L;
                        if (x[a] >= L)
                            x[a] -= L;
                    }
                }
                sph_particles_add(&f.p, x, v, m, RHO * (1.0 + 1e-3 * jit[0]), 0);
            }
    lahar_body moved = *body; /* shares the shape; only the pose changes */
    lahar_body_state st;
    if (state) {
        st = *state;
        for (int a = 0; a < 3; a++)
            st.x[a] += shift[a];
    } else { /* fixed: world-frame core, moved by transforming a copy of the shape */
        if (lahar_shape_copy(&moved.shape, &body->shape) != 0)
            abort();
        lahar_shape_transform(&moved.shape, NULL, shift, 1.0);
    }
    if (sph_fluid_attach_bodies(&f, 1, &moved) != 0)
        abort();
    if (!images)
        sph_coupling_set_periodic(&f.cpl, NULL, prm.opt.lo, prm.opt.hi);
    for (int64_t i = 0; i < f.p.n; i++)
        f.p.ax[i] = f.p.ay[i] = f.p.az[i] = 0.0;
    if (sph_coupling_apply(&f.cpl, &f.p, state ? &st : NULL, DT) != 0)
        fprintf(stderr, "note: %lld crossings\n", (long long)f.cpl.crossings);
    r->n = f.p.n;
    r->ncontacts = f.cpl.ncontacts;
    r->a = malloc((size_t)f.p.n * 3 * sizeof *r->a);
    if (!r->a)
        abort();
    for (int64_t i = 0; i < f.p.n; i++) {
        r->a[3 * i] = f.p.ax[i];
        r->a[3 * i + 1] = f.p.ay[i];
        r->a[3 * i + 2] = f.p.az[i];
    }
    memcpy(r->force, f.cpl.force[0], sizeof r->force);
    memcpy(r->torque, f.cpl.torque[0], sizeof r->torque);
    if (!state) { /* T_c = T_0 - c x F */
        const double *F = f.cpl.force[0];
        double c[3] = {c0[0] + shift[0], c0[1] + shift[1], c0[2] + shift[2]};
        r->torque[0] -= c[1] * F[2] - c[2] * F[1];
        r->torque[1] -= c[2] * F[0] - c[0] * F[2];
        r->torque[2] -= c[0] * F[1] - c[1] * F[0];
    }
    sph_fluid_free(&f);
    if (!state)
        lahar_shape_free(&moved.shape);
}

static double maxabs(const double *v, int64_t n)
{
    double m = 0.0;
    for (int64_t i = 0; i < n; i++)
        m = fmax(m, fabs(v[i]));
    return m;
}

/* The shifted result against the reference: contacts, every particle, force and torque (size: the
 * body's size, the lever of its normal forces, whose torques cancel to round-off). */
static void compare(const char *what, const result *ref, const result *got, double size)
{
    const double tol = 1e-9;
    CHECK(ref->n == got->n, "%s: %lld particles, reference %lld", what, (long long)got->n, (long long)ref->n);
    CHECK(ref->ncontacts == got->ncontacts && ref->ncontacts > 0, "%s: %lld contacts, reference %lld", what,
          (long long)got->ncontacts, (long long)ref->ncontacts);
    double amax = maxabs(ref->a, 3 * ref->n), da = 0.0;
    for (int64_t i = 0; i < 3 * ref->n && ref->n == got->n; i++)
        da = fmax(da, fabs(got->a[i] - ref->a[i]));
    double fmaxv = maxabs(ref->force, 3), tmax = maxabs(ref->torque, 3), df = 0.0, dtq = 0.0;
    for (int a = 0; a < 3; a++) {
        df = fmax(df, fabs(got->force[a] - ref->force[a]));
        dtq = fmax(dtq, fabs(got->torque[a] - ref->torque[a]));
    }
    CHECK(amax > 0.0 && da <= tol * amax, "%s: particle accelerations differ by %.3g of the largest", what,
          da / amax);
    CHECK(fmaxv > 0.0 && df <= tol * fmaxv, "%s: body force (%.12g, %.12g, %.12g), reference (%.12g, %.12g, %.12g)",
          what, got->force[0], got->force[1], got->force[2], ref->force[0], ref->force[1], ref->force[2]);
    CHECK(dtq <= tol * (tmax + fmaxv * size),
          "%s: body torque (%.12g, %.12g, %.12g), reference (%.12g, %.12g, %.12g)", what, got->torque[0],
          got->torque[1], got->torque[2], ref->torque[0], ref->torque[1], ref->torque[2]);
    printf("%-40s %5lld contacts  force (%+.6e, %+.6e, %+.6e)  torque z %+.6e  max rel diff: particle %.2e, "
           "force %.2e, torque %.2e\n",
           what, (long long)got->ncontacts, got->force[0], got->force[1], got->force[2], got->torque[2], da / amax,
           df / fmaxv, dtq / (tmax + fmaxv * size));
}

int main(void)
{
    const int per2[3] = {1, 1, 0};
    const double zero[3] = {0, 0, 0}, mid[3] = {0.1, 0.1, 0.0};

    /* 1. fixed disc, core in world coordinates (as the case loader gives fixed bodies) */
    {
        lahar_body disc;
        memset(&disc, 0, sizeof disc);
        lahar_shape_make_sphere(&disc.shape, 0.05);
        lahar_shape_transform(&disc.shape, NULL, mid, 1.0);
        disc.motion = LAHAR_MOTION_FIXED;
        disc.convex = 1;
        disc.q[0] = 1.0;
        result ref, got;
        evaluate(2, per2, 1, &disc, NULL, mid, zero, 20, 20, 1, &ref);
        const double shifts[3][3] = {{-0.1, -0.1, 0}, {0.1, 0.03, 0}, {0.12, -0.11, 0}};
        const char *names[3] = {"fixed disc on the corner (0, 0)", "fixed disc on the edge x = L",
                                "fixed disc across x = L and y = 0"};
        for (int s = 0; s < 3; s++) {
            evaluate(2, per2, 1, &disc, NULL, mid, shifts[s], 20, 20, 1, &got);
            compare(names[s], &ref, &got, 0.05);
            free(got.a);
        }
        /* a disc outside the period (ten periods away, as a marker body parked far from the
         * fluid) is outside the domain: no images, no contacts */
        {
            const double far[3] = {1.9, 2.0, 0};
            evaluate(2, per2, 1, &disc, NULL, mid, far, 20, 20, 1, &got);
            printf("%-40s %5lld contacts\n", "fixed disc outside the period", (long long)got.ncontacts);
            CHECK(got.ncontacts == 0, "a disc outside the period has %lld contacts", (long long)got.ncontacts);
            free(got.a);
        }
        /* 5. the same corner disc without images: only the particles in its own quadrant of the
         * period see it, and the force is a different vector */
        evaluate(2, per2, 0, &disc, NULL, mid, shifts[0], 20, 20, 1, &got);
        double fr = hypot(ref.force[0], ref.force[1]), dfn = hypot(got.force[0] - ref.force[0], got.force[1] - ref.force[1]);
        printf("%-40s %5lld contacts  force (%+.6e, %+.6e): off the reference by %.3f of it\n", "corner disc, no images",
               (long long)got.ncontacts, got.force[0], got.force[1], dfn / fr);
        CHECK(got.ncontacts < ref.ncontacts / 2 && dfn > 0.5 * fr,
              "without periodic images the corner disc still has %lld of %lld contacts, force off by %.3f", (long long)got.ncontacts,
              (long long)ref.ncontacts, dfn / fr);
        free(got.a);
        free(ref.a);
        lahar_shape_free(&disc.shape);
    }

    /* 2. free disc with a body state: translating and rotating, across the y boundary */
    {
        lahar_body disc;
        memset(&disc, 0, sizeof disc);
        lahar_shape_make_sphere(&disc.shape, 0.04);
        disc.motion = LAHAR_MOTION_FREE;
        disc.convex = 1;
        disc.q[0] = 1.0;
        disc.mass = 1e6;
        disc.inertia[2] = 1.0;
        lahar_body_state st;
        memset(&st, 0, sizeof st);
        st.x[0] = 0.1;
        st.x[1] = 0.1;
        st.q[0] = 1.0;
        st.v[0] = -0.01;
        st.v[1] = 0.004;
        st.w[2] = 0.8;
        memcpy(disc.x, st.x, sizeof st.x);
        disc.q[0] = 1.0;
        result ref, got;
        evaluate(2, per2, 1, &disc, &st, mid, zero, 20, 20, 1, &ref);
        const double shift[3] = {0.02, 0.11, 0};
        evaluate(2, per2, 1, &disc, &st, mid, shift, 20, 20, 1, &got);
        compare("free rotating disc on the edge y = L", &ref, &got, 0.04);
        /* the viscous (eq. 17-18) torque of the rotating disc, well above the round-off of the
         * radial normal forces' torques (1e-16 of F R) */
        CHECK(fabs(ref.torque[2]) > 1e-9 * 0.04 * hypot(ref.force[0], ref.force[1]), "no torque on the rotating disc");
        free(got.a);
        free(ref.a);
        lahar_shape_free(&disc.shape);
    }

    /* 3. fixed 3D box across the x and z boundaries, periodic in x and z, not y */
    {
        const int per3[3] = {1, 0, 1};
        const double half[3] = {0.03, 0.02, 0.025}, c3[3] = {0.1, 0.05, 0.1};
        lahar_body box;
        memset(&box, 0, sizeof box);
        lahar_shape_make_box(&box.shape, half, 0.01);
        lahar_shape_transform(&box.shape, NULL, c3, 1.0);
        box.motion = LAHAR_MOTION_FIXED;
        box.convex = 1;
        box.q[0] = 1.0;
        result ref, got;
        evaluate(3, per3, 1, &box, NULL, c3, zero, 20, 10, 20, &ref);
        const double shift[3] = {0.095, 0.0, -0.1};
        evaluate(3, per3, 1, &box, NULL, c3, shift, 20, 10, 20, &got);
        compare("fixed 3D box across x = L and z = 0", &ref, &got, 0.04);
        free(got.a);
        free(ref.a);
        lahar_shape_free(&box.shape);
    }
    /* 4. a wall longer than the period along x (a periodic channel's plate) spans x: no images
     * along it, the same contacts as without images (none counted twice) */
    {
        const int perx[3] = {1, 0, 0};
        const double half[2] = {1.0, 0.02}, t[3] = {0.1, -0.03 + 0.02, 0.0}; /* swept top at y = 0.02 */
        lahar_body plate;
        memset(&plate, 0, sizeof plate);
        lahar_shape_make_box2d(&plate.shape, half, 0.01);
        lahar_shape_transform(&plate.shape, NULL, t, 1.0);
        plate.motion = LAHAR_MOTION_FIXED;
        plate.convex = 1;
        plate.q[0] = 1.0;
        result ref, got;
        const double c[3] = {0.1, -0.01, 0.0};
        evaluate(2, perx, 0, &plate, NULL, c, zero, 20, 20, 1, &ref);
        evaluate(2, perx, 1, &plate, NULL, c, zero, 20, 20, 1, &got);
        compare("plate longer than the period", &ref, &got, 0.1);
        free(got.a);
        free(ref.a);
        lahar_shape_free(&plate.shape);
    }
    return failures != 0;
}
