/* Case loader and shape builder checks against analytic values:
 *  - mass properties: sphere, disc (exact formulas, 1e-12), capsule and 2D stadium (composite
 *    analytic formulas, 1e-12), rounded box and rounded rectangle (midpoint-grid integration of
 *    the exact distance function, 1e-3), an irregular rock (grid integration with
 *    geom_point_body_core, 2e-3);
 *  - principal frame of a rotated box (eigenvalues 1e-10, axes 1e-9) and its placement by the
 *    loader (world vertices reproduced to 1e-12);
 *  - convex hull of a cube's corners plus interior, face-centre and edge-midpoint points;
 *  - STL reading (ASCII tetrahedron, binary cube) written to the test's temp dir;
 *  - every case in cases/ loads, with positive masses and unit quaternions.
 * usage: test_case CASES_DIR TMP_DIR */
#include <dirent.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "case.h"
#include "geometry.h"
#include "shape_build.h"
#include "vec.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#include "test_util.h"

static double rel(double a, double b) { return fabs(a - b) / fabs(b); }

static void sort3(double d[3])
{
    for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++)
            if (d[j] < d[i]) {
                double t = d[i];
                d[i] = d[j];
                d[j] = t;
            }
}

/* Midpoint-grid integration of an indicator over a box [lo, hi]: volume, centroid, and the
 * inertia tensor per unit density about the centroid, returned as sorted eigenvalues. */
typedef int (*inside_fn)(const double p[3], const void *ctx);
static void grid_integrate(inside_fn in, const void *ctx, const double lo[3], const double hi[3], int n, int dim,
                           double *vol, double com[3], double eig[3])
{
    double h[3], s0 = 0, s1[3] = {0, 0, 0}, s2[3][3] = {{0}};
    for (int k = 0; k < 3; k++)
        h[k] = (hi[k] - lo[k]) / n;
    int nz = dim == 3 ? n : 1;
    double dv = h[0] * h[1] * (dim == 3 ? h[2] : 1.0);
    for (int iz = 0; iz < nz; iz++)
        for (int iy = 0; iy < n; iy++)
            for (int ix = 0; ix < n; ix++) {
                double p[3] = {lo[0] + (ix + 0.5) * h[0], lo[1] + (iy + 0.5) * h[1],
                               dim == 3 ? lo[2] + (iz + 0.5) * h[2] : 0.0};
                if (!in(p, ctx))
                    continue;
                s0 += dv;
                for (int a = 0; a < 3; a++) {
                    s1[a] += dv * p[a];
                    for (int b = 0; b < 3; b++)
                        s2[a][b] += dv * p[a] * p[b];
                }
            }
    *vol = s0;
    double C[3][3], J[3][3], V[3][3];
    for (int a = 0; a < 3; a++)
        com[a] = s1[a] / s0;
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++)
            C[a][b] = s2[a][b] - s0 * com[a] * com[b];
    double tr = C[0][0] + C[1][1] + C[2][2];
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++)
            J[a][b] = (a == b ? tr : 0.0) - C[a][b];
    lahar_sym3_eigen(J, eig, V);
    sort3(eig);
}

typedef struct {
    double half[3], r;
} rbox;
static int in_rbox(const double p[3], const void *ctx)
{
    const rbox *b = ctx;
    double s = 0;
    for (int k = 0; k < 3; k++) {
        double q = fabs(p[k]) - b->half[k];
        if (q > 0)
            s += q * q;
    }
    return s <= b->r * b->r;
}

/* Inside the swept convex shape: inside the core (behind every face plane) or within R of it
 * (geom_point_body_core measures the distance to the core's surface features). */
static int in_shape(const double p[3], const void *ctx)
{
    const lahar_shape *s = ctx;
    double x[3] = {0, 0, 0}, q[4] = {1, 0, 0, 0};
    int inside = 1;
    for (int f = 0; f < s->nf && inside; f++)
        inside = v3_dot(geom_face_normal(s, f), v3_sub(v3_load(p), v3_load(s->v[s->face_v[s->face_start[f]]]))) <= 0;
    vec3 c;
    int feat;
    return inside || geom_point_body_core(s, x, q, v3_load(p), &c, &feat) <= s->radius;
}

static void test_sphere_disc(void)
{
    lahar_shape s;
    lahar_mass_props mp;
    char err[256];
    double R = 0.1;
    CHECK(lahar_shape_make_sphere(&s, R) == 0, "make sphere");
    CHECK(lahar_shape_mass_properties(&s, 3, &mp, err, sizeof err) == 0, "sphere mass: %s", err);
    double V = 4.0 / 3.0 * M_PI * R * R * R;
    CHECK(rel(mp.volume, V) < 1e-12, "sphere volume %.15g vs %.15g", mp.volume, V);
    for (int k = 0; k < 3; k++)
        CHECK(rel(mp.inertia[k], 0.4 * V * R * R) < 1e-12, "sphere I%d %.15g vs 2/5 m R^2 %.15g", k, mp.inertia[k],
              0.4 * V * R * R);
    CHECK(lahar_shape_mass_properties(&s, 2, &mp, err, sizeof err) == 0, "disc mass: %s", err);
    double A = M_PI * R * R;
    CHECK(rel(mp.volume, A) < 1e-12, "disc area %.15g vs %.15g", mp.volume, A);
    CHECK(rel(mp.inertia[2], 0.5 * A * R * R) < 1e-12, "disc Izz %.15g vs 1/2 m R^2 %.15g", mp.inertia[2],
          0.5 * A * R * R);
    lahar_shape_free(&s);
}

static void test_capsule_stadium(void)
{
    lahar_shape s;
    lahar_mass_props mp;
    char err[256];
    double R = 0.05, L = 0.2, a[3] = {-0.1, 0, 0}, b[3] = {0.1, 0, 0};
    CHECK(lahar_shape_make_segment(&s, a, b, R) == 0, "make segment");
    CHECK(lahar_shape_mass_properties(&s, 3, &mp, err, sizeof err) == 0, "capsule: %s", err);
    /* cylinder + two hemispheres (hemisphere centroid 3R/8 from its flat face) */
    double Vc = M_PI * R * R * L, Vs = 4.0 / 3.0 * M_PI * R * R * R, mh = 0.5 * Vs, dh = 0.5 * L + 3.0 * R / 8.0;
    double Iax = 0.5 * Vc * R * R + 0.4 * Vs * R * R;
    double Iperp = Vc * (3 * R * R + L * L) / 12.0 + 2.0 * (83.0 / 320.0 * mh * R * R + mh * dh * dh);
    double got[3] = {mp.inertia[0], mp.inertia[1], mp.inertia[2]}, want[3] = {Iax, Iperp, Iperp};
    sort3(got);
    sort3(want);
    CHECK(rel(mp.volume, Vc + Vs) < 1e-12, "capsule volume %.15g vs %.15g", mp.volume, Vc + Vs);
    for (int k = 0; k < 3; k++)
        CHECK(rel(got[k], want[k]) < 1e-12, "capsule I%d %.15g vs %.15g", k, got[k], want[k]);
    /* 2D stadium: rectangle L x 2R + two half discs (centroid 4R/(3 pi) from the flat side) */
    CHECK(lahar_shape_mass_properties(&s, 2, &mp, err, sizeof err) == 0, "stadium: %s", err);
    double Ar = 2 * R * L, Ad = M_PI * R * R, mhd = 0.5 * Ad, e = 4.0 * R / (3.0 * M_PI);
    double Izz = Ar * (L * L + 4 * R * R) / 12.0 + 2.0 * (0.5 * mhd * R * R - mhd * e * e + mhd * (0.5 * L + e) * (0.5 * L + e));
    CHECK(rel(mp.volume, Ar + Ad) < 1e-12, "stadium area %.15g vs %.15g", mp.volume, Ar + Ad);
    CHECK(rel(mp.inertia[2], Izz) < 1e-12, "stadium Izz %.15g vs %.15g", mp.inertia[2], Izz);
    lahar_shape_free(&s);
}

static void test_box(void)
{
    lahar_shape s;
    lahar_mass_props mp;
    char err[256];
    rbox rb = {{0.1, 0.05, 0.03}, 0.01};
    CHECK(lahar_shape_make_box(&s, rb.half, rb.r) == 0, "make box");
    CHECK(s.nv == 8 && s.ne == 12 && s.nf == 6, "box topology %d %d %d", s.nv, s.ne, s.nf);
    CHECK(rel(lahar_shape_core_volume(&s), 8 * 0.1 * 0.05 * 0.03) < 1e-12, "box faces outward");
    CHECK(lahar_shape_mass_properties(&s, 3, &mp, err, sizeof err) == 0, "box: %s", err);
    double a = 0.2, b = 0.1, c = 0.06, R = rb.r;
    double steiner = a * b * c + 2 * R * (a * b + b * c + c * a) + M_PI * R * R * (a + b + c) + 4.0 / 3.0 * M_PI * R * R * R;
    CHECK(rel(mp.volume, steiner) < 1e-12, "rounded box volume %.15g vs Steiner %.15g", mp.volume, steiner);
    for (int k = 0; k < 3; k++)
        CHECK(fabs(mp.com[k]) < 1e-15, "box com %g", mp.com[k]);
    CHECK(fabs(mp.axes[0][0] - 1) + fabs(mp.axes[1][1] - 1) + fabs(mp.axes[2][2] - 1) == 0.0,
          "a box keeps its axes (no spurious rotation)");
    double lo[3], hi[3], gv, gc[3], ge[3];
    for (int k = 0; k < 3; k++) {
        hi[k] = rb.half[k] + R;
        lo[k] = -hi[k];
    }
    grid_integrate(in_rbox, &rb, lo, hi, 240, 3, &gv, gc, ge);
    double got[3] = {mp.inertia[0], mp.inertia[1], mp.inertia[2]};
    sort3(got);
    CHECK(rel(mp.volume, gv) < 1e-3, "box volume %.9g vs grid %.9g", mp.volume, gv);
    for (int k = 0; k < 3; k++)
        CHECK(rel(got[k], ge[k]) < 1e-3, "rounded box I%d %.9g vs grid %.9g (rel %.2e)", k, got[k], ge[k],
              rel(got[k], ge[k]));
    printf("rounded box: volume rel err vs grid %.2e, inertia %.2e %.2e %.2e\n", rel(mp.volume, gv), rel(got[0], ge[0]),
           rel(got[1], ge[1]), rel(got[2], ge[2]));
    lahar_shape_free(&s);
    /* vanishing radius: the plain box, I = m (b^2 + c^2) / 12 */
    CHECK(lahar_shape_make_box(&s, rb.half, 1e-9) == 0, "make box");
    CHECK(lahar_shape_mass_properties(&s, 3, &mp, err, sizeof err) == 0, "box: %s", err);
    double V = a * b * c;
    CHECK(rel(mp.inertia[0], V * (b * b + c * c) / 12) < 1e-6, "box Ixx %.12g vs %.12g", mp.inertia[0],
          V * (b * b + c * c) / 12);
    CHECK(rel(mp.inertia[2], V * (a * a + b * b) / 12) < 1e-6, "box Izz %.12g", mp.inertia[2]);
    lahar_shape_free(&s);
    /* 2D rounded rectangle (per unit thickness) against a 2D grid */
    rbox r2 = {{0.1, 0.04, 0.0}, 0.02};
    CHECK(lahar_shape_make_box2d(&s, r2.half, r2.r) == 0, "make box2d");
    CHECK(lahar_shape_mass_properties(&s, 2, &mp, err, sizeof err) == 0, "box2d: %s", err);
    double lo2[3] = {-0.12, -0.06, 0}, hi2[3] = {0.12, 0.06, 0};
    grid_integrate(in_rbox, &r2, lo2, hi2, 2000, 2, &gv, gc, ge);
    /* 2D grid: eigenvalues of the planar tensor are {int y^2, int x^2, int r^2} */
    double g2[3] = {mp.inertia[0], mp.inertia[1], mp.inertia[2]};
    sort3(g2);
    double a2 = 0.2, b2 = 0.08, R2 = 0.02;
    CHECK(rel(mp.volume, a2 * b2 + 2 * R2 * (a2 + b2) + M_PI * R2 * R2) < 1e-12, "rounded rectangle area");
    CHECK(rel(mp.volume, gv) < 1e-3, "rectangle area %.9g vs grid %.9g", mp.volume, gv);
    for (int k = 0; k < 3; k++)
        CHECK(rel(g2[k], ge[k]) < 1e-3, "rounded rectangle I%d %.9g vs grid %.9g", k, g2[k], ge[k]);
    lahar_shape_free(&s);
}

/* Deterministic pseudo-random numbers in [-1, 1). */
static double prand(uint64_t *st)
{
    *st = *st * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(*st >> 11) / (double)(1ull << 52) - 1.0;
}

static void test_hull_cube(void)
{
    double p[64][3];
    int n = 0;
    double h = 0.5;
    for (int i = 0; i < 8; i++, n++)
        for (int k = 0; k < 3; k++)
            p[n][k] = (i >> k & 1) ? h : -h;
    uint64_t st = 7;
    for (int i = 0; i < 10; i++, n++)
        for (int k = 0; k < 3; k++)
            p[n][k] = 0.9 * h * prand(&st); /* interior */
    for (int k = 0; k < 3; k++)
        for (int sgn = -1; sgn <= 1; sgn += 2, n++) { /* face centres */
            p[n][0] = p[n][1] = p[n][2] = 0;
            p[n][k] = sgn * h;
        }
    for (int i = 0; i < 4; i++, n++) { /* edge midpoints along x */
        p[n][0] = 0;
        p[n][1] = (i & 1) ? h : -h;
        p[n][2] = (i & 2) ? h : -h;
    }
    lahar_shape s;
    char err[256] = "";
    CHECK(lahar_shape_make_hull(&s, (const double(*)[3])p, n, 0.01, err, sizeof err) == 0, "hull: %s", err);
    CHECK(s.nv == 8 && s.nf == 6 && s.ne == 12, "cube hull of %d points: nv %d (8) nf %d (6) ne %d (12)", n, s.nv,
          s.nf, s.ne);
    for (int f = 0; f < s.nf; f++)
        CHECK(s.face_start[f + 1] - s.face_start[f] == 4, "hull face %d is a quad", f);
    CHECK(rel(lahar_shape_core_volume(&s), 8 * h * h * h) < 1e-12, "hull volume %.15g", lahar_shape_core_volume(&s));
    CHECK(lahar_shape_is_convex(&s, 3, 1e-12), "hull convex");
    lahar_shape_free(&s);
    /* degenerate inputs */
    double flat[5][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0.5, 0.2, 0}};
    CHECK(lahar_shape_make_hull(&s, (const double(*)[3])flat, 5, 0.01, err, sizeof err) != 0 && strstr(err, "coplanar"),
          "coplanar points rejected (%s)", err);
    CHECK(lahar_shape_make_hull(&s, (const double(*)[3])flat, 3, 0.01, err, sizeof err) != 0 && strstr(err, "at least 4"),
          "3 points rejected (%s)", err);
    CHECK(s.v == NULL, "nothing allocated on failure");
}

static void test_rotated_box(const char *tmpdir)
{
    /* box corners rotated by Q (axis (1, 2, 3), 40 deg) */
    double half[3] = {0.15, 0.1, 0.05}, R = 0.01, Q[3][3], p[8][3];
    quat q = q_axis_angle(v3_normalize(v3(1, 2, 3)), 40.0 * M_PI / 180.0);
    q_to_rotmat(q, Q);
    for (int i = 0; i < 8; i++) {
        vec3 c = v3((i & 1) ? half[0] : -half[0], (i & 2) ? half[1] : -half[1], (i & 4) ? half[2] : -half[2]);
        v3_store(q_rotate(q, c), p[i]);
    }
    lahar_shape s, box;
    lahar_mass_props mp, mb;
    char err[256] = "";
    CHECK(lahar_shape_make_hull(&s, (const double(*)[3])p, 8, R, err, sizeof err) == 0, "hull: %s", err);
    CHECK(lahar_shape_make_box(&box, half, R) == 0, "box");
    CHECK(lahar_shape_mass_properties(&s, 3, &mp, err, sizeof err) == 0, "rotated: %s", err);
    CHECK(lahar_shape_mass_properties(&box, 3, &mb, err, sizeof err) == 0, "box: %s", err);
    for (int j = 0; j < 3; j++) {
        /* principal axis j must be (up to sign) the rotated box axis with the same moment */
        int k = 0;
        for (int t = 1; t < 3; t++)
            if (fabs(mb.inertia[t] - mp.inertia[j]) < fabs(mb.inertia[k] - mp.inertia[j]))
                k = t;
        CHECK(rel(mp.inertia[j], mb.inertia[k]) < 1e-10, "rotated box moment %d %.15g vs %.15g", j, mp.inertia[j],
              mb.inertia[k]);
        double dot = mp.axes[0][j] * Q[0][k] + mp.axes[1][j] * Q[1][k] + mp.axes[2][j] * Q[2][k];
        CHECK(fabs(fabs(dot) - 1.0) < 1e-9, "principal axis %d vs box axis %d: |dot| = %.15f", j, k, fabs(dot));
    }
    /* the loader: the same corners as a body's vertices must be reproduced in the world */
    char path[1024];
    snprintf(path, sizeof path, "%s/rotated_box.yaml", tmpdir);
    FILE *fp = fopen(path, "w");
    if (!fp) {
        CHECK(0, "cannot write %s", path);
        lahar_shape_free(&s);
        lahar_shape_free(&box);
        return;
    }
    fprintf(fp, "dimensions: 3\ntime: {end: 1}\nmaterials: {rock: {density: 2000, young: 1e8, restitution: 0.5, "
                "friction: 0.5}}\nbodies:\n  - name: rb\n    shape: polyhedron\n    radius: %.17g\n"
                "    material: rock\n    position: [1, 2, 3]\n    vertices:\n", R);
    for (int i = 0; i < 8; i++)
        fprintf(fp, "      - [%.17g, %.17g, %.17g]\n", p[i][0], p[i][1], p[i][2]);
    fclose(fp);
    lahar_case c;
    CHECK(lahar_case_load(path, &c) == 0, "load %s", path);
    if (c.nbody == 1) {
        lahar_body *b = &c.bodies[0];
        CHECK(fabs(b->x[0] - 1) + fabs(b->x[1] - 2) + fabs(b->x[2] - 3) < 1e-14, "com at position");
        CHECK(rel(b->mass, 2000 * mb.volume) < 1e-12, "mass %.15g", b->mass);
        double maxerr = 0;
        for (int v = 0; v < b->shape.nv; v++) {
            vec3 w = geom_world_vertex(&b->shape, b->x, b->q, v);
            double best = 1e9;
            for (int i = 0; i < 8; i++)
                best = fmin(best, v3_norm(v3_sub(w, v3(1 + p[i][0], 2 + p[i][1], 3 + p[i][2]))));
            maxerr = fmax(maxerr, best);
        }
        CHECK(maxerr < 1e-12, "world vertices reproduced to %.3g m", maxerr);
        /* in the principal frame the core is axis-aligned: every |coordinate| is a half extent */
        for (int v = 0; v < b->shape.nv; v++)
            for (int k = 0; k < 3; k++) {
                double x = fabs(b->shape.v[v][k]);
                CHECK(fabs(x - 0.15) < 1e-12 || fabs(x - 0.1) < 1e-12 || fabs(x - 0.05) < 1e-12,
                      "principal-frame coordinate %.15g", x);
            }
    }
    lahar_case_free(&c);
    lahar_shape_free(&s);
    lahar_shape_free(&box);
}

static void test_rock_grid(void)
{
    double p[14][3];
    uint64_t st = 12345;
    for (int i = 0; i < 14; i++) {
        double sc[3] = {0.12, 0.08, 0.06};
        for (int k = 0; k < 3; k++)
            p[i][k] = sc[k] * prand(&st) + (k == 0 ? 0.03 : 0.0); /* off-centre on purpose */
    }
    lahar_shape s;
    lahar_mass_props mp;
    char err[256] = "";
    CHECK(lahar_shape_make_hull(&s, (const double(*)[3])p, 14, 0.015, err, sizeof err) == 0, "rock hull: %s", err);
    CHECK(lahar_shape_mass_properties(&s, 3, &mp, err, sizeof err) == 0, "rock: %s", err);
    double lo[3] = {1e9, 1e9, 1e9}, hi[3] = {-1e9, -1e9, -1e9};
    for (int v = 0; v < s.nv; v++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], s.v[v][k] - s.radius);
            hi[k] = fmax(hi[k], s.v[v][k] + s.radius);
        }
    double gv, gc[3], ge[3], got[3] = {mp.inertia[0], mp.inertia[1], mp.inertia[2]};
    grid_integrate(in_shape, &s, lo, hi, 90, 3, &gv, gc, ge);
    sort3(got);
    CHECK(rel(mp.volume, gv) < 2e-3, "rock volume %.9g vs grid %.9g", mp.volume, gv);
    for (int k = 0; k < 3; k++) {
        CHECK(fabs(mp.com[k] - gc[k]) < 2e-3 * 0.1, "rock com %d %.9g vs grid %.9g", k, mp.com[k], gc[k]);
        CHECK(rel(got[k], ge[k]) < 2e-3, "rock I%d %.9g vs grid %.9g", k, got[k], ge[k]);
    }
    printf("rock (%d vertices, %d faces): volume rel err vs grid %.2e, inertia %.2e %.2e %.2e\n", s.nv, s.nf,
           rel(mp.volume, gv), rel(got[0], ge[0]), rel(got[1], ge[1]), rel(got[2], ge[2]));
    lahar_shape_free(&s);
}

static void put_f32(FILE *fp, float f) { fwrite(&f, sizeof f, 1, fp); }

static void test_stl(const char *tmpdir)
{
    char path[1024], err[512] = "";
    lahar_shape s;
    /* ASCII tetrahedron, outward facets; again after a UTF-8 byte-order mark and a blank line, which
     * some exporters write before "solid" (an ASCII file all the same) */
    static const double tv[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    static const int tf[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    static const char *const lead[2] = {"", "\xef\xbb\xbf\n"};
    FILE *fp = NULL;
    for (int variant = 0; variant < 2; variant++) {
        snprintf(path, sizeof path, "%s/tetra%d.stl", tmpdir, variant);
        fp = fopen(path, "w");
        if (!fp) {
            CHECK(0, "cannot write %s", path);
            return;
        }
        fprintf(fp, "%ssolid tetra\n", lead[variant]);
        for (int f = 0; f < 4; f++) {
            fprintf(fp, " facet normal 0 0 0\n  outer loop\n");
            for (int c = 0; c < 3; c++)
                fprintf(fp, "   vertex %g %g %g\n", tv[tf[f][c]][0], tv[tf[f][c]][1], tv[tf[f][c]][2]);
            fprintf(fp, "  endloop\n endfacet\n");
        }
        fprintf(fp, "endsolid tetra\n");
        fclose(fp);
        CHECK(lahar_shape_read_stl(&s, path, 0.01, err, sizeof err) == 0, "ascii stl (variant %d): %s", variant, err);
        CHECK(s.nv == 4 && s.nf == 4 && s.ne == 6, "tetra: nv %d nf %d ne %d", s.nv, s.nf, s.ne);
        CHECK(rel(lahar_shape_core_volume(&s), 1.0 / 6.0) < 1e-12, "tetra volume %.15g", lahar_shape_core_volume(&s));
        lahar_shape_free(&s);
    }
    /* binary unit cube, 12 triangles: the 36 corners merge into 8 vertices */
    snprintf(path, sizeof path, "%s/cube.stl", tmpdir);
    fp = fopen(path, "wb");
    if (!fp) {
        CHECK(0, "cannot write %s", path);
        return;
    }
    lahar_shape box;
    double half[3] = {0.5, 0.5, 0.5};
    lahar_shape_make_box(&box, half, 0.01);
    char header[80] = "binary cube written by test_case";
    fwrite(header, 1, 80, fp);
    uint32_t nt = 12;
    fwrite(&nt, 4, 1, fp);
    for (int f = 0; f < 6; f++) {
        int *fv = box.face_v + box.face_start[f];
        int tri[2][3] = {{fv[0], fv[1], fv[2]}, {fv[0], fv[2], fv[3]}};
        for (int t = 0; t < 2; t++) {
            for (int k = 0; k < 3; k++)
                put_f32(fp, 0.0f);
            for (int c = 0; c < 3; c++)
                for (int k = 0; k < 3; k++)
                    put_f32(fp, (float)(box.v[tri[t][c]][k] + 0.5));
            uint16_t attr = 0;
            fwrite(&attr, 2, 1, fp);
        }
    }
    fclose(fp);
    lahar_shape_free(&box);
    CHECK(lahar_shape_read_stl(&s, path, 0.01, err, sizeof err) == 0, "binary stl: %s", err);
    CHECK(s.nv == 8 && s.nf == 12 && s.ne == 18, "cube: nv %d (8) nf %d (12) ne %d (18)", s.nv, s.nf, s.ne);
    CHECK(rel(lahar_shape_core_volume(&s), 1.0) < 1e-12, "cube volume %.15g", lahar_shape_core_volume(&s));
    CHECK(lahar_shape_is_convex(&s, 3, 1e-9), "cube convex");
    lahar_shape_free(&s);
    snprintf(path, sizeof path, "%s/missing.stl", tmpdir);
    CHECK(lahar_shape_read_stl(&s, path, 0.01, err, sizeof err) != 0 && strstr(err, path), "missing STL named: %s", err);
}

/* Writes text to path; 0, or -1 (counted as a failure) when the file cannot be written. */
static int write_text(const char *path, const char *text)
{
    FILE *fp = fopen(path, "w");
    if (!fp || fputs(text, fp) < 0) {
        CHECK(0, "cannot write %s", path);
        if (fp)
            fclose(fp);
        return -1;
    }
    return fclose(fp) == 0 ? 0 : -1;
}

/* Loader paths not covered by cases/: STL body (path relative to the case, scale, placement),
 * prescribed body, defaults, 2D polygon/box with orientation. Runs after test_stl (cube.stl). */
static void test_loader_misc(const char *tmpdir)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/misc3d.yaml", tmpdir);
    if (write_text(path, "dimensions: 3\ntime: {end: 2.0}\n"
                         "materials: {rock: {density: 1000, young: 1e8, restitution: 0.5, friction: 0.5}}\n"
                         "bodies:\n"
                         "  - {name: terrain, shape: stl, file: cube.stl, scale: 2, motion: fixed, radius: 0.01,\n"
                         "     material: rock, position: [10, 0, 0], orientation: {axis: [0, 0, 1], angle_deg: 90}}\n"
                         "  - {name: gate, shape: box, size: [0.2, 0.2, 0.2], radius: 0.01, motion: prescribed,\n"
                         "     material: rock, position: [0, 0, 5], velocity: [0, 0, 0.1]}\n") != 0)
        return;
    lahar_case c;
    CHECK(lahar_case_load(path, &c) == 0, "load %s", path);
    if (c.nbody == 2) {
        /* defaults */
        CHECK(c.gravity[2] == -9.81 && c.dt_max == 1e-3 && c.dt_min == 1e-9 && c.output_interval == 0.02 &&
                  c.forces_interval == 0 && strcmp(c.dem_engine, "spheropoly") == 0 && c.dem_dt_safety == 0.02 &&
                  c.materials[0].model == LAHAR_CONTACT_HERTZ && c.materials[0].poisson == 0.25 &&
                  fabs(c.materials[0].kt_ratio - 2.0 / 7.0) < 1e-15 && c.output_fields == 0x1f && c.output_forces == 1,
              "defaults filled in");
        const lahar_body *t = &c.bodies[0], *g = &c.bodies[1];
        /* cube.stl spans [0, 1]^3; scaled by 2, turned 90 deg about z, moved to x = 10:
         * world x in [8, 10], y in [0, 2], z in [0, 2] */
        double lo[3] = {1e9, 1e9, 1e9}, hi[3] = {-1e9, -1e9, -1e9};
        for (int v = 0; v < t->shape.nv; v++)
            for (int k = 0; k < 3; k++) {
                lo[k] = fmin(lo[k], t->shape.v[v][k]);
                hi[k] = fmax(hi[k], t->shape.v[v][k]);
            }
        CHECK(fabs(lo[0] - 8) + fabs(hi[0] - 10) + fabs(lo[1]) + fabs(hi[1] - 2) + fabs(lo[2]) + fabs(hi[2] - 2) < 1e-12,
              "STL placed in the world: [%g %g] [%g %g] [%g %g]", lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]);
        CHECK(t->motion == LAHAR_MOTION_FIXED && t->mass == 0 && t->q[0] == 1 && t->x[0] == 0, "fixed body frame");
        CHECK(g->motion == LAHAR_MOTION_PRESCRIBED && g->v[2] == 0.1 && g->mass > 0 && g->x[2] == 5,
              "prescribed body keeps its velocity, has mass properties");
    }
    lahar_case_free(&c);

    snprintf(path, sizeof path, "%s/misc2d.yaml", tmpdir);
    if (write_text(path, "dimensions: 2\ntime: {end: 1.0}\n"
                         "materials: {rock: {density: 2000, model: linear, kn: 1e6, restitution: 0.5, friction: 0.5}}\n"
                         "bodies:\n"
                         "  - {name: tri, shape: polygon, radius: 0.01, material: rock, position: [1, 1],\n"
                         "     vertices: [[0, 0], [0.3, 0], [0, 0.3], [0.05, 0.05]], angular_velocity: 2}\n"
                         "  - {name: slab, shape: box, size: [0.4, 0.1], radius: 0.01, material: rock, position: [0, 0],\n"
                         "     orientation: {angle_deg: 30}}\n") != 0)
        return;
    CHECK(lahar_case_load(path, &c) == 0, "load %s", path);
    if (c.nbody == 2) {
        const lahar_body *t = &c.bodies[0], *s = &c.bodies[1];
        CHECK(t->shape.nv == 3 && t->shape.nf == 0 && t->shape.ne == 3, "2D hull drops the interior point");
        CHECK(t->w[2] == 2 && t->x[2] == 0 && fabs(t->q[1]) + fabs(t->q[2]) < 1e-15, "2D body stays in the plane");
        double ang = 2 * atan2(s->q[3], s->q[0]) * 180 / M_PI;
        CHECK(fabs(ang - 30) < 1e-9, "2D box orientation %.12g deg", ang);
        double R = 0.01, a = 0.38, b = 0.08, A = a * b + 2 * R * (a + b) + M_PI * R * R;
        CHECK(rel(s->mass, 2000 * A) < 1e-12, "2D box mass per unit thickness %.15g vs %.15g", s->mass, 2000 * A);
    }
    lahar_case_free(&c);
}

static void test_jacobi(void)
{
    uint64_t st = 99;
    double A[3][3], d[3], V[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = i; j < 3; j++)
            A[i][j] = A[j][i] = prand(&st);
    lahar_sym3_eigen(A, d, V);
    double err = 0, det = V[0][0] * (V[1][1] * V[2][2] - V[1][2] * V[2][1]) -
                          V[0][1] * (V[1][0] * V[2][2] - V[1][2] * V[2][0]) + V[0][2] * (V[1][0] * V[2][1] - V[1][1] * V[2][0]);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double s = 0;
            for (int k = 0; k < 3; k++)
                s += V[i][k] * d[k] * V[j][k];
            err = fmax(err, fabs(s - A[i][j]));
        }
    CHECK(err < 1e-14, "Jacobi reconstruction error %.3g", err);
    CHECK(fabs(det - 1) < 1e-14, "Jacobi eigenvectors form a rotation (det %.17g)", det);
}

static int name_cmp(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

static void test_cases_dir(const char *dir)
{
    DIR *d = opendir(dir);
    CHECK(d != NULL, "open %s", dir);
    if (!d)
        return;
    char *names[256];
    int n = 0;
    struct dirent *de;
    while ((de = readdir(d)) && n < 256) {
        if (lahar_test_is_case_file(de->d_name))
            names[n++] = strdup(de->d_name);
    }
    closedir(d);
    qsort(names, (size_t)n, sizeof *names, name_cmp);
    CHECK(n >= 3, "at least the three example cases in %s (found %d)", dir, n);
    for (int i = 0; i < n; i++) {
        char path[2048];
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        lahar_case c;
        int rc = lahar_case_load(path, &c);
        CHECK(rc == 0, "%s loads", path);
        int nfree = 0;
        for (int b = 0; b < c.nbody; b++) {
            const lahar_body *bd = &c.bodies[b];
            double qn = sqrt(bd->q[0] * bd->q[0] + bd->q[1] * bd->q[1] + bd->q[2] * bd->q[2] + bd->q[3] * bd->q[3]);
            CHECK(fabs(qn - 1) < 1e-14, "%s: %s unit quaternion", names[i], bd->name);
            if (bd->motion == LAHAR_MOTION_FIXED) {
                CHECK(bd->mass == 0, "%s: fixed %s has mass 0", names[i], bd->name);
            } else {
                nfree++;
                CHECK(bd->mass > 0 && bd->inertia[0] > 0 && bd->inertia[1] > 0 && bd->inertia[2] > 0 && bd->convex,
                      "%s: %s mass %g inertia %g %g %g", names[i], bd->name, bd->mass, bd->inertia[0], bd->inertia[1],
                      bd->inertia[2]);
            }
        }
        if (rc == 0)
            printf("%s: %dD, %d bodies (%d moving), %d materials, check %s\n", names[i], c.dim, c.nbody, nfree,
                   c.nmaterial, c.check.enabled ? c.check.reference : "-");
        if (strcmp(names[i], "dem_bounce_3d.yaml") == 0)
            CHECK(c.check.enabled && strcmp(c.check.reference, "restitution") == 0, "bounce case has check: restitution");
        if (strcmp(names[i], "dem_incline_2d.yaml") == 0)
            CHECK(c.dim == 2 && c.check.enabled && strcmp(c.check.reference, "incline_roll") == 0,
                  "incline case is 2D with check: incline_roll");
        if (strcmp(names[i], "dem_drop_3d.yaml") == 0) {
            CHECK(nfree >= 30 && nfree <= 60, "drop case has 30-60 moving bodies (%d)", nfree);
            /* identical rocks share one mass computation and give bitwise-identical results */
            int a = -1, same = 0, pairs = 0;
            for (int b = 0; b < c.nbody; b++)
                if (strncmp(c.bodies[b].name, "rockA", 5) == 0) {
                    if (a < 0) {
                        a = b;
                        continue;
                    }
                    pairs++;
                    same += c.bodies[b].mass == c.bodies[a].mass && c.bodies[b].shape.nv == c.bodies[a].shape.nv &&
                            memcmp(c.bodies[b].shape.v, c.bodies[a].shape.v,
                                   (size_t)c.bodies[a].shape.nv * sizeof *c.bodies[a].shape.v) == 0;
                }
            CHECK(pairs > 0 && same == pairs, "copies of rockA are identical (%d of %d)", same, pairs);
        }
        lahar_case_free(&c);
        free(names[i]);
    }
}

/* The default c0 (10 U_ref) counts the moving bodies: a 20 m/s boulder into still, shallow water
 * (free fall over 0.5 m: 3.1 m/s) must give c0 = 200 m/s, not 31 (docs/stability.md: a
 * body faster than c0 outruns the water's pressure wave and crosses it). A spinning disc counts
 * its rim: |w| (r_core + radius). Fixed bodies do not count. */
static void test_default_c0_bodies(const char *tmpdir)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/c0_bodies.yaml", tmpdir);
    if (write_text(path, "dimensions: 2\ntime: {end: 0.1}\n"
                         "materials: {rock: {density: 2650, model: linear, kn: 1e8, restitution: 0.5, friction: 0.5}}\n"
                         "bodies:\n"
                         "  - {name: floor, shape: box, size: [4, 0.1], radius: 0.01, motion: fixed, material: rock,\n"
                         "     position: [0, -0.06]}\n"
                         "  - {name: boulder, shape: disc, radius: 0.2, material: rock, position: [-1, 1], velocity: [20, 0]}\n"
                         "  - {name: wheel, shape: disc, radius: 0.1, material: rock, position: [1, 1], angular_velocity: 30}\n"
                         "sph:\n  dx: 0.05\n  blocks:\n    - {name: pool, box: {lo: [-1.5, 0], hi: [1.5, 0.5]}}\n") != 0)
        return;
    lahar_case c;
    CHECK(lahar_case_load(path, &c) == 0, "load %s", path);
    CHECK(fabs(c.sph.c0 - 200.0) < 1e-9, "default c0 with a 20 m/s boulder: %g m/s (expected 200)", c.sph.c0);
    lahar_case_free(&c);
    if (write_text(path, "dimensions: 2\ntime: {end: 0.1}\n"
                         "materials: {rock: {density: 2650, model: linear, kn: 1e8, restitution: 0.5, friction: 0.5}}\n"
                         "bodies:\n"
                         "  - {name: wheel, shape: disc, radius: 0.1, material: rock, position: [1, 1], angular_velocity: 60}\n"
                         "sph:\n  dx: 0.05\n  blocks:\n    - {name: pool, box: {lo: [-1.5, 0], hi: [1.5, 0.5]}}\n") != 0)
        return;
    CHECK(lahar_case_load(path, &c) == 0, "load %s", path);
    /* a disc is a point core swept by its radius: rim speed 60 x 0.1 = 6 m/s > sqrt(2 g 0.5) */
    CHECK(fabs(c.sph.c0 - 60.0) < 1e-9, "default c0 with a disc spinning at 60 rad/s: %g m/s (expected 60)", c.sph.c0);
    lahar_case_free(&c);
}

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: %s CASES_DIR TMP_DIR\n", argv[0]);
        return 1;
    }
    test_jacobi();
    test_sphere_disc();
    test_capsule_stadium();
    test_box();
    test_hull_cube();
    test_rotated_box(argv[2]);
    test_rock_grid();
    test_stl(argv[2]);
    test_loader_misc(argv[2]);
    test_default_c0_bodies(argv[2]);
    test_cases_dir(argv[1]);
    printf("%d checks, %d failures\n", checks, failures);
    return failures ? 1 : 0;
}
