/* Building sphero-polyhedra (see shape_build.h for the conventions): what every builder shares
 * (allocation, edges from faces, face normals; shape_private.h), the primitives (sphere, segment,
 * boxes, plane, polyline), polyhedra from vertices and faces, convexity, core volume and
 * transforms. Convex hulls: shape_hull.c; STL files: shape_stl.c; mass properties: shape_mass.c;
 * the lattice of SPH particle blocks: particle_block.c. */
#include "errmsg.h"
#include "shape_build.h"

#include <stdlib.h>
#include <string.h>

#include "shape_private.h"
#include "vec.h"

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
int shape_alloc(lahar_shape *s, int nv, int ne, int nf, int nfv, double radius)
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

/* Bounding-box diagonal: the length scale of geometric tolerances. */
double points_scale(const double (*p)[3], int n)
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

int edge_cmp(const void *a, const void *b)
{
    const int *x = a, *y = b;
    if (x[0] != y[0])
        return x[0] < y[0] ? -1 : 1;
    return (x[1] > y[1]) - (x[1] < y[1]);
}

/* Unique undirected edges (i < j, sorted) of all faces; replaces s->e. */
int shape_build_edges(lahar_shape *s)
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
vec3 face_newell(const lahar_shape *s, int f)
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
int shape_make_ring2d(lahar_shape *s, const double (*p)[2], int n, int closed, double radius)
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
