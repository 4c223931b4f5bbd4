/* The "spheropoly" DEM engine: rigid sphero-polyhedra (Galindo-Torres 2009-2013 as used in paper
 * Trujillo-Vela et al. 2020, sec. 3) with linear or Hertz normal contacts, a tangential spring with Coulomb limit, a
 * uniform grid broad phase (dense or hashed), per-body feature grids for big surfaces, kick-drift-kick
 * leap-frog for translation and an exactly rotating splitting (NO_SQUISH / Dullweber-Leimkuhler-
 * McLachlan 1997) for rotation. Conventions are documented in dem_node/README.md. */
#include "spheropoly.h"
#include "spheropoly_impl.h"
#include <float.h>
#include <limits.h>
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include "dem_contact.h"
#include "geometry.h"


/* ---------------------------------------------------------------------------------------------- */

static void *xcalloc(size_t n, size_t size) { return calloc(n ? n : 1, size); }

static int grow(void **p, int *cap, int need, size_t size)
{
    if (need <= *cap) return 0;
    int c = *cap > 0 ? *cap : 64;
    while (c < need) c *= 2;
    void *q = realloc(*p, (size_t)c * size);
    if (!q) return -1;
    *p = q;
    *cap = c;
    return 0;
}

static double mstar_of(const lahar_dem_engine *e, int a, int b)
{
    const sp_geo *ga = &e->geo[a], *gb = &e->geo[b];
    int fa = ga->motion == LAHAR_MOTION_FREE, fb = gb->motion == LAHAR_MOTION_FREE;
    if (fa && fb) return ga->mass * gb->mass / (ga->mass + gb->mass);
    return fa ? ga->mass : gb->mass; /* fixed / prescribed partner: infinite mass */
}

/* Update world vertices, face polygons/normals and (non-free) boxes of body i. */
static void body_update_world(lahar_dem_engine *e, int i)
{
    sp_geo *g = &e->geo[i];
    sp_state *s = &e->st[i];
    for (int k = 0; k < g->nv; k++) e->vw[g->v0 + k] = v3_add(s->x, q_rotate(s->q, e->vb[g->v0 + k]));
    for (int f = 0; f < g->nf; f++) e->nw[g->f0 + f] = q_rotate(s->q, e->nb[g->f0 + f]);
    /* the face polygons of a body are consecutive in fv/fw */
    int nfv = g->nf > 0 ? e->fstart[g->fs0 + g->nf] - e->fstart[g->fs0] : 0;
    const int *fv = e->fv + (g->nf > 0 ? e->fstart[g->fs0] : 0);
    vec3 *fw = e->fw + (g->nf > 0 ? e->fstart[g->fs0] : 0);
    const vec3 *vw = e->vw + g->v0;
    for (int k = 0; k < nfv; k++) fw[k] = vw[fv[k]];
    if (g->motion == LAHAR_MOTION_FREE) return; /* free bodies are binned by centre, not by box */
    vec3 lo = v3(DBL_MAX, DBL_MAX, DBL_MAX), hi = v3(-DBL_MAX, -DBL_MAX, -DBL_MAX);
    for (int k = 0; k < g->nv; k++) {
        vec3 w = e->vw[g->v0 + k];
        lo = v3(fmin(lo.x, w.x), fmin(lo.y, w.y), fmin(lo.z, w.z));
        hi = v3(fmax(hi.x, w.x), fmax(hi.y, w.y), fmax(hi.z, w.z));
    }
    vec3 r = v3(g->radius, g->radius, g->radius);
    g->aabb_lo = v3_sub(lo, r);
    g->aabb_hi = v3_add(hi, r);
}

/* World angular velocity from the angular momentum: w = R I^-1 R^T L (2D: about z only). */
static void body_update_omega(lahar_dem_engine *e, int i)
{
    sp_geo *g = &e->geo[i];
    sp_state *s = &e->st[i];
    if (e->dim == 2) {
        s->w = v3(0.0, 0.0, s->L.z / g->inertia[2]);
        return;
    }
    if (g->isotropic) {
        s->w = v3_scale(s->L, 1.0 / g->inertia[0]);
        return;
    }
    vec3 pb = q_rotate_inv(s->q, s->L);
    vec3 wb = v3(pb.x / g->inertia[0], pb.y / g->inertia[1], pb.z / g->inertia[2]);
    s->w = q_rotate(s->q, wb);
}

/* ---------------------------------------------------------------------------------------------- */
/* Narrow phase                                                                                    */

typedef struct {
    const lahar_dem_engine *e;
    int a, b;
    const dem_pair_law *law;
    double mstar, h;
    sp_thread *t;
} sp_pair_ctx;

static uint64_t contact_key_hash(int a, int b, int type, int fa, int fb)
{
    uint64_t k = (uint64_t)(uint32_t)a * 0x9E3779B97F4A7C15ull;
    k ^= (uint64_t)(uint32_t)b + 0x7F4A7C159E3779B9ull + (k << 6) + (k >> 2);
    k ^= (uint64_t)(uint32_t)type * 0xBF58476D1CE4E5B9ull + (k << 6) + (k >> 2);
    k ^= (uint64_t)(uint32_t)fa * 0x94D049BB133111EBull + (k << 6) + (k >> 2);
    k ^= (uint64_t)(uint32_t)fb + 0x2545F4914F6CDD1Dull + (k << 6) + (k >> 2);
    k ^= k >> 31;
    return k;
}

static const sp_contact *history_find(const lahar_dem_engine *e, int a, int b, int type, int fa, int fb)
{
    if (e->nprev == 0) return NULL;
    uint64_t m = (uint64_t)e->hash_n - 1;
    for (uint64_t h = contact_key_hash(a, b, type, fa, fb) & m;; h = (h + 1) & m) {
        int i = e->hash[h];
        if (i < 0) return NULL;
        const sp_contact *c = &e->prev[i];
        if (c->a == a && c->b == b && c->type == type && c->fa == fa && c->fb == fb) return c;
    }
}

/* The vertex a contact hangs on (side 0: a vertex of body a, 1: of body b), -1 for edge-edge. */
static int contact_vertex(int type, int fa, int fb, int *side)
{
    *side = (type == SP_FV || type == SP_EV) ? 1 : 0;
    if (type == SP_EE) return -1;
    return *side ? fb : fa;
}

/* When a vertex slides from one feature of the other body to the next (a rock rolling across the
 * triangles of a terrain), the contact gets a new key. It inherits the spring of the previous
 * contact of the same vertex and body pair if that one had about the same normal (within ~8 deg)
 * and a nearby contact point, so that rolling/sticking does not restart at every mesh edge. */
static const sp_contact *history_find_moved(const lahar_dem_engine *e, int a, int b, int type, int fa, int fb,
                                            vec3 n, vec3 cp, double reach)
{
    int side, v = contact_vertex(type, fa, fb, &side);
    if (e->nprev == 0 || v < 0) return NULL;
    uint64_t m = (uint64_t)e->hash_n - 1;
    const sp_contact *best = NULL;
    double bestd = reach * reach;
    for (uint64_t h = contact_key_hash(a, b, 100 + side, v, -1) & m;; h = (h + 1) & m) {
        int i = e->vhash[h];
        if (i < 0) return best;
        const sp_contact *c = &e->prev[i];
        int cs, cv = contact_vertex(c->type, c->fa, c->fb, &cs);
        if (c->a != a || c->b != b || cs != side || cv != v || v3_dot(c->n, n) < 0.99) continue;
        double d2 = v3_norm2(v3_sub(c->cp, cp));
        if (d2 < bestd) {
            bestd = d2;
            best = c;
        }
    }
}

static int history_rebuild(lahar_dem_engine *e)
{
    int need = 16;
    while (need < 2 * e->nprev) need *= 2;
    if (need > e->hash_cap) {
        int cap = need > 2 * e->hash_cap ? need : 2 * e->hash_cap; /* at least double: grow rarely */
        int *h = realloc(e->hash, sizeof(int) * (size_t)cap);
        if (!h) return -1;
        e->hash = h;
        h = realloc(e->vhash, sizeof(int) * (size_t)cap);
        if (!h) return -1;
        e->vhash = h;
        e->hash_cap = cap;
    }
    e->hash_n = need;
    memset(e->hash, 0xff, sizeof(int) * (size_t)need);
    memset(e->vhash, 0xff, sizeof(int) * (size_t)need);
    uint64_t m = (uint64_t)need - 1;
    for (int i = 0; i < e->nprev; i++) {
        const sp_contact *c = &e->prev[i];
        uint64_t h = contact_key_hash(c->a, c->b, c->type, c->fa, c->fb) & m;
        while (e->hash[h] >= 0) h = (h + 1) & m;
        e->hash[h] = i;
        int side, v = contact_vertex(c->type, c->fa, c->fb, &side);
        if (v < 0) continue;
        h = contact_key_hash(c->a, c->b, 100 + side, v, -1) & m;
        while (e->vhash[h] >= 0) h = (h + 1) & m;
        e->vhash[h] = i;
    }
    return 0;
}

/* A feature pair whose cores are at pa (on a) and pb (on b): a contact when the swept surfaces
 * overlap. a_flat / b_flat: the feature is a face (infinite curvature radius for Hertz). Records
 * the geometry and the spring carried over from the last step; pair_forces adds the forces. */
static void contact_emit(sp_pair_ctx *x, int type, int fa, int fb, vec3 pa, vec3 pb, int a_flat, int b_flat,
                         vec3 fallback_n)
{
    const lahar_dem_engine *e = x->e;
    const sp_geo *ga = &e->geo[x->a], *gb = &e->geo[x->b];
    double rsum = ga->radius + gb->radius;
    vec3 dvec = v3_sub(pb, pa);
    double d2 = v3_norm2(dvec);
    if (d2 >= rsum * rsum) return;
    double d = sqrt(d2);
    vec3 n = d > 1e-12 * rsum ? v3_scale(dvec, 1.0 / d) : fallback_n;
    /* contact point in the middle of the overlap */
    vec3 cp = v3_scale(v3_add(v3_axpy(ga->radius, n, pa), v3_axpy(-gb->radius, n, pb)), 0.5);
    /* tangential spring from the last step, rotated onto the current tangent plane (magnitude kept) */
    vec3 xi = v3(0.0, 0.0, 0.0);
    const sp_contact *old = history_find(e, x->a, x->b, type, fa, fb);
    if (!old) old = history_find_moved(e, x->a, x->b, type, fa, fb, n, cp, 0.5 * rsum);
    if (old) {
        double m0 = v3_norm(old->xi);
        xi = v3_axpy(-v3_dot(old->xi, n), n, old->xi);
        double m1 = v3_norm(xi);
        if (m1 > 0.0) xi = v3_scale(xi, m0 / m1);
    }
    sp_thread *t = x->t;
    if (t->n == t->cap && grow((void **)&t->c, &t->cap, t->n + 1, sizeof(sp_contact))) {
        t->oom = 1;
        return;
    }
    sp_contact *o = &t->c[t->n++];
    o->a = x->a;
    o->b = x->b;
    o->type = type;
    o->fa = fa;
    o->fb = fb;
    o->xi = xi;
    o->f = v3(0.0, 0.0, 0.0);
    o->cp = cp;
    o->n = n;
    o->delta = rsum - d;
    /* R*: sweep radius for a vertex or edge, infinite for a face (Canelas et al. 2015 eq. 16) */
    o->rstar = a_flat ? gb->radius : (b_flat ? ga->radius : ga->radius * gb->radius / rsum);
}

/* Forces of the contacts c[0..n) of one body pair. Each point has the pair's spring and dashpot;
 * k points pressing along the same normal (a face lying on a face: 4 corners) act in parallel as a
 * spring k kn with dashpot k c, whose damping ratio would be sqrt(k) zeta. Dividing each dashpot by
 * sqrt(k) keeps the requested restitution for flat impacts (README, "multi-point contacts"). */
static void pair_forces(const sp_pair_ctx *x, sp_contact *c, int n)
{
    const lahar_dem_engine *e = x->e;
    const sp_state *sa = &e->st[x->a], *sb = &e->st[x->b];
    for (int i = 0; i < n; i++) {
        sp_contact *o = &c[i];
        int k = 0;
        for (int j = 0; j < n; j++) k += v3_dot(o->n, c[j].n) > 0.9; /* within ~25 deg, itself included */
        vec3 va = v3_add(sa->v, v3_cross(sa->w, v3_sub(o->cp, sa->x)));
        vec3 vb = v3_add(sb->v, v3_cross(sb->w, v3_sub(o->cp, sb->x)));
        vec3 vr = v3_sub(vb, va);
        double vn = v3_dot(vr, o->n);
        vec3 vt = v3_axpy(-vn, o->n, vr);
        double ks, cn;
        double fn = dem_normal_force(x->law, o->delta, -vn, x->mstar, o->rstar, 1.0 / sqrt((double)k), &ks, &cn);
        o->xi = v3_axpy(x->h, vt, o->xi);
        vec3 ft = dem_tangential_force(x->law, &o->xi, vt, fn, ks, cn);
        o->f = v3_axpy(fn, o->n, ft);
    }
}

/* Features of one side of a pair: all of them, or the candidates from its feature grid. */
typedef struct {
    int body, nv, ne, nf;
    const int *v, *e, *f; /* NULL = 0..n-1 */
} sp_side;

static inline int side_id(const int *list, int k) { return list ? list[k] : k; }

/* Is world point p in the Voronoi region of vertex i of body g (all its edges point away)? */
static int vertex_region(const lahar_dem_engine *e, const sp_geo *g, int i, vec3 p)
{
    vec3 vi = e->vw[g->v0 + i];
    vec3 dp = v3_sub(p, vi);
    for (int k = e->vadj_start[g->va0 + i]; k < e->vadj_start[g->va0 + i + 1]; k++)
        if (v3_dot(dp, v3_sub(e->vw[g->v0 + e->vadj[k]], vi)) > 0.0) return 0;
    return 1;
}

/* Does p project inside one of the faces adjacent to edge j of body g? (then vertex-face owns it) */
static int edge_face_owns(const lahar_dem_engine *e, const sp_geo *g, int j, vec3 p)
{
    if (e->dim == 2) return 0;
    for (int s = 0; s < 2; s++) {
        int f = e->edge_face[g->e0 + j][s];
        if (f < 0) continue;
        int b = e->fstart[g->fs0 + f], m = e->fstart[g->fs0 + f + 1] - b;
        if (m >= 3 && geom_point_polygon_inside(p, e->fw + b, m, e->nw[g->f0 + f], NULL)) return 1;
    }
    return 0;
}

/* vertex i of body gv against face f of body gf; v_is_a: the vertex belongs to body a */
static void test_vertex_face(sp_pair_ctx *x, const sp_geo *gv, int i, const sp_geo *gf, int f, int v_is_a)
{
    const lahar_dem_engine *e = x->e;
    vec3 p = e->vw[gv->v0 + i];
    vec3 nrm = e->nw[gf->f0 + f];
    double rsum = gv->radius + gf->radius;
    double dplane = v3_dot(v3_sub(p, e->fw[e->fstart[gf->fs0 + f]]), nrm);
    if (fabs(dplane) >= rsum) return;
    int b = e->fstart[gf->fs0 + f], m = e->fstart[gf->fs0 + f + 1] - b;
    vec3 c;
    if (m < 3 || !geom_point_polygon_inside(p, e->fw + b, m, nrm, &c)) return; /* outside the face: an edge or
                                                                                  vertex contact owns it */
    vec3 side = dplane >= 0.0 ? nrm : v3_neg(nrm); /* from the face towards the vertex */
    if (v_is_a) contact_emit(x, SP_VF, i, f, p, c, 0, 1, v3_neg(side));
    else contact_emit(x, SP_FV, f, i, c, p, 1, 0, side);
}

static void test_vertex_edge(sp_pair_ctx *x, const sp_geo *gv, int i, const sp_geo *ge, int j, int v_is_a)
{
    const lahar_dem_engine *e = x->e;
    vec3 p = e->vw[gv->v0 + i];
    vec3 q0 = e->vw[ge->v0 + e->edge[ge->e0 + j][0]], q1 = e->vw[ge->v0 + e->edge[ge->e0 + j][1]];
    double t;
    double rsum = gv->radius + ge->radius;
    if (geom_point_segment_dist2(p, q0, q1, &t) >= rsum * rsum || t <= 0.0 || t >= 1.0) return; /* ends: vertex-vertex */
    vec3 c = v3_axpy(t, v3_sub(q1, q0), q0);
    if (edge_face_owns(e, ge, j, p)) return;
    vec3 dir = v3_normalize(v3_sub(e->st[x->b].x, e->st[x->a].x));
    if (v_is_a) contact_emit(x, SP_VE, i, j, p, c, 0, 0, dir);
    else contact_emit(x, SP_EV, j, i, c, p, 0, 0, dir);
}

static void pair_narrow(sp_pair_ctx *x, const sp_side *A, const sp_side *B)
{
    const lahar_dem_engine *e = x->e;
    const sp_geo *ga = &e->geo[A->body], *gb = &e->geo[B->body];
    double rsum = ga->radius + gb->radius;
    int three_d = e->dim == 3;
    vec3 dir_ab = v3_normalize(v3_sub(e->st[B->body].x, e->st[A->body].x));
    if (three_d) {
        for (int k = 0; k < A->nv; k++)
            for (int l = 0; l < B->nf; l++) test_vertex_face(x, ga, side_id(A->v, k), gb, side_id(B->f, l), 1);
        for (int l = 0; l < B->nv; l++)
            for (int k = 0; k < A->nf; k++) test_vertex_face(x, gb, side_id(B->v, l), ga, side_id(A->f, k), 0);
        /* edge-edge only when the closest points are interior to both edges and the edges are not
         * parallel (then vertex-edge contacts at the ends carry the load) */
        /* Prefilter: two segments are at least |m_a - m_b| - h_a - h_b apart (midpoints m,
         * half-lengths h), so pairs with that bound >= rsum (plus a margin for rounding) cannot
         * touch and skip the closest-point computation without changing any result. */
        vec3 *emid = x->t->emid;
        double *ehalf = x->t->ehalf;
        for (int l = 0; l < B->ne; l++) {
            int j = side_id(B->e, l);
            vec3 q0 = e->vw[gb->v0 + e->edge[gb->e0 + j][0]], q1 = e->vw[gb->v0 + e->edge[gb->e0 + j][1]];
            emid[l] = v3_scale(v3_add(q0, q1), 0.5);
            ehalf[l] = 0.5 * v3_norm(v3_sub(q1, q0));
        }
        for (int k = 0; k < A->ne; k++) {
            int i = side_id(A->e, k);
            vec3 p0 = e->vw[ga->v0 + e->edge[ga->e0 + i][0]], p1 = e->vw[ga->v0 + e->edge[ga->e0 + i][1]];
            vec3 da = v3_sub(p1, p0);
            vec3 ma = v3_scale(v3_add(p0, p1), 0.5);
            double ha = 0.5 * v3_norm(da);
            for (int l = 0; l < B->ne; l++) {
                double reach = (ha + ehalf[l] + rsum) * (1.0 + 1e-9);
                if (v3_norm2(v3_sub(emid[l], ma)) > reach * reach) continue;
                int j = side_id(B->e, l);
                vec3 q0 = e->vw[gb->v0 + e->edge[gb->e0 + j][0]], q1 = e->vw[gb->v0 + e->edge[gb->e0 + j][1]];
                vec3 db = v3_sub(q1, q0);
                vec3 cr = v3_cross(da, db);
                if (v3_norm2(cr) <= 1e-6 * v3_norm2(da) * v3_norm2(db)) continue; /* within ~0.06 deg */
                vec3 cp, cq;
                double s, t;
                double d = geom_segment_segment_param(p0, p1, q0, q1, &s, &t, &cp, &cq);
                if (d >= rsum || s <= 0.0 || s >= 1.0 || t <= 0.0 || t >= 1.0) continue;
                vec3 fbn = v3_normalize(cr);
                if (v3_dot(fbn, dir_ab) < 0.0) fbn = v3_neg(fbn);
                contact_emit(x, SP_EE, i, j, cp, cq, 0, 0, fbn);
            }
        }
    }
    for (int k = 0; k < A->nv; k++)
        for (int l = 0; l < B->ne; l++) test_vertex_edge(x, ga, side_id(A->v, k), gb, side_id(B->e, l), 1);
    for (int l = 0; l < B->nv; l++)
        for (int k = 0; k < A->ne; k++) test_vertex_edge(x, gb, side_id(B->v, l), ga, side_id(A->e, k), 0);
    for (int k = 0; k < A->nv; k++) {
        int i = side_id(A->v, k);
        vec3 p = e->vw[ga->v0 + i];
        for (int l = 0; l < B->nv; l++) {
            int j = side_id(B->v, l);
            vec3 q = e->vw[gb->v0 + j];
            if (v3_norm2(v3_sub(p, q)) >= rsum * rsum) continue;
            if (!vertex_region(e, gb, j, p) || !vertex_region(e, ga, i, q)) continue;
            contact_emit(x, SP_VV, i, j, p, q, 0, 0, dir_ab);
        }
    }
}

static void side_filter(const lahar_dem_engine *e, sp_side *sd, const sp_geo *g, vec3 c, double rad, int *keep[3])
{
    double r2 = rad * rad;
    int n = 0;
    for (int k = 0; k < sd->nv; k++) {
        int i = side_id(sd->v, k);
        if (v3_norm2(v3_sub(e->vw[g->v0 + i], c)) < r2) keep[0][n++] = i;
    }
    sd->v = keep[0];
    sd->nv = n;
    n = 0;
    for (int k = 0; k < sd->ne; k++) {
        int i = side_id(sd->e, k);
        vec3 p0 = e->vw[g->v0 + e->edge[g->e0 + i][0]], p1 = e->vw[g->v0 + e->edge[g->e0 + i][1]];
        /* an end within reach keeps the edge without the segment distance (which is <= it) */
        if (v3_norm2(v3_sub(p0, c)) < r2 || v3_norm2(v3_sub(p1, c)) < r2 || geom_point_segment_dist2(c, p0, p1, NULL) < r2)
            keep[1][n++] = i;
    }
    sd->e = keep[1];
    sd->ne = n;
    n = 0;
    for (int k = 0; k < sd->nf; k++) {
        int i = side_id(sd->f, k);
        if (fabs(v3_dot(v3_sub(c, e->fw[e->fstart[g->fs0 + i]]), e->nw[g->f0 + i])) < rad) keep[2][n++] = i;
    }
    sd->f = keep[2];
    sd->nf = n;
}

/* All contacts of broad-phase pair (a, b), a < b, into the thread buffer. */
static void pair_contacts(lahar_dem_engine *e, int a, int b, double h, sp_thread *t)
{
    const sp_geo *ga = &e->geo[a], *gb = &e->geo[b];
    sp_pair_ctx x = {e, a, b, &e->laws[ga->material * e->nmat + gb->material], mstar_of(e, a, b), h, t};
    sp_side A = {a, ga->nv, ga->ne, e->dim == 3 ? ga->nf : 0, NULL, NULL, NULL};
    sp_side B = {b, gb->nv, gb->ne, e->dim == 3 ? gb->nf : 0, NULL, NULL, NULL};
    /* a big body (feature grid) is reduced to the features near the other's bounding ball */
    sp_side *big = NULL;
    const sp_geo *gbig = NULL, *gsmall = NULL;
    int ibig = -1, ismall = -1;
    if (ga->grid >= 0 && (gb->grid < 0 || ga->nv + ga->ne + ga->nf >= gb->nv + gb->ne + gb->nf)) {
        big = &A; gbig = ga; gsmall = gb; ibig = a; ismall = b;
    } else if (gb->grid >= 0) {
        big = &B; gbig = gb; gsmall = ga; ibig = b; ismall = a;
    }
    if (big) {
        vec3 c = q_rotate_inv(e->st[ibig].q, v3_sub(e->st[ismall].x, e->st[ibig].x));
        geom_feature_grid_query(&e->grids[gbig->grid], c, gsmall->bound, &t->fq);
        big->nv = t->fq.nout[GEOM_FEATURE_VERTEX];
        big->ne = t->fq.nout[GEOM_FEATURE_EDGE];
        big->nf = e->dim == 3 ? t->fq.nout[GEOM_FEATURE_FACE] : 0;
        big->v = t->fq.out[GEOM_FEATURE_VERTEX];
        big->e = t->fq.out[GEOM_FEATURE_EDGE];
        big->f = t->fq.out[GEOM_FEATURE_FACE];
    }
    /* keep only the features that can reach the other body's bounding ball: a feature of A
     * touches B only if its core is within bound_B + R_A of B's centre */
    side_filter(e, &A, ga, e->st[b].x, gb->bound + ga->radius, t->keep[0]);
    side_filter(e, &B, gb, e->st[a].x, ga->bound + gb->radius, t->keep[1]);
    if (!(A.nv || A.ne || A.nf) || !(B.nv || B.ne || B.nf)) return;
    int first = t->n;
    pair_narrow(&x, &A, &B);
    if (t->oom) return;
    /* Faces and edges own their boundaries inclusively, so a vertex exactly over a shared mesh edge
     * or vertex (a rock rolling along a grid line of a terrain) is found once per face: keep the
     * first of contacts at the same point with the same normal. */
    int n = first;
    for (int i = first; i < t->n; i++) {
        const sp_contact *c = &t->c[i];
        double tol2 = 1e-12 * (ga->radius + gb->radius) * (ga->radius + gb->radius);
        int dup = 0;
        for (int j = first; j < n && !dup; j++)
            dup = v3_norm2(v3_sub(t->c[j].cp, c->cp)) < tol2 && v3_dot(t->c[j].n, c->n) > 0.999999;
        if (!dup) t->c[n++] = *c;
    }
    t->n = n;
    pair_forces(&x, t->c + first, t->n - first);
}

/* ---------------------------------------------------------------------------------------------- */
/* Broad phase: free bodies binned by centre in a hashed uniform grid of cell >= the largest
 * bounding diameter (so neighbours are within the 27 surrounding cells, half of them visited); fixed and prescribed
 * bodies (few, possibly huge) are tested against every free body by box. O(N) per step. */

static uint32_t cell_hash(long long x, long long y, long long z)
{
    uint64_t h = (uint64_t)x * 73856093ull ^ (uint64_t)y * 19349663ull ^ (uint64_t)z * 83492791ull;
    h ^= h >> 29;
    h *= 0xBF58476D1CE4E5B9ull;
    h ^= h >> 32;
    return (uint32_t)h;
}

/* Bucket of a cell: dense index inside the bodies' box, -1 outside it; hashed otherwise. */
static inline int bucket_of_cell(const lahar_dem_engine *e, long long x, long long y, long long z)
{
    if (!e->dense) return (int)(cell_hash(x, y, z) & (uint32_t)(e->nhash - 1));
    x -= e->dlo[0];
    y -= e->dlo[1];
    z -= e->dlo[2];
    if (x < 0 || y < 0 || z < 0 || x >= e->dn[0] || y >= e->dn[1] || z >= e->dn[2]) return -1;
    return (int)((z * e->dn[1] + y) * e->dn[0] + x);
}

static int add_pair(lahar_dem_engine *e, int a, int b)
{
    if (e->npair == e->pair_cap && grow((void **)&e->pairs, &e->pair_cap, e->npair + 1, sizeof(int[2]))) return -1;
    e->pairs[e->npair][0] = a < b ? a : b;
    e->pairs[e->npair][1] = a < b ? b : a;
    e->npair++;
    return 0;
}

/* Bucket of a cell of level lev in the hashed grid. */
static inline int bucket_of_level_cell(const lahar_dem_engine *e, int lev, long long x, long long y, long long z)
{
    return (int)((cell_hash(x, y, z) ^ (uint32_t)lev * 0x9E3779B9u) & (uint32_t)(e->nhash - 1));
}

/* Cell of each free body at its own level (cellc), and the box lo..hi of those cells. */
static void cells_of_free(lahar_dem_engine *e, long long lo[3], long long hi[3])
{
    for (int d = 0; d < 3; d++) {
        lo[d] = LLONG_MAX;
        hi[d] = LLONG_MIN;
    }
    for (int k = 0; k < e->nfree; k++) {
        const sp_state *s = &e->st[e->free_ids[k]];
        double inv = e->cell_inv[e->level[k]];
        e->cellc[k][0] = (long long)floor(s->x.x * inv);
        e->cellc[k][1] = (long long)floor(s->x.y * inv);
        e->cellc[k][2] = e->dim == 3 ? (long long)floor(s->x.z * inv) : 0;
        for (int d = 0; d < 3; d++) {
            lo[d] = e->cellc[k][d] < lo[d] ? e->cellc[k][d] : lo[d];
            hi[d] = e->cellc[k][d] > hi[d] ? e->cellc[k][d] : hi[d];
        }
    }
}

/* The free bodies binned by bucket into bins, bucket_start[h] the first of bucket h. One level: a
 * dense grid over the bodies' box lo..hi when it is small enough (cache-friendly: bodies sorted by
 * cell, neighbours adjacent in memory), else hashed (any extent); several levels (sizes differing
 * by more than 2x): hashed on (level, cell). -1: no memory for the buckets. */
static int bin_free(lahar_dem_engine *e, const long long lo[3], const long long hi[3])
{
    double ncell = (double)(hi[0] - lo[0] + 1) * (double)(hi[1] - lo[1] + 1) * (double)(hi[2] - lo[2] + 1);
    e->dense = e->nlevel == 1 && ncell <= 8.0 * e->nfree + 1024.0;
    int nb = e->dense ? (int)ncell : e->nhash;
    for (int d = 0; d < 3; d++) {
        e->dlo[d] = lo[d];
        e->dn[d] = hi[d] - lo[d] + 1;
    }
    if (nb + 1 > e->bucket_cap) {
        int cap = e->bucket_cap;
        if (grow((void **)&e->bucket_start, &cap, nb + 1, sizeof(int))) return -1;
        e->bucket_cap = cap;
    }
    e->nbucket = nb;
    memset(e->bucket_start, 0, sizeof(int) * (size_t)(nb + 1));
    for (int k = 0; k < e->nfree; k++) {
        e->bucket_of[k] = e->nlevel == 1 ? bucket_of_cell(e, e->cellc[k][0], e->cellc[k][1], e->cellc[k][2])
                                         : bucket_of_level_cell(e, e->level[k], e->cellc[k][0], e->cellc[k][1],
                                                                e->cellc[k][2]);
        e->bucket_start[e->bucket_of[k] + 1]++;
    }
    for (int i = 0; i < nb; i++) e->bucket_start[i + 1] += e->bucket_start[i];
    /* counting sort into one cache line per body, so that a bucket is read contiguously */
    for (int k = 0; k < e->nfree; k++) {
        int i = e->free_ids[k];
        sp_bin *bn = &e->bins[e->bucket_start[e->bucket_of[k]]++];
        memcpy(bn->c, e->cellc[k], sizeof bn->c);
        bn->x = e->st[i].x;
        bn->bound = e->geo[i].bound;
        bn->id = i;
        bn->level = e->level[k];
    }
    for (int i = nb; i > 0; i--) e->bucket_start[i] = e->bucket_start[i - 1];
    e->bucket_start[0] = 0;
    return 0;
}

/* The pairs of binned free bodies whose bounding spheres overlap. Same level: the own cell
 * (partners j > i) and the half shell of 13 (2D: 4) neighbours after it in (z, y, x) order, so
 * that each pair is met once. Coarser levels (cell >= both diameters): all 27 (9) cells around
 * the body, so a pair of different levels is met once, from its smaller body. Two fast spheres
 * meet on the fast path, not here. -1: no memory for the pairs. */
static int pairs_of_free(lahar_dem_engine *e)
{
    int zr = e->dim == 3 ? 1 : 0;
    for (int mk = 0; mk < e->nfree; mk++) {
        const sp_bin bi = e->bins[mk];
        for (int lev = bi.level; lev < e->nlevel; lev++) {
            if (lev > bi.level && e->level_count[lev] == 0) continue;
            int same = lev == bi.level;
            long long c0[3] = {bi.c[0], bi.c[1], bi.c[2]};
            if (!same) {
                c0[0] = (long long)floor(bi.x.x * e->cell_inv[lev]);
                c0[1] = (long long)floor(bi.x.y * e->cell_inv[lev]);
                c0[2] = e->dim == 3 ? (long long)floor(bi.x.z * e->cell_inv[lev]) : 0;
            }
            for (int dz = same ? 0 : -zr; dz <= zr; dz++)
                for (int dy = (same && dz == 0) ? 0 : -1; dy <= 1; dy++)
                    for (int dx = (same && dz == 0 && dy == 0) ? 0 : -1; dx <= 1; dx++) {
                        int own = same && dz == 0 && dy == 0 && dx == 0;
                        long long cx = c0[0] + dx, cy = c0[1] + dy, cz = c0[2] + dz;
                        int h = e->nlevel == 1 ? bucket_of_cell(e, cx, cy, cz)
                                               : bucket_of_level_cell(e, lev, cx, cy, cz);
                        if (h < 0) continue;
                        for (int m = e->bucket_start[h]; m < e->bucket_start[h + 1]; m++) {
                            const sp_bin *bj = &e->bins[m];
                            if ((own && bj->id <= bi.id) || bj->level != lev || bj->c[0] != cx || bj->c[1] != cy ||
                                bj->c[2] != cz)
                                continue;
                            if (e->geo[bi.id].fast_sphere && e->geo[bj->id].fast_sphere) continue;
                            double r = bi.bound + bj->bound;
                            if (v3_norm2(v3_sub(bj->x, bi.x)) < r * r && add_pair(e, bi.id, bj->id)) return -1;
                        }
                    }
        }
    }
    return 0;
}

/* The pairs of a free body and a large (fixed or prescribed) body whose boxes overlap. A sphere
 * meets the fast path's walls there; only the other large bodies here. -1: no memory. */
static int pairs_with_large(lahar_dem_engine *e)
{
    const sp_spheres *sph = e->sph;
    const int *sph_large = NULL;
    int nsph_large = sph ? sps_general_large(e, &sph_large) : 0;
    /* without such bodies only the free bodies that are not spheres are visited */
    const int *fids = sph && nsph_large == 0 ? e->move_ids : e->free_ids;
    int nf = sph && nsph_large == 0 ? e->nmove_free : e->nfree;
    for (int k = 0; k < nf; k++) {
        int i = fids[k];
        const int *lids = e->large_ids;
        int nl = e->nlarge;
        if (e->geo[i].fast_sphere) {
            lids = sph_large;
            nl = nsph_large;
        }
        if (nl == 0) continue;
        vec3 c = e->st[i].x;
        double r = e->geo[i].bound;
        for (int l = 0; l < nl; l++) {
            const sp_geo *gl = &e->geo[lids[l]];
            if (c.x + r < gl->aabb_lo.x || c.x - r > gl->aabb_hi.x || c.y + r < gl->aabb_lo.y ||
                c.y - r > gl->aabb_hi.y || c.z + r < gl->aabb_lo.z || c.z - r > gl->aabb_hi.z)
                continue;
            if (add_pair(e, i, lids[l])) return -1;
        }
    }
    return 0;
}

/* The candidate pairs of the general path (e->pairs, npair of them): free with free, free with
 * large, and the spheres beyond a fast-path wall's rim. -1: no memory. */
static int broad_phase(lahar_dem_engine *e)
{
    e->npair = 0;
    const sp_spheres *sph = e->sph;
    /* free spheres meet each other on the fast path (spheropoly_spheres.c): with no other free
     * body there is nothing to bin */
    if (e->nfree > 0 && !(sph && e->nfree == sps_nspheres(e))) {
        long long lo[3], hi[3];
        cells_of_free(e, lo, hi);
        if (bin_free(e, lo, hi) || pairs_of_free(e)) return -1;
    }
    if (pairs_with_large(e)) return -1;
    /* spheres beyond the rim of a fast-path wall: edges and corners of the face */
    if (sph && sps_fallback_pairs(e, add_pair)) return -1;
    return 0;
}

/* ---------------------------------------------------------------------------------------------- */
/* Forces                                                                                          */

/* Contacts and contact forces at the current positions; h is the time since the last evaluation
 * (advances the tangential springs). Returns 0, or -1 with err set. */
static int compute_forces(lahar_dem_engine *e, double h, char *err, size_t errlen)
{
    if (e->sph && sps_forces(e, h, err, errlen)) return -1;
    if (e->sph && sps_needs_sync(e)) sps_sync(e); /* the general path reads the spheres' body states */
    if (broad_phase(e)) {
        snprintf(err, errlen, "spheropoly: out of memory in the broad phase");
        return -1;
    }
    int oom = 0;
    for (int t = 0; t < e->nthr; t++) e->thr[t].n = 0;
#pragma omp parallel num_threads(e->nthr) reduction(| : oom) if (e->npair >= 512)
    {
        sp_thread *t = &e->thr[omp_get_thread_num()];
        t->n = 0;
        t->oom = 0;
        /* static schedule: each thread takes one contiguous block of pairs in order, so
         * concatenating the thread buffers in thread order gives the contacts in pair order */
#pragma omp for schedule(static)
        for (int p = 0; p < e->npair; p++) pair_contacts(e, e->pairs[p][0], e->pairs[p][1], h, t);
        oom |= t->oom;
    }
    int total = 0;
    for (int t = 0; t < e->nthr; t++) total += e->thr[t].n; /* threads beyond the team size left n = 0 */
    if (oom || total > e->contact_cap) {
        int cap = e->contact_cap, cap2 = e->contact_cap;
        if (oom || grow((void **)&e->cur, &cap, total, sizeof(sp_contact)) ||
            grow((void **)&e->prev, &cap2, total, sizeof(sp_contact))) {
            snprintf(err, errlen, "spheropoly: out of memory for %d contacts", total);
            return -1;
        }
        e->contact_cap = cap < cap2 ? cap : cap2;
    }
    int n = 0;
    for (int t = 0; t < e->nthr; t++) {
        if (e->thr[t].n) memcpy(e->cur + n, e->thr[t].c, sizeof(sp_contact) * (size_t)e->thr[t].n);
        n += e->thr[t].n;
    }
    /* the new contacts become the history of the next evaluation */
    sp_contact *tmp = e->prev;
    e->prev = e->cur;
    e->cur = tmp;
    e->nprev = n;
    e->contacts_evaluated += n;
    if (history_rebuild(e)) {
        snprintf(err, errlen, "spheropoly: out of memory for the contact history");
        return -1;
    }
    /* serial accumulation in contact order: bitwise deterministic for any thread count. The fast
     * path's spheres start from their fast-path sums (sps_accumulate), the other bodies from 0. */
    if (e->sph) {
        /* no general contact on a sphere: its force is its fast-path sum, which the next kick
         * takes straight from the fast path (sps_kick) instead of a pass over the body states */
        int defer = 1;
        for (int k = 0; k < n && defer; k++) defer = !e->geo[e->prev[k].a].fast_sphere && !e->geo[e->prev[k].b].fast_sphere;
        if (defer) sps_defer(e);
        else sps_accumulate(e);
    }
    int nother = e->sph ? e->nother : e->nbody;
    for (int k = 0; k < nother; k++) {
        int i = e->sph ? e->other_ids[k] : k;
        e->st[i].fc = v3(0.0, 0.0, 0.0);
        e->st[i].tc = v3(0.0, 0.0, 0.0);
        e->ncontact_body[i] = 0;
    }
    if (e->sph) sps_accumulate_walls(e);
    for (int k = 0; k < n; k++) {
        const sp_contact *c = &e->prev[k];
        sp_state *sa = &e->st[c->a], *sb = &e->st[c->b];
        sa->fc = v3_sub(sa->fc, c->f);
        sb->fc = v3_add(sb->fc, c->f);
        sa->tc = v3_sub(sa->tc, v3_cross(v3_sub(c->cp, sa->x), c->f));
        sb->tc = v3_add(sb->tc, v3_cross(v3_sub(c->cp, sb->x), c->f));
        e->ncontact_body[c->a]++;
        e->ncontact_body[c->b]++;
        /* the sweep radii are the contact halo of a sphero-polyhedron: an overlap of the smaller
         * one lets a core reach into the other body, where the contact normal is lost */
        double rmin = fmin(e->geo[c->a].radius, e->geo[c->b].radius);
        if (c->delta > e->max_overlap * rmin) {
            snprintf(err, errlen,
                     "spheropoly: overlap %.3g m between bodies %d '%s' and %d '%s' exceeds %g x the smaller "
                     "sweep radius %.3g m at substep %ld (time step too large or bodies interpenetrating)",
                     c->delta, c->a, e->names[c->a], c->b, e->names[c->b], e->max_overlap, rmin, e->step);
            /* the free body of the pair is the one to name (a wall does not move) */
            int a = e->geo[c->a].motion == LAHAR_MOTION_FREE ? c->a : c->b, b = a == c->a ? c->b : c->a;
            e->fault = (lahar_dem_fault){.body = a, .other = b, .value = c->delta, .limit = e->max_overlap * rmin,
                                         .substep = e->step};
            snprintf(e->fault.what, sizeof e->fault.what, "overlap");
            v3_store(c->cp, e->fault.x);
            e->has_fault = 1;
            return -1;
        }
    }
    if (e->dim == 2)
        for (int i = 0; i < e->nbody; i++) {
            e->st[i].fc.z = 0.0;
            e->st[i].tc.x = e->st[i].tc.y = 0.0;
        }
    return 0;
}

/* ---------------------------------------------------------------------------------------------- */
/* Integration                                                                                     */

/* Exact free rotation about body axis k for time tau: the flow of H_k = Pi_k^2 / (2 I_k). */
static void rotate_about_axis(quat *q, vec3 *pi, const double inertia[3], int k, double tau)
{
    if (!(inertia[k] > 0.0)) return;
    double pk = v3_get(*pi, k);
    double th = tau * pk / inertia[k];
    vec3 axis = v3(k == 0, k == 1, k == 2);
    *q = q_mul(*q, q_axis_angle(axis, th));
    /* Pi is the body-frame angular momentum: the body turns by +th, Pi turns by -th */
    double c = cos(th), s = sin(th);
    if (k == 0) *pi = v3(pi->x, c * pi->y + s * pi->z, -s * pi->y + c * pi->z);
    else if (k == 1) *pi = v3(c * pi->x - s * pi->z, pi->y, s * pi->x + c * pi->z);
    else *pi = v3(c * pi->x + s * pi->y, -s * pi->x + c * pi->y, pi->z);
}

/* hdrift > 0: the spheres drift right after their kick (one pass; drift() leaves them out) */
static void kick(lahar_dem_engine *e, double half, const lahar_body_load *loads, double hdrift)
{
    /* each body only writes its own state: bitwise the same on any thread count */
    /* free spheres have their own loop (spheropoly_spheres.c), the others are listed in move_ids */
    if (e->sph) sps_kick(e, half, loads, hdrift);
    const int *ids = e->sph ? e->move_ids : e->free_ids;
    int nids = e->sph ? e->nmove_free : e->nfree;
#pragma omp parallel for schedule(static) num_threads(e->nthr) if (nids >= SP_PAR_MIN_BODIES)
    for (int k = 0; k < nids; k++) {
        int i = ids[k];
        sp_state *s = &e->st[i];
        double m = e->geo[i].mass;
        vec3 f = v3_axpy(m, e->g, s->fc), t = s->tc;
        if (loads) {
            f = v3_add(f, v3_load(loads[i].force));
            t = v3_add(t, v3_load(loads[i].torque));
        }
        if (e->dim == 2) {
            f.z = 0.0;
            t.x = t.y = 0.0;
        }
        s->v = v3_axpy(half / m, f, s->v);
        s->L = v3_axpy(half, t, s->L);
        body_update_omega(e, i);
    }
}

static void drift(lahar_dem_engine *e, double h)
{
    int nids = e->sph ? e->nmove : e->nbody;
#pragma omp parallel for schedule(static) num_threads(e->nthr) if (nids >= SP_PAR_MIN_BODIES)
    for (int k = 0; k < nids; k++) {
        int i = e->sph ? e->move_ids[k] : k;
        sp_geo *g = &e->geo[i];
        sp_state *s = &e->st[i];
        if (g->motion == LAHAR_MOTION_FIXED) continue;
        s->x = v3_axpy(h, s->v, s->x);
        if (g->motion == LAHAR_MOTION_PRESCRIBED) {
            double wn = v3_norm(s->w);
            if (wn > 0.0) s->q = q_normalize(q_mul(q_axis_angle(v3_scale(s->w, 1.0 / wn), wn * h), s->q));
        } else if (e->dim == 2) {
            s->q = q_normalize(q_mul(q_axis_angle(v3(0.0, 0.0, 1.0), h * s->L.z / g->inertia[2]), s->q));
        } else if (g->isotropic) {
            /* equal moments: w = L / I is constant, the free motion is one rotation by |w| h */
            double wn = v3_norm(s->L) / g->inertia[0];
            if (wn > 0.0) s->q = q_normalize(q_mul(q_axis_angle(v3_scale(s->L, 1.0 / v3_norm(s->L)), wn * h), s->q));
        } else {
            /* symmetric splitting X(h/2) Y(h/2) Z(h) Y(h/2) X(h/2) of the free rigid body, each an
             * exact rotation: Dullweber, Leimkuhler & McLachlan, J. Chem. Phys. 107 (1997) 5840 */
            vec3 pi = q_rotate_inv(s->q, s->L);
            rotate_about_axis(&s->q, &pi, g->inertia, 0, 0.5 * h);
            rotate_about_axis(&s->q, &pi, g->inertia, 1, 0.5 * h);
            rotate_about_axis(&s->q, &pi, g->inertia, 2, h);
            rotate_about_axis(&s->q, &pi, g->inertia, 1, 0.5 * h);
            rotate_about_axis(&s->q, &pi, g->inertia, 0, 0.5 * h);
            s->q = q_normalize(s->q);
        }
        if (g->motion == LAHAR_MOTION_FREE) body_update_omega(e, i);
        body_update_world(e, i);
    }
}

/* Non-finite or runaway states stop the run before they reach the grid (cell indices of a NaN or
 * of 1e300 would overflow). */
static int check_finite(lahar_dem_engine *e, char *err, size_t errlen)
{
    /* quick pass: the spheres on their compact copy, then the other free bodies; the full loop
     * below only runs to name the first offender */
    if (e->sph && sps_finite(e)) {
        int ok = 1;
        for (int k = 0; k < e->nmove_free && ok; k++) {
            const sp_state *s = &e->st[e->move_ids[k]];
            double sum = s->x.x + s->x.y + s->x.z + s->v.x + s->v.y + s->v.z + s->L.x + s->L.y + s->L.z + s->q.w;
            ok = isfinite(sum) && fabs(s->x.x) <= 1e12 && fabs(s->x.y) <= 1e12 && fabs(s->x.z) <= 1e12;
        }
        if (ok) return 0;
    }
    for (int k = 0; k < e->nfree; k++) {
        int i = e->free_ids[k];
        const sp_state st = sps_state(e, i), *s = &st;
        double sum = s->x.x + s->x.y + s->x.z + s->v.x + s->v.y + s->v.z + s->L.x + s->L.y + s->L.z + s->q.w;
        if (isfinite(sum) && fabs(s->x.x) <= 1e12 && fabs(s->x.y) <= 1e12 && fabs(s->x.z) <= 1e12) continue;
        double far = fmax(fabs(s->x.x), fmax(fabs(s->x.y), fabs(s->x.z)));
        {
            snprintf(err, errlen, "spheropoly: body %d '%s' has a %s state at substep %ld", i, e->names[i],
                     isfinite(sum) ? "runaway (|x| > 1e12 m)" : "non-finite", e->step);
            lahar_dem_fault *f = &e->fault;
            *f = (lahar_dem_fault){.body = i, .other = -1, .value = isfinite(sum) ? far : NAN,
                                   .limit = isfinite(sum) ? 1e12 : NAN, .substep = e->step};
            snprintf(f->what, sizeof f->what, "%s", isfinite(sum) ? "runaway" : "non-finite state");
            v3_store(s->x, f->x);
            e->has_fault = 1;
            return -1;
        }
    }
    return 0;
}

static int sp_advance(lahar_dem_engine *e, double dt, const lahar_body_load *loads, char *err, size_t errlen)
{
    e->has_fault = 0;
    if (!(dt > 0.0)) {
        snprintf(err, errlen, "spheropoly: step %g must be positive", dt);
        return -1;
    }
    int n = (int)dem_substeps(dt, e->dt_stable);
    double h = dt / n;
    /* the report averages fc + load over the substeps; one substep without loads: the state's fc/tc */
    int average = !(n == 1 && !loads);
    if (average)
        for (int i = 0; i < e->nbody; i++) e->rep_f[i] = e->rep_t[i] = v3(0.0, 0.0, 0.0);
    for (int k = 0; k < n; k++) {
        kick(e, 0.5 * h, loads, h);
        drift(e, h);
        e->step++;
        if (check_finite(e, err, errlen) || compute_forces(e, h, err, errlen)) return -1;
        kick(e, 0.5 * h, loads, 0.0);
        if (check_finite(e, err, errlen)) return -1;
        if (!average) continue;
        for (int i = 0; i < e->nbody; i++) {
            vec3 f, t;
            sps_fc(e, i, &f, &t);
            if (loads) {
                f = v3_add(f, v3_load(loads[i].force));
                t = v3_add(t, v3_load(loads[i].torque));
            }
            e->rep_f[i] = v3_add(e->rep_f[i], f);
            e->rep_t[i] = v3_add(e->rep_t[i], t);
        }
    }
    for (int i = 0; average && i < e->nbody; i++) {
        e->rep_f[i] = v3_scale(e->rep_f[i], 1.0 / n);
        e->rep_t[i] = v3_scale(e->rep_t[i], 1.0 / n);
    }
    e->rep_n = average ? n : 0;
    return n;
}

/* ---------------------------------------------------------------------------------------------- */
/* Setup                                                                                           */

static int sp_fault(const lahar_dem_engine *e, lahar_dem_fault *out)
{
    if (e->has_fault)
        *out = e->fault;
    return e->has_fault;
}

static void sp_destroy(lahar_dem_engine *e)
{
    if (!e) return;
    sps_destroy(e);
    for (int i = 0; i < e->ngrid; i++) geom_feature_grid_free(&e->grids[i]);
    if (e->thr)
        for (int t = 0; t < e->nthr; t++) {
            free(e->thr[t].c);
            free(e->thr[t].emid);
            free(e->thr[t].ehalf);
            geom_feature_query_free(&e->thr[t].fq);
            for (int sd = 0; sd < 2; sd++)
                for (int k = 0; k < 3; k++) free(e->thr[t].keep[sd][k]);
        }
    free(e->thr);
    free(e->grids);
    free(e->geo);
    free(e->st);
    free(e->names);
    free(e->laws);
    free(e->vb);
    free(e->vw);
    free(e->vadj_start);
    free(e->vadj);
    free(e->edge);
    free(e->edge_face);
    free(e->fstart);
    free(e->fv);
    free(e->fw);
    free(e->nb);
    free(e->nw);
    free(e->free_ids);
    free(e->large_ids);
    free(e->cellc);
    free(e->level);
    free(e->bucket_start);
    free(e->bucket_of);
    free(e->bins);
    free(e->pairs);
    free(e->prev);
    free(e->cur);
    free(e->hash);
    free(e->vhash);
    free(e->rep_f);
    free(e->rep_t);
    free(e->ncontact_body);
    free(e);
}

/* Engine-wide stable step: dem_dt_safety x the shortest contact period over the free bodies and
 * every material they may touch (see README: m* = m/2 against other free bodies, m against fixed
 * ones; Hertz at the impact speed of a fall across the whole scene). */
static double stable_dt_of(const lahar_dem_engine *e, const lahar_case *c)
{
    double safety = c->dem_dt_safety > 0.0 ? c->dem_dt_safety : 0.02;
    vec3 lo = v3(DBL_MAX, DBL_MAX, DBL_MAX), hi = v3(-DBL_MAX, -DBL_MAX, -DBL_MAX);
    double vmax = 0.0;
    for (int i = 0; i < e->nbody; i++) {
        const sp_geo *g = &e->geo[i];
        for (int k = 0; k < g->nv; k++) {
            vec3 w = e->vw[g->v0 + k];
            lo = v3(fmin(lo.x, w.x), fmin(lo.y, w.y), fmin(lo.z, w.z));
            hi = v3(fmax(hi.x, w.x), fmax(hi.y, w.y), fmax(hi.z, w.z));
        }
        double v = v3_norm(e->st[i].v) + v3_norm(e->st[i].w) * g->bound;
        if (v > vmax) vmax = v;
    }
    double extent = e->nbody > 0 ? v3_norm(v3_sub(hi, lo)) : 0.0;
    double vimpact = dem_impact_speed(vmax, v3_norm(e->g), extent);
    dem_step_body *sb = malloc((size_t)(e->nbody > 0 ? e->nbody : 1) * sizeof *sb);
    if (!sb) return 0.0; /* create reports it */
    for (int i = 0; i < e->nbody; i++)
        sb[i] = (dem_step_body){.material = e->geo[i].material, .free = e->geo[i].motion == LAHAR_MOTION_FREE,
                                .radius = e->geo[i].radius, .mass = e->geo[i].mass};
    double dt = dem_stable_dt(sb, e->nbody, e->laws, e->nmat, vimpact, safety, c->dt_max);
    free(sb);
    return dt;
}

static int build_topology(lahar_dem_engine *e, int i, const lahar_shape *s, char *err, size_t errlen)
{
    sp_geo *g = &e->geo[i];
    /* vertex neighbours through edges (CSR) */
    int *deg = e->vadj_start + g->va0;
    for (int k = 0; k <= s->nv; k++) deg[k] = 0;
    for (int k = 0; k < s->ne; k++) {
        int a = s->e[k][0], b = s->e[k][1];
        if (a < 0 || a >= s->nv || b < 0 || b >= s->nv) {
            snprintf(err, errlen, "spheropoly: body %d '%s': edge %d uses a missing vertex", i, e->names[i], k);
            return -1;
        }
        deg[a + 1]++;
        deg[b + 1]++;
    }
    for (int k = 0; k < s->nv; k++) deg[k + 1] += deg[k];
    int base = 2 * g->e0; /* each body owns 2 ne adjacency slots from 2 e0 */
    for (int k = 0; k <= s->nv; k++) deg[k] += base;
    int *fill = malloc(sizeof(int) * (size_t)(s->nv + 1));
    if (!fill) return -1;
    memcpy(fill, deg, sizeof(int) * (size_t)(s->nv + 1));
    for (int k = 0; k < s->ne; k++) {
        int a = s->e[k][0], b = s->e[k][1];
        e->vadj[fill[a]++] = b;
        e->vadj[fill[b]++] = a;
    }
    free(fill);
    /* faces adjacent to each edge: the faces using both its vertices consecutively */
    for (int k = 0; k < s->ne; k++) e->edge_face[g->e0 + k][0] = e->edge_face[g->e0 + k][1] = -1;
    for (int f = 0; f < s->nf; f++) {
        int b0 = s->face_start[f], m = s->face_start[f + 1] - b0;
        for (int j = 0; j < m; j++) {
            int va = s->face_v[b0 + j], vb = s->face_v[b0 + (j + 1) % m];
            for (int k = 0; k < s->ne; k++) {
                if (!((s->e[k][0] == va && s->e[k][1] == vb) || (s->e[k][0] == vb && s->e[k][1] == va))) continue;
                int *ef = e->edge_face[g->e0 + k];
                if (ef[0] < 0) ef[0] = f;
                else if (ef[1] < 0 && ef[0] != f) ef[1] = f;
            }
        }
    }
    return 0;
}

static int sp_oom(char *err, size_t errlen)
{
    snprintf(err, errlen, "spheropoly: out of memory");
    return -1;
}

/* Numbers of vertices, edges, faces and face-vertex entries: the pools' sizes, a body's offsets
 * into them, or the largest body with a feature grid. */
typedef struct {
    int nv, ne, nf, nfv;
} sp_counts;

static void set_scene_constants(lahar_dem_engine *e, const lahar_case *c)
{
    e->dim = c->dim == 2 ? 2 : 3;
    e->nbody = c->nbody;
    e->max_overlap = c->stability.max_overlap > 0.0 ? c->stability.max_overlap : 0.5; /* 0: a case built in code */
    e->nmat = c->nmaterial;
    e->g = v3_load(c->gravity);
    if (e->dim == 2) e->g.z = 0.0;
}

/* Every body's refusals come before anything is sized by it; tot gets the pools' sizes. */
static int check_bodies(const lahar_dem_engine *e, const lahar_case *c, int nb, sp_counts *tot, char *err,
                        size_t errlen)
{
    if (e->nmat <= 0 && nb > 0) {
        snprintf(err, errlen, "spheropoly: the case has bodies but no materials");
        return -1;
    }
    *tot = (sp_counts){0, 0, 0, 0};
    for (int i = 0; i < nb; i++) {
        const lahar_body *b = &c->bodies[i];
        const lahar_shape *s = &b->shape;
        if (b->material < 0 || b->material >= c->nmaterial) {
            snprintf(err, errlen, "spheropoly: body %d '%s': material index %d out of range", i, b->name, b->material);
            return -1;
        }
        if (s->nv < 1 || !(s->radius > 0.0)) {
            snprintf(err, errlen, "spheropoly: body %d '%s': needs at least one vertex and a sweep radius > 0", i, b->name);
            return -1;
        }
        if (b->motion == LAHAR_MOTION_FREE) {
            int bad = !(b->mass > 0.0) || !(b->inertia[2] > 0.0);
            if (e->dim == 3) bad |= !(b->inertia[0] > 0.0) || !(b->inertia[1] > 0.0);
            if (bad) {
                snprintf(err, errlen, "spheropoly: free body %d '%s' needs positive mass and principal inertia", i, b->name);
                return -1;
            }
        }
        tot->nv += s->nv;
        tot->ne += s->ne;
        tot->nf += s->nf;
        tot->nfv += s->nf > 0 ? s->face_start[s->nf] : 0;
    }
    return 0;
}

/* One allocation per pool for all the bodies, sized by check_bodies (sp_geo holds each body's
 * offsets into the pools). */
static int alloc_pools(lahar_dem_engine *e, int nb, const sp_counts *tot, char *err, size_t errlen)
{
    int nv = tot->nv, ne = tot->ne, nf = tot->nf, nfv = tot->nfv;
    e->geo = xcalloc((size_t)nb, sizeof *e->geo);
    e->st = xcalloc((size_t)nb, sizeof *e->st);
    e->names = xcalloc((size_t)nb, sizeof *e->names);
    e->laws = xcalloc((size_t)(e->nmat * e->nmat), sizeof *e->laws);
    e->vb = xcalloc((size_t)nv, sizeof(vec3));
    e->vw = xcalloc((size_t)nv, sizeof(vec3));
    e->vadj_start = xcalloc((size_t)(nv + nb), sizeof(int));
    e->vadj = xcalloc((size_t)(2 * ne), sizeof(int));
    e->edge = xcalloc((size_t)ne, sizeof(int[2]));
    e->edge_face = xcalloc((size_t)ne, sizeof(int[2]));
    e->fstart = xcalloc((size_t)(nf + nb), sizeof(int));
    e->fv = xcalloc((size_t)nfv, sizeof(int));
    e->fw = xcalloc((size_t)nfv, sizeof(vec3));
    e->nb = xcalloc((size_t)nf, sizeof(vec3));
    e->nw = xcalloc((size_t)nf, sizeof(vec3));
    e->free_ids = xcalloc((size_t)nb, sizeof(int));
    e->large_ids = xcalloc((size_t)nb, sizeof(int));
    e->cellc = xcalloc((size_t)nb, sizeof(long long[3]));
    e->grids = xcalloc((size_t)nb, sizeof(geom_feature_grid));
    e->rep_f = xcalloc((size_t)nb, sizeof(vec3));
    e->rep_t = xcalloc((size_t)nb, sizeof(vec3));
    e->ncontact_body = xcalloc((size_t)nb, sizeof(int));
    if (!e->geo || !e->st || !e->names || !e->laws || !e->vb || !e->vw || !e->vadj_start || !e->vadj || !e->edge ||
        !e->edge_face || !e->fstart || !e->fv || !e->fw || !e->nb || !e->nw || !e->free_ids || !e->large_ids ||
        !e->cellc || !e->grids || !e->rep_f || !e->rep_t || !e->ncontact_body)
        return sp_oom(err, errlen);
    return 0;
}

static int make_pair_laws(lahar_dem_engine *e, const lahar_case *c, char *err, size_t errlen)
{
    for (int a = 0; a < e->nmat; a++)
        for (int b = 0; b < e->nmat; b++)
            if (dem_pair_law_make(&c->materials[a], &c->materials[b], &e->laws[a * e->nmat + b], err, errlen))
                return -1;
    return 0;
}

/* Body i's constants into geo[i] and its shape into the pools at the offsets `at` (vertices in
 * the body frame; fixed bodies arrive in world coordinates with x = 0, q = 1). */
static int copy_shape(lahar_dem_engine *e, const lahar_case *c, int i, const sp_counts *at, char *err, size_t errlen)
{
    const lahar_body *b = &c->bodies[i];
    const lahar_shape *s = &b->shape;
    sp_geo *g = &e->geo[i];
    const int ov = at->nv, oe = at->ne, of = at->nf, ofv = at->nfv;
    snprintf(e->names[i], LAHAR_NAME_MAX, "%s", b->name);
    g->nv = s->nv;
    g->ne = s->ne;
    g->nf = s->nf;
    g->v0 = ov;
    g->va0 = ov + i;
    g->e0 = oe;
    g->f0 = of;
    g->fs0 = of + i;
    g->radius = s->radius;
    g->material = b->material;
    g->motion = b->motion;
    g->mass = b->mass;
    memcpy(g->inertia, b->inertia, sizeof g->inertia);
    g->isotropic = g->inertia[0] == g->inertia[1] && g->inertia[1] == g->inertia[2];
    g->grid = -1;
    double rb = 0.0;
    for (int k = 0; k < s->nv; k++) {
        e->vb[ov + k] = v3_load(s->v[k]);
        rb = fmax(rb, v3_norm(e->vb[ov + k]));
    }
    g->bound = rb + s->radius;
    for (int k = 0; k < s->ne; k++) {
        e->edge[oe + k][0] = s->e[k][0];
        e->edge[oe + k][1] = s->e[k][1];
    }
    for (int f = 0; f < s->nf; f++) {
        e->fstart[g->fs0 + f] = ofv + s->face_start[f];
        e->nb[of + f] = geom_face_normal(s, f);
    }
    e->fstart[g->fs0 + s->nf] = ofv + (s->nf > 0 ? s->face_start[s->nf] : 0);
    int nfvi = s->nf > 0 ? s->face_start[s->nf] : 0;
    for (int k = 0; k < nfvi; k++) {
        if (s->face_v[k] < 0 || s->face_v[k] >= s->nv) {
            snprintf(err, errlen, "spheropoly: body %d '%s': face uses a missing vertex", i, b->name);
            return -1;
        }
        e->fv[ofv + k] = s->face_v[k];
    }
    return build_topology(e, i, s, err, errlen);
}

/* Body i's state. 2D bodies stay exactly in the x-y plane; a free body also carries its angular
 * momentum, which the rotation integrates (body_update_omega turns it back into w). */
static void set_initial_state(lahar_dem_engine *e, const lahar_body *b, int i)
{
    const sp_geo *g = &e->geo[i];
    sp_state *st = &e->st[i];
    st->x = v3_load(b->x);
    st->q = q_normalize(q_load(b->q));
    if (e->dim == 2) { /* keep 2D exactly planar */
        st->x.z = 0.0;
        st->q.x = st->q.y = 0.0;
        st->q = q_normalize(st->q);
    }
    st->v = b->motion == LAHAR_MOTION_FIXED ? v3(0, 0, 0) : v3_load(b->v);
    st->w = b->motion == LAHAR_MOTION_FIXED ? v3(0, 0, 0) : v3_load(b->w);
    if (e->dim == 2) {
        st->v.z = 0.0;
        st->w.x = st->w.y = 0.0;
    }
    if (b->motion != LAHAR_MOTION_FREE) return;
    if (e->dim == 2) st->L = v3(0.0, 0.0, g->inertia[2] * st->w.z);
    else {
        vec3 wb = q_rotate_inv(st->q, st->w);
        st->L = q_rotate(st->q, v3(g->inertia[0] * wb.x, g->inertia[1] * wb.y, g->inertia[2] * wb.z));
    }
}

/* A body with many features (a terrain, an STL) gets a feature grid, so that a contact looks only
 * at the features near its partner; `big` keeps the largest such body, which sizes the threads'
 * query scratch. */
static int build_body_grid(lahar_dem_engine *e, int i, const lahar_body *b, sp_counts *big, char *err, size_t errlen)
{
    const lahar_shape *s = &b->shape;
    if (s->nv + s->ne + s->nf <= SP_GRID_MIN_FEATURES) return 0;
    if (geom_feature_grid_build(&e->grids[e->ngrid], s)) {
        e->ngrid++; /* counted: sp_destroy frees a half-built grid */
        snprintf(err, errlen, "spheropoly: out of memory for the feature grid of body '%s'", b->name);
        return -1;
    }
    e->geo[i].grid = e->ngrid++;
    big->nv = s->nv > big->nv ? s->nv : big->nv;
    big->ne = s->ne > big->ne ? s->ne : big->ne;
    big->nf = s->nf > big->nf ? s->nf : big->nf;
    return 0;
}

/* Body i in full: shape, state, its side of the broad phase (free bodies are binned, the others
 * are boxes), its grid and its world geometry. `at` moves on to the next body's offsets. */
static int load_body(lahar_dem_engine *e, const lahar_case *c, int i, sp_counts *at, sp_counts *big, char *err,
                     size_t errlen)
{
    const lahar_body *b = &c->bodies[i];
    const lahar_shape *s = &b->shape;
    if (copy_shape(e, c, i, at, err, errlen)) return -1;
    set_initial_state(e, b, i);
    if (b->motion == LAHAR_MOTION_FREE) e->free_ids[e->nfree++] = i;
    else e->large_ids[e->nlarge++] = i;
    if (build_body_grid(e, i, b, big, err, errlen)) return -1;
    at->nv += s->nv;
    at->ne += s->ne;
    at->nf += s->nf;
    at->nfv += s->nf > 0 ? s->face_start[s->nf] : 0;
    body_update_world(e, i);
    return 0;
}

/* Grid levels: the largest bounding diameter D sets the coarsest cell; a body lives in the finest
 * cell D / 2^h that still holds its diameter, so a boulder among gravel does not blow the cell up
 * for everybody, while sizes within a factor 2 share one level. */
static int make_grid_levels(lahar_dem_engine *e, int nb, char *err, size_t errlen)
{
    double dmax = 0.0;
    for (int k = 0; k < e->nfree; k++) dmax = fmax(dmax, 2.0 * e->geo[e->free_ids[k]].bound);
    dmax = dmax > 0.0 ? dmax * (1.0 + 1e-9) : 1.0;
    e->level = xcalloc((size_t)nb, sizeof(int));
    if (!e->level) return sp_oom(err, errlen);
    int hmax = 0;
    for (int k = 0; k < e->nfree; k++) {
        double dk = 2.0 * e->geo[e->free_ids[k]].bound;
        int hk = 0; /* halvings of D that still hold dk */
        while (hk < 20 && ldexp(dmax, -(hk + 1)) >= dk) hk++;
        e->level[k] = hk;
        hmax = hk > hmax ? hk : hmax;
    }
    e->nlevel = hmax + 1;
    for (int k = 0; k < e->nfree; k++) {
        e->level[k] = hmax - e->level[k]; /* level 0 = finest, nlevel - 1 = coarsest (cell D) */
        e->level_count[e->level[k]]++;
    }
    for (int l = 0; l < e->nlevel; l++) e->cell_inv[l] = 1.0 / ldexp(dmax, -(hmax - l));
    return 0;
}

/* The broad phase's buckets, sized for the largest dense grid it builds (8 nfree + 1024 cells) and
 * for the hash (at least 2 nfree entries), so that binning does not grow them. */
static int alloc_broad_phase(lahar_dem_engine *e, int nb, char *err, size_t errlen)
{
    e->nhash = 16;
    while (e->nhash < 2 * e->nfree) e->nhash *= 2;
    e->bucket_cap = 8 * e->nfree + 1026 > e->nhash + 1 ? 8 * e->nfree + 1026 : e->nhash + 1;
    e->bucket_start = xcalloc((size_t)e->bucket_cap, sizeof(int));
    e->bucket_of = xcalloc((size_t)nb, sizeof(int));
    e->bins = xcalloc((size_t)nb, sizeof(sp_bin));
    if (!e->bucket_start || !e->bucket_of || !e->bins) return sp_oom(err, errlen);
    return 0;
}

/* Per thread of the narrow phase: a feature-grid query able to serve the largest gridded body
 * (big) and the feature culling's scratch for the largest body of all. */
static int alloc_thread_scratch(lahar_dem_engine *e, int nb, const sp_counts *big, char *err, size_t errlen)
{
    e->nthr = omp_get_max_threads();
    if (e->nthr < 1) e->nthr = 1;
    e->thr = xcalloc((size_t)e->nthr, sizeof(sp_thread));
    if (!e->thr) return sp_oom(err, errlen);
    int allv = 1, alle = 1, allf = 1;
    for (int i = 0; i < nb; i++) {
        allv = e->geo[i].nv > allv ? e->geo[i].nv : allv;
        alle = e->geo[i].ne > alle ? e->geo[i].ne : alle;
        allf = e->geo[i].nf > allf ? e->geo[i].nf : allf;
    }
    for (int t = 0; t < e->nthr; t++) {
        sp_thread *th = &e->thr[t];
        int bad = geom_feature_query_init(&th->fq, big->nv, big->ne, big->nf);
        th->emid = malloc(sizeof(vec3) * (size_t)alle);
        th->ehalf = malloc(sizeof(double) * (size_t)alle);
        bad |= !th->emid || !th->ehalf;
        for (int sd = 0; sd < 2; sd++) {
            th->keep[sd][0] = malloc(sizeof(int) * (size_t)allv);
            th->keep[sd][1] = malloc(sizeof(int) * (size_t)alle);
            th->keep[sd][2] = malloc(sizeof(int) * (size_t)allf);
            bad |= !th->keep[sd][0] || !th->keep[sd][1] || !th->keep[sd][2];
        }
        if (bad) return sp_oom(err, errlen);
    }
    return 0;
}

/* Pre-size the per-step arrays for a dense pile (about 3 contacts and 4 pairs per body, up to
 * 4 points for a face on a face) so that the steady state never grows them; they still double
 * when a scene needs more (test_dem_noalloc checks that advance allocates nothing). */
static int presize_step_arrays(lahar_dem_engine *e, int nb, char *err, size_t errlen)
{
    int ccap = 4 * nb + 64, pcap = 8 * e->nfree + 64;
    e->pairs = malloc(sizeof(int[2]) * (size_t)pcap);
    e->cur = malloc(sizeof(sp_contact) * (size_t)ccap);
    e->prev = malloc(sizeof(sp_contact) * (size_t)ccap);
    int hcap = 16;
    while (hcap < 2 * ccap) hcap *= 2;
    e->hash = malloc(sizeof(int) * (size_t)hcap);
    e->vhash = malloc(sizeof(int) * (size_t)hcap);
    if (!e->pairs || !e->cur || !e->prev || !e->hash || !e->vhash) return sp_oom(err, errlen);
    e->pair_cap = pcap;
    e->contact_cap = ccap;
    e->hash_cap = hcap;
    for (int t = 0; t < e->nthr; t++) { /* one static block of pairs may hold most contacts */
        e->thr[t].c = malloc(sizeof(sp_contact) * (size_t)ccap);
        if (!e->thr[t].c) return sp_oom(err, errlen);
        e->thr[t].cap = ccap;
    }
    return 0;
}

static lahar_dem_engine *sp_create(const lahar_case *c, char *err, size_t errlen)
{
    lahar_dem_engine *e = calloc(1, sizeof *e);
    if (!e) {
        sp_oom(err, errlen);
        return NULL;
    }
    set_scene_constants(e, c);
    int nb = c->nbody > 0 ? c->nbody : 0;
    sp_counts tot, at = {0, 0, 0, 0}, big = {0, 0, 0, 0};
    if (check_bodies(e, c, nb, &tot, err, errlen) || alloc_pools(e, nb, &tot, err, errlen) ||
        make_pair_laws(e, c, err, errlen))
        goto fail;
    for (int i = 0; i < nb; i++)
        if (load_body(e, c, i, &at, &big, err, errlen)) goto fail;
    if (make_grid_levels(e, nb, err, errlen) || alloc_broad_phase(e, nb, err, errlen) ||
        alloc_thread_scratch(e, nb, &big, err, errlen) || presize_step_arrays(e, nb, err, errlen))
        goto fail;
    e->dt_stable = stable_dt_of(e, c);
    if (!(e->dt_stable > 0.0)) {
        sp_oom(err, errlen);
        goto fail;
    }
    if (sps_create(e, err, errlen)) goto fail;
    if (check_finite(e, err, errlen) || compute_forces(e, 0.0, err, errlen)) goto fail;
    if (e->sph) sps_accumulate(e); /* the body states hold the forces between advances */
    return e;
fail:
    sp_destroy(e);
    return NULL;
}

/* ---------------------------------------------------------------------------------------------- */
/* Queries and restart                                                                             */

static double sp_stable_dt(const lahar_dem_engine *e) { return e->dt_stable; }
static int sp_nbody(const lahar_dem_engine *e) { return e->nbody; }
static int sp_ncontacts(const lahar_dem_engine *e) { return e->nprev + sps_ncontacts(e); }
static long long sp_contacts_evaluated(const lahar_dem_engine *e) { return e->contacts_evaluated; }

static void sp_get_state(const lahar_dem_engine *e, int i, lahar_body_state *out)
{
    const sp_state st = sps_state(e, i), *s = &st;
    v3_store(s->x, out->x);
    q_store(s->q, out->q);
    v3_store(s->v, out->v);
    v3_store(s->w, out->w);
}

static void sp_get_report(const lahar_dem_engine *e, int i, lahar_body_report *out)
{
    if (e->rep_n > 0) {
        v3_store(e->rep_f[i], out->force);
        v3_store(e->rep_t[i], out->torque);
    } else {
        vec3 f, t;
        sps_fc(e, i, &f, &t);
        v3_store(f, out->force);
        v3_store(t, out->torque);
    }
    out->ncontacts = sps_ncontact_of(e, i);
}

static double sp_kinetic_energy(const lahar_dem_engine *e)
{
    double k = 0.0;
    for (int j = 0; j < e->nfree; j++) {
        int i = e->free_ids[j];
        const sp_state st = sps_state(e, i), *s = &st;
        k += 0.5 * e->geo[i].mass * v3_norm2(s->v) + 0.5 * v3_dot(s->L, s->w);
    }
    return k;
}

/* version 2: followed by the springs of the sphere fast path */
static const char sp_magic[8] = {'L', 'H', 'R', 'S', 'P', 'R', 'S', '2'};

static int sp_write_restart(const lahar_dem_engine *e, FILE *f)
{
    int ok = fwrite(sp_magic, 1, 8, f) == 8;
    ok = ok && fwrite(&e->nbody, sizeof(int), 1, f) == 1;
    ok = ok && fwrite(&e->step, sizeof(long), 1, f) == 1;
    /* the spheres' states and counts from the fast path (sps_state): the same bytes as body states
     * kept up to date */
    for (int i = 0; ok && i < e->nbody; i++) {
        sp_state st = sps_state(e, i);
        ok = fwrite(&st, sizeof st, 1, f) == 1;
    }
    ok = ok && fwrite(&e->nprev, sizeof(int), 1, f) == 1;
    ok = ok && fwrite(e->prev, sizeof(sp_contact), (size_t)e->nprev, f) == (size_t)e->nprev;
    for (int i = 0; ok && i < e->nbody; i++) {
        int m = sps_ncontact_of(e, i);
        ok = fwrite(&m, sizeof m, 1, f) == 1;
    }
    ok = ok && sps_write_restart(e, f) == 0;
    return ok ? 0 : -1;
}

static int sp_read_restart(lahar_dem_engine *e, FILE *f)
{
    char magic[8];
    int nbody, n;
    long step;
    if (fread(magic, 1, 8, f) != 8 || memcmp(magic, sp_magic, 8) != 0) return -1;
    if (fread(&nbody, sizeof(int), 1, f) != 1 || nbody != e->nbody) return -1;
    if (fread(&step, sizeof(long), 1, f) != 1) return -1;
    if (fread(e->st, sizeof(sp_state), (size_t)nbody, f) != (size_t)nbody) return -1;
    if (fread(&n, sizeof(int), 1, f) != 1 || n < 0) return -1;
    int cap = e->contact_cap, cap2 = e->contact_cap;
    if (grow((void **)&e->cur, &cap, n, sizeof(sp_contact)) || grow((void **)&e->prev, &cap2, n, sizeof(sp_contact)))
        return -1;
    e->contact_cap = cap < cap2 ? cap : cap2;
    if (fread(e->prev, sizeof(sp_contact), (size_t)n, f) != (size_t)n) return -1;
    if (fread(e->ncontact_body, sizeof(int), (size_t)nbody, f) != (size_t)nbody) return -1;
    if (sps_read_restart(e, f)) return -1;
    e->nprev = n;
    e->step = step;
    e->rep_n = 0;
    for (int i = 0; i < e->nbody; i++) body_update_world(e, i);
    return history_rebuild(e);
}

const lahar_dem_engine_ops lahar_dem_spheropoly_ops = {
    .name = "spheropoly",
    .version = "1.0",
    .create = sp_create,
    .stable_dt = sp_stable_dt,
    .advance = sp_advance,
    .nbody = sp_nbody,
    .get_state = sp_get_state,
    .get_report = sp_get_report,
    .ncontacts = sp_ncontacts,
    .kinetic_energy = sp_kinetic_energy,
    .contacts_evaluated = sp_contacts_evaluated,
    .write_restart = sp_write_restart,
    .read_restart = sp_read_restart,
    .destroy = sp_destroy,
    .fault = sp_fault,
};
