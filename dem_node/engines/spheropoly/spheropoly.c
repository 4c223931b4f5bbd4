/* The "spheropoly" DEM engine: rigid sphero-polyhedra (Galindo-Torres 2009-2013 as used in paper
 * Trujillo-Vela et al. 2020, sec. 3) with linear or Hertz normal contacts, a tangential spring with Coulomb limit, a
 * uniform grid broad phase (dense or hashed), per-body feature grids for big surfaces, kick-drift-kick
 * leap-frog for translation and an exactly rotating splitting (NO_SQUISH / Dullweber-Leimkuhler-
 * McLachlan 1997) for rotation. Conventions are documented in dem_node/README.md.
 * This file: the function table, one force evaluation, integration, advance, queries and restart;
 * the broad phase, narrow phase, creation and sphere fast path are in spheropoly_*.c (README.md). */
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
void spp_body_update_world(lahar_dem_engine *e, int i)
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
int spp_compute_forces(lahar_dem_engine *e, double h, char *err, size_t errlen)
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
        spp_body_update_world(e, i);
    }
}

/* Non-finite or runaway states stop the run before they reach the grid (cell indices of a NaN or
 * of 1e300 would overflow). */
int spp_check_finite(lahar_dem_engine *e, char *err, size_t errlen)
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
        if (spp_check_finite(e, err, errlen) || spp_compute_forces(e, h, err, errlen)) return -1;
        kick(e, 0.5 * h, loads, 0.0);
        if (spp_check_finite(e, err, errlen)) return -1;
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
/* Queries and restart                                                                             */

static double sp_stable_dt(const lahar_dem_engine *e) { return e->dt_stable; }
static int sp_nbody(const lahar_dem_engine *e) { return e->nbody; }
static int sp_ncontacts(const lahar_dem_engine *e) { return e->nprev + sps_ncontacts(e); }
static long long sp_contacts_evaluated(const lahar_dem_engine *e) { return e->contacts_evaluated; }

static int sp_fault(const lahar_dem_engine *e, lahar_dem_fault *out)
{
    if (e->has_fault)
        *out = e->fault;
    return e->has_fault;
}

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
    for (int i = 0; i < e->nbody; i++) spp_body_update_world(e, i);
    return spp_history_rebuild(e);
}

const lahar_dem_engine_ops lahar_dem_spheropoly_ops = {
    .name = "spheropoly",
    .version = "1.0",
    .create = spp_create,
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
    .destroy = spp_destroy,
    .fault = sp_fault,
};
