/* Convex hulls (shape_build.h): a 2D polygon from points (Andrew's monotone chain) and a 3D
 * polyhedron from points (exact supporting planes, coplanar triangles merged into faces); the
 * rock shapes of a case given as points. */
#include "errmsg.h"
#include "shape_build.h"

#include <stdlib.h>
#include <string.h>

#include "shape_private.h"
#include "vec.h"

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
