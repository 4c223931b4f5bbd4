/* The benchmark pile (see dem_pile.h). */
#include "dem_pile.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include "dem_test_util.h"
#include "shape_build.h"
#include "vec.h"

static double pile_rand(unsigned *s)
{
    *s = *s * 1664525u + 1013904223u;
    return (*s >> 8) / 16777216.0;
}

static void pile_need(int ok, const char *what)
{
    if (!ok) {
        fprintf(stderr, "dem_pile: %s failed\n", what);
        exit(2);
    }
}

/* A rock like rockA..D of the drop case: hull of 10 points within ~3 cm, sweep radius 1 cm,
 * moved into its principal frame. */
static void pile_rock(lahar_case *c, int mat, const double x[3], unsigned *seed)
{
    lahar_body *b = &c->bodies[c->nbody];
    double p[10][3];
    for (int k = 0; k < 10; k++) {
        double u[3] = {pile_rand(seed) - 0.5, pile_rand(seed) - 0.5, pile_rand(seed) - 0.5};
        double un = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]) + 1e-9;
        double r = 0.018 + 0.008 * pile_rand(seed);
        for (int d = 0; d < 3; d++) p[k][d] = r * u[d] / un;
    }
    char err[256];
    lahar_mass_props mp;
    pile_need(lahar_shape_make_hull(&b->shape, (const double(*)[3])p, 10, 0.01, err, sizeof err) == 0, "make_hull");
    pile_need(lahar_shape_mass_properties(&b->shape, 3, &mp, err, sizeof err) == 0, "mass_properties");
    lahar_shape_to_principal(&b->shape, &mp);
    snprintf(b->name, sizeof b->name, "rock%d", c->nbody);
    b->material = mat;
    b->motion = LAHAR_MOTION_FREE;
    b->convex = 1;
    b->mass = mp.volume * c->materials[mat].density;
    for (int k = 0; k < 3; k++) b->inertia[k] = mp.inertia[k] * c->materials[mat].density;
    for (int k = 0; k < 3; k++) b->x[k] = x[k];
    b->q[0] = 1.0;
    c->nbody++;
}

void dem_pile_case(lahar_case *c, int n, int layers, int hertz, unsigned seed)
{
    dem_pile_case_kind(c, n, layers, hertz, seed, 0);
}

void dem_pile_case_kind(lahar_case *c, int n, int layers, int hertz, unsigned seed, int only)
{
    const double g[3] = {0, 0, -9.81};
    dem_test_case_init(c, 3, g, n + 5);
    int m = hertz ? dem_test_material(c, "rock", LAHAR_CONTACT_HERTZ, 2650.0, 0.0, 1e8, 0.25, 0.5, 0.5)
                  : dem_test_material(c, "rock", LAHAR_CONTACT_LINEAR, 2650.0, 2e5, 0.0, 0.0, 0.5, 0.5);
    int side = (int)ceil(sqrt(n / (double)layers));
    const double spacing = 0.085; /* > the largest bounding diameter (~0.08, checked below) */
    double half = 0.5 * side * spacing + 0.02;
    const double floor_c[3] = {0, 0, 0}, up[3] = {0, 0, 1}, fsize[2] = {2 * half + 0.1, 2 * half + 0.1};
    dem_test_plane(c, "floor", m, floor_c, up, fsize, 0.01);
    double height = layers * spacing + 0.2, wsize[2] = {2 * half + 0.1, height};
    for (int k = 0; k < 4; k++) {
        double nrm[3] = {k == 0 ? 1.0 : (k == 1 ? -1.0 : 0.0), k == 2 ? 1.0 : (k == 3 ? -1.0 : 0.0), 0.0};
        double cen[3] = {-half * nrm[0], -half * nrm[1], 0.5 * height};
        double sz[2] = {wsize[0], wsize[1]}; /* width x height for either normal (make_plane) */
        char name[16];
        snprintf(name, sizeof name, "wall%d", k);
        dem_test_plane(c, name, m, cen, nrm, sz, 0.01);
    }
    for (int k = 0; k < n; k++) {
        int ix = k % side, iy = (k / side) % side, iz = k / (side * side);
        double x[3] = {-half + 0.02 + (ix + 0.5) * spacing, -half + 0.02 + (iy + 0.5) * spacing, 0.01 + (iz + 0.5) * spacing};
        char name[16];
        snprintf(name, sizeof name, "b%d", k);
        int kind = only > 0 ? only - 1 : k % 3;
        if (kind == 0) {
            dem_test_sphere(c, name, m, 0.03 + 0.007 * pile_rand(&seed), x, LAHAR_MOTION_FREE);
        } else {
            quat q = q_normalize((quat){pile_rand(&seed) - 0.5, pile_rand(&seed) - 0.5, pile_rand(&seed) - 0.5,
                                        pile_rand(&seed) - 0.5});
            if (kind == 1) {
                double q4[4], hb[3] = {0.015 + 0.006 * pile_rand(&seed), 0.013 + 0.006 * pile_rand(&seed), 0.012};
                q_store(q, q4);
                dem_test_box(c, name, m, hb, 0.008, x, q4, LAHAR_MOTION_FREE);
            } else {
                pile_rock(c, m, x, &seed);
                q_store(q, c->bodies[c->nbody - 1].q);
            }
        }
        lahar_body *b = &c->bodies[c->nbody - 1];
        for (int d = 0; d < 3; d++) b->v[d] = 0.2 * (pile_rand(&seed) - 0.5);
        double bound = 0.0;
        for (int v = 0; v < b->shape.nv; v++)
            bound = fmax(bound, sqrt(b->shape.v[v][0] * b->shape.v[v][0] + b->shape.v[v][1] * b->shape.v[v][1] +
                                     b->shape.v[v][2] * b->shape.v[v][2]));
        pile_need(2.0 * (bound + b->shape.radius) < spacing, "bounding diameter < lattice spacing");
    }
}
