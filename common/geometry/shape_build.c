/* Building sphero-polyhedra and their mass properties (see shape_build.h for the conventions). */
#include "errmsg.h"
#include "shape_build.h"

#include <errno.h>
#include <float.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "geometry.h"
#include "vec.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

void lahar_shape_free(lahar_shape *s)
{
    if (!s)
        return;
    free(s->v);
    free(s->e);
    free(s->face_start);
    free(s->face_v);
    memset(s, 0, sizeof *s);
}

/* Allocate the arrays of a shape (face_start always has nf + 1 entries). */
static int shape_alloc(lahar_shape *s, int nv, int ne, int nf, int nfv, double radius)
{
    memset(s, 0, sizeof *s);
    s->nv = nv;
    s->ne = ne;
    s->nf = nf;
    s->radius = radius;
    s->v = calloc((size_t)(nv > 0 ? nv : 1), sizeof *s->v);
    s->e = calloc((size_t)(ne > 0 ? ne : 1), sizeof *s->e);
    s->face_start = calloc((size_t)nf + 1, sizeof *s->face_start);
    s->face_v = calloc((size_t)(nfv > 0 ? nfv : 1), sizeof *s->face_v);
    if (!s->v || !s->e || !s->face_start || !s->face_v) {
        lahar_shape_free(s);
        return -1;
    }
    return 0;
}

int lahar_shape_copy(lahar_shape *dst, const lahar_shape *src)
{
    int nfv = src->face_start ? src->face_start[src->nf] : 0;
    if (shape_alloc(dst, src->nv, src->ne, src->nf, nfv, src->radius) != 0)
        return -1;
    if (src->nv)
        memcpy(dst->v, src->v, (size_t)src->nv * sizeof *src->v);
    if (src->ne)
        memcpy(dst->e, src->e, (size_t)src->ne * sizeof *src->e);
    if (src->face_start)
        memcpy(dst->face_start, src->face_start, ((size_t)src->nf + 1) * sizeof *src->face_start);
    if (nfv)
        memcpy(dst->face_v, src->face_v, (size_t)nfv * sizeof *src->face_v);
    return 0;
}

static vec3 shape_vertex(const lahar_shape *s, int i) { return v3_load(s->v[i]); }

/* Bounding-box diagonal: the length scale of geometric tolerances. */
static double points_scale(const double (*p)[3], int n)
{
    double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    for (int i = 0; i < n; i++)
        for (int k = 0; k < 3; k++) {
            if (i == 0 || p[i][k] < lo[k])
                lo[k] = p[i][k];
            if (i == 0 || p[i][k] > hi[k])
                hi[k] = p[i][k];
        }
    double d = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                    (hi[2] - lo[2]) * (hi[2] - lo[2]));
    return d > 0.0 ? d : 1.0;
}

/* --- edges from faces ------------------------------------------------------------------------ */

static int edge_cmp(const void *a, const void *b)
{
    const int *x = a, *y = b;
    if (x[0] != y[0])
        return x[0] < y[0] ? -1 : 1;
    return (x[1] > y[1]) - (x[1] < y[1]);
}

/* Unique undirected edges (i < j, sorted) of all faces; replaces s->e. */
static int shape_build_edges(lahar_shape *s)
{
    int nfv = s->face_start[s->nf];
    int (*tmp)[2] = malloc((size_t)(nfv > 0 ? nfv : 1) * sizeof *tmp);
    if (!tmp)
        return -1;
    int n = 0;
    for (int f = 0; f < s->nf; f++) {
        int a0 = s->face_start[f], cnt = s->face_start[f + 1] - a0;
        for (int k = 0; k < cnt; k++) {
            int i = s->face_v[a0 + k], j = s->face_v[a0 + (k + 1) % cnt];
            tmp[n][0] = i < j ? i : j;
            tmp[n][1] = i < j ? j : i;
            n++;
        }
    }
    qsort(tmp, (size_t)n, sizeof *tmp, edge_cmp);
    int m = 0;
    for (int k = 0; k < n; k++)
        if (m == 0 || edge_cmp(tmp[k], tmp[m - 1]) != 0) {
            tmp[m][0] = tmp[k][0];
            tmp[m][1] = tmp[k][1];
            m++;
        }
    free(s->e);
    s->e = tmp;
    s->ne = m;
    return 0;
}

/* Newell normal (not normalised: its length is twice the face area). */
static vec3 face_newell(const lahar_shape *s, int f)
{
    int a0 = s->face_start[f], cnt = s->face_start[f + 1] - a0;
    vec3 n = v3(0, 0, 0);
    for (int k = 0; k < cnt; k++) {
        vec3 p = shape_vertex(s, s->face_v[a0 + k]), q = shape_vertex(s, s->face_v[a0 + (k + 1) % cnt]);
        n.x += (p.y - q.y) * (p.z + q.z);
        n.y += (p.z - q.z) * (p.x + q.x);
        n.z += (p.x - q.x) * (p.y + q.y);
    }
    return n;
}

/* --- primitives -------------------------------------------------------------------------------- */

int lahar_shape_make_sphere(lahar_shape *s, double radius)
{
    if (shape_alloc(s, 1, 0, 0, 0, radius) != 0)
        return -1;
    return 0;
}

int lahar_shape_make_segment(lahar_shape *s, const double a[3], const double b[3], double radius)
{
    if (shape_alloc(s, 2, 1, 0, 0, radius) != 0)
        return -1;
    memcpy(s->v[0], a, sizeof s->v[0]);
    memcpy(s->v[1], b, sizeof s->v[1]);
    s->e[0][0] = 0;
    s->e[0][1] = 1;
    return 0;
}

int lahar_shape_make_box(lahar_shape *s, const double half[3], double radius)
{
    if (shape_alloc(s, 8, 12, 6, 24, radius) != 0)
        return -1;
    /* vertex i: bit k set -> +half[k] */
    for (int i = 0; i < 8; i++)
        for (int k = 0; k < 3; k++)
            s->v[i][k] = (i >> k & 1) ? half[k] : -half[k];
    static const int loop[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    int f = 0;
    for (int k = 0; k < 3; k++)
        for (int side = 0; side < 2; side++, f++) {
            int i = (k + 1) % 3, j = (k + 2) % 3;
            s->face_start[f] = 4 * f;
            for (int c = 0; c < 4; c++)
                s->face_v[4 * f + c] = (side << k) | (loop[c][0] << i) | (loop[c][1] << j);
            s->face_start[f + 1] = 4 * f + 4;
            /* loop is counter-clockwise about +axis k (i, j, k right-handed); reverse on the - side */
            if (!side) {
                int t = s->face_v[4 * f + 1];
                s->face_v[4 * f + 1] = s->face_v[4 * f + 3];
                s->face_v[4 * f + 3] = t;
            }
        }
    if (shape_build_edges(s) != 0) {
        lahar_shape_free(s);
        return -1;
    }
    return 0;
}

/* A closed 2D ring p[0..n-1] in the x-y plane, counter-clockwise: edges (i, i+1). */
static int shape_make_ring2d(lahar_shape *s, const double (*p)[2], int n, int closed, double radius)
{
    int ne = closed ? n : n - 1;
    if (shape_alloc(s, n, ne, 0, 0, radius) != 0)
        return -1;
    for (int i = 0; i < n; i++) {
        s->v[i][0] = p[i][0];
        s->v[i][1] = p[i][1];
        s->v[i][2] = 0.0;
    }
    for (int i = 0; i < ne; i++) {
        s->e[i][0] = i;
        s->e[i][1] = (i + 1) % n;
    }
    return 0;
}

int lahar_shape_make_box2d(lahar_shape *s, const double half[2], double radius)
{
    double p[4][2] = {{-half[0], -half[1]}, {half[0], -half[1]}, {half[0], half[1]}, {-half[0], half[1]}};
    return shape_make_ring2d(s, (const double(*)[2])p, 4, 1, radius);
}

int lahar_shape_make_plane(lahar_shape *s, const double c[3], const double n[3], const double size[2],
                           double radius)
{
    vec3 nn = v3_normalize(v3_load(n)), ex = v3(1, 0, 0);
    vec3 u = v3_sub(ex, v3_scale(nn, v3_dot(ex, nn)));
    if (v3_norm(u) < 1e-6) {
        vec3 ey = v3(0, 1, 0);
        u = v3_sub(ey, v3_scale(nn, v3_dot(ey, nn)));
    }
    u = v3_normalize(u);
    vec3 w = v3_cross(nn, u), cc = v3_load(c);
    if (shape_alloc(s, 4, 4, 1, 4, radius) != 0)
        return -1;
    static const double sg[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    for (int i = 0; i < 4; i++) {
        vec3 p = v3_add(cc, v3_add(v3_scale(u, 0.5 * size[0] * sg[i][0]), v3_scale(w, 0.5 * size[1] * sg[i][1])));
        v3_store(p, s->v[i]);
        s->face_v[i] = i;
    }
    s->face_start[0] = 0;
    s->face_start[1] = 4;
    if (shape_build_edges(s) != 0) {
        lahar_shape_free(s);
        return -1;
    }
    return 0;
}

int lahar_shape_make_polyline(lahar_shape *s, const double (*p)[3], int n, int closed, double radius,
                              char *err, size_t errlen)
{
    memset(s, 0, sizeof *s);
    if (n < 2) {
        lahar_errf(err, errlen, "a polyline needs at least 2 points (got %d)", n);
        return -1;
    }
    double scale = points_scale(p, n);
    for (int i = 0; i + 1 < n + (closed ? 1 : 0); i++) {
        int j = (i + 1) % n;
        if (hypot(p[j][0] - p[i][0], p[j][1] - p[i][1]) <= 1e-12 * scale) {
            lahar_errf(err, errlen, "points %d and %d coincide (zero-length segment)", i, j);
            return -1;
        }
    }
    double (*q)[2] = malloc((size_t)n * sizeof *q);
    if (!q)
        return -1;
    for (int i = 0; i < n; i++) {
        q[i][0] = p[i][0];
        q[i][1] = p[i][1];
    }
    int rc = shape_make_ring2d(s, (const double(*)[2])q, n, closed, radius);
    free(q);
    return rc;
}

/* --- 2D convex hull (Andrew's monotone chain) ---------------------------------------------------- */

typedef struct {
    double x, y;
    int id;
} pt2;

static int pt2_cmp(const void *a, const void *b)
{
    const pt2 *p = a, *q = b;
    if (p->x != q->x)
        return p->x < q->x ? -1 : 1;
    if (p->y != q->y)
        return p->y < q->y ? -1 : 1;
    return (p->id > q->id) - (p->id < q->id);
}

static double cross2(pt2 o, pt2 a, pt2 b) { return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x); }

/* Counter-clockwise hull of pts[0..n-1] (sorted in place) into out (capacity n + 1), dropping
 * points within tol (area-like: |cross| <= tol) of a hull edge. Returns the hull size. */
static int hull2d(pt2 *pts, int n, double tol, pt2 *out)
{
    qsort(pts, (size_t)n, sizeof *pts, pt2_cmp);
    int k = 0;
    for (int i = 0; i < n; i++) {
        while (k >= 2 && cross2(out[k - 2], out[k - 1], pts[i]) <= tol)
            k--;
        out[k++] = pts[i];
    }
    for (int i = n - 2, t = k + 1; i >= 0; i--) {
        while (k >= t && cross2(out[k - 2], out[k - 1], pts[i]) <= tol)
            k--;
        out[k++] = pts[i];
    }
    return k > 1 ? k - 1 : k;
}

int lahar_shape_make_polygon_hull(lahar_shape *s, const double (*p)[3], int n, double radius, char *err,
                                  size_t errlen)
{
    memset(s, 0, sizeof *s);
    if (n < 3) {
        lahar_errf(err, errlen, "a polygon needs at least 3 points (got %d)", n);
        return -1;
    }
    pt2 *pts = malloc((size_t)n * sizeof *pts), *h = malloc(((size_t)n + 1) * sizeof *h);
    double (*q)[2] = malloc((size_t)n * sizeof *q);
    int rc = -1;
    if (!pts || !h || !q)
        goto done;
    for (int i = 0; i < n; i++) {
        pts[i].x = p[i][0];
        pts[i].y = p[i][1];
        pts[i].id = i;
    }
    double L = points_scale(p, n);
    int m = hull2d(pts, n, 1e-12 * L * L, h);
    if (m < 3) {
        lahar_errf(err, errlen, "the points are collinear (degenerate polygon)");
        goto done;
    }
    for (int i = 0; i < m; i++) {
        q[i][0] = h[i].x;
        q[i][1] = h[i].y;
    }
    rc = shape_make_ring2d(s, (const double(*)[2])q, m, 1, radius);
done:
    free(pts);
    free(h);
    free(q);
    return rc;
}

/* --- 3D convex hull ------------------------------------------------------------------------------- */

/* The faces found so far by lahar_shape_make_hull: fan lists (face f is fv[fstart[f] ..
 * fstart[f + 1])) and, per face, which points lie on its plane (member[f * n + i]). */
typedef struct {
    int *fstart, *fv;
    int nf, nfv, cap_f, cap_fv;
    unsigned char *member;
} hull_faces;

static void hull_faces_free(hull_faces *hf)
{
    free(hf->fstart);
    free(hf->fv);
    free(hf->member);
}

/* The plane through points i, j, k of p as the outward normal nn and offset d (nn . x = d):
 * 1 when it supports the set (every point on or behind it), 0 when points lie on both sides or
 * the triple is (nearly) collinear, -1 when every point lies on it. */
static int hull_supporting_plane(const double (*p)[3], int n, int i, int j, int k, double L, double eps, vec3 *nn,
                                 double *d)
{
    vec3 a = v3_load(p[i]), b = v3_load(p[j]), c = v3_load(p[k]);
    *nn = v3_cross(v3_sub(b, a), v3_sub(c, a));
    if (v3_norm(*nn) <= 1e-12 * L * L)
        return 0; /* (nearly) collinear triple: no plane */
    *nn = v3_normalize(*nn);
    *d = v3_dot(*nn, a);
    int pos = 0, neg = 0;
    for (int m = 0; m < n && !(pos && neg); m++) {
        double sd = v3_dot(*nn, v3_load(p[m])) - *d;
        pos |= sd > eps;
        neg |= sd < -eps;
    }
    if (pos && neg)
        return 0;
    if (!pos && !neg)
        return -1;
    if (pos) { /* outward normal: the other points are behind the face */
        *nn = v3_neg(*nn);
        *d = -*d;
    }
    return 1;
}

/* The face polygon in the plane (nn, d) through a and b: the points on the plane (onplane[m]) and
 * their 2D convex hull h, counter-clockwise seen from outside; returns its corner count. */
static int hull_face_polygon(const double (*p)[3], int n, vec3 a, vec3 b, vec3 nn, double d, double L, double eps,
                             unsigned char *onplane, pt2 *pts, pt2 *h)
{
    /* in-plane basis (u, w, nn) right-handed, so counter-clockwise in (u, w) is counter-clockwise
     * seen from outside */
    vec3 u = v3_normalize(v3_sub(b, a)), w = v3_cross(nn, u);
    int np = 0;
    for (int m = 0; m < n; m++) {
        vec3 q = v3_load(p[m]);
        onplane[m] = fabs(v3_dot(nn, q) - d) <= eps;
        if (onplane[m]) {
            pts[np].x = v3_dot(v3_sub(q, a), u);
            pts[np].y = v3_dot(v3_sub(q, a), w);
            pts[np].id = m;
            np++;
        }
    }
    return hull2d(pts, np, 1e-12 * L * L, h);
}

/* Append a face (its corners h[0..nh), the points on its plane onplane[0..n)). */
static int hull_faces_add(hull_faces *hf, const pt2 *h, int nh, const unsigned char *onplane, int n)
{
    if (hf->nf + 1 > hf->cap_f || hf->nfv + nh > hf->cap_fv) {
        while (hf->nf + 1 > hf->cap_f)
            hf->cap_f *= 2;
        while (hf->nfv + nh > hf->cap_fv)
            hf->cap_fv *= 2;
        int *t1 = realloc(hf->fstart, ((size_t)hf->cap_f + 1) * sizeof *hf->fstart);
        if (t1)
            hf->fstart = t1;
        int *t2 = realloc(hf->fv, (size_t)hf->cap_fv * sizeof *hf->fv);
        if (t2)
            hf->fv = t2;
        if (!t1 || !t2)
            return -1;
    }
    unsigned char *t3 = realloc(hf->member, (size_t)(hf->nf + 1) * (size_t)n);
    if (!t3)
        return -1;
    hf->member = t3;
    memcpy(hf->member + (size_t)hf->nf * n, onplane, (size_t)n);
    for (int t = 0; t < nh; t++)
        hf->fv[hf->nfv++] = h[t].id;
    hf->fstart[++hf->nf] = hf->nfv;
    return 0;
}

/* The shape of the faces: the points that are corners of some face, in input order. */
static int hull_to_shape(lahar_shape *s, const double (*p)[3], int n, const hull_faces *hf, double radius)
{
    int *newid = malloc((size_t)n * sizeof *newid);
    if (!newid)
        return -1;
    for (int m = 0; m < n; m++)
        newid[m] = -1;
    for (int t = 0; t < hf->nfv; t++)
        newid[hf->fv[t]] = 0;
    int nv = 0;
    for (int m = 0; m < n; m++)
        if (newid[m] == 0)
            newid[m] = nv++;
    int rc = shape_alloc(s, nv, 0, hf->nf, hf->nfv, radius);
    if (rc == 0) {
        for (int m = 0; m < n; m++)
            if (newid[m] >= 0)
                memcpy(s->v[newid[m]], p[m], sizeof s->v[0]);
        memcpy(s->face_start, hf->fstart, ((size_t)hf->nf + 1) * sizeof *hf->fstart);
        for (int t = 0; t < hf->nfv; t++)
            s->face_v[t] = newid[hf->fv[t]];
        if (shape_build_edges(s) != 0) {
            lahar_shape_free(s);
            rc = -1;
        }
    }
    free(newid);
    return rc;
}

/* Every supporting plane through three of the points is a face; the face polygon is the 2D hull
 * of the points lying on that plane. O(n^3) with early exit: meant for rocks, not meshes. */
int lahar_shape_make_hull(lahar_shape *s, const double (*p)[3], int n, double radius, char *err, size_t errlen)
{
    memset(s, 0, sizeof *s);
    if (n < 4) {
        lahar_errf(err, errlen, "a polyhedron needs at least 4 vertices (got %d)", n);
        return -1;
    }
    if (n > 512) { /* O(n^3): 400 points take about a second */
        lahar_errf(err, errlen, "too many points for the convex hull (%d > 512); give faces", n);
        return -1;
    }
    double L = points_scale(p, n), eps = 1e-9 * L;
    hull_faces hf = {.cap_f = 16, .cap_fv = 64};
    hf.fstart = malloc(((size_t)hf.cap_f + 1) * sizeof *hf.fstart);
    hf.fv = malloc((size_t)hf.cap_fv * sizeof *hf.fv);
    unsigned char *onplane = malloc((size_t)n);
    pt2 *pts = malloc((size_t)n * sizeof *pts), *h = malloc(((size_t)n + 1) * sizeof *h);
    int rc = -1;
    if (!hf.fstart || !hf.fv || !onplane || !pts || !h)
        goto done;
    hf.fstart[0] = 0;
    for (int i = 0; i < n; i++)
        for (int j = i + 1; j < n; j++)
            for (int k = j + 1; k < n; k++) {
                vec3 nn;
                double d;
                int sup = hull_supporting_plane(p, n, i, j, k, L, eps, &nn, &d);
                if (sup < 0) {
                    lahar_errf(err, errlen, "all %d vertices are coplanar (degenerate polyhedron)", n);
                    goto done;
                }
                if (sup == 0)
                    continue;
                int known = 0; /* a face already found through another triple of its points */
                for (int f = 0; f < hf.nf && !known; f++)
                    known = hf.member[(size_t)f * n + i] && hf.member[(size_t)f * n + j] &&
                            hf.member[(size_t)f * n + k];
                if (known)
                    continue;
                int nh = hull_face_polygon(p, n, v3_load(p[i]), v3_load(p[j]), nn, d, L, eps, onplane, pts, h);
                if (nh >= 3 && hull_faces_add(&hf, h, nh, onplane, n) != 0)
                    goto done;
            }
    if (hf.nf < 4) {
        lahar_errf(err, errlen, "the vertices span no volume (degenerate polyhedron)");
        goto done;
    }
    rc = hull_to_shape(s, p, n, &hf, radius);
done:
    hull_faces_free(&hf);
    free(onplane);
    free(pts);
    free(h);
    return rc;
}

/* --- polyhedron from faces --------------------------------------------------------------------- */

int lahar_shape_make_polyhedron(lahar_shape *s, const double (*v)[3], int nv, const int *face_start,
                                const int *face_v, int nf, double radius, char *err, size_t errlen)
{
    memset(s, 0, sizeof *s);
    if (nv < 4) {
        lahar_errf(err, errlen, "a polyhedron needs at least 4 vertices (got %d)", nv);
        return -1;
    }
    if (nf < 4) {
        lahar_errf(err, errlen, "a closed polyhedron needs at least 4 faces (got %d)", nf);
        return -1;
    }
    double L = points_scale(v, nv);
    for (int f = 0; f < nf; f++) {
        int cnt = face_start[f + 1] - face_start[f];
        if (cnt < 3) {
            lahar_errf(err, errlen, "face %d has %d vertices; a face needs at least 3", f, cnt);
            return -1;
        }
        for (int k = 0; k < cnt; k++) {
            int id = face_v[face_start[f] + k];
            if (id < 0 || id >= nv) {
                lahar_errf(err, errlen, "face %d refers to vertex %d; vertices are numbered 0..%d", f, id, nv - 1);
                return -1;
            }
            for (int l = 0; l < k; l++)
                if (face_v[face_start[f] + l] == id) {
                    lahar_errf(err, errlen, "face %d uses vertex %d twice", f, id);
                    return -1;
                }
        }
    }
    int nfv = face_start[nf];
    if (shape_alloc(s, nv, 0, nf, nfv, radius) != 0)
        return -1;
    memcpy(s->v, v, (size_t)nv * sizeof *s->v);
    memcpy(s->face_start, face_start, ((size_t)nf + 1) * sizeof *face_start);
    memcpy(s->face_v, face_v, (size_t)nfv * sizeof *face_v);
    for (int f = 0; f < nf; f++) {
        vec3 nn = face_newell(s, f);
        if (v3_norm(nn) <= 1e-12 * L * L) {
            lahar_errf(err, errlen, "face %d has zero area (degenerate polyhedron)", f);
            lahar_shape_free(s);
            return -1;
        }
        nn = v3_normalize(nn);
        vec3 a = shape_vertex(s, s->face_v[s->face_start[f]]);
        for (int k = s->face_start[f]; k < s->face_start[f + 1]; k++)
            if (fabs(v3_dot(nn, v3_sub(shape_vertex(s, s->face_v[k]), a))) > 1e-6 * L) {
                lahar_errf(err, errlen, "face %d is not planar (vertex %d is off its plane)", f, s->face_v[k]);
                lahar_shape_free(s);
                return -1;
            }
    }
    char *used = calloc((size_t)nv, 1);
    if (!used) {
        lahar_shape_free(s);
        return -1;
    }
    for (int t = 0; t < nfv; t++)
        used[face_v[t]] = 1;
    for (int i = 0; i < nv; i++)
        if (!used[i]) {
            lahar_errf(err, errlen, "vertex %d is not used by any face", i);
            free(used);
            lahar_shape_free(s);
            return -1;
        }
    free(used);
    if (shape_build_edges(s) != 0) {
        lahar_shape_free(s);
        return -1;
    }
    return 0;
}

/* --- STL ---------------------------------------------------------------------------------------------- */

typedef struct {
    double p[3];
    int id;
} stl_vert;

static int stl_vert_cmp(const void *a, const void *b)
{
    const stl_vert *x = a, *y = b;
    for (int k = 0; k < 3; k++)
        if (x->p[k] != y->p[k])
            return x->p[k] < y->p[k] ? -1 : 1;
    return (x->id > y->id) - (x->id < y->id);
}

static float stl_float_le(const unsigned char *b)
{
    uint32_t u = (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* Read the raw triangle corners (3 per triangle) of an ASCII or binary STL into *out. */
static int stl_read_corners(const char *path, stl_vert **out, int *ncorner, char *err, size_t errlen)
{
    FILE *fp = lahar_fopen_input(path, "rb");
    if (!fp) {
        lahar_errf(err, errlen, "cannot open STL file '%s': %s", path, strerror(errno));
        return -1;
    }
    long size = -1;
    if (fseek(fp, 0, SEEK_END) == 0)
        size = ftell(fp);
    rewind(fp);
    unsigned char hdr[84];
    size_t got = fread(hdr, 1, sizeof hdr, fp);
    stl_vert *v = NULL;
    int n = 0, cap = 0;
    if (got == sizeof hdr) {
        uint32_t ntri = (uint32_t)hdr[80] | (uint32_t)hdr[81] << 8 | (uint32_t)hdr[82] << 16 | (uint32_t)hdr[83] << 24;
        if (size == 84 + 50 * (long)ntri && ntri < (1u << 24)) {
            v = malloc((size_t)(ntri ? ntri : 1) * 3 * sizeof *v);
            if (!v) {
                fclose(fp);
                return -1;
            }
            for (uint32_t t = 0; t < ntri; t++) {
                unsigned char rec[50];
                if (fread(rec, 1, sizeof rec, fp) != sizeof rec) {
                    lahar_errf(err, errlen, "STL file '%s' is truncated", path);
                    free(v);
                    fclose(fp);
                    return -1;
                }
                for (int c = 0; c < 3; c++, n++) {
                    for (int k = 0; k < 3; k++)
                        v[n].p[k] = stl_float_le(rec + 12 + 12 * c + 4 * k);
                    v[n].id = n;
                    if (!isfinite(v[n].p[0]) || !isfinite(v[n].p[1]) || !isfinite(v[n].p[2])) {
                        lahar_errf(err, errlen, "STL file '%s': triangle %u has a coordinate that is not a finite "
                                   "number; repair the mesh", path, (unsigned)t + 1);
                        free(v);
                        fclose(fp);
                        return -1;
                    }
                }
            }
            fclose(fp);
            *out = v;
            *ncorner = n;
            return 0;
        }
    }
    /* ASCII: every "vertex x y z" is a corner; three corners make a facet; "endsolid" ends it (a
     * file cut short, e.g. by a full disk or an interrupted copy, has none) */
    rewind(fp);
    char tok[64];
    int ended = 0, ascii = got >= 5 && memcmp(hdr, "solid", 5) == 0;
    while (fscanf(fp, "%63s", tok) == 1) {
        ended |= strcmp(tok, "endsolid") == 0;
        if (strcmp(tok, "vertex") != 0)
            continue;
        double x, y, z;
        if (fscanf(fp, "%lf %lf %lf", &x, &y, &z) != 3 || !isfinite(x) || !isfinite(y) || !isfinite(z)) {
            lahar_errf(err, errlen, "STL file '%s': vertex %d is not followed by three finite numbers", path, n + 1);
            free(v);
            fclose(fp);
            return -1;
        }
        if (n == cap) {
            cap = cap ? 2 * cap : 96;
            stl_vert *t = realloc(v, (size_t)cap * sizeof *v);
            if (!t) {
                free(v);
                fclose(fp);
                return -1;
            }
            v = t;
        }
        v[n].p[0] = x;
        v[n].p[1] = y;
        v[n].p[2] = z;
        v[n].id = n;
        n++;
    }
    fclose(fp);
    if (!ascii && got == sizeof hdr) {
        uint32_t ntri = (uint32_t)hdr[80] | (uint32_t)hdr[81] << 8 | (uint32_t)hdr[82] << 16 | (uint32_t)hdr[83] << 24;
        lahar_errf(err, errlen, "STL file '%s' is not ASCII STL (it does not start with 'solid'), and as binary STL "
                   "its header's %u triangles need %.0f bytes but the file has %ld: it is cut short or not STL; "
                   "export it again", path, (unsigned)ntri, 84.0 + 50.0 * ntri, size);
        free(v);
        return -1;
    }
    if (n == 0 || n % 3 != 0 || !ended) {
        lahar_errf(err, errlen, "STL file '%s' holds %d vertices%s (neither valid ASCII nor binary STL, or "
                   "cut short); export it again", path, n,
                   n == 0 || n % 3 ? ", not a positive multiple of 3" : " and no 'endsolid' line");
        free(v);
        return -1;
    }
    *out = v;
    *ncorner = n;
    return 0;
}

int lahar_shape_read_stl(lahar_shape *s, const char *path, double radius, char *err, size_t errlen)
{
    memset(s, 0, sizeof *s);
    stl_vert *c = NULL;
    int nc = 0;
    if (stl_read_corners(path, &c, &nc, err, errlen) != 0)
        return -1;
    int rc = -1;
    stl_vert *sorted = malloc((size_t)nc * sizeof *sorted);
    int *uid = malloc((size_t)nc * sizeof *uid), *newid = malloc((size_t)nc * sizeof *newid);
    int *tri = malloc((size_t)nc * sizeof *tri);
    if (!sorted || !uid || !newid || !tri)
        goto done;
    /* merge identical coordinates: sort, give equal runs one id, then renumber by first use */
    memcpy(sorted, c, (size_t)nc * sizeof *c);
    qsort(sorted, (size_t)nc, sizeof *sorted, stl_vert_cmp);
    int nu = 0;
    for (int i = 0; i < nc; i++) {
        if (i > 0 && memcmp(sorted[i].p, sorted[i - 1].p, sizeof sorted[i].p) != 0)
            nu++;
        uid[sorted[i].id] = nu;
    }
    nu++;
    for (int i = 0; i < nu; i++)
        newid[i] = -1;
    int nv = 0;
    for (int i = 0; i < nc; i++)
        if (newid[uid[i]] < 0)
            newid[uid[i]] = nv++;
    int nt = 0;
    for (int t = 0; t < nc / 3; t++) {
        int a = newid[uid[3 * t]], b = newid[uid[3 * t + 1]], d = newid[uid[3 * t + 2]];
        if (a == b || b == d || a == d)
            continue; /* collapsed triangle */
        tri[3 * nt] = a;
        tri[3 * nt + 1] = b;
        tri[3 * nt + 2] = d;
        nt++;
    }
    if (nt == 0) {
        lahar_errf(err, errlen, "STL file '%s' has no non-degenerate triangle", path);
        goto done;
    }
    if (shape_alloc(s, nv, 0, nt, 3 * nt, radius) != 0)
        goto done;
    for (int i = 0; i < nc; i++)
        memcpy(s->v[newid[uid[i]]], c[i].p, sizeof s->v[0]);
    for (int t = 0; t <= nt; t++)
        s->face_start[t] = 3 * t;
    memcpy(s->face_v, tri, (size_t)(3 * nt) * sizeof *tri);
    if (shape_build_edges(s) != 0) {
        lahar_shape_free(s);
        goto done;
    }
    rc = 0;
done:
    free(c);
    free(sorted);
    free(uid);
    free(newid);
    free(tri);
    return rc;
}

/* --- convexity, volume, transforms ------------------------------------------------------------ */

int lahar_shape_is_convex(const lahar_shape *s, int dim, double tol)
{
    if (s->nv <= 2)
        return 1;
    if (dim == 2) {
        if (s->ne != s->nv)
            return 0; /* open polyline */
        for (int i = 0; i < s->ne; i++) {
            vec3 a = shape_vertex(s, s->e[i][0]), b = shape_vertex(s, s->e[i][1]);
            double len = hypot(b.x - a.x, b.y - a.y);
            for (int m = 0; m < s->nv; m++) {
                vec3 p = shape_vertex(s, m);
                double side = ((b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x)) / len;
                if (side < -tol)
                    return 0;
            }
        }
        return 1;
    }
    if (s->nf == 0)
        return 0;
    for (int f = 0; f < s->nf; f++) {
        vec3 nn = v3_normalize(face_newell(s, f)), a = shape_vertex(s, s->face_v[s->face_start[f]]);
        for (int m = 0; m < s->nv; m++)
            if (v3_dot(nn, v3_sub(shape_vertex(s, m), a)) > tol)
                return 0;
    }
    return 1;
}

double lahar_shape_core_volume(const lahar_shape *s)
{
    double vol = 0.0;
    for (int f = 0; f < s->nf; f++) {
        int a0 = s->face_start[f], cnt = s->face_start[f + 1] - a0;
        vec3 p0 = shape_vertex(s, s->face_v[a0]);
        for (int k = 1; k + 1 < cnt; k++) {
            vec3 p1 = shape_vertex(s, s->face_v[a0 + k]), p2 = shape_vertex(s, s->face_v[a0 + k + 1]);
            vol += v3_dot(p0, v3_cross(p1, p2)) / 6.0;
        }
    }
    return vol;
}

void lahar_shape_transform(lahar_shape *s, const double R[3][3], const double t[3], double scale)
{
    for (int i = 0; i < s->nv; i++) {
        double p[3] = {scale * s->v[i][0], scale * s->v[i][1], scale * s->v[i][2]};
        for (int k = 0; k < 3; k++)
            s->v[i][k] = (R ? R[k][0] * p[0] + R[k][1] * p[1] + R[k][2] * p[2] : p[k]) + (t ? t[k] : 0.0);
    }
}

/* --- mass properties ------------------------------------------------------------------------------ */

/* Volume, first moment and second moment (int x x^T dV) about the shape origin. */
typedef struct {
    double vol;
    double m1[3];
    double m2[3][3];
} moments;

static void mom_add_outer(moments *m, double w, vec3 a, vec3 b)
{
    double x[3] = {a.x, a.y, a.z}, y[3] = {b.x, b.y, b.z};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            m->m2[i][j] += w * x[i] * y[j];
}

/* Second moment of a simplex (tetrahedron k = 4 or triangle k = 3 corners p) of signed measure
 * V: int x x^T = V / (k (k + 1)) (sum p p^T + s s^T), s = sum p; added with weight w. */
static void mom_add_simplex_m2(moments *m, double V, const vec3 *p, int k, double w)
{
    vec3 s = v3(0, 0, 0);
    for (int i = 0; i < k; i++)
        s = v3_add(s, p[i]);
    double c = w * V / (double)(k * (k + 1));
    for (int i = 0; i < k; i++)
        mom_add_outer(m, c, p[i], p[i]);
    mom_add_outer(m, c, s, s);
}

/* Circular or cylindrical sector integrals over phi in [0, th] of d(phi) = cos u + sin w. */
static void wedge_dirs(double th, double *c1, double *s1, double *cc, double *ss, double *cs)
{
    *c1 = sin(th);              /* int cos */
    *s1 = 1.0 - cos(th);        /* int sin */
    *cc = 0.5 * th + 0.25 * sin(2.0 * th);
    *ss = 0.5 * th - 0.25 * sin(2.0 * th);
    *cs = 0.5 * sin(th) * sin(th);
}

/* Per edge and per vertex of a 3D core, what its wedge and sector need (moments_3d): the edge's
 * dihedral opening theta and the unit vectors u, w spanning it, the faces on each side; the
 * vertex's solid angle omega and first moment mv of its normal cone; the face normals. */
typedef struct {
    double *theta;
    vec3 *eu, *ew;
    int *ef1, *ef2; /* the faces at each edge: f1 walks it i -> j, f2 walks j -> i */
    double *omega;
    vec3 *mv, *fn;
} sweep_parts;

static void sweep_parts_free(sweep_parts *sp)
{
    free(sp->theta);
    free(sp->eu);
    free(sp->ew);
    free(sp->ef1);
    free(sp->ef2);
    free(sp->omega);
    free(sp->mv);
    free(sp->fn);
}

static int sweep_parts_alloc(sweep_parts *sp, int ne, int nv, int nf)
{
    sp->theta = calloc((size_t)ne, sizeof *sp->theta);
    sp->eu = calloc((size_t)ne, sizeof *sp->eu);
    sp->ew = calloc((size_t)ne, sizeof *sp->ew);
    sp->ef1 = calloc((size_t)ne, sizeof *sp->ef1);
    sp->ef2 = calloc((size_t)ne, sizeof *sp->ef2);
    sp->omega = calloc((size_t)nv, sizeof *sp->omega);
    sp->mv = calloc((size_t)nv, sizeof *sp->mv);
    sp->fn = calloc((size_t)(nf ? nf : 1), sizeof *sp->fn);
    return sp->theta && sp->eu && sp->ew && sp->ef1 && sp->ef2 && sp->omega && sp->mv && sp->fn ? 0 : -1;
}

/* A capsule (segment core): the edge wedge is a full cylinder, the vertex cones hemispheres. */
static void capsule_parts(const lahar_shape *s, sweep_parts *sp)
{
    vec3 a = shape_vertex(s, 0), b = shape_vertex(s, 1), t = v3_normalize(v3_sub(b, a));
    vec3 ref = fabs(t.x) < 0.9 ? v3(1, 0, 0) : v3(0, 1, 0);
    sp->eu[0] = v3_normalize(v3_cross(t, ref));
    sp->ew[0] = v3_cross(t, sp->eu[0]);
    sp->theta[0] = 2.0 * M_PI;
    sp->omega[0] = sp->omega[1] = 2.0 * M_PI;
    sp->mv[0] = v3_scale(t, -M_PI); /* half of theta times the unit vector away from the edge */
    sp->mv[1] = v3_scale(t, M_PI);
}

/* The core polyhedron (tetrahedra from the vertex centroid to each fan triangle) and the face
 * prisms (each triangle extruded by R along its face's normal); the face normals into sp->fn. */
static void add_core_and_face_prisms(const lahar_shape *s, sweep_parts *sp, moments *m)
{
    const double R = s->radius;
    vec3 o = v3(0, 0, 0);
    for (int i = 0; i < s->nv; i++)
        o = v3_add(o, shape_vertex(s, i));
    o = v3_scale(o, 1.0 / s->nv);
    for (int f = 0; f < s->nf; f++) {
        int a0 = s->face_start[f], cnt = s->face_start[f + 1] - a0;
        sp->fn[f] = v3_normalize(face_newell(s, f));
        vec3 p0 = shape_vertex(s, s->face_v[a0]);
        for (int k = 1; k + 1 < cnt; k++) {
            vec3 p1 = shape_vertex(s, s->face_v[a0 + k]), p2 = shape_vertex(s, s->face_v[a0 + k + 1]);
            vec3 tet[4] = {o, p0, p1, p2};
            double V = v3_dot(v3_sub(p0, o), v3_cross(v3_sub(p1, o), v3_sub(p2, o))) / 6.0;
            m->vol += V;
            for (int c = 0; c < 3; c++)
                m->m1[c] += V * 0.25 * (v3_get(o, c) + v3_get(p0, c) + v3_get(p1, c) + v3_get(p2, c));
            mom_add_simplex_m2(m, V, tet, 4, 1.0);
            /* face prism: triangle T extruded by R along the normal n:
             * int x = R int_T y + A R^2/2 n, int x x^T = R int_T y y^T
             *   + R^2/2 (int_T y n^T + n int_T y^T) + A R^3/3 n n^T */
            vec3 tri[3] = {p0, p1, p2}, n = sp->fn[f];
            double A = 0.5 * v3_norm(v3_cross(v3_sub(p1, p0), v3_sub(p2, p0)));
            vec3 cy = v3_scale(v3_add(v3_add(p0, p1), p2), A / 3.0); /* int_T y */
            m->vol += A * R;
            for (int c = 0; c < 3; c++)
                m->m1[c] += R * v3_get(cy, c) + A * R * R * 0.5 * v3_get(n, c);
            mom_add_simplex_m2(m, A, tri, 3, R);
            mom_add_outer(m, 0.5 * R * R, cy, n);
            mom_add_outer(m, 0.5 * R * R, n, cy);
            mom_add_outer(m, A * R * R * R / 3.0, n, n);
        }
    }
}

/* The two faces at each edge (one walking it each way); -1 when the polyhedron is open (an edge
 * with fewer or more faces, or walked twice the same way). */
static int find_edge_faces(const lahar_shape *s, sweep_parts *sp)
{
    for (int k = 0; k < s->ne; k++)
        sp->ef1[k] = sp->ef2[k] = -1;
    for (int f = 0; f < s->nf; f++) {
        int a0 = s->face_start[f], cnt = s->face_start[f + 1] - a0;
        for (int k = 0; k < cnt; k++) {
            int key[2] = {s->face_v[a0 + k], s->face_v[a0 + (k + 1) % cnt]};
            int sorted[2] = {key[0] < key[1] ? key[0] : key[1], key[0] < key[1] ? key[1] : key[0]};
            int *hit = bsearch(sorted, s->e, (size_t)s->ne, sizeof *s->e, edge_cmp);
            if (!hit)
                return -1;
            int ei = (int)((int(*)[2])hit - s->e);
            int *slot = key[0] == s->e[ei][0] ? &sp->ef1[ei] : &sp->ef2[ei];
            if (*slot >= 0)
                return -1;
            *slot = f;
        }
    }
    for (int k = 0; k < s->ne; k++)
        if (sp->ef1[k] < 0 || sp->ef2[k] < 0)
            return -1;
    return 0;
}

/* Each edge's opening between its faces' normals, each vertex's normal-cone first moment
 * (1/2 sum over its edges of theta (v - w)/|v - w|) and solid angle (the angle defect 2 pi - sum of
 * the face corner angles). */
static void edge_and_vertex_angles(const lahar_shape *s, sweep_parts *sp)
{
    for (int k = 0; k < s->ne; k++) {
        vec3 n1 = sp->fn[sp->ef1[k]], n2 = sp->fn[sp->ef2[k]];
        sp->theta[k] = atan2(v3_norm(v3_cross(n1, n2)), v3_dot(n1, n2));
        sp->eu[k] = n1;
        vec3 w = v3_sub(n2, v3_scale(n1, v3_dot(n1, n2)));
        sp->ew[k] = v3_norm(w) > 1e-300 ? v3_normalize(w) : v3(0, 0, 0);
        vec3 a = shape_vertex(s, s->e[k][0]), b = shape_vertex(s, s->e[k][1]);
        vec3 t = v3_normalize(v3_sub(a, b));
        sp->mv[s->e[k][0]] = v3_add(sp->mv[s->e[k][0]], v3_scale(t, 0.5 * sp->theta[k]));
        sp->mv[s->e[k][1]] = v3_sub(sp->mv[s->e[k][1]], v3_scale(t, 0.5 * sp->theta[k]));
    }
    for (int i = 0; i < s->nv; i++)
        sp->omega[i] = 2.0 * M_PI;
    for (int f = 0; f < s->nf; f++) {
        int a0 = s->face_start[f], cnt = s->face_start[f + 1] - a0;
        for (int k = 0; k < cnt; k++) {
            int i = s->face_v[a0 + k];
            vec3 p = shape_vertex(s, i), prev = shape_vertex(s, s->face_v[a0 + (k + cnt - 1) % cnt]),
                 next = shape_vertex(s, s->face_v[a0 + (k + 1) % cnt]);
            vec3 d1 = v3_sub(prev, p), d2 = v3_sub(next, p);
            sp->omega[i] -= atan2(v3_norm(v3_cross(d1, d2)), v3_dot(d1, d2));
        }
    }
}

/* The edge wedges: x = a + s t + r (cos phi u + sin phi w), s in [0, L], r in [0, R],
 * phi in [0, theta]. */
static void add_edge_wedges(const lahar_shape *s, int ne, const sweep_parts *sp, moments *m)
{
    const double R = s->radius;
    for (int k = 0; k < ne; k++) {
        vec3 a = shape_vertex(s, s->e[k][0]), b = shape_vertex(s, s->e[k][1]);
        double Lk = v3_norm(v3_sub(b, a));
        vec3 t = v3_scale(v3_sub(b, a), 1.0 / Lk);
        double c1, s1, cc, ss, cs;
        wedge_dirs(sp->theta[k], &c1, &s1, &cc, &ss, &cs);
        double V = 0.5 * sp->theta[k] * R * R * Lk;
        vec3 D1 = v3_add(v3_scale(sp->eu[k], c1), v3_scale(sp->ew[k], s1)); /* int d dphi */
        vec3 ic = v3_add(v3_scale(a, Lk), v3_scale(t, 0.5 * Lk * Lk)); /* int_0^L c(s) ds */
        m->vol += V;
        for (int c = 0; c < 3; c++)
            m->m1[c] += 0.5 * sp->theta[k] * R * R * v3_get(ic, c) + Lk * R * R * R / 3.0 * v3_get(D1, c);
        /* int c c^T ds = L a a^T + L^2/2 (a t^T + t a^T) + L^3/3 t t^T, times theta R^2/2 */
        double wr = 0.5 * sp->theta[k] * R * R;
        mom_add_outer(m, wr * Lk, a, a);
        mom_add_outer(m, wr * 0.5 * Lk * Lk, a, t);
        mom_add_outer(m, wr * 0.5 * Lk * Lk, t, a);
        mom_add_outer(m, wr * Lk * Lk * Lk / 3.0, t, t);
        mom_add_outer(m, R * R * R / 3.0, ic, D1);
        mom_add_outer(m, R * R * R / 3.0, D1, ic);
        double w4 = Lk * pow(R, 4) / 4.0;
        mom_add_outer(m, w4 * cc, sp->eu[k], sp->eu[k]);
        mom_add_outer(m, w4 * ss, sp->ew[k], sp->ew[k]);
        mom_add_outer(m, w4 * cs, sp->eu[k], sp->ew[k]);
        mom_add_outer(m, w4 * cs, sp->ew[k], sp->eu[k]);
    }
}

/* The vertex sectors: x = v + r u over the normal cone (solid angle omega, int u = mv). */
static void add_vertex_sectors(const lahar_shape *s, const sweep_parts *sp, moments *m)
{
    const double R = s->radius;
    for (int i = 0; i < s->nv; i++) {
        vec3 p = shape_vertex(s, i);
        double V = sp->omega[i] * R * R * R / 3.0, w = pow(R, 4) / 4.0;
        m->vol += V;
        for (int c = 0; c < 3; c++)
            m->m1[c] += V * v3_get(p, c) + w * v3_get(sp->mv[i], c);
        mom_add_outer(m, V, p, p);
        mom_add_outer(m, w, p, sp->mv[i]);
        mom_add_outer(m, w, sp->mv[i], p);
    }
}

/* Volume, first and second moments of a 3D sphero-polyhedron: the core, the face prisms, the edge
 * wedges and the vertex sectors (a sphere, a capsule or a closed polyhedron swept by R). */
static int moments_3d(const lahar_shape *s, moments *m, char *err, size_t errlen)
{
    const double R = s->radius;
    memset(m, 0, sizeof *m);
    /* all vertex sectors together contribute R^5/5 * int_{S^2} u u^T = (4 pi / 15) R^5 I */
    for (int i = 0; i < 3; i++)
        m->m2[i][i] += 4.0 * M_PI / 15.0 * pow(R, 5);
    if (s->nv == 1) {
        vec3 c = shape_vertex(s, 0);
        double V = 4.0 / 3.0 * M_PI * R * R * R;
        m->vol += V;
        for (int k = 0; k < 3; k++)
            m->m1[k] += V * v3_get(c, k);
        mom_add_outer(m, V, c, c);
        return 0;
    }
    const int capsule = s->nf == 0 && s->nv == 2;
    if (!capsule && s->nf < 4) {
        lahar_errf(err, errlen, "mass properties need a closed core (sphere, segment or polyhedron)");
        return -1;
    }
    const int ne = capsule ? 1 : s->ne;
    sweep_parts sp;
    int rc = sweep_parts_alloc(&sp, ne, s->nv, s->nf);
    if (rc != 0) {
        lahar_errf(err, errlen, "out of memory computing the mass properties");
    } else if (capsule) {
        capsule_parts(s, &sp);
    } else {
        add_core_and_face_prisms(s, &sp, m);
        rc = find_edge_faces(s, &sp);
        if (rc != 0)
            lahar_errf(err, errlen, "mass properties need a closed polyhedron (every edge shared by two faces "
                       "walking it in opposite directions)");
        else
            edge_and_vertex_angles(s, &sp);
    }
    if (rc == 0) {
        add_edge_wedges(s, ne, &sp, m);
        add_vertex_sectors(s, &sp, m);
    }
    sweep_parts_free(&sp);
    return rc;
}

/* 2D, per unit thickness: the CCW ring v[0..n-1] (n = 1 disc, n = 2 stadium), its edge rectangles
 * and its vertex sectors (opening = exterior angle between the neighbouring edge normals). */
static int moments_2d(const lahar_shape *s, moments *m, char *err, size_t errlen)
{
    const double R = s->radius;
    int n = s->nv;
    memset(m, 0, sizeof *m);
    if (n > 2 && s->ne != n) {
        lahar_errf(err, errlen, "mass properties need a closed 2D polygon");
        return -1;
    }
    /* all vertex sectors together: R^4/4 int_0^{2pi} u u^T = (pi/4) R^4 I_2 */
    m->m2[0][0] += 0.25 * M_PI * pow(R, 4);
    m->m2[1][1] += 0.25 * M_PI * pow(R, 4);
    if (n == 1) {
        vec3 c = shape_vertex(s, 0);
        double A = M_PI * R * R;
        m->vol = A;
        m->m1[0] = A * c.x;
        m->m1[1] = A * c.y;
        mom_add_outer(m, A, c, c);
        return 0;
    }
    vec3 o = v3(0, 0, 0);
    for (int i = 0; i < n; i++)
        o = v3_add(o, shape_vertex(s, i));
    o = v3_scale(o, 1.0 / n);
    for (int i = 0; i < n; i++) {
        vec3 a = shape_vertex(s, i), b = shape_vertex(s, (i + 1) % n), prev = shape_vertex(s, (i + n - 1) % n);
        /* core triangle (o, a, b) */
        double A = 0.5 * ((a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x));
        vec3 tri[3] = {o, a, b};
        m->vol += A;
        m->m1[0] += A * (o.x + a.x + b.x) / 3.0;
        m->m1[1] += A * (o.y + a.y + b.y) / 3.0;
        mom_add_simplex_m2(m, A, tri, 3, 1.0);
        /* edge rectangle a + s t + h nrm, nrm = outward (right of a -> b for CCW) */
        double Le = hypot(b.x - a.x, b.y - a.y);
        vec3 t = v3((b.x - a.x) / Le, (b.y - a.y) / Le, 0), nrm = v3(t.y, -t.x, 0);
        vec3 ic = v3_add(v3_scale(a, Le), v3_scale(t, 0.5 * Le * Le)); /* int_0^L c ds */
        m->vol += Le * R;
        for (int c = 0; c < 2; c++)
            m->m1[c] += R * v3_get(ic, c) + Le * 0.5 * R * R * v3_get(nrm, c);
        mom_add_outer(m, R * Le, a, a);
        mom_add_outer(m, R * 0.5 * Le * Le, a, t);
        mom_add_outer(m, R * 0.5 * Le * Le, t, a);
        mom_add_outer(m, R * Le * Le * Le / 3.0, t, t);
        mom_add_outer(m, 0.5 * R * R, ic, nrm);
        mom_add_outer(m, 0.5 * R * R, nrm, ic);
        mom_add_outer(m, Le * R * R * R / 3.0, nrm, nrm);
        /* vertex sector at a between the normal of (prev, a) and of (a, b) */
        double Lp = hypot(a.x - prev.x, a.y - prev.y);
        vec3 np = v3((a.y - prev.y) / Lp, -(a.x - prev.x) / Lp, 0);
        double d = v3_dot(np, nrm);
        double phi = acos(d > 1.0 ? 1.0 : (d < -1.0 ? -1.0 : d));
        double al = atan2(np.y, np.x);
        vec3 mu = v3(sin(al + phi) - sin(al), cos(al) - cos(al + phi), 0); /* int u dphi */
        double As = 0.5 * R * R * phi;
        m->vol += As;
        for (int c = 0; c < 2; c++)
            m->m1[c] += As * v3_get(a, c) + R * R * R / 3.0 * v3_get(mu, c);
        mom_add_outer(m, As, a, a);
        mom_add_outer(m, R * R * R / 3.0, a, mu);
        mom_add_outer(m, R * R * R / 3.0, mu, a);
    }
    (void)err;
    (void)errlen;
    return 0;
}

void lahar_sym3_eigen(const double a[3][3], double d[3], double V[3][3])
{
    double A[3][3];
    memcpy(A, a, sizeof A);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            V[i][j] = i == j ? 1.0 : 0.0;
    static const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
    for (int sweep = 0; sweep < 50; sweep++) {
        int rotated = 0;
        for (int pq = 0; pq < 3; pq++) {
            int p = pairs[pq][0], q = pairs[pq][1];
            double scale = fabs(A[p][p]) + fabs(A[q][q]);
            if (fabs(A[p][q]) <= 1e-14 * scale || A[p][q] == 0.0) {
                A[p][q] = A[q][p] = 0.0;
                continue;
            }
            rotated = 1;
            double th = (A[q][q] - A[p][p]) / (2.0 * A[p][q]);
            double t = (th >= 0.0 ? 1.0 : -1.0) / (fabs(th) + sqrt(th * th + 1.0));
            double c = 1.0 / sqrt(t * t + 1.0), sn = t * c;
            double J[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
            J[p][p] = c;
            J[q][q] = c;
            J[p][q] = sn;
            J[q][p] = -sn;
            double T[3][3], B[3][3], W[3][3];
            for (int i = 0; i < 3; i++) /* T = A J */
                for (int j = 0; j < 3; j++)
                    T[i][j] = A[i][0] * J[0][j] + A[i][1] * J[1][j] + A[i][2] * J[2][j];
            for (int i = 0; i < 3; i++) /* B = J^T T */
                for (int j = 0; j < 3; j++)
                    B[i][j] = J[0][i] * T[0][j] + J[1][i] * T[1][j] + J[2][i] * T[2][j];
            for (int i = 0; i < 3; i++)
                for (int j = 0; j < 3; j++)
                    W[i][j] = V[i][0] * J[0][j] + V[i][1] * J[1][j] + V[i][2] * J[2][j];
            memcpy(A, B, sizeof A);
            A[p][q] = A[q][p] = 0.0;
            memcpy(V, W, sizeof W);
        }
        if (!rotated)
            break;
    }
    for (int i = 0; i < 3; i++)
        d[i] = A[i][i];
}

int lahar_shape_mass_properties(const lahar_shape *s, int dim, lahar_mass_props *mp, char *err, size_t errlen)
{
    moments m;
    memset(mp, 0, sizeof *mp);
    if ((dim == 2 ? moments_2d(s, &m, err, errlen) : moments_3d(s, &m, err, errlen)) != 0)
        return -1;
    if (!(m.vol > 0.0)) {
        lahar_errf(err, errlen, "the shape has no volume");
        return -1;
    }
    mp->volume = m.vol;
    double c[3] = {m.m1[0] / m.vol, m.m1[1] / m.vol, m.m1[2] / m.vol};
    if (dim == 2)
        c[2] = 0.0;
    memcpy(mp->com, c, sizeof c);
    double C[3][3]; /* second moment about the centre of mass */
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            C[i][j] = m.m2[i][j] - m.vol * c[i] * c[j];
    if (dim == 2) {
        double cxx = C[0][0], cyy = C[1][1], cxy = 0.5 * (C[0][1] + C[1][0]);
        double th = fabs(cxy) <= 1e-14 * (cxx + cyy) ? 0.0 : 0.5 * atan2(2.0 * cxy, cxx - cyy);
        double co = cos(th), si = sin(th);
        double xx = cxx * co * co + 2.0 * cxy * co * si + cyy * si * si;
        double yy = cxx * si * si - 2.0 * cxy * co * si + cyy * co * co;
        mp->inertia[0] = yy;
        mp->inertia[1] = xx;
        mp->inertia[2] = xx + yy;
        double ax[3][3] = {{co, -si, 0}, {si, co, 0}, {0, 0, 1}};
        memcpy(mp->axes, ax, sizeof ax);
        return 0;
    }
    double J[3][3], tr = C[0][0] + C[1][1] + C[2][2];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            J[i][j] = (i == j ? tr : 0.0) - 0.5 * (C[i][j] + C[j][i]);
    lahar_sym3_eigen(J, mp->inertia, mp->axes);
    return 0;
}

void lahar_shape_to_principal(lahar_shape *s, const lahar_mass_props *mp)
{
    for (int i = 0; i < s->nv; i++) {
        double d[3] = {s->v[i][0] - mp->com[0], s->v[i][1] - mp->com[1], s->v[i][2] - mp->com[2]};
        for (int k = 0; k < 3; k++)
            s->v[i][k] = mp->axes[0][k] * d[0] + mp->axes[1][k] * d[1] + mp->axes[2][k] * d[2];
    }
}

/* ---- SPH particle regions ------------------------------------------------------------------ */

/* Even-odd rule (crossings of the ray +x from p with the polygon's edges; Franklin's half-open
 * vertex rule so a ray through a vertex counts once). */
static int block_polygon_contains(const lahar_particle_block *b, const double x[3])
{
    int inside = 0;
    for (int i = 0, j = b->nvert - 1; i < b->nvert; j = i++)
        inside ^= geom_ray_crosses_edge(b->vert[i][0], b->vert[i][1], b->vert[j][0], b->vert[j][1], x[0], x[1]);
    return inside;
}

/* The directions of the inside test's rays: skew to every axis and diagonal so that rays from
 * lattice points miss the edges and vertices of meshes built on round coordinates. */
static const double block_ray_dirs[3][3] = {{1.0, 0.3183098861837907, 0.2078795763507619},
                                            {-0.5772156649015329, 1.0, 0.6931471805599453},
                                            {0.2718281828459045, -0.4142135623730951, 1.0}};

/* Does the ray o + s d (s > 0) cross triangle t of mesh block b (Moller-Trumbore)? Returns 1 or 0;
 * sets *ambiguous when the ray passes within 1e-9 (in barycentric terms) of an edge, or starts
 * on the face. */
static int block_ray_crosses_triangle(const lahar_particle_block *b, int t, vec3 o, vec3 d, int *ambiguous)
{
    const double eps = 1e-9;
    vec3 p0 = v3_load(b->vert[b->tri[t][0]]), p1 = v3_load(b->vert[b->tri[t][1]]);
    vec3 p2 = v3_load(b->vert[b->tri[t][2]]);
    vec3 e1 = v3_sub(p1, p0), e2 = v3_sub(p2, p0);
    vec3 pv = v3_cross(d, e2);
    double det = v3_dot(e1, pv);
    if (det == 0.0)
        return 0; /* ray parallel to the triangle's plane */
    double inv = 1.0 / det;
    vec3 tv = v3_sub(o, p0);
    double u = v3_dot(tv, pv) * inv;
    if (u < -eps || u > 1.0 + eps)
        return 0;
    vec3 qv = v3_cross(tv, e1);
    double v = v3_dot(d, qv) * inv;
    if (v < -eps || u + v > 1.0 + eps)
        return 0;
    double s = v3_dot(e2, qv) * inv;
    double scale = sqrt(v3_norm2(e1) + v3_norm2(e2));
    if (fabs(s) <= eps * scale || u < eps || v < eps || u + v > 1.0 - eps) {
        if (s >= -eps * scale)
            *ambiguous = 1; /* (behind the start it is irrelevant) */
        return 0;
    }
    return s > 0.0;
}

/* Parity of the crossings of a ray from x with the triangles, trying the next direction while
 * the ray is ambiguous. Returns 1 inside, 0 outside. */
static int block_mesh_contains(const lahar_particle_block *b, const double x[3])
{
    const vec3 o = v3_load(x);
    int crossings = 0;
    for (int k = 0; k < 3; k++) {
        const vec3 d = v3_normalize(v3_load(block_ray_dirs[k]));
        int ambiguous = 0;
        crossings = 0;
        for (int t = 0; t < b->ntri && !ambiguous; t++)
            crossings += block_ray_crosses_triangle(b, t, o, d, &ambiguous);
        if (!ambiguous)
            break;
    }
    return crossings & 1;
}

/* The triangles of a mesh block binned by their shadow along the first ray direction: a 2D grid
 * in the plane normal to it (axes u, w), each triangle listed in every cell its shadow's box
 * (grown by 1e-6 of its size) meets. A ray from x can only cross, or pass near, the triangles
 * listed in the cell of x's shadow: the others leave it more than 1e-6 (barycentric) outside,
 * far beyond the test's 1e-9, so that the candidates give the same crossings and the same
 * ambiguity as all triangles. For the lattice of a block cut from a large surface (a terrain)
 * this visits a few triangles per point instead of all of them. */
typedef struct {
    vec3 d, u, w;   /* ray direction and the two axes of the shadow plane */
    double lo[2], h;
    int n[2];
    int *start, *items;
} block_ray_grid;

static void block_ray_shadow_box(const lahar_particle_block *b, const block_ray_grid *g, int t, double lo[2], double hi[2])
{
    lo[0] = lo[1] = DBL_MAX;
    hi[0] = hi[1] = -DBL_MAX;
    for (int j = 0; j < 3; j++) {
        vec3 p = v3_load(b->vert[b->tri[t][j]]);
        double c[2] = {v3_dot(p, g->u), v3_dot(p, g->w)};
        for (int a = 0; a < 2; a++) {
            lo[a] = fmin(lo[a], c[a]);
            hi[a] = fmax(hi[a], c[a]);
        }
    }
    double grow = 1e-6 * fmax(hi[0] - lo[0], hi[1] - lo[1]) + 1e-12 * (fabs(lo[0]) + fabs(lo[1]) + fabs(hi[0]) + fabs(hi[1]));
    for (int a = 0; a < 2; a++) {
        lo[a] -= grow;
        hi[a] += grow;
    }
}

static void block_ray_cells(const block_ray_grid *g, const double lo[2], const double hi[2], int c0[2], int c1[2])
{
    for (int a = 0; a < 2; a++) {
        double f0 = floor((lo[a] - g->lo[a]) / g->h), f1 = floor((hi[a] - g->lo[a]) / g->h);
        c0[a] = f0 < 0.0 ? 0 : f0 > g->n[a] - 1 ? g->n[a] - 1 : (int)f0;
        c1[a] = f1 < 0.0 ? 0 : f1 > g->n[a] - 1 ? g->n[a] - 1 : (int)f1;
    }
}

static void block_ray_grid_free(block_ray_grid *g)
{
    free(g->start);
    free(g->items);
    g->start = g->items = NULL;
}

/* Returns 0, 1 when the mesh's extent cannot be binned (then no grid), or -1 when out of memory. */
static int block_ray_grid_build(const lahar_particle_block *b, block_ray_grid *g)
{
    memset(g, 0, sizeof *g);
    g->d = v3_normalize(v3_load(block_ray_dirs[0]));
    /* u: the axis least aligned with d made normal to it; w = d x u */
    g->u = v3_normalize(v3_sub(v3(0.0, 0.0, 1.0), v3_scale(g->d, g->d.z)));
    g->w = v3_cross(g->d, g->u);
    double lo[2] = {DBL_MAX, DBL_MAX}, hi[2] = {-DBL_MAX, -DBL_MAX};
    for (int t = 0; t < b->ntri; t++) {
        double tl[2], th[2];
        block_ray_shadow_box(b, g, t, tl, th);
        for (int a = 0; a < 2; a++) {
            lo[a] = fmin(lo[a], tl[a]);
            hi[a] = fmax(hi[a], th[a]);
        }
    }
    if (!(isfinite(lo[0]) && isfinite(lo[1]) && isfinite(hi[0] - lo[0]) && isfinite(hi[1] - lo[1])))
        return 1; /* extents no grid can bin (coordinates near DBL_MAX): the per-point test */
    /* about one triangle per cell */
    double area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
    g->h = area > 0.0 ? sqrt(area / b->ntri) : fmax(hi[0] - lo[0], hi[1] - lo[1]) + 1.0;
    long ncell = 1;
    for (int a = 0; a < 2; a++) {
        g->lo[a] = lo[a];
        double n = ceil((hi[a] - lo[a]) / g->h);
        g->n[a] = n < 1.0 ? 1 : n > 4096.0 ? 4096 : (int)n;
        ncell *= g->n[a];
    }
    g->h = fmax(g->h, fmax((hi[0] - lo[0]) / g->n[0], (hi[1] - lo[1]) / g->n[1]));
    g->start = calloc((size_t)ncell + 1, sizeof *g->start);
    if (!g->start)
        return -1;
    for (int pass = 0; pass < 2; pass++) {
        for (int t = 0; t < b->ntri; t++) {
            double tl[2], th[2];
            int c0[2], c1[2];
            block_ray_shadow_box(b, g, t, tl, th);
            block_ray_cells(g, tl, th, c0, c1);
            for (int j = c0[1]; j <= c1[1]; j++)
                for (int i = c0[0]; i <= c1[0]; i++) {
                    long c = (long)j * g->n[0] + i;
                    if (pass == 0)
                        g->start[c + 1]++;
                    else
                        g->items[g->start[c]++] = t;
                }
        }
        if (pass == 0) {
            for (long c = 0; c < ncell; c++)
                g->start[c + 1] += g->start[c];
            g->items = malloc((size_t)(g->start[ncell] > 0 ? g->start[ncell] : 1) * sizeof *g->items);
            if (!g->items) {
                block_ray_grid_free(g);
                return -1;
            }
        } else {
            for (long c = ncell; c > 0; c--)
                g->start[c] = g->start[c - 1];
            g->start[0] = 0;
        }
    }
    return 0;
}

/* block_mesh_contains through the grid: the first direction over the candidates; an ambiguous
 * ray falls back to the full test (which finds the same ambiguity and goes on to the next). */
static int block_mesh_contains_grid(const lahar_particle_block *b, const block_ray_grid *g, const double x[3])
{
    const vec3 o = v3_load(x);
    double c[2] = {v3_dot(o, g->u), v3_dot(o, g->w)};
    for (int a = 0; a < 2; a++)
        if (c[a] < g->lo[a] || c[a] > g->lo[a] + g->n[a] * g->h)
            return 0; /* outside every triangle's shadow: no crossing, and not ambiguous */
    int ci[2], cj[2];
    block_ray_cells(g, c, c, ci, cj);
    long cell = (long)ci[1] * g->n[0] + ci[0];
    int ambiguous = 0, crossings = 0;
    for (int k = g->start[cell]; k < g->start[cell + 1] && !ambiguous; k++)
        crossings += block_ray_crosses_triangle(b, g->items[k], o, g->d, &ambiguous);
    return ambiguous ? block_mesh_contains(b, x) : crossings & 1;
}

/* x within the block's bounds [lo, hi) */
static int block_in_bounds(const lahar_particle_block *b, int dim, const double x[3])
{
    for (int a = 0; a < dim; a++)
        if (!(x[a] >= b->lo[a] && x[a] < b->hi[a]))
            return 0;
    return 1;
}

int lahar_particle_block_contains(const lahar_particle_block *b, int dim, const double x[3])
{
    if (!block_in_bounds(b, dim, x))
        return 0;
    switch (b->kind) {
    case LAHAR_BLOCK_BOX: return 1;
    case LAHAR_BLOCK_POLYGON: return b->nvert >= 3 && block_polygon_contains(b, x);
    case LAHAR_BLOCK_MESH: return dim == 3 && b->ntri > 0 && block_mesh_contains(b, x);
    default: return 0;
    }
}

/* Lattice points per axis, as doubles (not finite for a non-finite extent or dx). */
static void block_lattice_dims(const lahar_particle_block *b, int dim, double dx, double n[3])
{
    for (int a = 0; a < 3; a++) {
        n[a] = (a == 2 && dim == 2) ? 1.0 : floor((b->hi[a] - b->lo[a]) / dx + 1e-9);
        if (n[a] < 0.0)
            n[a] = 0.0;
    }
}

double lahar_particle_block_box_filled(const lahar_particle_block *b, int dim, double dx, double filled[3])
{
    double n[3], fraction = 1.0;
    block_lattice_dims(b, dim, dx, n);
    for (int a = 0; a < 3; a++) {
        double side = b->hi[a] - b->lo[a];
        filled[a] = a < dim ? n[a] * dx : side;
        if (a < dim && b->kind == LAHAR_BLOCK_BOX && side > 0.0)
            fraction *= filled[a] / side;
    }
    return fraction;
}

double lahar_particle_block_lattice_size(const lahar_particle_block *b, int dim, double dx)
{
    double n[3];
    block_lattice_dims(b, dim, dx, n);
    double size = n[0] * n[1] * n[2];
    return size == size ? size : INFINITY; /* NaN (an extent of inf / inf) counts as too large */
}

int64_t lahar_particle_block_lattice_keep(const lahar_particle_block *b, int dim, double dx,
                                          int (*keep)(double x[3], void *ctx), void *ctx, int64_t most,
                                          double (*out)[3], int64_t cap)
{
    double nd[3];
    block_lattice_dims(b, dim, dx, nd);
    /* a lattice no run could hold (or whose indices would not fit int64): refused, not walked */
    if (!(lahar_particle_block_lattice_size(b, dim, dx) <= LAHAR_LATTICE_MAX))
        return -1;
    /* an axis without a point: no point at all (and another axis may still be beyond int64, its
     * product with 0 within the bound) */
    if (nd[0] == 0.0 || nd[1] == 0.0 || nd[2] == 0.0)
        return 0;
    int64_t n[3] = {(int64_t)nd[0], (int64_t)nd[1], (int64_t)nd[2]};
    int64_t count = 0;
    block_ray_grid grid;
    int gridded = b->kind == LAHAR_BLOCK_MESH && dim == 3 && b->ntri > GEOM_FEATURE_GRID_MIN;
    if (gridded) {
        int rc = block_ray_grid_build(b, &grid);
        if (rc < 0)
            return -1;
        gridded = rc == 0;
    }
    for (int64_t i = 0; i < n[0]; i++)
        for (int64_t j = 0; j < n[1]; j++)
            for (int64_t k = 0; k < n[2]; k++) {
                double x[3] = {b->lo[0] + ((double)i + 0.5) * dx, b->lo[1] + ((double)j + 0.5) * dx,
                               dim == 2 ? 0.0 : b->lo[2] + ((double)k + 0.5) * dx};
                /* the lattice point of a box is inside by construction (the +1e-9 above may put
                 * the last one a hair past hi) */
                if (gridded ? !(block_in_bounds(b, dim, x) && block_mesh_contains_grid(b, &grid, x))
                            : b->kind != LAHAR_BLOCK_BOX && !lahar_particle_block_contains(b, dim, x))
                    continue;
                if (keep && !keep(x, ctx))
                    continue;
                if (out && count < cap)
                    memcpy(out[count], x, sizeof x);
                if (++count == most)
                    goto done;
            }
done:
    if (gridded)
        block_ray_grid_free(&grid);
    return count;
}

int64_t lahar_particle_block_lattice(const lahar_particle_block *b, int dim, double dx, double (*out)[3], int64_t cap)
{
    return lahar_particle_block_lattice_keep(b, dim, dx, NULL, NULL, -1, out, cap);
}

void lahar_particle_block_bounds(lahar_particle_block *b, int dim)
{
    for (int a = 0; a < 3; a++) {
        b->lo[a] = b->nvert > 0 ? INFINITY : 0.0;
        b->hi[a] = b->nvert > 0 ? -INFINITY : 0.0;
    }
    for (int i = 0; i < b->nvert; i++)
        for (int a = 0; a < 3; a++) {
            b->lo[a] = fmin(b->lo[a], b->vert[i][a]);
            b->hi[a] = fmax(b->hi[a], b->vert[i][a]);
        }
    if (dim == 2)
        b->lo[2] = b->hi[2] = 0.0;
}

void lahar_particle_block_free(lahar_particle_block *b)
{
    free(b->vert);
    free(b->tri);
    b->vert = NULL;
    b->tri = NULL;
    b->nvert = b->ntri = 0;
}
