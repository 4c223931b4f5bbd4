/* The "spheropoly" DEM engine: rigid sphero-polyhedra (Galindo-Torres 2009-2013 as used in paper
 * Trujillo-Vela et al. 2020, sec. 3) with linear or Hertz normal contacts, a tangential spring with Coulomb limit, a
 * uniform grid broad phase (dense or hashed), per-body feature grids for big surfaces, kick-drift-kick
 * leap-frog for translation and an exactly rotating splitting (NO_SQUISH / Dullweber-Leimkuhler-
 * McLachlan 1997) for rotation. Conventions are documented in dem_node/README.md. */
#include "spheropoly.h"
#include "spheropoly_impl.h"
#include <float.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>
#include "dem_contact.h"
#include "geometry.h"


/* ---------------------------------------------------------------------------------------------- */

static void *xcalloc(size_t n, size_t size) { return calloc(n ? n : 1, size); }

int spp_grow(void **p, int *cap, int need, size_t size)
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
/* Forces                                                                                          */

/* Contacts and contact forces at the current positions; h is the time since the last evaluation
 * (advances the tangential springs). Returns 0, or -1 with err set. */
static int compute_forces(lahar_dem_engine *e, double h, char *err, size_t errlen)
{
    if (e->sph && sps_forces(e, h, err, errlen)) return -1;
    if (e->sph && sps_needs_sync(e)) sps_sync(e); /* the general path reads the spheres' body states */
    if (spp_broad_phase(e)) {
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
        for (int p = 0; p < e->npair; p++) spp_pair_contacts(e, e->pairs[p][0], e->pairs[p][1], h, t);
        oom |= t->oom;
    }
    int total = 0;
    for (int t = 0; t < e->nthr; t++) total += e->thr[t].n; /* threads beyond the team size left n = 0 */
    if (oom || total > e->contact_cap) {
        int cap = e->contact_cap, cap2 = e->contact_cap;
        if (oom || spp_grow((void **)&e->cur, &cap, total, sizeof(sp_contact)) ||
            spp_grow((void **)&e->prev, &cap2, total, sizeof(sp_contact))) {
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
    if (spp_history_rebuild(e)) {
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
    if (spp_grow((void **)&e->cur, &cap, n, sizeof(sp_contact)) || spp_grow((void **)&e->prev, &cap2, n, sizeof(sp_contact)))
        return -1;
    e->contact_cap = cap < cap2 ? cap : cap2;
    if (fread(e->prev, sizeof(sp_contact), (size_t)n, f) != (size_t)n) return -1;
    if (fread(e->ncontact_body, sizeof(int), (size_t)nbody, f) != (size_t)nbody) return -1;
    if (sps_read_restart(e, f)) return -1;
    e->nprev = n;
    e->step = step;
    e->rep_n = 0;
    for (int i = 0; i < e->nbody; i++) body_update_world(e, i);
    return spp_history_rebuild(e);
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
