/* The narrow phase of the spheropoly engine (README.md "Contact detection"): the contacts of one
 * broad-phase pair of bodies. The features of each side are culled (a big body's through its feature
 * grid), the feature pairs tested (vertex-face, edge-edge, vertex-edge, vertex-vertex), each contact
 * takes its tangential spring from the previous evaluation through the contact history (a hash
 * over the last contacts, rebuilt after each evaluation), and the pair's contact forces are added. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include "spheropoly_impl.h"
#include "dem_contact.h"
#include "geometry.h"

static double mstar_of(const lahar_dem_engine *e, int a, int b)
{
    const sp_geo *ga = &e->geo[a], *gb = &e->geo[b];
    int fa = ga->motion == LAHAR_MOTION_FREE, fb = gb->motion == LAHAR_MOTION_FREE;
    if (fa && fb) return ga->mass * gb->mass / (ga->mass + gb->mass);
    return fa ? ga->mass : gb->mass; /* fixed / prescribed partner: infinite mass */
}

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

int spp_history_rebuild(lahar_dem_engine *e)
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
    if (t->n == t->cap && spp_grow((void **)&t->c, &t->cap, t->n + 1, sizeof(sp_contact))) {
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
void spp_pair_contacts(lahar_dem_engine *e, int a, int b, double h, sp_thread *t)
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
