/* Geometry of sphero-polyhedra: closest points between vertices, edges and faces of the cores.
 * Everything here works on cores (the polytope before sweeping); callers subtract the sweep radii. */
#include "geometry.h"
#include <float.h>
#include <stddef.h>

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
    vec3 nn = v3_normalize(normal);
    vec3 pp = v3_axpy(-v3_dot(v3_sub(p, poly[0]), nn), nn, p); /* projection on the plane */
    int in = 1;
    for (int i = 0; i < n && in; i++) {
        vec3 a = poly[i], b = poly[(i + 1) % n];
        vec3 ab = v3_sub(b, a);
        /* inclusive with a relative tolerance so that points on an edge count as inside */
        if (v3_dot(v3_cross(ab, v3_sub(pp, a)), nn) < -1e-12 * v3_norm2(ab)) in = 0;
    }
    if (in) {
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
    double best = DBL_MAX;
    vec3 bc = v3_load(x);
    int bf = 0;
    for (int i = 0; i < s->nv; i++) {
        vec3 w = geom_world_vertex(s, x, q, i);
        double d = v3_norm(v3_sub(p, w));
        if (d < best) { best = d; bc = w; bf = 0; }
    }
    for (int i = 0; i < s->ne; i++) {
        vec3 a = geom_world_vertex(s, x, q, s->e[i][0]), b = geom_world_vertex(s, x, q, s->e[i][1]);
        vec3 cc;
        double t;
        double d = geom_point_segment_param(p, a, b, &cc, &t);
        if (d < best && t > 0.0 && t < 1.0) { best = d; bc = cc; bf = 1; }
    }
    vec3 poly[GEOM_FACE_MAX];
    for (int f = 0; f < s->nf; f++) {
        int m = face_world(s, x, q, f, poly);
        vec3 n = q_rotate(q_load(q), geom_face_normal(s, f));
        vec3 cc;
        int in;
        double d = geom_point_polygon(p, poly, m, n, &cc, &in);
        if (in && d < best) { best = d; bc = cc; bf = 2; }
    }
    if (c) *c = bc;
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
