/* Particle blocks: the lattice fill of boxes, polygons and closed STL meshes, and the cut-out of
 * bodies (common/geometry/particle_block.c lahar_particle_block_*, common/io/case.c lahar_case_block_lattice),
 * against exact counts and analytic areas/volumes:
 *  - an L-shaped (non-convex) polygon whose corners lie on lattice-cell boundaries holds exactly
 *    area / dx^2 points, in either orientation, and the notch stays empty;
 *  - a triangle with irrational slopes: |N dx^2 - A| <= the area of the cells its boundary can
 *    touch, (2 P/dx + 4) dx^2 (every misclassified lattice point's cell meets the boundary), and
 *    within 1 % at 100 points across;
 *  - a cube STL (binary, 12 triangles) aligned with the lattice holds exactly (L/dx)^3 points,
 *    and points whose ray leaves through an edge or a corner are still inside;
 *  - a closed, non-convex, star-shaped mesh (perturbed icosphere, 1280 triangles, ASCII STL):
 *    N dx^3 against the mesh's own volume (divergence theorem) within 1 %, and within the
 *    boundary-shell bound A sqrt(3) dx; its lattice walk (triangles binned by their shadow) keeps
 *    exactly the points the per-point inside test keeps;
 *  - cut-out: a water box around a fixed disc, a free 2D box turned by 30 degrees and a 3D
 *    sphere loses exactly the lattice points an independent distance test puts inside them, and
 *    so does a fixed wavy bed of 119 features (cut through its feature grid);
 *  - every sph: default is the documented value (c0 = 10 sqrt(2 g H) computed independently);
 *  - sph.body_layers: around a sphere in a periodic cube (3D) and a disc in a closed box (2D) the
 *    points within N dx of the surface lie on the layers R + (l + 1/2) dx to 1e-9 dx, the inner
 *    layers hold round(shell volume / dx^D) points, no two points of the first layer are closer
 *    than 0.7 dx, and the fill holds the fluid's volume / dx^D to within the layers' rounding.
 * usage: test_case_blocks TMP_DIR */
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

static lahar_particle_block polygon_block(const double (*p)[2], int n)
{
    lahar_particle_block b;
    memset(&b, 0, sizeof b);
    b.kind = LAHAR_BLOCK_POLYGON;
    b.nvert = n;
    b.vert = calloc((size_t)n, sizeof *b.vert);
    for (int i = 0; i < n; i++) {
        b.vert[i][0] = p[i][0];
        b.vert[i][1] = p[i][1];
    }
    lahar_particle_block_bounds(&b, 2);
    return b;
}

static void test_polygons(void)
{
    const double dx = 0.01;
    /* L shape: 0.3 x 0.2 minus the 0.2 x 0.1 notch at the top right; area 0.04 */
    const double L[6][2] = {{0, 0}, {0.3, 0}, {0.3, 0.1}, {0.1, 0.1}, {0.1, 0.2}, {0, 0.2}};
    double Lrev[6][2];
    for (int i = 0; i < 6; i++)
        memcpy(Lrev[i], L[5 - i], sizeof Lrev[i]);
    lahar_particle_block a = polygon_block(L, 6), b = polygon_block((const double(*)[2])Lrev, 6);
    int64_t na = lahar_particle_block_lattice(&a, 2, dx, NULL, 0), nb = lahar_particle_block_lattice(&b, 2, dx, NULL, 0);
    CHECK(na == 400, "L polygon: %lld lattice points, expected area/dx^2 = 400", (long long)na);
    CHECK(nb == na, "L polygon reversed: %lld points, counter-clockwise gave %lld", (long long)nb, (long long)na);
    double in_notch[3] = {0.25, 0.15, 0}, in_foot[3] = {0.25, 0.05, 0}, in_stem[3] = {0.05, 0.15, 0};
    CHECK(!lahar_particle_block_contains(&a, 2, in_notch), "L polygon: the notch must be outside");
    CHECK(lahar_particle_block_contains(&a, 2, in_foot) && lahar_particle_block_contains(&a, 2, in_stem),
          "L polygon: foot and stem must be inside");
    /* the points written are the ones counted, and all are inside */
    double (*pts)[3] = malloc(400 * sizeof *pts);
    int64_t nw = lahar_particle_block_lattice(&a, 2, dx, pts, 400);
    int all_in = nw == 400;
    for (int64_t i = 0; i < 400 && all_in; i++)
        all_in = lahar_particle_block_contains(&a, 2, pts[i]) && pts[i][2] == 0.0;
    CHECK(all_in, "L polygon: written lattice points are inside with z = 0");
    free(pts);
    lahar_particle_block_free(&a);
    lahar_particle_block_free(&b);

    /* triangle with irrational slopes */
    const double T[3][2] = {{0.0, 0.0}, {M_SQRT2 / 10.0, 0.0137}, {0.031, M_PI / 30.0}};
    lahar_particle_block t = polygon_block(T, 3);
    double area = 0.5 * fabs((T[1][0] - T[0][0]) * (T[2][1] - T[0][1]) - (T[2][0] - T[0][0]) * (T[1][1] - T[0][1]));
    double per = 0;
    for (int i = 0; i < 3; i++)
        per += hypot(T[(i + 1) % 3][0] - T[i][0], T[(i + 1) % 3][1] - T[i][1]);
    double h = 0.1 / 100.0;
    int64_t nt = lahar_particle_block_lattice(&t, 2, h, NULL, 0);
    double err = fabs((double)nt * h * h - area);
    double bound = (2.0 * per / h + 4.0) * h * h;
    printf("triangle: %lld points, area %.6g vs %.6g (rel %.2e, boundary-cell bound %.2e)\n", (long long)nt,
           (double)nt * h * h, area, err / area, bound / area);
    CHECK(err <= bound, "triangle: |N dx^2 - A| = %g exceeds the boundary-cell bound %g", err, bound);
    CHECK(err / area < 0.01, "triangle: lattice area off by %.3g %% (> 1 %%)", 100 * err / area);
    lahar_particle_block_free(&t);
}

static void write_binary_cube(const char *path, double L)
{
    FILE *f = fopen(path, "wb");
    if (!f)
        return;
    char header[80] = "lahar test cube";
    fwrite(header, 1, 80, f);
    uint32_t n = 12;
    fwrite(&n, 4, 1, f);
    static const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (int q = 0; q < 6; q++)
        for (int t = 0; t < 2; t++) {
            int idx[3] = {quads[q][0], quads[q][1 + t], quads[q][2 + t]};
            float rec[12] = {0};
            for (int k = 0; k < 3; k++) {
                int c = idx[k];
                rec[3 + 3 * k] = (float)((c & 1) ? L : 0.0);
                rec[4 + 3 * k] = (float)((c & 2) ? L : 0.0);
                rec[5 + 3 * k] = (float)((c & 4) ? L : 0.0);
            }
            fwrite(rec, 4, 12, f);
            uint16_t attr = 0;
            fwrite(&attr, 2, 1, f);
        }
    fclose(f);
}

/* Icosphere refined `levels` times, radius r(direction) = R (1 + 0.25 sin(3 phi) sin(theta)^2):
 * star-shaped, closed, not convex. Written as ASCII STL; returns its volume by the divergence
 * theorem and its area. */
typedef struct {
    int nv, nt, cap_v, cap_t;
    double (*v)[3];
    int (*t)[3];
} mesh;

static int mesh_mid(mesh *m, int a, int b, int *cache_a, int *cache_b, int *cache_m, int *nc)
{
    int lo = a < b ? a : b, hi = a < b ? b : a;
    for (int i = 0; i < *nc; i++)
        if (cache_a[i] == lo && cache_b[i] == hi)
            return cache_m[i];
    vec3 p = v3_normalize(v3_scale(v3_add(v3_load(m->v[a]), v3_load(m->v[b])), 0.5));
    v3_store(p, m->v[m->nv]);
    cache_a[*nc] = lo;
    cache_b[*nc] = hi;
    cache_m[*nc] = m->nv;
    (*nc)++;
    return m->nv++;
}

static void write_star_mesh(const char *path, double R, int levels, double *volume, double *area)
{
    const double g = (1.0 + sqrt(5.0)) / 2.0;
    double iv[12][3] = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                        {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
    int it[20][3] = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                     {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                     {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    int maxt = 20, maxv = 12;
    for (int l = 0; l < levels; l++) {
        maxv += 3 * maxt / 2;
        maxt *= 4;
    }
    mesh m = {12, 20, maxv, maxt, calloc((size_t)maxv, sizeof(double[3])), calloc((size_t)maxt, sizeof(int[3]))};
    for (int i = 0; i < 12; i++)
        v3_store(v3_normalize(v3_load(iv[i])), m.v[i]);
    memcpy(m.t, it, sizeof it);
    int *ca = malloc((size_t)maxv * sizeof(int)), *cb = malloc((size_t)maxv * sizeof(int)),
        *cm = malloc((size_t)maxv * sizeof(int));
    int (*nt)[3] = calloc((size_t)maxt, sizeof *nt);
    for (int l = 0; l < levels; l++) {
        int nc = 0, k = 0;
        for (int t = 0; t < m.nt; t++) {
            int a = m.t[t][0], b = m.t[t][1], c = m.t[t][2];
            int ab = mesh_mid(&m, a, b, ca, cb, cm, &nc), bc = mesh_mid(&m, b, c, ca, cb, cm, &nc),
                cc = mesh_mid(&m, c, a, ca, cb, cm, &nc);
            int q[4][3] = {{a, ab, cc}, {b, bc, ab}, {c, cc, bc}, {ab, bc, cc}};
            memcpy(nt[k], q, sizeof q);
            k += 4;
        }
        m.nt = k;
        memcpy(m.t, nt, (size_t)k * sizeof *nt);
    }
    for (int i = 0; i < m.nv; i++) {
        double x = m.v[i][0], y = m.v[i][1], z = m.v[i][2];
        double phi = atan2(y, x), s2 = 1.0 - z * z;
        double r = R * (1.0 + 0.25 * sin(3.0 * phi) * s2);
        m.v[i][0] = r * x;
        m.v[i][1] = r * y;
        m.v[i][2] = r * z;
    }
    FILE *f = fopen(path, "w");
    *volume = 0;
    *area = 0;
    if (f)
        fputs("solid star\n", f);
    for (int t = 0; t < m.nt; t++) {
        vec3 p0 = v3_load(m.v[m.t[t][0]]), p1 = v3_load(m.v[m.t[t][1]]), p2 = v3_load(m.v[m.t[t][2]]);
        *volume += v3_dot(p0, v3_cross(p1, p2)) / 6.0;
        *area += 0.5 * v3_norm(v3_cross(v3_sub(p1, p0), v3_sub(p2, p0)));
        if (f) {
            fputs(" facet normal 0 0 0\n  outer loop\n", f);
            for (int k = 0; k < 3; k++)
                fprintf(f, "   vertex %.17g %.17g %.17g\n", m.v[m.t[t][k]][0], m.v[m.t[t][k]][1], m.v[m.t[t][k]][2]);
            fputs("  endloop\n endfacet\n", f);
        }
    }
    if (f) {
        fputs("endsolid star\n", f);
        fclose(f);
    }
    *volume = fabs(*volume);
    free(ca);
    free(cb);
    free(cm);
    free(nt);
    free(m.v);
    free(m.t);
}

static int write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (!f)
        return -1;
    fputs(text, f);
    fclose(f);
    return 0;
}

static void test_meshes(const char *tmp)
{
    char path[4096], stl[4096];
    /* cube 0.1 m, offset by position, lattice aligned with its faces: exactly 10^3 points */
    snprintf(stl, sizeof stl, "%s/blocks_cube.stl", tmp);
    write_binary_cube(stl, 0.1);
    snprintf(path, sizeof path, "%s/blocks_cube.yaml", tmp);
    write_file(path, "dimensions: 3\ntime: {end: 1}\nsph:\n  dx: 0.01\n  blocks:\n"
                     "    - {name: cube, stl: {file: blocks_cube.stl, position: [1, 2, 3]}}\n");
    lahar_case c;
    if (lahar_case_load(path, &c) == 0) {
        const lahar_particle_block *b = &c.blocks[0];
        int64_t n = lahar_particle_block_lattice(b, 3, c.sph_dx, NULL, 0);
        CHECK(b->kind == LAHAR_BLOCK_MESH && b->ntri == 12 && b->nvert == 8, "cube: mesh of 8 vertices, 12 triangles");
        CHECK(fabs(b->lo[0] - 1.0) < 1e-7 && fabs(b->hi[2] - 3.1) < 1e-7, "cube: bounds moved to position");
        CHECK(n == 1000, "cube STL: %lld lattice points, expected (L/dx)^3 = 1000", (long long)n);
        CHECK(lahar_case_block_lattice(&c, 0, NULL, 0) == 1000, "cube STL: no body, nothing cut");
        /* points whose first ray (direction (1, 1/pi, e^(-pi/2))) leaves the cube exactly through
         * an edge or a corner, where two or three triangles meet: parity alone would be wrong */
        vec3 d0 = v3_normalize(v3(1.0, 0.3183098861837907, 0.2078795763507619));
        const double *lo = b->lo, *hi = b->hi; /* the mesh's own (float-rounded) coordinates */
        const double targets[3][3] = {{hi[0], 0.5 * (lo[1] + hi[1]), hi[2]}, {hi[0], hi[1], hi[2]},
                                      {hi[0], hi[1], 0.5 * (lo[2] + hi[2])}};
        for (int k = 0; k < 3; k++) {
            double x[3];
            v3_store(v3_sub(v3_load(targets[k]), v3_scale(d0, 0.05)), x);
            CHECK(lahar_particle_block_contains(b, 3, x), "cube STL: point [%g, %g, %g] whose ray grazes an edge or a "
                  "corner must be inside", x[0], x[1], x[2]);
        }
        lahar_case_free(&c);
    } else
        CHECK(0, "cube case does not load");

    /* star-shaped non-convex closed mesh, scale 0.5 applied by the loader */
    double vol = 0, area = 0;
    snprintf(stl, sizeof stl, "%s/blocks_star.stl", tmp);
    write_star_mesh(stl, 0.2, 3, &vol, &area);
    vol *= 0.125; /* scale 0.5 */
    area *= 0.25;
    snprintf(path, sizeof path, "%s/blocks_star.yaml", tmp);
    write_file(path, "dimensions: 3\ntime: {end: 1}\nsph:\n  dx: 0.005\n  blocks:\n"
                     "    - {name: star, stl: {file: blocks_star.stl, scale: 0.5}}\n");
    if (lahar_case_load(path, &c) == 0) {
        const lahar_particle_block *b = &c.blocks[0];
        double dx = c.sph_dx;
        int64_t n = lahar_particle_block_lattice(b, 3, dx, NULL, 0);
        double err = fabs((double)n * dx * dx * dx - vol), bound = area * sqrt(3.0) * dx;
        printf("star mesh: %d triangles, %lld points, volume %.6g vs %.6g (rel %.2e, shell bound %.2e)\n", b->ntri,
               (long long)n, (double)n * dx * dx * dx, vol, err / vol, bound / vol);
        CHECK(b->ntri == 1280, "star mesh: %d triangles, expected 1280", b->ntri);
        CHECK(err <= bound, "star mesh: volume error %g above the boundary-shell bound %g", err, bound);
        CHECK(err / vol < 0.01, "star mesh: lattice volume off by %.3g %% (> 1 %%)", 100 * err / vol);
        /* non-convex: a point between two lobes, inside the bounding box, is outside */
        double between[3] = {0.0, 0.0, 0.0}, dent[3];
        /* r(phi) is smallest at phi = -pi/6 (sin 3 phi = -1): R 0.75 x 0.5; probe at 0.9 R 0.5 */
        dent[0] = 0.5 * 0.2 * 0.9 * cos(-M_PI / 6);
        dent[1] = 0.5 * 0.2 * 0.9 * sin(-M_PI / 6);
        dent[2] = 0.0;
        /* more than GEOM_FEATURE_GRID_MIN triangles: the lattice walk bins them by their shadow
         * along the ray; it must keep exactly the points the per-point test keeps, in order */
        int64_t nb[3], brute = 0, same = 0;
        for (int a = 0; a < 3; a++)
            nb[a] = (int64_t)floor((b->hi[a] - b->lo[a]) / dx + 1e-9);
        double (*pts)[3] = malloc((size_t)(n > 0 ? n : 1) * sizeof *pts);
        lahar_particle_block_lattice(b, 3, dx, pts, n);
        for (int64_t i = 0; i < nb[0]; i++)
            for (int64_t j = 0; j < nb[1]; j++)
                for (int64_t k = 0; k < nb[2]; k++) {
                    double x[3] = {b->lo[0] + (i + 0.5) * dx, b->lo[1] + (j + 0.5) * dx, b->lo[2] + (k + 0.5) * dx};
                    if (!lahar_particle_block_contains(b, 3, x))
                        continue;
                    same += brute < n && memcmp(pts[brute], x, sizeof x) == 0;
                    brute++;
                }
        free(pts);
        CHECK(b->ntri > GEOM_FEATURE_GRID_MIN, "star mesh: %d triangles take the binned path", b->ntri);
        CHECK(brute == n && same == n, "star mesh: the binned lattice walk keeps %lld points, the per-point test "
              "%lld (%lld the same, in order)", (long long)n, (long long)brute, (long long)same);
        CHECK(lahar_particle_block_contains(b, 3, between), "star mesh: centre inside");
        CHECK(!lahar_particle_block_contains(b, 3, dent), "star mesh: a point in a dent (0.9 R > 0.75 R) is outside");
        lahar_case_free(&c);
    } else
        CHECK(0, "star case does not load");
}

/* Independent inside tests for the cut-out: disc, rotated rounded rectangle, sphere. */
static void test_cutout(const char *tmp)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/blocks_cut2d.yaml", tmp);
    write_file(path, "dimensions: 2\ntime: {end: 1}\n"
                     "materials: {rock: {density: 2650, model: linear, kn: 1e6, restitution: 0.5, friction: 0.5}}\n"
                     "bodies:\n"
                     "  - {name: disc, shape: disc, motion: fixed, material: rock, radius: 0.0377, position: [0.1013, 0.0991]}\n"
                     "  - {name: crate, shape: box, material: rock, radius: 0.004, size: [0.06, 0.03], position: [0.3, 0.1],\n"
                     "     orientation: {angle_deg: 30}}\n"
                     "sph:\n  dx: 0.002\n  blocks:\n    - {name: water, box: {lo: [0, 0], hi: [0.4, 0.2]}}\n");
    lahar_case c;
    if (lahar_case_load(path, &c) == 0) {
        const double dx = 0.002;
        int64_t total = 200 * 100, inside = 0;
        const double ca = cos(M_PI / 6), sa = sin(M_PI / 6), hx = 0.03 - 0.004, hy = 0.015 - 0.004, R = 0.004;
        for (int i = 0; i < 200; i++)
            for (int j = 0; j < 100; j++) {
                double x = (i + 0.5) * dx, y = (j + 0.5) * dx;
                int in = hypot(x - 0.1013, y - 0.0991) < 0.0377;
                /* rounded rectangle: distance from the core rectangle in the box frame < R */
                double u = ca * (x - 0.3) + sa * (y - 0.1), w = -sa * (x - 0.3) + ca * (y - 0.1);
                double ex = fmax(fabs(u) - hx, 0.0), ey = fmax(fabs(w) - hy, 0.0);
                in = in || hypot(ex, ey) < R;
                inside += in;
            }
        int64_t n = lahar_case_block_lattice(&c, 0, NULL, 0);
        CHECK(n == total - inside, "2D cut-out: %lld particles, expected %lld - %lld inside the disc and the box",
              (long long)n, (long long)total, (long long)inside);
        printf("2D cut-out: %lld of %lld lattice points outside the disc and the turned box\n", (long long)n,
               (long long)total);
        lahar_case_free(&c);
    } else
        CHECK(0, "2D cut-out case does not load");

    snprintf(path, sizeof path, "%s/blocks_cut3d.yaml", tmp);
    write_file(path, "dimensions: 3\ntime: {end: 1}\n"
                     "materials: {rock: {density: 2650, young: 1e8, restitution: 0.5, friction: 0.5}}\n"
                     "bodies:\n"
                     "  - {name: ball, shape: sphere, material: rock, radius: 0.0311, position: [0.05, 0.049, 0.052]}\n"
                     "  - {name: brick, shape: box, motion: fixed, material: rock, radius: 0.002, size: [0.03, 0.02, 0.04],\n"
                     "     position: [0.15, 0.05, 0.05]}\n"
                     "sph:\n  dx: 0.005\n  blocks:\n    - {name: water, box: {lo: [0, 0, 0], hi: [0.2, 0.1, 0.1]}}\n");
    if (lahar_case_load(path, &c) == 0) {
        const double dx = 0.005;
        int64_t total = 40 * 20 * 20, inside = 0;
        const double h[3] = {0.013, 0.008, 0.018}, R = 0.002, ctr[3] = {0.15, 0.05, 0.05};
        for (int i = 0; i < 40; i++)
            for (int j = 0; j < 20; j++)
                for (int k = 0; k < 20; k++) {
                    double x[3] = {(i + 0.5) * dx, (j + 0.5) * dx, (k + 0.5) * dx};
                    int in = sqrt((x[0] - 0.05) * (x[0] - 0.05) + (x[1] - 0.049) * (x[1] - 0.049) +
                                  (x[2] - 0.052) * (x[2] - 0.052)) < 0.0311;
                    double e2 = 0;
                    for (int a = 0; a < 3; a++) {
                        double e = fmax(fabs(x[a] - ctr[a]) - h[a], 0.0);
                        e2 += e * e;
                    }
                    inside += in || sqrt(e2) < R;
                }
        int64_t n = lahar_case_block_lattice(&c, 0, NULL, 0);
        CHECK(n == total - inside, "3D cut-out: %lld particles, expected %lld - %lld inside the sphere and the brick",
              (long long)n, (long long)total, (long long)inside);
        printf("3D cut-out: %lld of %lld lattice points outside the sphere and the brick\n", (long long)n,
               (long long)total);
        lahar_case_free(&c);
    } else
        CHECK(0, "3D cut-out case does not load");
}

/* A fixed body with more than GEOM_FEATURE_GRID_MIN features (a wavy bed, one polyline of 60
 * vertices, 119 features) is cut out through its feature grid: exactly the lattice points an
 * independent distance test (to the nearest of its 59 segments, < radius) puts inside it. */
static void test_cutout_big_body(const char *tmp)
{
    enum { NV = 60 };
    char path[4096], verts[NV * 64] = "";
    double vx[NV], vy[NV];
    for (int i = 0; i < NV; i++) {
        vx[i] = 0.4 * i / (NV - 1);
        vy[i] = 0.05 + 0.02 * sin(9.0 * vx[i]) + 0.01 * cos(37.0 * vx[i]);
        char v[64];
        snprintf(v, sizeof v, "%s[%.17g, %.17g]", i ? ", " : "", vx[i], vy[i]);
        strcat(verts, v);
    }
    snprintf(path, sizeof path, "%s/blocks_cut_bed.yaml", tmp);
    FILE *f = fopen(path, "w");
    if (!f) {
        CHECK(0, "cannot write %s", path);
        return;
    }
    fprintf(f, "dimensions: 2\ntime: {end: 1}\n"
               "materials: {rock: {density: 2650, model: linear, kn: 1e6, restitution: 0.5, friction: 0.5}}\n"
               "bodies:\n  - {name: bed, shape: polyline, motion: fixed, material: rock, radius: 0.0043,\n"
               "     vertices: [%s]}\n"
               "sph:\n  dx: 0.002\n  blocks:\n    - {name: water, box: {lo: [0, 0], hi: [0.4, 0.12]}}\n", verts);
    fclose(f);
    lahar_case c;
    if (lahar_case_load(path, &c) == 0) {
        const lahar_shape *s = &c.bodies[0].shape;
        const double dx = 0.002, R = 0.0043;
        int64_t total = 200 * 60, inside = 0;
        for (int i = 0; i < 200; i++)
            for (int j = 0; j < 60; j++) {
                double x = (i + 0.5) * dx, y = (j + 0.5) * dx, best = INFINITY;
                for (int e = 0; e + 1 < NV; e++) {
                    double ax = vx[e], ay = vy[e], bx = vx[e + 1] - ax, by = vy[e + 1] - ay;
                    double t = fmin(1.0, fmax(0.0, ((x - ax) * bx + (y - ay) * by) / (bx * bx + by * by)));
                    best = fmin(best, hypot(x - ax - t * bx, y - ay - t * by));
                }
                inside += best < R;
            }
        int64_t n = lahar_case_block_lattice(&c, 0, NULL, 0);
        CHECK(s->nv + s->ne + s->nf > GEOM_FEATURE_GRID_MIN, "wavy bed: %d features take the feature grid",
              s->nv + s->ne + s->nf);
        CHECK(n == total - inside, "wavy bed cut-out: %lld particles, expected %lld - %lld within the sweep radius",
              (long long)n, (long long)total, (long long)inside);
        printf("wavy bed cut-out: %lld of %lld lattice points outside the bed's sweep\n", (long long)n, (long long)total);
        lahar_case_free(&c);
    } else
        CHECK(0, "wavy bed case does not load");
}

/* The documented defaults of sph: (cases/dem_drop_3d.yaml) are the loaded values. */
static void test_defaults(const char *tmp)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/blocks_defaults.yaml", tmp);
    write_file(path, "dimensions: 2\ntime: {end: 1}\nsph:\n  dx: 0.01\n  kernel: quintic\n"
                     "  blocks: [{box: {lo: [0, 0.1], hi: [0.3, 0.3]}}, {box: {lo: [0.3, 0.1], hi: [0.4, 0.2]}, velocity: [0.5, 0]}]\n");
    lahar_case c;
    if (lahar_case_load(path, &c) != 0) {
        CHECK(0, "defaults case does not load");
        return;
    }
    const lahar_sph_options *o = &c.sph;
    double c0 = 10.0 * sqrt(2.0 * 9.81 * 0.2); /* fluid height: blocks span y = 0.1 .. 0.3 */
    CHECK(c.sph_density == 1000.0, "density default 1000 (got %g)", c.sph_density);
    CHECK(!strcmp(o->kernel, "quintic") && o->h_over_dx == 1.3, "kernel quintic, h_over_dx 1.3 (got %s, %g)", o->kernel,
          o->h_over_dx);
    CHECK(fabs(o->c0 - c0) < 1e-12 * c0, "c0 default 10 sqrt(2 g H) = %.15g (got %.15g)", c0, o->c0);
    CHECK(o->eos == LAHAR_SPH_EOS_LINEAR && o->gamma == 7.0, "eos linear, gamma 7");
    CHECK(o->mu == 1e-3 && o->alpha == 0.0 && o->delta == 0.1, "viscosity 1e-3, alpha 0, delta 0.1 (got %g %g %g)",
          o->mu, o->alpha, o->delta);
    CHECK(o->cfl == 0.25 && o->cfl_force == 0.25 && o->cfl_visc == 0.125, "cfl 0.25, 0.25, 0.125");
    CHECK(o->body_force[0] == 0 && o->body_force[1] == 0 && !o->periodic[0] && !o->periodic[1], "no body force, "
          "not periodic");
    CHECK(o->shepard_interval == 0 && !o->sps && o->sps_cs == 0.12, "Shepard off, SPS off (cs 0.12)");
    CHECK(o->halo == 0.005 && o->kappa == 3.0, "halo dx/2 = 0.005, kappa = quintic support 3 (got %g, %g)", o->halo,
          o->kappa);
    CHECK(o->wall_viscous == LAHAR_SPH_WALL_HALFSPACE, "wall_viscous halfspace");
    CHECK(c.nblock == 2 && !strcmp(c.blocks[0].name, "block0") && !strcmp(c.blocks[1].name, "block1") &&
              c.blocks[1].v[0] == 0.5 && c.blocks[0].kind == LAHAR_BLOCK_BOX,
          "block names default to block<i>, velocity kept");
    lahar_case_free(&c);
}

/* sph.body_layers (common/io/case.c case_block_layers): layers on the surface of a round body. */
static void layers_check(const char *tmp, const char *name, int dim, const char *yaml, double R, const double ctr[3],
                         double L, int nl, double dx, double fluid_cells, int periodic)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s.yaml", tmp, name);
    write_file(path, yaml);
    lahar_case c;
    if (lahar_case_load(path, &c) != 0) {
        CHECK(0, "%s: case does not load", name);
        return;
    }
    int64_t n = lahar_case_block_lattice(&c, 0, NULL, 0);
    double (*pt)[3] = malloc((size_t)(n > 0 ? n : 1) * sizeof *pt);
    CHECK(pt && lahar_case_block_lattice(&c, 0, pt, n) == n, "%s: the fill writes as many points as it counts", name);
    int64_t count[8] = {0}, off = 0, near = 0;
    double mind = INFINITY, d0 = INFINITY;
    for (int64_t i = 0; pt && i < n; i++) {
        double e2 = 0.0;
        for (int a = 0; a < dim; a++) {
            double e = pt[i][a] - ctr[a];
            if (periodic)
                e -= L * floor(e / L + 0.5);
            e2 += e * e;
        }
        double d = (sqrt(e2) - R) / dx;
        mind = fmin(mind, d);
        if (d >= nl - 1e-6)
            continue;
        near++;
        int l = (int)floor(d);
        if (l < 0 || l >= nl || fabs(d - (l + 0.5)) > 1e-9)
            off++;
        else
            count[l]++;
    }
    /* the closest pair on the first layer */
    for (int64_t i = 0; pt && i < n; i++)
        for (int64_t j = i + 1; j < n; j++) {
            double e2i = 0.0, e2j = 0.0, r2 = 0.0;
            for (int a = 0; a < dim; a++) {
                double ei = pt[i][a] - ctr[a], ej = pt[j][a] - ctr[a], eij = pt[i][a] - pt[j][a];
                if (periodic)
                    ei -= L * floor(ei / L + 0.5), ej -= L * floor(ej / L + 0.5), eij -= L * floor(eij / L + 0.5);
                e2i += ei * ei, e2j += ej * ej, r2 += eij * eij;
            }
            if (sqrt(e2i) - R < dx && sqrt(e2j) - R < dx)
                d0 = fmin(d0, sqrt(r2) / dx);
        }
    CHECK(off == 0, "%s: %lld of %lld points within %d dx of the surface are off the layers", name, (long long)off,
          (long long)near, nl);
    CHECK(mind > 0.5 - 1e-9, "%s: a point %.3g dx from the surface (the first layer is at dx/2)", name, mind);
    for (int l = 0; l + 1 < nl; l++) {
        double r0 = R + l * dx, r1 = r0 + dx;
        double vol = dim == 3 ? 4.0 * M_PI / 3.0 * (pow(r1, 3) - pow(r0, 3)) / pow(dx, 3) : M_PI * (r1 * r1 - r0 * r0) / (dx * dx);
        CHECK(count[l] == llround(vol), "%s: layer %d holds %lld points, expected round(%.3f)", name, l,
              (long long)count[l], vol);
    }
    CHECK(d0 > 0.7, "%s: two points of the first layer %.3g dx apart (< 0.7 dx)", name, d0);
    CHECK(fabs((double)n - fluid_cells) <= 0.5 * nl + 0.5, "%s: %lld points for a fluid of %.2f dx^%d", name,
          (long long)n, fluid_cells, dim);
    printf("%s: %lld points (fluid volume %.2f dx^%d), first layer %lld points, closest pair %.3f dx\n", name,
           (long long)n, fluid_cells, dim, (long long)count[0], d0);
    free(pt);
    lahar_case_free(&c);
}

static void test_body_layers(const char *tmp)
{
    const double a = 0.0620350, dx = 0.0125, L = 0.2, ctr[3] = {0.1, 0.1, 0.1};
    layers_check(tmp, "layers3d", 3,
                 "dimensions: 3\ntime: {end: 1}\n"
                 "materials: {rock: {density: 2650, model: linear, kn: 1e6, restitution: 0.5, friction: 0.5}}\n"
                 "bodies:\n  - {name: sphere, shape: sphere, motion: fixed, material: rock, radius: 0.0620350, "
                 "position: [0.1, 0.1, 0.1]}\n"
                 "sph:\n  dx: 0.0125\n  c0: 0.2\n  body_layers: 3\n  periodic: {x: [0, 0.2], y: [0, 0.2], z: [0, 0.2]}\n"
                 "  blocks:\n    - {name: water, box: {lo: [0, 0, 0], hi: [0.2, 0.2, 0.2]}}\n",
                 a, ctr, L, 3, dx, (L * L * L - 4.0 * M_PI / 3.0 * a * a * a) / (dx * dx * dx), 1);
    const double c2[3] = {0.2013, 0.0991, 0.0}, R2 = 0.0377, dx2 = 0.004;
    layers_check(tmp, "layers2d", 2,
                 "dimensions: 2\ntime: {end: 1}\n"
                 "materials: {rock: {density: 2650, model: linear, kn: 1e6, restitution: 0.5, friction: 0.5}}\n"
                 "bodies:\n  - {name: disc, shape: disc, motion: fixed, material: rock, radius: 0.0377, "
                 "position: [0.2013, 0.0991]}\n"
                 "sph:\n  dx: 0.004\n  c0: 1\n  body_layers: 2\n"
                 "  blocks:\n    - {name: water, box: {lo: [0, 0], hi: [0.4, 0.2]}}\n",
                 R2, c2, 0.0, 2, dx2, (0.4 * 0.2 - M_PI * R2 * R2) / (dx2 * dx2), 0);
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: %s TMP_DIR\n", argv[0]);
        return 2;
    }
    test_defaults(argv[1]);
    test_polygons();
    test_meshes(argv[1]);
    test_cutout(argv[1]);
    test_cutout_big_body(argv[1]);
    test_body_layers(argv[1]);
    printf("%d checks, %d failures\n", checks, failures);
    return failures ? 1 : 0;
}
