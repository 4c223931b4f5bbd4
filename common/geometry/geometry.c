/* Geometry of sphero-polyhedra: closest points between vertices, edges and faces of the cores.
 * Everything here works on cores (the polytope before sweeping); callers subtract the sweep radii. */
#include "geometry.h"
#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

double geom_point_segment_param(vec3 p, vec3 a, vec3 b, vec3 *c, double *t)
{
    vec3 ab = v3_sub(b, a);
    double l2 = v3_norm2(ab);
    double s = 0.0;
    if (l2 > 0.0) {
        s = v3_dot(v3_sub(p, a), ab) / l2;
        s = s < 0.0 ? 0.0 : (s > 1.0 ? 1.0 : s);
    }
    vec3 q = v3_axpy(s, ab, a);
    if (c) *c = q;
    if (t) *t = s;
    return v3_norm(v3_sub(p, q));
}

double geom_point_segment(vec3 p, vec3 a, vec3 b, vec3 *c)
{
    return geom_point_segment_param(p, a, b, c, NULL);
}

static double clamp01(double x) { return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x); }

/* Closest points of two segments (Ericson, Real-Time Collision Detection, 5.1.9), with the
 * parallel case resolved to the middle of the overlap of the projections so that the answer is
 * well defined (and symmetric) for collinear overlapping edges. */
double geom_segment_segment_param(vec3 p0, vec3 p1, vec3 q0, vec3 q1, double *s_out, double *t_out,
                                  vec3 *cp, vec3 *cq)
{
    vec3 d1 = v3_sub(p1, p0), d2 = v3_sub(q1, q0), r = v3_sub(p0, q0);
    double a = v3_dot(d1, d1), e = v3_dot(d2, d2), f = v3_dot(d2, r);
    double s, t;
    const double tiny = 1e-300;
    if (a <= tiny && e <= tiny) {
        s = t = 0.0;
    } else if (a <= tiny) {
        s = 0.0;
        t = clamp01(f / e);
    } else {
        double c = v3_dot(d1, r);
        if (e <= tiny) {
            t = 0.0;
            s = clamp01(-c / a);
        } else {
            double b = v3_dot(d1, d2);
            double denom = a * e - b * b;
            if (denom > 1e-14 * a * e) {
                s = clamp01((b * f - c * e) / denom);
                t = (b * s + f) / e;
                if (t < 0.0) {
                    t = 0.0;
                    s = clamp01(-c / a);
                } else if (t > 1.0) {
                    t = 1.0;
                    s = clamp01((b - c) / a);
                }
            } else {
                /* parallel: project q0, q1 on p's line and take the middle of the overlap */
                double sq0 = -c / a, sq1 = (b - c) / a;
                double lo = sq0 < sq1 ? sq0 : sq1, hi = sq0 < sq1 ? sq1 : sq0;
                lo = lo > 0.0 ? lo : 0.0;
                hi = hi < 1.0 ? hi : 1.0;
                s = lo <= hi ? 0.5 * (lo + hi) : (sq0 < 0.0 && sq1 < 0.0 ? 0.0 : 1.0);
                vec3 ps = v3_axpy(s, d1, p0);
                t = clamp01(v3_dot(v3_sub(ps, q0), d2) / e);
                if (lo > hi) { /* disjoint projections: refine s from the chosen q end */
                    vec3 qt = v3_axpy(t, d2, q0);
                    s = clamp01(v3_dot(v3_sub(qt, p0), d1) / a);
                }
            }
        }
    }
    vec3 x = v3_axpy(s, d1, p0), y = v3_axpy(t, d2, q0);
    if (cp) *cp = x;
    if (cq) *cq = y;
    if (s_out) *s_out = s;
    if (t_out) *t_out = t;
    return v3_norm(v3_sub(x, y));
}

double geom_segment_segment(vec3 p0, vec3 p1, vec3 q0, vec3 q1, vec3 *cp, vec3 *cq)
{
    return geom_segment_segment_param(p0, p1, q0, q1, NULL, NULL, cp, cq);
}

int geom_point_polygon_inside(vec3 p, const vec3 *poly, int n, vec3 normal, vec3 *proj)
{
    vec3 nn = v3_normalize(normal);
    vec3 pp = v3_axpy(-v3_dot(v3_sub(p, poly[0]), nn), nn, p); /* projection on the plane */
    if (proj) *proj = pp;
    for (int i = 0; i < n; i++) {
        vec3 a = poly[i], b = poly[i + 1 < n ? i + 1 : 0];
        vec3 ab = v3_sub(b, a);
        /* inclusive with a relative tolerance so that points on an edge count as inside */
        if (v3_dot(v3_cross(ab, v3_sub(pp, a)), nn) < -1e-12 * v3_norm2(ab)) return 0;
    }
    return 1;
}

double geom_point_polygon(vec3 p, const vec3 *poly, int n, vec3 normal, vec3 *c, int *inside)
{
    if (inside) *inside = 0;
    if (n <= 0) {
        if (c) *c = p;
        return 0.0;
    }
    if (n == 1) {
        if (c) *c = poly[0];
        return v3_norm(v3_sub(p, poly[0]));
    }
    if (n == 2) return geom_point_segment(p, poly[0], poly[1], c);
    vec3 pp;
    if (geom_point_polygon_inside(p, poly, n, normal, &pp)) {
        if (inside) *inside = 1;
        if (c) *c = pp;
        return v3_norm(v3_sub(p, pp));
    }
    double best = DBL_MAX;
    vec3 bc = poly[0];
    for (int i = 0; i < n; i++) {
        vec3 q;
        double d = geom_point_segment(p, poly[i], poly[(i + 1) % n], &q);
        if (d < best) {
            best = d;
            bc = q;
        }
    }
    if (c) *c = bc;
    return best;
}

vec3 geom_world_vertex(const lahar_shape *s, const double x[3], const double q[4], int i)
{
    return v3_add(v3_load(x), q_rotate(q_load(q), v3_load(s->v[i])));
}

vec3 geom_face_normal(const lahar_shape *s, int f)
{
    vec3 n = v3(0.0, 0.0, 0.0);
    int b = s->face_start[f], m = s->face_start[f + 1] - b;
    for (int k = 0; k < m; k++) {
        vec3 a = v3_load(s->v[s->face_v[b + k]]);
        vec3 c = v3_load(s->v[s->face_v[b + (k + 1) % m]]);
        n.x += (a.y - c.y) * (a.z + c.z);
        n.y += (a.z - c.z) * (a.x + c.x);
        n.z += (a.x - c.x) * (a.y + c.y);
    }
    return v3_normalize(n);
}

int geom_point_in_core(const lahar_shape *s, int convex, int dim, const double x[3], const double q[4], vec3 p)
{
    /* in the shape's frame (one rotation of p; fixed bodies: the same frame bit for bit) */
    const vec3 pb = q_rotate_inv(q_load(q), v3_sub(p, v3_load(x)));
    if (dim == 3) {
        if (s->nf < 4 || !convex)
            return 0;
        for (int f = 0; f < s->nf; f++) {
            vec3 a = v3_load(s->v[s->face_v[s->face_start[f]]]);
            if (v3_dot(v3_sub(pb, a), geom_face_normal(s, f)) >= 0.0)
                return 0;
        }
        return 1;
    }
    if (s->nv < 3 || s->ne != s->nv)
        return 0;
    int in = 0;
    for (int e = 0; e < s->ne; e++) {
        const double *a = s->v[s->e[e][0]], *b = s->v[s->e[e][1]];
        in ^= geom_ray_crosses_edge(a[0], a[1], b[0], b[1], pb.x, pb.y);
    }
    return in;
}

/* World-frame polygon of face f into buf (at most cap vertices; larger faces are truncated, which
 * only the brute-force helpers here could hit: the DEM engine keeps its own world copies). */
enum { GEOM_FACE_MAX = 64 };
static int face_world(const lahar_shape *s, const double x[3], const double q[4], int f, vec3 *buf)
{
    int b = s->face_start[f], m = s->face_start[f + 1] - b;
    if (m > GEOM_FACE_MAX) m = GEOM_FACE_MAX;
    for (int k = 0; k < m; k++) buf[k] = geom_world_vertex(s, x, q, s->face_v[b + k]);
    return m;
}

double geom_point_body_core(const lahar_shape *s, const double x[3], const double q[4], vec3 p,
                            vec3 *c, int *feature)
{
    /* in the shape's frame: one rotation of p instead of one per vertex, edge end and face
     * corner (for a fixed body, x = 0 and q = identity, the frames coincide bit for bit) */
    quat qq = q_load(q);
    vec3 pb = q_rotate_inv(qq, v3_sub(p, v3_load(x)));
    double best = DBL_MAX;
    vec3 bc = v3(0.0, 0.0, 0.0);
    int bf = 0;
    for (int i = 0; i < s->nv; i++) {
        vec3 w = v3_load(s->v[i]);
        double d = v3_norm(v3_sub(pb, w));
        if (d < best) { best = d; bc = w; bf = 0; }
    }
    for (int i = 0; i < s->ne; i++) {
        vec3 cc;
        double t;
        double d = geom_point_segment_param(pb, v3_load(s->v[s->e[i][0]]), v3_load(s->v[s->e[i][1]]), &cc, &t);
        if (d < best && t > 0.0 && t < 1.0) { best = d; bc = cc; bf = 1; }
    }
    vec3 poly[GEOM_FACE_MAX];
    for (int f = 0; f < s->nf; f++) {
        int b = s->face_start[f], m = s->face_start[f + 1] - b;
        if (m > GEOM_FACE_MAX) m = GEOM_FACE_MAX;
        vec3 n = geom_face_normal(s, f);
        /* the distance to a face is at least the distance to its plane: a face whose plane is
         * farther than the best feature so far cannot be closer (most faces of a box) */
        if (m >= 3 && fabs(v3_dot(v3_sub(pb, v3_load(s->v[s->face_v[b]])), n)) > best) continue;
        for (int j = 0; j < m; j++) poly[j] = v3_load(s->v[s->face_v[b + j]]);
        vec3 cc;
        int in;
        double d = geom_point_polygon(pb, poly, m, n, &cc, &in);
        if (in && d < best) { best = d; bc = cc; bf = 2; }
    }
    if (c) *c = v3_add(v3_load(x), q_rotate(qq, bc));
    if (feature) *feature = bf;
    return best;
}

/* 1 when segment [a, b] pierces the face polygon (so the cores intersect). */
static int segment_pierces_face(vec3 a, vec3 b, const vec3 *poly, int m, vec3 n)
{
    if (m < 3) return 0;
    double da = v3_dot(v3_sub(a, poly[0]), n), db = v3_dot(v3_sub(b, poly[0]), n);
    if ((da > 0.0 && db > 0.0) || (da < 0.0 && db < 0.0) || da == db) return 0;
    vec3 x = v3_axpy(da / (da - db), v3_sub(b, a), a);
    int in;
    geom_point_polygon(x, poly, m, n, NULL, &in);
    return in;
}

static double body_vertices_vs_body(const lahar_shape *a, const double xa[3], const double qa[4],
                                    const lahar_shape *b, const double xb[3], const double qb[4])
{
    double best = DBL_MAX;
    for (int i = 0; i < a->nv; i++) {
        double d = geom_point_body_core(b, xb, qb, geom_world_vertex(a, xa, qa, i), NULL, NULL);
        if (d < best) best = d;
    }
    return best;
}

static double edges_vs_faces(const lahar_shape *a, const double xa[3], const double qa[4],
                             const lahar_shape *b, const double xb[3], const double qb[4])
{
    vec3 poly[GEOM_FACE_MAX];
    for (int f = 0; f < b->nf; f++) {
        int m = face_world(b, xb, qb, f, poly);
        vec3 n = q_rotate(q_load(qb), geom_face_normal(b, f));
        for (int i = 0; i < a->ne; i++) {
            vec3 p0 = geom_world_vertex(a, xa, qa, a->e[i][0]), p1 = geom_world_vertex(a, xa, qa, a->e[i][1]);
            if (segment_pierces_face(p0, p1, poly, m, n)) return 0.0;
        }
    }
    return DBL_MAX;
}

double geom_body_core_distance(const lahar_shape *a, const double xa[3], const double qa[4],
                               const lahar_shape *b, const double xb[3], const double qb[4])
{
    double best = body_vertices_vs_body(a, xa, qa, b, xb, qb);
    double d = body_vertices_vs_body(b, xb, qb, a, xa, qa);
    if (d < best) best = d;
    for (int i = 0; i < a->ne; i++) {
        vec3 p0 = geom_world_vertex(a, xa, qa, a->e[i][0]), p1 = geom_world_vertex(a, xa, qa, a->e[i][1]);
        for (int j = 0; j < b->ne; j++) {
            vec3 q0 = geom_world_vertex(b, xb, qb, b->e[j][0]), q1 = geom_world_vertex(b, xb, qb, b->e[j][1]);
            d = geom_segment_segment(p0, p1, q0, q1, NULL, NULL);
            if (d < best) best = d;
        }
    }
    if (edges_vs_faces(a, xa, qa, b, xb, qb) == 0.0 || edges_vs_faces(b, xb, qb, a, xa, qa) == 0.0) best = 0.0;
    return best;
}

/* ---------------------------------------------------------------------------------------------- */
/* Feature grid                                                                                    */

static void feature_box(const lahar_shape *s, int type, int i, double lo[3], double hi[3])
{
    int nvtx = 1, base = 0;
    const int *ids = &i;
    int pair[2];
    if (type == GEOM_FEATURE_EDGE) {
        pair[0] = s->e[i][0];
        pair[1] = s->e[i][1];
        ids = pair;
        nvtx = 2;
    } else if (type == GEOM_FEATURE_FACE) {
        base = s->face_start[i];
        nvtx = s->face_start[i + 1] - base;
        ids = s->face_v + base;
    }
    for (int k = 0; k < 3; k++) {
        lo[k] = DBL_MAX;
        hi[k] = -DBL_MAX;
    }
    for (int j = 0; j < nvtx; j++)
        for (int k = 0; k < 3; k++) {
            double x = s->v[ids[j]][k];
            if (x < lo[k]) lo[k] = x;
            if (x > hi[k]) hi[k] = x;
        }
    for (int k = 0; k < 3; k++) {
        lo[k] -= s->radius;
        hi[k] += s->radius;
    }
}

static int clampi(int x, int lo, int hi) { return x < lo ? lo : (x > hi ? hi : x); }

static void cell_range(const geom_feature_grid *g, const double lo[3], const double hi[3], int c0[3], int c1[3])
{
    for (int k = 0; k < 3; k++) {
        c0[k] = clampi((int)floor((lo[k] - g->lo[k]) / g->h), 0, g->n[k] - 1);
        c1[k] = clampi((int)floor((hi[k] - g->lo[k]) / g->h), 0, g->n[k] - 1);
    }
}

int geom_feature_grid_build(geom_feature_grid *g, const lahar_shape *s)
{
    memset(g, 0, sizeof *g);
    int count[3] = {s->nv, s->ne, s->nf};
    double blo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, bhi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
    double size_sum = 0.0;
    int nfeat = 0;
    for (int t = 0; t < 3; t++)
        for (int i = 0; i < count[t]; i++) {
            double lo[3], hi[3], m = 0.0;
            feature_box(s, t, i, lo, hi);
            for (int k = 0; k < 3; k++) {
                if (lo[k] < blo[k]) blo[k] = lo[k];
                if (hi[k] > bhi[k]) bhi[k] = hi[k];
                if (hi[k] - lo[k] > m) m = hi[k] - lo[k];
            }
            if (t != GEOM_FEATURE_VERTEX) { /* vertices are points; edges/faces set the scale */
                size_sum += m;
                nfeat++;
            }
        }
    /* cell about the mean feature size, so that a feature touches a few cells; grown until the
     * grid has at most ~8 cells per feature */
    double h = nfeat > 0 ? size_sum / nfeat : 2.0 * s->radius;
    if (!(h > 0.0)) h = 1.0;
    long ncell;
    int total = s->nv + s->ne + s->nf;
    for (;;) {
        ncell = 1;
        for (int k = 0; k < 3; k++) {
            g->n[k] = (int)ceil((bhi[k] - blo[k]) / h);
            if (g->n[k] < 1) g->n[k] = 1;
            ncell *= g->n[k];
        }
        if (ncell <= 8L * total + 64) break;
        h *= 1.5;
    }
    g->h = h;
    for (int k = 0; k < 3; k++) g->lo[k] = blo[k];
    for (int t = 0; t < 3; t++) {
        g->nitem[t] = count[t];
        g->start[t] = calloc((size_t)ncell + 1, sizeof(int));
        if (!g->start[t]) return -1;
        for (int pass = 0; pass < 2; pass++) {
            for (int i = 0; i < count[t]; i++) {
                double lo[3], hi[3];
                int c0[3], c1[3];
                feature_box(s, t, i, lo, hi);
                cell_range(g, lo, hi, c0, c1);
                for (int z = c0[2]; z <= c1[2]; z++)
                    for (int y = c0[1]; y <= c1[1]; y++)
                        for (int x = c0[0]; x <= c1[0]; x++) {
                            long c = ((long)z * g->n[1] + y) * g->n[0] + x;
                            if (pass == 0) g->start[t][c + 1]++;
                            else g->items[t][g->start[t][c]++] = i;
                        }
            }
            if (pass == 0) {
                for (long c = 0; c < ncell; c++) g->start[t][c + 1] += g->start[t][c];
                g->items[t] = malloc(sizeof(int) * (size_t)(g->start[t][ncell] > 0 ? g->start[t][ncell] : 1));
                if (!g->items[t]) return -1;
            } else {
                /* the fill advanced each start to the next cell's start: shift back */
                for (long c = ncell; c > 0; c--) g->start[t][c] = g->start[t][c - 1];
                g->start[t][0] = 0;
            }
        }
    }
    return 0;
}

void geom_feature_grid_free(geom_feature_grid *g)
{
    for (int t = 0; t < 3; t++) {
        free(g->start[t]);
        free(g->items[t]);
        g->start[t] = g->items[t] = NULL;
    }
}

int geom_feature_query_init(geom_feature_query *q, int nv, int ne, int nf)
{
    memset(q, 0, sizeof *q);
    int n[3] = {nv, ne, nf};
    for (int t = 0; t < 3; t++) {
        q->cap[t] = n[t] > 0 ? n[t] : 1;
        q->stamp[t] = calloc((size_t)q->cap[t], sizeof(int));
        q->out[t] = malloc(sizeof(int) * (size_t)q->cap[t]);
        if (!q->stamp[t] || !q->out[t]) return -1;
    }
    return 0;
}

void geom_feature_query_free(geom_feature_query *q)
{
    for (int t = 0; t < 3; t++) {
        free(q->stamp[t]);
        free(q->out[t]);
        q->stamp[t] = q->out[t] = NULL;
    }
}

void geom_feature_grid_query(const geom_feature_grid *g, vec3 c, double r, geom_feature_query *q)
{
    double lo[3] = {c.x - r, c.y - r, c.z - r}, hi[3] = {c.x + r, c.y + r, c.z + r};
    q->query++;
    if (q->query == 0x7fffffff) { /* wrap: clear the stamps (once per 2^31 queries) */
        for (int t = 0; t < 3; t++) memset(q->stamp[t], 0, sizeof(int) * (size_t)q->cap[t]);
        q->query = 1;
    }
    for (int t = 0; t < 3; t++) q->nout[t] = 0;
    for (int k = 0; k < 3; k++)
        if (hi[k] < g->lo[k] || lo[k] > g->lo[k] + g->n[k] * g->h) return;
    int c0[3], c1[3];
    cell_range(g, lo, hi, c0, c1);
    for (int z = c0[2]; z <= c1[2]; z++)
        for (int y = c0[1]; y <= c1[1]; y++)
            for (int x = c0[0]; x <= c1[0]; x++) {
                long cell = ((long)z * g->n[1] + y) * g->n[0] + x;
                for (int t = 0; t < 3; t++)
                    for (int k = g->start[t][cell]; k < g->start[t][cell + 1]; k++) {
                        int i = g->items[t][k];
                        if (q->stamp[t][i] != q->query) {
                            q->stamp[t][i] = q->query;
                            q->out[t][q->nout[t]++] = i;
                        }
                    }
            }
}

double geom_point_body_core_near(const geom_feature_grid *g, const lahar_shape *s, const double x[3],
                                 const double q[4], vec3 p, double max_dist, vec3 *c, int *feature)
{
    /* work in the shape's frame, where the grid and the vertices live */
    quat qq = q_load(q);
    vec3 pb = q_rotate_inv(qq, v3_sub(p, v3_load(x)));
    double lo[3] = {pb.x - max_dist, pb.y - max_dist, pb.z - max_dist};
    double hi[3] = {pb.x + max_dist, pb.y + max_dist, pb.z + max_dist};
    for (int k = 0; k < 3; k++)
        if (hi[k] < g->lo[k] || lo[k] > g->lo[k] + g->n[k] * g->h) return DBL_MAX;
    int c0[3], c1[3];
    cell_range(g, lo, hi, c0, c1);
    double best = DBL_MAX;
    vec3 bc = pb;
    int bf = -1;
    vec3 poly[GEOM_FACE_MAX];
    /* a feature may be listed in several cells: evaluating it twice does not change the minimum */
    for (int z = c0[2]; z <= c1[2]; z++)
        for (int y = c0[1]; y <= c1[1]; y++)
            for (int xx = c0[0]; xx <= c1[0]; xx++) {
                long cell = ((long)z * g->n[1] + y) * g->n[0] + xx;
                for (int k = g->start[GEOM_FEATURE_VERTEX][cell]; k < g->start[GEOM_FEATURE_VERTEX][cell + 1]; k++) {
                    vec3 v = v3_load(s->v[g->items[GEOM_FEATURE_VERTEX][k]]);
                    double d = v3_norm(v3_sub(pb, v));
                    if (d < best) { best = d; bc = v; bf = 0; }
                }
                for (int k = g->start[GEOM_FEATURE_EDGE][cell]; k < g->start[GEOM_FEATURE_EDGE][cell + 1]; k++) {
                    int i = g->items[GEOM_FEATURE_EDGE][k];
                    vec3 cc;
                    double t;
                    double d = geom_point_segment_param(pb, v3_load(s->v[s->e[i][0]]), v3_load(s->v[s->e[i][1]]), &cc, &t);
                    if (d < best && t > 0.0 && t < 1.0) { best = d; bc = cc; bf = 1; }
                }
                for (int k = g->start[GEOM_FEATURE_FACE][cell]; k < g->start[GEOM_FEATURE_FACE][cell + 1]; k++) {
                    int f = g->items[GEOM_FEATURE_FACE][k];
                    int b = s->face_start[f], m = s->face_start[f + 1] - b;
                    if (m > GEOM_FACE_MAX) m = GEOM_FACE_MAX;
                    for (int j = 0; j < m; j++) poly[j] = v3_load(s->v[s->face_v[b + j]]);
                    vec3 cc;
                    int in;
                    double d = geom_point_polygon(pb, poly, m, geom_face_normal(s, f), &cc, &in);
                    if (in && d < best) { best = d; bc = cc; bf = 2; }
                }
            }
    if (bf < 0 || best > max_dist) return DBL_MAX;
    if (c) *c = v3_add(v3_load(x), q_rotate(qq, bc));
    if (feature) *feature = bf;
    return best;
}

int geom_body_grids_build(geom_body_grids *g, const lahar_body *bodies, int nbody)
{
    const size_t nb = (size_t)(nbody > 0 ? nbody : 1);
    g->nbody = nbody;
    g->grid = calloc(nb, sizeof *g->grid);
    g->has = calloc(nb, sizeof *g->has);
    if (!g->grid || !g->has) {
        geom_body_grids_free(g);
        return -1;
    }
    for (int b = 0; b < nbody; b++) {
        const lahar_shape *s = &bodies[b].shape;
        if (s->nv + s->ne + s->nf <= GEOM_FEATURE_GRID_MIN)
            continue;
        g->has[b] = 1; /* freed below even when half built */
        if (geom_feature_grid_build(&g->grid[b], s) != 0) {
            geom_body_grids_free(g);
            return -1;
        }
    }
    return 0;
}

void geom_body_grids_free(geom_body_grids *g)
{
    for (int b = 0; g->has && b < g->nbody; b++)
        if (g->has[b])
            geom_feature_grid_free(&g->grid[b]);
    free(g->grid);
    free(g->has);
    memset(g, 0, sizeof *g);
}

double geom_body_grids_core(const geom_body_grids *g, int b, const lahar_shape *s, const double x[3],
                            const double q[4], vec3 p, double reach, vec3 *c, int *feature)
{
    if (g && g->has && g->has[b])
        return geom_point_body_core_near(&g->grid[b], s, x, q, p, reach, c, feature);
    return geom_point_body_core(s, x, q, p, c, feature);
}
