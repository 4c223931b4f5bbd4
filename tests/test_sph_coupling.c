/* SPH-DEM coupling (sph_coupling.h, Trujillo-Vela et al. 2020 eq. 12-21) on single particles, against the
 * closed forms:
 *  1. a particle at rest inside the halo of a flat plate: F = K_n (eps - d) n with
 *     K_n = 0.1 m_min/dt^2 (eq. 15), exactly (1e-12); the plate gets -F at the surface point
 *     (eq. 20) and the torque (x_s - x_b) x (-F) (eq. 21);
 *  2. a particle sliding along the plate outside the halo: only the viscous force
 *     m (2 mu/rho) G(d) u_rel, opposed to the motion; none beyond the kernel support;
 *  2b. ghost walls: no continuity rate at the corner of a sliding lid for a particle at rest;
 *  3. a rotating, translating free disc: u_rel = u - v - w x (x_s - x_b) (eq. 16), torque R F_t;
 *  4. crossings: a particle inside the sweep or deep inside the core is counted and named, and the
 *     normal force pushes it out; 3D box: face and edge normals;
 *  5. a 3600-particle cloud around a plate and a disc: per-body resultants bitwise the same on
 *     1 and 2 threads, and equal to minus the sum of the particle forces (1e-12). */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "shape_build.h"
#include "sph_fluid.h"

#include "test_util.h"

static const double DX = 0.01, RHO = 1000, MU = 0.01, DT = 1e-4;

static void plate2d(lahar_body *b)
{
    memset(b, 0, sizeof *b);
    double half[2] = {1.0, 0.02}, R = 0.01, t[3] = {0.0, -0.03, 0.0}; /* swept top surface at y = 0 */
    lahar_shape_make_box2d(&b->shape, half, R);
    lahar_shape_transform(&b->shape, NULL, t, 1.0);
    b->motion = LAHAR_MOTION_FIXED;
    b->convex = 1;
    b->q[0] = 1.0;
}

static void disc2d(lahar_body *b, double R)
{
    memset(b, 0, sizeof *b);
    lahar_shape_make_sphere(&b->shape, R);
    b->motion = LAHAR_MOTION_FREE;
    b->convex = 1;
    b->q[0] = 1.0;
    b->mass = 1e6; /* heavier than a particle: m_min stays the particle's */
    b->inertia[2] = 1.0;
}

static void one_particle(sph_fluid *f, int dim, const double x[3], const double v[3], int nbody, const lahar_body *b)
{
    sph_params prm;
    sph_params_default(&prm);
    prm.opt.delta = 0.0;
    prm.dim = dim;
    prm.dx = DX;
    prm.rho0 = RHO;
    prm.opt.c0 = 10;
    prm.opt.mu = MU;
    char err[256];
    if (sph_fluid_init(f, &prm, 4, err, sizeof err) != 0)
        abort();
    sph_particles_add(&f->p, x, v, RHO * pow(DX, dim), RHO, 0);
    if (sph_fluid_attach_bodies(f, nbody, b) != 0)
        abort();
    sph_cells_sort(&f->cells, &f->p);
    sph_fluid_rates(f, NULL, DT);
}

static double rel(double a, double b) { return fabs(a - b) / fmax(fabs(b), 1e-300); }

int main(void)
{
    lahar_body plate;
    plate2d(&plate);
    const double m2 = RHO * DX * DX, eps = 0.5 * DX, kn = 0.1 * m2 / (DT * DT);
    sph_fluid f;

    /* 1. normal force */
    {
        double d = 0.3 * DX, x[3] = {0.1, d, 0}, v[3] = {0, 0, 0};
        one_particle(&f, 2, x, v, 1, &plate);
        double fy = kn * (eps - d);
        CHECK(rel(f.cpl.kn, kn) < 1e-14, "K_n %.17g, expected 0.1 m/dt^2 = %.17g", f.cpl.kn, kn);
        CHECK(rel(f.p.ay[0] * m2, fy) < 1e-12 && fabs(f.p.ax[0] * m2) < 1e-12 * fy, "normal force %.17g, expected %.17g",
              f.p.ay[0] * m2, fy);
        CHECK(f.cpl.ncontacts == 1 && rel(f.cpl.force[0][1], -fy) < 1e-12, "plate force %g, expected %g",
              f.cpl.force[0][1], -fy);
        const sph_contact *c = &f.cpl.contacts[0];
        CHECK(fabs(c->xs[0] - 0.1) < 1e-15 && fabs(c->xs[1]) < 1e-15 && rel(c->delta, eps - d) < 1e-12,
              "virtual particle (%g, %g), delta %g", c->xs[0], c->xs[1], c->delta);
        /* eq. 21 about the plate's reference point (origin of its world-frame vertices) */
        CHECK(rel(f.cpl.torque[0][2], 0.1 * -fy) < 1e-12, "plate torque %g, expected %g", f.cpl.torque[0][2],
              0.1 * -fy);
        CHECK(f.cpl.crossings == 0, "crossing reported");
        printf("normal: d = 0.3 dx, F = %.6g N/m = K_n (eps - d), K_n = %.6g\n", f.p.ay[0] * m2, kn);
        sph_fluid_free(&f);
    }
    /* 2. viscous force only (outside the halo), and nothing beyond the support */
    {
        double d = 0.8 * DX, x[3] = {0.1, d, 0}, v[3] = {0.2, 0, 0};
        one_particle(&f, 2, x, v, 1, &plate);
        double G = sph_coupling_halfspace_factor(&f.cpl, d), fx = m2 * 2.0 * MU / RHO * G * 0.2;
        CHECK(G < 0.0, "G(d) = %g should be negative (drag)", G);
        CHECK(rel(f.p.ax[0] * m2, fx) < 1e-12 && fabs(f.p.ay[0]) < 1e-15 * fabs(fx),
              "viscous force (%g, %g), expected (%g, 0)", f.p.ax[0] * m2, f.p.ay[0] * m2, fx);
        CHECK(rel(f.cpl.force[0][0], -fx) < 1e-12, "plate drag %g, expected %g", f.cpl.force[0][0], -fx);
        double support = f.k.support;
        sph_fluid_free(&f);
        x[1] = support * 1.0001;
        one_particle(&f, 2, x, v, 1, &plate);
        CHECK(f.cpl.ncontacts == 0 && f.p.ax[0] == 0.0, "force beyond the kernel support");
        sph_fluid_free(&f);
    }
    /* 2b. ghost walls at a corner: the plate slides along +x (a lid) into a fixed wall at x = 0.
     * A particle at rest in the corner moves along neither wall's normal relative to that wall, so
     * the walls' continuity rates must give it nothing; the corner correction once took the
     * plate's velocity along the side wall's normal (a source: a closed box lost volume). */
    {
        lahar_body walls[2];
        plate2d(&walls[0]);
        walls[0].motion = LAHAR_MOTION_PRESCRIBED;
        walls[0].v[0] = 0.5;
        walls[0].mass = 1e6;
        walls[0].inertia[2] = 1.0;
        memset(&walls[1], 0, sizeof walls[1]);
        double half[2] = {0.02, 1.0}, R = 0.01, t[3] = {-0.03, 0.0, 0.0}; /* swept face at x = 0 */
        lahar_shape_make_box2d(&walls[1].shape, half, R);
        lahar_shape_transform(&walls[1].shape, NULL, t, 1.0);
        walls[1].motion = LAHAR_MOTION_FIXED;
        walls[1].convex = 1;
        walls[1].q[0] = 1.0;
        sph_params prm;
        sph_params_default(&prm);
        prm.opt.delta = 0.0;
        prm.dim = 2, prm.dx = DX, prm.rho0 = RHO, prm.opt.c0 = 10, prm.opt.mu = MU;
        prm.opt.wall_pressure = LAHAR_SPH_WALL_PRESSURE_GHOST;
        char err[256];
        if (sph_fluid_init(&f, &prm, 4, err, sizeof err) != 0)
            abort();
        double x[3] = {0.7 * DX, 0.7 * DX, 0}, v[3] = {0, 0, 0};
        sph_particles_add(&f.p, x, v, m2, RHO, 0);
        if (sph_fluid_attach_bodies(&f, 2, walls) != 0)
            abort();
        sph_cells_sort(&f.cells, &f.p);
        sph_fluid_rates(&f, NULL, DT);
        /* scale: the rate one wall's ghosts give a particle approaching it at the lid's speed */
        const double scale = RHO * 0.5 / DX;
        CHECK(f.cpl.ncontacts == 2 && fabs(f.p.drho[0]) < 1e-12 * scale,
              "corner of a sliding lid and a fixed wall: continuity rate %.3e kg/m^3/s for a particle at rest (0; "
              "scale %.3g)", f.p.drho[0], scale);
        printf("ghost corner of a sliding lid: continuity rate of a particle at rest %.1e kg/m^3/s\n", f.p.drho[0]);
        sph_fluid_free(&f);
        lahar_shape_free(&walls[0].shape);
        lahar_shape_free(&walls[1].shape);
    }
    /* 3. rotating, translating free disc */
    {
        lahar_body disc;
        const double R = 0.05, w = 3.0, vb = 0.1;
        disc2d(&disc, R);
        disc.v[1] = vb;
        disc.w[2] = w;
        double d = 0.8 * DX, x[3] = {R + d, 0, 0}, v[3] = {0, 0, 0};
        one_particle(&f, 2, x, v, 1, &disc);
        double urel_y = 0.0 - vb - w * R; /* eq. 16 at x_s = (R, 0) */
        double G = sph_coupling_body_halfspace_factor(&f.cpl, 0, d), fy = m2 * 2.0 * MU / RHO * G * urel_y;
        CHECK(rel(f.p.ay[0] * m2, fy) < 1e-12, "disc: tangential force %g, expected %g", f.p.ay[0] * m2, fy);
        /* the disc's ghost layers curve away from the particle: fewer ghosts in the support than
         * on a flat wall, about (d + s)/(2 R) of the first layer (s = dx/2): 13 % at R = 5 dx */
        double Gflat = sph_coupling_halfspace_factor(&f.cpl, d);
        CHECK(G / Gflat > 0.80 && G / Gflat < 0.95, "disc R = 5 dx: G / G_flat = %.4f (0.80 .. 0.95)", G / Gflat);
        printf("disc R = 5 dx: G(0.8 dx) / G_flat = %.4f\n", G / Gflat);
        CHECK(rel(f.cpl.torque[0][2], R * -fy) < 1e-12, "disc torque %g, expected R F = %g", f.cpl.torque[0][2],
              R * -fy);
        printf("disc: u_rel = %.3f m/s, F_t = %.6g N/m (particle), body torque %.6g N m/m\n", urel_y, fy,
               f.cpl.torque[0][2]);
        sph_fluid_free(&f);
        lahar_shape_free(&disc.shape);
    }
    /* 3b. a disc much larger than the support has the flat wall's layers */
    {
        lahar_body disc;
        const double R = 1000 * DX;
        disc2d(&disc, R);
        double x[3] = {R + 0.8 * DX, 0, 0}, v[3] = {0, 0, 0};
        one_particle(&f, 2, x, v, 1, &disc);
        for (double d = 0.3 * DX; d < f.k.support; d += 0.4 * DX) {
            double G = sph_coupling_body_halfspace_factor(&f.cpl, 0, d), Gflat = sph_coupling_halfspace_factor(&f.cpl, d);
            CHECK(fabs(G - Gflat) <= 2e-3 * fabs(Gflat), "disc R = 1000 dx, d = %.2f dx: G %g, G_flat %g", d / DX, G,
                  Gflat);
        }
        sph_fluid_free(&f);
        lahar_shape_free(&disc.shape);
    }
    /* 3c. particle shifting next to a body: a block of water resting on the plate; the first row
     * has neighbours only above it, so -A h^2 grad C points into the plate. That part is dropped:
     * the row may shift along the plate, never towards it. */
    {
        sph_params prm;
        sph_params_default(&prm);
        prm.opt.delta = 0.0;
        prm.dim = 2, prm.dx = DX, prm.rho0 = RHO, prm.opt.c0 = 10, prm.opt.mu = MU, prm.opt.shifting = 0.05;
        char err[256];
        if (sph_fluid_init(&f, &prm, 200, err, sizeof err) != 0)
            abort();
        double lo[3] = {0.05, 0.0, 0.0}, hi[3] = {0.15, 0.05, 0.0}, v0[3] = {0, 0, 0};
        sph_particles_add_box(&f.p, 2, DX, RHO, lo, hi, v0);
        for (int64_t i = 0; i < f.p.n; i++) /* a little disorder, so the rows also shift along the plate */
            f.p.x[i] += 0.1 * DX * sin(37.0 * (double)i);
        if (sph_fluid_attach_bodies(&f, 1, &plate) != 0)
            abort();
        double y0[200], x0[200];
        for (int64_t i = 0; i < f.p.n; i++)
            x0[f.p.id[i]] = f.p.x[i], y0[f.p.id[i]] = f.p.y[i];
        sph_fluid_step(&f, 1e-8, NULL);
        double worst_down = 0.0, along = 0.0;
        int first_row = 0;
        for (int64_t i = 0; i < f.p.n; i++) {
            if (y0[f.p.id[i]] > DX)
                continue;
            first_row++;
            worst_down = fmin(worst_down, f.p.y[i] - y0[f.p.id[i]]);
            along = fmax(along, fabs(f.p.x[i] - x0[f.p.id[i]]));
        }
        CHECK(first_row == 10 && worst_down > -1e-12 * DX && along > 1e-6 * DX,
              "shifting by the plate: %d first-row particles, largest move towards it %.3e m (0), largest along it "
              "%.3e m (> 0)", first_row, -worst_down, along);
        printf("shifting by a plate: first row moves along it up to %.3g dx, towards it %.1e m\n", along / DX, -worst_down);
        sph_fluid_free(&f);
    }
    /* 4. crossings */
    {
        double x[3] = {0.2, -0.002, 0}, v[3] = {0, 0, 0};
        one_particle(&f, 2, x, v, 1, &plate);
        CHECK(f.cpl.crossings == 1 && f.cpl.cross_body == 0 && f.cpl.cross_particle_id == 0 &&
                  fabs(f.cpl.cross_depth - 0.002) < 1e-12,
              "inside the sweep: crossings %lld body %d depth %g", (long long)f.cpl.crossings, f.cpl.cross_body,
              f.cpl.cross_depth);
        CHECK(f.p.ay[0] > 0.0, "inside the sweep: pushed down (%g)", f.p.ay[0]);
        sph_fluid_free(&f);
        x[1] = -0.025; /* inside the core, nearer its top face */
        one_particle(&f, 2, x, v, 1, &plate);
        CHECK(f.cpl.crossings == 1 && f.p.ay[0] > 0.0, "inside the core: crossings %lld, a_y %g",
              (long long)f.cpl.crossings, f.p.ay[0]);
        sph_fluid_free(&f);

        lahar_body box;
        memset(&box, 0, sizeof box);
        double half[3] = {0.1, 0.1, 0.1};
        lahar_shape_make_box(&box.shape, half, 0.01);
        box.motion = LAHAR_MOTION_FREE;
        box.convex = 1;
        box.mass = 1e3;
        box.q[0] = 1.0;
        double xf[3] = {0.05, 0.02, 0.11 + 0.3 * DX}, xe[3] = {0.11, 0.0, 0.11}, xi[3] = {0.0, 0.01, 0.05};
        const double m3 = RHO * DX * DX * DX;
        one_particle(&f, 3, xf, v, 1, &box);
        CHECK(rel(f.p.az[0] * m3, 0.1 * m3 / (DT * DT) * (eps - 0.3 * DX)) < 1e-12 && fabs(f.p.ax[0]) < 1e-9 &&
                  fabs(f.p.ay[0]) < 1e-9,
              "3D face: a = (%g, %g, %g)", f.p.ax[0], f.p.ay[0], f.p.az[0]);
        sph_fluid_free(&f);
        one_particle(&f, 3, xe, v, 1, &box); /* off the edge x = z = 0.1: normal (1, 0, 1)/sqrt 2 */
        CHECK(f.cpl.ncontacts == 1 && fabs(f.p.ax[0] - f.p.az[0]) < 1e-9 * fabs(f.p.ax[0]) && fabs(f.p.ay[0]) < 1e-9,
              "3D edge: a = (%g, %g, %g)", f.p.ax[0], f.p.ay[0], f.p.az[0]);
        sph_fluid_free(&f);
        one_particle(&f, 3, xi, v, 1, &box);
        CHECK(f.cpl.crossings == 1 && f.p.az[0] > 0.0, "3D inside the core: crossings %lld, a_z %g (out through the nearest face, z = +0.1)",
              (long long)f.cpl.crossings, f.p.az[0]);
        sph_fluid_free(&f);
        lahar_shape_free(&box.shape);
    }
    /* 4b. a big shape (feature grid path, > GEOM_FEATURE_GRID_MIN features): a 2D polygon of
     * 120 vertices; the force equals the brute-force closest point's K_n (eps - d) n */
    {
        lahar_body poly;
        memset(&poly, 0, sizeof poly);
        double pts[120][3];
        for (int i = 0; i < 120; i++) {
            pts[i][0] = 0.1 * cos(2 * M_PI * i / 120.0);
            pts[i][1] = 0.1 * sin(2 * M_PI * i / 120.0);
            pts[i][2] = 0.0;
        }
        char err[128];
        if (lahar_shape_make_polyline(&poly.shape, (const double(*)[3])pts, 120, 1, 0.005, err, sizeof err) != 0)
            abort();
        poly.motion = LAHAR_MOTION_FIXED;
        poly.q[0] = 1.0;
        double worst = 0.0;
        int n_in = 0;
        for (int t = 0; t < 40; t++) {
            double ang = 0.37 + t * 0.157, rr = 0.1 + 0.005 + (0.2 + 0.01 * t) * DX;
            double x[3] = {rr * cos(ang), rr * sin(ang), 0}, v[3] = {0, 0, 0};
            one_particle(&f, 2, x, v, 1, &poly);
            CHECK(f.cpl.grids.has[0] == 1, "no feature grid for a 240-feature shape");
            vec3 cp;
            double dc = geom_point_body_core(&poly.shape, poly.x, poly.q, v3_load(x), &cp, NULL);
            double delta = eps - (dc - 0.005);
            double fx = delta > 0 ? kn * delta * (x[0] - cp.x) / dc : 0.0, fy = delta > 0 ? kn * delta * (x[1] - cp.y) / dc : 0.0;
            double e = hypot(f.p.ax[0] * m2 - fx, f.p.ay[0] * m2 - fy) / fmax(hypot(fx, fy), kn * 1e-3 * DX);
            worst = fmax(worst, e);
            n_in += delta > 0;
            sph_fluid_free(&f);
        }
        CHECK(worst < 1e-12 && n_in > 5, "grid path off brute force by %.2e (%d in the halo)", worst, n_in);
        double xc[3] = {0.01, 0.0, 0}, v0[3] = {0, 0, 0}; /* deep inside, far from every feature */
        one_particle(&f, 2, xc, v0, 1, &poly);
        CHECK(f.cpl.crossings == 1, "particle inside a big polygon not counted (%lld)", (long long)f.cpl.crossings);
        sph_fluid_free(&f);
        lahar_shape_free(&poly.shape);
    }
    /* 5. many particles: thread-count independence and action = reaction */
    {
        lahar_body bodies[2];
        plate2d(&bodies[0]);
        disc2d(&bodies[1], 0.1);
        bodies[1].x[0] = 0.3;
        bodies[1].x[1] = 0.3;
        bodies[1].w[2] = 1.0;
        double res[2][2][3];
        for (int th = 1; th <= 2; th++) {
            omp_set_num_threads(th);
            sph_params prm;
            sph_params_default(&prm);
            prm.opt.delta = 0.0;
            prm.dim = 2;
            prm.dx = DX;
            prm.rho0 = RHO;
            prm.opt.c0 = 10;
            prm.opt.mu = MU;
            char err[256];
            sph_fluid_init(&f, &prm, 3600, err, sizeof err);
            unsigned long long s = 12345;
            for (int i = 0; i < 60; i++)
                for (int j = 0; j < 60; j++) {
                    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
                    double jit = (double)(s >> 11) / 9007199254740992.0 - 0.5;
                    double x[3] = {(i + 0.5) * DX + 0.3 * jit * DX, (j + 0.5) * DX - 0.3 * jit * DX, 0};
                    double v[3] = {jit, -0.5 * jit, 0};
                    sph_particles_add(&f.p, x, v, m2, RHO, 0);
                }
            sph_fluid_attach_bodies(&f, 2, bodies);
            sph_cells_sort(&f.cells, &f.p);
            /* coupling forces alone: the rates without the fluid part */
            for (int64_t i = 0; i < f.p.n; i++)
                f.p.ax[i] = f.p.ay[i] = f.p.az[i] = 0.0;
            sph_coupling_apply(&f.cpl, &f.p, NULL, DT);
            double sum[3] = {0, 0, 0};
            for (int64_t i = 0; i < f.p.n; i++) {
                sum[0] += f.p.ax[i] * m2;
                sum[1] += f.p.ay[i] * m2;
            }
            double tot[3] = {f.cpl.force[0][0] + f.cpl.force[1][0], f.cpl.force[0][1] + f.cpl.force[1][1], 0};
            CHECK(fabs(sum[0] + tot[0]) <= 1e-12 * fabs(tot[0]) + 1e-12 &&
                      fabs(sum[1] + tot[1]) <= 1e-12 * fabs(tot[1]) + 1e-12,
                  "action (%g, %g) != -reaction (%g, %g)", sum[0], sum[1], tot[0], tot[1]);
            memcpy(res[th - 1][0], f.cpl.force[0], sizeof res[0][0]);
            memcpy(res[th - 1][1], f.cpl.force[1], sizeof res[0][1]);
            if (th == 2)
                printf("cloud: %lld contacts, plate force (%.6g, %.6g), disc force (%.6g, %.6g), crossings %lld\n",
                       (long long)f.cpl.ncontacts, f.cpl.force[0][0], f.cpl.force[0][1], f.cpl.force[1][0],
                       f.cpl.force[1][1], (long long)f.cpl.crossings);
            sph_fluid_free(&f);
        }
        CHECK(memcmp(res[0], res[1], sizeof res[0]) == 0, "body forces differ between 1 and 2 threads");
        lahar_shape_free(&bodies[0].shape);
        lahar_shape_free(&bodies[1].shape);
    }
    lahar_shape_free(&plate.shape);
    if (failures)
        return 1;
    printf("PASS test_sph_coupling\n");
    return 0;
}
