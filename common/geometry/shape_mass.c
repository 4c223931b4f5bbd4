/* Mass properties of the swept solid (shape_build.h), exact to rounding: core, face prisms, edge
 * wedges and vertex sectors in 3D, polygon, edge rectangles and vertex sectors in 2D; the
 * principal frame (symmetric 3x3 eigen-decomposition). */
#include "errmsg.h"
#include "shape_build.h"

#include <stdlib.h>
#include <string.h>

#include "shape_private.h"
#include "vec.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

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
