/* Geometry unit tests: closest points of segments (crossing, parallel, degenerate, clamped),
 * point-polygon, and body core distances against brute-force sampling of the core surfaces. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include "dem_test_util.h"
#include "geometry.h"
#include "shape_build.h"

static void check_vec(const char *what, vec3 a, vec3 b, double tol)
{
    double d = v3_norm(v3_sub(a, b));
    dem_test_check(d <= tol, "%s = (%g %g %g), expected (%g %g %g), |diff| %.2e", what, a.x, a.y, a.z, b.x, b.y, b.z, d);
}

static double urand(unsigned *s)
{
    *s = *s * 1664525u + 1013904223u;
    return (*s >> 8) / 16777216.0;
}

/* points on the surface of the core of a placed shape: every face sampled on a fine grid */
static int sample_core(const lahar_shape *s, const double x[3], const double q[4], int n, vec3 *out)
{
    int k = 0;
    for (int f = 0; f < s->nf; f++) {
        int b = s->face_start[f];
        /* quad faces of a box: bilinear grid over the corners 0,1,2,3 */
        vec3 c0 = geom_world_vertex(s, x, q, s->face_v[b]), c1 = geom_world_vertex(s, x, q, s->face_v[b + 1]);
        vec3 c2 = geom_world_vertex(s, x, q, s->face_v[b + 2]), c3 = geom_world_vertex(s, x, q, s->face_v[b + 3]);
        for (int i = 0; i <= n; i++)
            for (int j = 0; j <= n; j++) {
                double u = (double)i / n, v = (double)j / n;
                vec3 p = v3_add(v3_add(v3_scale(c0, (1 - u) * (1 - v)), v3_scale(c1, u * (1 - v))),
                                v3_add(v3_scale(c2, u * v), v3_scale(c3, (1 - u) * v)));
                out[k++] = p;
            }
    }
    return k;
}

int main(void)
{
    vec3 cp, cq;
    double s, t, d;
    /* crossing skew segments */
    d = geom_segment_segment_param(v3(-1, 0, 0), v3(1, 0, 0), v3(0, -1, 1), v3(0, 1, 1), &s, &t, &cp, &cq);
    dem_test_abs("crossing: distance", d, 1.0, 1e-14);
    check_vec("crossing: cp", cp, v3(0, 0, 0), 1e-14);
    check_vec("crossing: cq", cq, v3(0, 0, 1), 1e-14);
    dem_test_check(fabs(s - 0.5) < 1e-14 && fabs(t - 0.5) < 1e-14, "crossing: s = %g, t = %g (0.5, 0.5)", s, t);
    /* parallel, overlapping projections: middle of the overlap */
    d = geom_segment_segment_param(v3(0, 0, 0), v3(2, 0, 0), v3(1, 1, 0), v3(3, 1, 0), &s, &t, &cp, &cq);
    dem_test_abs("parallel overlap: distance", d, 1.0, 1e-14);
    check_vec("parallel overlap: cp (middle of overlap)", cp, v3(1.5, 0, 0), 1e-14);
    check_vec("parallel overlap: cq", cq, v3(1.5, 1, 0), 1e-14);
    /* parallel, disjoint */
    d = geom_segment_segment(v3(0, 0, 0), v3(1, 0, 0), v3(2, 1, 0), v3(3, 1, 0), &cp, &cq);
    dem_test_abs("parallel disjoint: distance", d, sqrt(2.0), 1e-14);
    check_vec("parallel disjoint: cp", cp, v3(1, 0, 0), 1e-14);
    check_vec("parallel disjoint: cq", cq, v3(2, 1, 0), 1e-14);
    /* anti-parallel collinear overlap */
    d = geom_segment_segment(v3(0, 0, 0), v3(2, 0, 0), v3(3, 0, 0), v3(1, 0, 0), &cp, &cq);
    dem_test_abs("collinear overlap: distance", d, 0.0, 1e-14);
    /* degenerate: a point against a segment, and two points */
    d = geom_segment_segment_param(v3(0, 0, 0), v3(0, 0, 0), v3(-1, 1, 0), v3(1, 1, 0), &s, &t, &cp, &cq);
    dem_test_abs("degenerate point-segment: distance", d, 1.0, 1e-14);
    check_vec("degenerate point-segment: cq", cq, v3(0, 1, 0), 1e-14);
    d = geom_segment_segment(v3(1, 2, 3), v3(1, 2, 3), v3(1, 2, 5), v3(1, 2, 5), &cp, &cq);
    dem_test_abs("degenerate point-point: distance", d, 2.0, 1e-14);
    /* clamped end */
    d = geom_segment_segment_param(v3(0, 0, 0), v3(1, 0, 0), v3(2, -1, 1), v3(2, 1, 1), &s, &t, &cp, &cq);
    dem_test_abs("clamped: distance", d, sqrt(2.0), 1e-14);
    dem_test_check(s == 1.0 && fabs(t - 0.5) < 1e-14, "clamped: s = %g (1), t = %g (0.5)", s, t);
    /* random segments against brute-force sampling */
    unsigned seed = 12345u;
    double worst = 0.0;
    int bad = 0;
    for (int it = 0; it < 200; it++) {
        vec3 p[4];
        for (int k = 0; k < 4; k++) p[k] = v3(urand(&seed), urand(&seed), urand(&seed));
        if (it % 4 == 0) p[3] = v3_add(p[2], v3_scale(v3_sub(p[1], p[0]), 0.7)); /* parallel */
        d = geom_segment_segment(p[0], p[1], p[2], p[3], &cp, &cq);
        double best = DBL_MAX;
        for (int i = 0; i <= 400; i++)
            for (int j = 0; j <= 400; j++) {
                vec3 a = v3_axpy(i / 400.0, v3_sub(p[1], p[0]), p[0]), b = v3_axpy(j / 400.0, v3_sub(p[3], p[2]), p[2]);
                double dd = v3_norm(v3_sub(a, b));
                if (dd < best) best = dd;
            }
        if (d > best + 1e-12 || best - d > 5e-3) bad++;
        if (best - d > worst) worst = best - d;
        if (fabs(v3_norm(v3_sub(cp, cq)) - d) > 1e-12) bad++;
    }
    dem_test_check(bad == 0, "200 random segment pairs vs 401x401 sampling: %d bad, sampling excess <= %.2e", bad, worst);

    /* point-polygon: unit square in z = 0 */
    vec3 sq[4] = {v3(0, 0, 0), v3(1, 0, 0), v3(1, 1, 0), v3(0, 1, 0)};
    int in;
    d = geom_point_polygon(v3(0.3, 0.4, 2.0), sq, 4, v3(0, 0, 1), &cp, &in);
    dem_test_check(in == 1 && fabs(d - 2.0) < 1e-14, "point above square: inside %d, distance %g (2)", in, d);
    check_vec("point above square: closest", cp, v3(0.3, 0.4, 0), 1e-14);
    d = geom_point_polygon(v3(1.5, 0.5, 0.0), sq, 4, v3(0, 0, 1), &cp, &in);
    dem_test_check(in == 0 && fabs(d - 0.5) < 1e-14, "point beside an edge: inside %d, distance %g (0.5)", in, d);
    d = geom_point_polygon(v3(2.0, 2.0, 1.0), sq, 4, v3(0, 0, 1), &cp, &in);
    dem_test_check(in == 0 && fabs(d - sqrt(3.0)) < 1e-14, "point off a corner: distance %g (sqrt 3)", d);
    check_vec("point off a corner: closest", cp, v3(1, 1, 0), 1e-14);
    d = geom_point_polygon(v3(1.0, 0.5, -1.0), sq, 4, v3(0, 0, 1), &cp, &in);
    dem_test_check(in == 1, "point below an edge counts as inside (boundary inclusive): %d", in);

    /* crossed edges of two boxes: A's top edge along x, B's bottom edge along y, 0.05 apart */
    lahar_shape A = {0}, B = {0};
    const double half[3] = {0.5, 0.5, 0.5};
    lahar_shape_make_box(&A, half, 0.01);
    lahar_shape_make_box(&B, half, 0.01);
    double h = 0.5 * sqrt(2.0);
    quat qa = q_axis_angle(v3(1, 0, 0), M_PI / 4), qb = q_axis_angle(v3(0, 1, 0), M_PI / 4);
    double xa[3] = {0, 0, 0}, xb[3] = {0.1, -0.05, 2 * h + 0.05}, qa4[4], qb4[4];
    q_store(qa, qa4);
    q_store(qb, qb4);
    d = geom_body_core_distance(&A, xa, qa4, &B, xb, qb4);
    dem_test_abs("crossed box edges: core distance", d, 0.05, 1e-12);

    /* random box placements: core distance against sampling of the core faces */
    static vec3 sa[6 * 41 * 41], sb[6 * 41 * 41];
    int nbad = 0;
    double maxerr = 0.0;
    for (int it = 0; it < 6; it++) {
        quat r1 = q_normalize((quat){urand(&seed) - 0.5, urand(&seed) - 0.5, urand(&seed) - 0.5, urand(&seed) - 0.5});
        quat r2 = q_normalize((quat){urand(&seed) - 0.5, urand(&seed) - 0.5, urand(&seed) - 0.5, urand(&seed) - 0.5});
        double q1[4], q2[4], x1[3] = {0, 0, 0};
        double x2[3] = {1.2 + urand(&seed), urand(&seed) - 0.5, urand(&seed) - 0.5};
        q_store(r1, q1);
        q_store(r2, q2);
        d = geom_body_core_distance(&A, x1, q1, &B, x2, q2);
        int na = sample_core(&A, x1, q1, 40, sa), nbb = sample_core(&B, x2, q2, 40, sb);
        double best = DBL_MAX;
        for (int i = 0; i < na; i++)
            for (int j = 0; j < nbb; j++) {
                double dd = v3_norm2(v3_sub(sa[i], sb[j]));
                if (dd < best) best = dd;
            }
        best = sqrt(best);
        if (d > best + 1e-12 || best - d > 0.03) nbad++;
        if (fabs(best - d) > maxerr) maxerr = fabs(best - d);
        /* point-body: the closest core point of B to A's centre, against the samples */
        vec3 c;
        int feat;
        double dp = geom_point_body_core(&B, x2, q2, v3(0, 0, 0), &c, &feat);
        double bp = DBL_MAX;
        for (int j = 0; j < nbb; j++) bp = fmin(bp, v3_norm(sb[j]));
        if (dp > bp + 1e-12 || bp - dp > 0.03 || fabs(v3_norm(c) - dp) > 1e-12) nbad++;
    }
    dem_test_check(nbad == 0, "6 random box pairs: core and point distances vs 41x41-per-face sampling, %d bad, "
                              "max |sampled - exact| %.3g (<= 0.03 sampling resolution)", nbad, maxerr);
    /* feature grid: closest core point near a bumpy 30 x 30 x 2 triangle terrain and near a
     * rotated box, against the brute-force geom_point_body_core */
    {
        enum { N = 30 };
        static double tv[(N + 1) * (N + 1)][3];
        static int fs[2 * N * N + 1], fv[6 * N * N];
        for (int j = 0; j <= N; j++)
            for (int i = 0; i <= N; i++) {
                double *v = tv[j * (N + 1) + i];
                v[0] = 3.0 * i / N;
                v[1] = 3.0 * j / N;
                v[2] = 0.2 * sin(2.0 * v[0]) * cos(1.5 * v[1]);
            }
        int nf = 0;
        for (int j = 0; j < N; j++)
            for (int i = 0; i < N; i++) {
                int a = j * (N + 1) + i, b = a + 1, cc = a + N + 2, dd = a + N + 1;
                int tri[2][3] = {{a, b, cc}, {a, cc, dd}};
                for (int t2 = 0; t2 < 2; t2++, nf++) {
                    fs[nf] = 3 * nf;
                    for (int k = 0; k < 3; k++) fv[3 * nf + k] = tri[t2][k];
                }
            }
        fs[nf] = 3 * nf;
        lahar_shape T = {0};
        char err[256];
        int rc = lahar_shape_make_polyhedron(&T, (const double(*)[3])tv, (N + 1) * (N + 1), fs, fv, nf, 0.01, err,
                                             sizeof err);
        dem_test_check(rc == 0, "terrain mesh built (%s)", rc ? err : "1800 triangles");
        const lahar_shape *shapes[2] = {&T, &B};
        double xs[2][3] = {{0, 0, 0}, {0.3, -0.2, 0.5}}, qs[2][4] = {{1, 0, 0, 0}, {0, 0, 0, 0}};
        q_store(q_normalize((quat){0.9, 0.3, -0.2, 0.4}), qs[1]);
        int bad = 0, near = 0, far = 0;
        for (int sh = 0; sh < 2; sh++) {
            geom_feature_grid g;
            dem_test_check(geom_feature_grid_build(&g, shapes[sh]) == 0, "feature grid built");
            for (int it = 0; it < 2000; it++) {
                vec3 p = sh == 0 ? v3(3.0 * urand(&seed), 3.0 * urand(&seed), 0.6 * urand(&seed) - 0.3)
                                 : v3(0.3 + 2.4 * urand(&seed) - 1.2, -0.2 + 2.4 * urand(&seed) - 1.2, 0.5 + 2.4 * urand(&seed) - 1.2);
                vec3 cb, cn;
                int fb, fn;
                double db = geom_point_body_core(shapes[sh], xs[sh], qs[sh], p, &cb, &fb);
                double dn = geom_point_body_core_near(&g, shapes[sh], xs[sh], qs[sh], p, 0.15, &cn, &fn);
                if (db <= 0.15) {
                    near++;
                    if (fabs(dn - db) > 1e-12 || v3_norm(v3_sub(cn, cb)) > 1e-9 || fn != fb) bad++;
                } else {
                    far++;
                    if (dn != DBL_MAX) bad++;
                }
            }
            geom_feature_grid_free(&g);
        }
        dem_test_check(bad == 0 && near > 200 && far > 200,
                       "grid point queries (terrain + rotated box): %d within 0.15 m equal brute force, %d beyond "
                       "return none, %d bad", near, far, bad);
        /* the grids of a set of bodies: the terrain gets one, the 26-feature box none; the one query
         * goes through the terrain's grid (nothing beyond the reach) and scans the box at any
         * distance */
        lahar_body bodies[2] = {{.shape = T}, {.shape = B}};
        geom_body_grids gs;
        dem_test_check(geom_body_grids_build(&gs, bodies, 2) == 0 && gs.has[0] == 1 && gs.has[1] == 0,
                       "body grids: the 1800-triangle terrain has a grid, the box none");
        int bad_set = 0, far_box = 0;
        for (int it = 0; it < 2000; it++) {
            const int sh = it % 2;
            vec3 p = sh == 0 ? v3(3.0 * urand(&seed), 3.0 * urand(&seed), 0.6 * urand(&seed) - 0.3)
                             : v3(0.3 + 4.0 * urand(&seed) - 2.0, -0.2 + 4.0 * urand(&seed) - 2.0, 0.5 + 4.0 * urand(&seed) - 2.0);
            vec3 cb, cs;
            double db = geom_point_body_core(shapes[sh], xs[sh], qs[sh], p, &cb, NULL);
            double ds = geom_body_grids_core(&gs, sh, shapes[sh], xs[sh], qs[sh], p, 0.15, &cs, NULL);
            far_box += sh == 1 && db > 0.15;
            if (sh == 1 || db <= 0.15) {
                if (ds != db || v3_norm(v3_sub(cs, cb)) > 1e-9) bad_set++;
            } else if (ds != DBL_MAX)
                bad_set++;
        }
        dem_test_check(bad_set == 0 && far_box > 200,
                       "body grids query: terrain through its grid, box by full scan (%d beyond the reach), %d bad",
                       far_box, bad_set);
        geom_body_grids_free(&gs);
        dem_test_check(gs.grid == NULL && gs.has == NULL, "body grids freed");
        lahar_shape_free(&T);
    }
    lahar_shape_free(&A);
    lahar_shape_free(&B);
    return dem_test_failures ? 1 : 0;
}
