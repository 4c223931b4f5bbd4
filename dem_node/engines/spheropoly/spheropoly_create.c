/* Creation and destruction of the spheropoly engine: the case's bodies checked and copied into the
 * engine's pools (shapes, topology, initial states, feature grids of big bodies), the grid levels
 * and buckets of the broad phase, the narrow phase's scratch per thread, the per-step arrays
 * pre-sized (README.md "Determinism and restart": no allocation in the steady state), the stable
 * step (README.md "Step size"), the sphere fast path, and the first force evaluation. */
#include <float.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>
#include "spheropoly_impl.h"
#include "dem_contact.h"
#include "geometry.h"

static void *xcalloc(size_t n, size_t size) { return calloc(n ? n : 1, size); }

void spp_destroy(lahar_dem_engine *e)
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
        e->ngrid++; /* counted: spp_destroy frees a half-built grid */
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
    spp_body_update_world(e, i);
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

lahar_dem_engine *spp_create(const lahar_case *c, char *err, size_t errlen)
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
    if (spp_check_finite(e, err, errlen) || spp_compute_forces(e, 0.0, err, errlen)) goto fail;
    if (e->sph) sps_accumulate(e); /* the body states hold the forces between advances */
    return e;
fail:
    spp_destroy(e);
    return NULL;
}
