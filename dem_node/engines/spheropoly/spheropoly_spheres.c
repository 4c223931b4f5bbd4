/* The sphere fast path of the spheropoly engine (dem_node/engines/spheropoly/README.md "Sphere fast path").
 *
 * A free body with one vertex at its centre and no edge or face is a sphere (a disc in 2D). Pairs
 * of such spheres, and a sphere against a fixed flat wall (one face, 3D), skip the feature
 * machinery of the general narrow phase: the contact is the centre line (sphere-sphere) or the
 * projection of the centre on the face (vertex-face), with the same contact laws (dem_contact.h)
 * and the same conventions as the general path (overlap, contact point in the middle of the
 * overlap, R*, m*, tangential spring rotated onto the tangent plane).
 *
 * Verlet list with skin: the pairs whose swept surfaces are closer than `skin` are listed, sorted
 * by (sphere a, sphere b), and the list is rebuilt only when a sphere moved more than skin/2 since
 * the last build (two spheres then closed at most `skin`). The spring of a pair lives in the list
 * entry; a rebuild hands the springs of the touching pairs over by merging the two sorted lists.
 * Each sphere sums its contacts in ascending partner order (pair index order of the sorted list),
 * then its walls, so the result does not depend on when the list was built: a restart rebuilds the
 * list and continues bit for bit. Threads take parts of consecutive spheres; the entries whose
 * partner lies in a later part are computed first (phase 1) and enter both sums in their place in
 * that order, so any thread count gives the same bits (every thread writes only its own spheres).
 *
 * The spheres' state (x, v, w, L, q) lives in compact arrays here; the engine's body states of the
 * spheres are written only when the general path meets a sphere (sps_sync) and read through
 * sps_state.
 *
 * This file: the fast path's set-up, its list containers, the spheres' integration and state, and
 * restart; the list build is in spheropoly_spheres_list.c, the forces in
 * spheropoly_spheres_forces.c, the data they share in spheropoly_spheres_impl.h. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include "spheropoly_spheres_impl.h"
#include "soa_alloc.h"

/* Skin: this fraction of the smallest sphere radius (LAMMPS's bench uses 0.1 d). */
#define SPS_SKIN_FRACTION 0.2

/* ---------------------------------------------------------------------------------------------- */

int sps_list_reserve(sps_list *l, int need)
{
    if (need <= l->cap) return 0;
    int c = l->cap > 0 ? l->cap : 256;
    while (c < need) c *= 2;
    void *p[12];
    p[0] = realloc(l->a, sizeof(int) * (size_t)c);
    if (p[0]) l->a = p[0];
    p[1] = realloc(l->b, sizeof(int) * (size_t)c);
    if (p[1]) l->b = p[1];
    p[2] = realloc(l->xi, sizeof(vec3) * (size_t)c);
    if (p[2]) l->xi = p[2];
    p[3] = realloc(l->touch, (size_t)c);
    if (p[3]) l->touch = p[3];
    p[4] = realloc(l->fall, (size_t)c);
    if (p[4]) l->fall = p[4];
    p[5] = realloc(l->f, sizeof(vec3) * (size_t)c);
    if (p[5]) l->f = p[5];
    p[6] = realloc(l->ta, sizeof(vec3) * (size_t)c);
    if (p[6]) l->ta = p[6];
    p[7] = realloc(l->tb, sizeof(vec3) * (size_t)c);
    if (p[7]) l->tb = p[7];
    p[8] = realloc(l->delta, sizeof(double) * (size_t)c);
    if (p[8]) l->delta = p[8];
    p[9] = realloc(l->pc, sizeof(dem_pair_consts) * (size_t)c);
    if (p[9]) l->pc = p[9];
    p[10] = realloc(l->deep, (size_t)c);
    if (p[10]) l->deep = p[10];
    p[11] = realloc(l->ci, sizeof(int) * (size_t)c);
    if (p[11]) l->ci = p[11];
    for (int k = 0; k < 12; k++)
        if (!p[k]) return -1;
    l->cap = c;
    return 0;
}

static void list_free(sps_list *l)
{
    free(l->a);
    free(l->b);
    free(l->xi);
    free(l->touch);
    free(l->fall);
    free(l->deep);
    free(l->ci);
    free(l->f);
    free(l->ta);
    free(l->tb);
    free(l->delta);
    free(l->pc);
}

static int hist_reserve(sps_hist *h, int need)
{
    if (need <= h->cap) return 0;
    int c = h->cap > 0 ? h->cap : 256;
    while (c < need) c *= 2;
    int *a = realloc(h->a, sizeof(int) * (size_t)c);
    if (a) h->a = a;
    int *b = realloc(h->b, sizeof(int) * (size_t)c);
    if (b) h->b = b;
    vec3 *x = realloc(h->xi, sizeof(vec3) * (size_t)c);
    if (x) h->xi = x;
    if (!a || !b || !x) return -1;
    h->cap = c;
    return 0;
}

/* The touching entries of list l (already sorted) into h. */
int sps_hist_take(sps_hist *h, const sps_list *l)
{
    int n = 0;
    for (int p = 0; p < l->n; p++) n += l->touch[p];
    if (hist_reserve(h, n)) return -1;
    h->n = 0;
    for (int p = 0; p < l->n; p++)
        if (l->touch[p]) {
            h->a[h->n] = l->a[p];
            h->b[h->n] = l->b[p];
            h->xi[h->n] = l->xi[p];
            h->n++;
        }
    return 0;
}

/* Hand the springs of h to the equal (a, b) entries of the new list l (both sorted). */
void sps_hist_give(const sps_hist *h, sps_list *l)
{
    int j = 0;
    for (int p = 0; p < l->n; p++) {
        l->touch[p] = 0;
        l->xi[p] = v3(0.0, 0.0, 0.0);
        l->fall[p] = 0;
        l->f[p] = l->ta[p] = l->tb[p] = v3(0.0, 0.0, 0.0);
        while (j < h->n && (h->a[j] < l->a[p] || (h->a[j] == l->a[p] && h->b[j] < l->b[p]))) j++;
        if (j < h->n && h->a[j] == l->a[p] && h->b[j] == l->b[p]) {
            l->touch[p] = 1;
            l->xi[p] = h->xi[j];
        }
    }
}

int sps_is_sphere(const lahar_dem_engine *e, int i) { return e->sph && e->sph->of_body[i] >= 0; }
int sps_is_wall(const lahar_dem_engine *e, int i) { return e->sph && e->sph->wall_of_body[i] >= 0; }
int sps_ncontacts(const lahar_dem_engine *e) { return e->sph ? e->sph->ncontact : 0; }
int sps_nspheres(const lahar_dem_engine *e) { return e->sph ? e->sph->n : 0; }
int sps_general_large(const lahar_dem_engine *e, const int **ids)
{
    *ids = e->sph->gen_large;
    return e->sph->ngen;
}

static void sps_load(lahar_dem_engine *e);

/* Whether body g has the fast path's shape: a single vertex at its centre, no edge, no face. */
static int sphere_shaped(const lahar_dem_engine *e, const sp_geo *g)
{
    vec3 v = e->vb[g->v0];
    return g->nv == 1 && g->ne == 0 && g->nf == 0 && v.x == 0.0 && v.y == 0.0 && v.z == 0.0;
}

/* The free bodies that the fast path will take: none means no fast path at all. */
static int count_spheres(const lahar_dem_engine *e)
{
    int ns = 0;
    for (int k = 0; k < e->nfree; k++) ns += sphere_shaped(e, &e->geo[e->free_ids[k]]);
    return ns;
}

/* The per-body maps and the per-sphere arrays (SoA) for ns spheres of nb bodies. Every array is
 * tried, so that a failure leaves the same partial set as before; -1 if any is missing. */
static int alloc_sphere_arrays(sp_spheres *s, int ns, int nb)
{
    s->of_body = malloc(sizeof(int) * (size_t)nb);
    s->wall_of_body = malloc(sizeof(int) * (size_t)nb);
    s->body = lahar_soa_calloc((size_t)ns, sizeof(int));
    s->wall_body = malloc(sizeof(int) * (size_t)(nb > 0 ? nb : 1));
    s->gen_large = malloc(sizeof(int) * (size_t)(nb > 0 ? nb : 1));
    s->rad = lahar_soa_calloc((size_t)ns, sizeof(double));
    s->mass = lahar_soa_calloc((size_t)ns, sizeof(double));
    s->mat = lahar_soa_calloc((size_t)ns, sizeof(int));
    s->iner = lahar_soa_calloc((size_t)ns, sizeof(double));
    s->inv_iner = lahar_soa_calloc((size_t)ns, sizeof(double));
    s->v0 = lahar_soa_calloc((size_t)ns, sizeof(int));
    s->x = lahar_soa_calloc((size_t)ns, sizeof(vec3));
    s->v = lahar_soa_calloc((size_t)ns, sizeof(vec3));
    s->w = lahar_soa_calloc((size_t)ns, sizeof(vec3));
    s->L = lahar_soa_calloc((size_t)ns, sizeof(vec3));
    s->qw = lahar_soa_calloc((size_t)ns, sizeof(double));
    s->qx = lahar_soa_calloc((size_t)ns, sizeof(double));
    s->qy = lahar_soa_calloc((size_t)ns, sizeof(double));
    s->qz = lahar_soa_calloc((size_t)ns, sizeof(double));
    s->x0 = lahar_soa_calloc((size_t)ns, sizeof(vec3));
    s->bcount = lahar_soa_calloc((size_t)ns + 1, sizeof(int));
    s->wstart = lahar_soa_calloc((size_t)ns + 1, sizeof(int));
    s->sf = lahar_soa_calloc((size_t)ns, sizeof(vec3));
    s->st = lahar_soa_calloc((size_t)ns, sizeof(vec3));
    s->scnt = lahar_soa_calloc((size_t)ns, sizeof(int));
    s->pstart = lahar_soa_calloc((size_t)ns + 1, sizeof(int));
    if (!s->of_body || !s->wall_of_body || !s->body || !s->wall_body || !s->gen_large || !s->rad || !s->mass ||
        !s->x0 || !s->mat || !s->iner || !s->inv_iner || !s->v0 || !s->x || !s->v || !s->w || !s->L || !s->qw ||
        !s->qx || !s->qy || !s->qz || !s->bcount || !s->wstart || !s->sf || !s->st || !s->scnt || !s->pstart)
        return -1;
    return 0;
}

/* The wall cache, the thread partition (with its cross entries) and the cell binning of the list
 * build; -1 if any array is missing (all are tried, as in alloc_sphere_arrays). */
static int alloc_wall_part_arrays(const lahar_dem_engine *e, sp_spheres *s, int ns, int nb)
{
    s->wunit = malloc(sizeof(vec3) * (size_t)(nb > 0 ? nb : 1));
    s->wnrm = malloc(sizeof(vec3) * (size_t)(nb > 0 ? nb : 1));
    s->wp0 = malloc(sizeof(vec3) * (size_t)(nb > 0 ? nb : 1));
    s->wrad = malloc(sizeof(double) * (size_t)(nb > 0 ? nb : 1));
    s->npart = ns >= SPS_PAR_MIN && e->nthr > 1 ? e->nthr : 1;
    s->part = calloc((size_t)s->npart + 1, sizeof(int));
    s->xstart = calloc((size_t)s->npart + 1, sizeof(int));
    s->xcap = s->npart > 1 ? 2 * ns + 64 : 1;
    s->xpair = malloc(sizeof(int) * (size_t)s->xcap);
    s->xin = malloc(sizeof(int) * (size_t)s->xcap);
    s->xinstart = calloc((size_t)s->npart + 1, sizeof(int));
    s->cell_of = lahar_soa_calloc((size_t)ns, sizeof(int));
    s->order = lahar_soa_calloc((size_t)ns, sizeof(int));
    s->ncell_cap = 8 * ns + 1024 + 1;
    s->cell_start = malloc(sizeof(int) * (size_t)(s->ncell_cap + 1));
    if (!s->wunit || !s->wnrm || !s->wp0 || !s->wrad || !s->part || !s->xstart || !s->xpair || !s->xin ||
        !s->xinstart || !s->cell_of || !s->order || !s->cell_start)
        return -1;
    return 0;
}

/* Sort the bodies: free spheres onto the fast path (their constants copied), single-face fixed
 * walls in 3D to its wall list, other fixed or prescribed bodies to its general list. The skin is
 * a fraction of the smallest sphere, so that a list stays valid over several steps. */
static void classify_bodies(lahar_dem_engine *e, sp_spheres *s)
{
    double rmin = DBL_MAX;
    for (int i = 0; i < e->nbody; i++) {
        sp_geo *g = &e->geo[i];
        s->of_body[i] = -1;
        s->wall_of_body[i] = -1;
        if (g->motion == LAHAR_MOTION_FREE && sphere_shaped(e, g)) {
            s->of_body[i] = s->n;
            e->geo[i].fast_sphere = 1;
            s->body[s->n] = i;
            s->rad[s->n] = g->radius;
            s->mass[s->n] = g->mass;
            s->mat[s->n] = g->material;
            s->iner[s->n] = e->dim == 2 ? g->inertia[2] : g->inertia[0];
            s->inv_iner[s->n] = 1.0 / s->iner[s->n];
            s->v0[s->n] = g->v0;
            rmin = fmin(rmin, g->radius);
            s->rmax = fmax(s->rmax, g->radius);
            s->n++;
        } else if (g->motion == LAHAR_MOTION_FIXED && e->dim == 3 && g->nf == 1 && g->grid < 0 &&
                   e->fstart[g->fs0 + 1] - e->fstart[g->fs0] >= 3) {
            s->wall_of_body[i] = s->nwall;
            s->wall_body[s->nwall++] = i;
        } else if (g->motion != LAHAR_MOTION_FREE) {
            s->gen_large[s->ngen++] = i;
        }
    }
    s->skin = SPS_SKIN_FRACTION * rmin;
}

/* The bodies the general path still handles: other_ids (all but the fast spheres) and move_ids
 * (the free ones first, nmove_free of them, then the prescribed). -1: no memory. */
static int list_general_bodies(lahar_dem_engine *e)
{
    int nb = e->nbody;
    e->move_ids = malloc(sizeof(int) * (size_t)(nb > 0 ? nb : 1));
    e->other_ids = malloc(sizeof(int) * (size_t)(nb > 0 ? nb : 1));
    if (!e->move_ids || !e->other_ids) return -1;
    for (int i = 0; i < nb; i++)
        if (!e->geo[i].fast_sphere) e->other_ids[e->nother++] = i;
    for (int i = 0; i < nb; i++)
        if (e->geo[i].motion == LAHAR_MOTION_FREE && !e->geo[i].fast_sphere) e->move_ids[e->nmove++] = i;
    e->nmove_free = e->nmove;
    for (int i = 0; i < nb; i++)
        if (e->geo[i].motion == LAHAR_MOTION_PRESCRIBED) e->move_ids[e->nmove++] = i;
    return 0;
}

/* Pre-size the lists, their histories and the candidate scratch so that the step loop seldom
 * grows them: a dense pile has ~7 listed partners per sphere (half list) and 2 walls. -1: no memory. */
static int presize_lists(sp_spheres *s)
{
    if (sps_list_reserve(&s->pl, 8 * s->n + 64) || sps_list_reserve(&s->wl, 2 * s->n + 64) ||
        hist_reserve(&s->ph, 8 * s->n + 64) || hist_reserve(&s->wh, 2 * s->n + 64))
        return -1;
    s->cand_cap = 256;
    s->cand = malloc(sizeof(int) * (size_t)s->cand_cap);
    if (!s->cand) return -1;
    return 0;
}

/* The sphere fast path, when some free body is a plain sphere: its arrays, the bodies sorted
 * between it and the general path, pre-sized lists, and the spheres' state loaded. */
int sps_create(lahar_dem_engine *e, char *err, size_t errlen)
{
    int ns = count_spheres(e);
    if (ns == 0) return 0;
    sp_spheres *s = calloc(1, sizeof *s);
    e->sph = s;
    if (!s) goto oom;
    /* both allocation steps run whatever the first returns (every array tried, as before) */
    int bad = alloc_sphere_arrays(s, ns, e->nbody);
    if (alloc_wall_part_arrays(e, s, ns, e->nbody)) bad = -1;
    if (bad) goto oom;
    classify_bodies(e, s);
    if (list_general_bodies(e) || presize_lists(s)) goto oom;
    sps_load(e);
    return 0;
oom:
    snprintf(err, errlen, "spheropoly: out of memory for the sphere fast path");
    return -1;
}

void sps_destroy(lahar_dem_engine *e)
{
    sp_spheres *s = e->sph;
    if (!s) return;
    list_free(&s->pl);
    list_free(&s->wl);
    free(s->ph.a);
    free(s->ph.b);
    free(s->ph.xi);
    free(s->wh.a);
    free(s->wh.b);
    free(s->wh.xi);
    free(s->of_body);
    free(s->wall_of_body);
    lahar_soa_free(s->body);
    free(s->wall_body);
    free(s->gen_large);
    lahar_soa_free(s->rad);
    lahar_soa_free(s->mass);
    lahar_soa_free(s->mat);
    lahar_soa_free(s->iner);
    lahar_soa_free(s->inv_iner);
    lahar_soa_free(s->v0);
    lahar_soa_free(s->x);
    lahar_soa_free(s->v);
    lahar_soa_free(s->w);
    lahar_soa_free(s->L);
    lahar_soa_free(s->qw);
    lahar_soa_free(s->qx);
    lahar_soa_free(s->qy);
    lahar_soa_free(s->qz);
    lahar_soa_free(s->x0);
    lahar_soa_free(s->bcount);
    lahar_soa_free(s->wstart);
    lahar_soa_free(s->sf);
    lahar_soa_free(s->st);
    lahar_soa_free(s->scnt);
    lahar_soa_free(s->pstart);
    free(s->wunit);
    free(s->wnrm);
    free(s->wp0);
    free(s->wrad);
    free(s->part);
    free(s->xstart);
    free(s->xpair);
    free(s->xin);
    free(s->xinstart);
    lahar_soa_free(s->cell_of);
    lahar_soa_free(s->order);
    free(s->cell_start);
    free(s->cand);
    free(s);
    free(e->move_ids);
    free(e->other_ids);
    e->move_ids = e->other_ids = NULL;
    e->sph = NULL;
}

/* ---------------------------------------------------------------------------------------------- */
/* Integration of the free spheres: the same kick-drift-kick as the general bodies (README,
 * "Integration") with the sphere's equal moments: w = L / I, and the drift turns the orientation by
 * the single exact rotation exp(h L / I) (2D: about z). The compact arrays are the spheres' state:
 * the body states (e->st) are written only when the general path needs them (sps_sync) and read
 * through sps_state. Each sphere writes only its own entries. */

/* Contact force and torque of sphere k as the kick takes them. */
static inline void sphere_fc(const lahar_dem_engine *e, const sp_spheres *s, int k, vec3 *f, vec3 *t)
{
    if (s->deferred) { /* what sps_accumulate (and spp_compute_forces' 2D projection) would have written */
        *f = s->sf[k];
        *t = s->st[k];
        if (e->dim == 2) {
            f->z = 0.0;
            t->x = t->y = 0.0;
        }
    } else {
        *f = e->st[s->body[k]].fc;
        *t = e->st[s->body[k]].tc;
    }
}

static inline int state_ok(vec3 x, vec3 v, vec3 w)
{
    double sum = x.x + x.y + x.z + v.x + v.y + v.z + w.x + w.y + w.z;
    return isfinite(sum) && fabs(x.x) <= 1e12 && fabs(x.y) <= 1e12 && fabs(x.z) <= 1e12;
}

void sps_kick(lahar_dem_engine *e, double half, const lahar_body_load *loads, double hdrift)
{
    sp_spheres *s = e->sph;
    const vec3 g = e->g;
    const int two_d = e->dim == 2, n = s->n;
    const double ah = 0.5 * hdrift, uxy = two_d ? 0.0 : 1.0;
    int ok = 1;
    double worst = 0.0, p2max = 0.0;
#pragma omp parallel num_threads(e->nthr) if (n >= SPS_PAR_MIN)
    {
#pragma omp for schedule(static) reduction(& : ok) reduction(max : worst, p2max)
        for (int k = 0; k < n; k++) {
            double m = s->mass[k];
            vec3 f, t;
            sphere_fc(e, s, k, &f, &t);
            f = v3_axpy(m, g, f);
            if (loads) {
                int i = s->body[k];
                f = v3_add(f, v3_load(loads[i].force));
                t = v3_add(t, v3_load(loads[i].torque));
            }
            if (two_d) {
                f.z = 0.0;
                t.x = t.y = 0.0;
            }
            vec3 v = v3_axpy(half / m, f, s->v[k]), L = v3_axpy(half, t, s->L[k]);
            vec3 w = two_d ? v3(0.0, 0.0, L.z / s->iner[k]) : v3_scale(L, s->inv_iner[k]); /* = L (1/I) */
            s->v[k] = v;
            s->L[k] = L;
            s->w[k] = w;
            vec3 x = s->x[k];
            if (hdrift > 0.0) { /* the drift that follows the first kick */
                x = v3_axpy(hdrift, v, x);
                s->x[k] = x;
                double d2 = v3_norm2(v3_sub(x, s->x0[k]));
                worst = d2 > worst ? d2 : worst;
                double a = ah * s->inv_iner[k], p2 = (uxy * (L.x * L.x + L.y * L.y) + L.z * L.z) * (a * a);
                p2max = p2 > p2max ? p2 : p2max;
            }
            ok &= state_ok(x, v, w);
        }
        /* the orientations turn by the angle h |L| / I about L (2D: about z): q <- exp(h/(2I) L) q.
         * All angles small (the usual case): a loop without a branch (q_exp_scaled's series and
         * q_renormalize's Newton step written out, q stays within 1e-15 of unit length); else
         * q_exp_scaled and q_renormalize per sphere. p2max is final here (after the loop's barrier),
         * so every thread takes the same branch. */
        if (hdrift > 0.0 && p2max <= 1e-4) {
            double *qw = s->qw, *qx = s->qx, *qy = s->qy, *qz = s->qz;
            const double *Ld = &s->L[0].x, *ii = s->inv_iner;
#pragma omp for simd schedule(static)
            for (int k = 0; k < n; k++) {
                double lx = uxy * Ld[3 * k], ly = uxy * Ld[3 * k + 1], lz = Ld[3 * k + 2], a = ah * ii[k];
                double p2 = (lx * lx + ly * ly + lz * lz) * (a * a);
                double c = 1.0 + p2 * (-1.0 / 2.0 + p2 * (1.0 / 24.0 + p2 * (-1.0 / 720.0)));
                double sn = a * (1.0 + p2 * (-1.0 / 6.0 + p2 * (1.0 / 120.0 + p2 * (-1.0 / 5040.0))));
                double rx = lx * sn, ry = ly * sn, rz = lz * sn, q0 = qw[k], q1 = qx[k], q2 = qy[k], q3 = qz[k];
                double nw = c * q0 - rx * q1 - ry * q2 - rz * q3, nx = c * q1 + rx * q0 + ry * q3 - rz * q2;
                double ny = c * q2 - rx * q3 + ry * q0 + rz * q1, nz = c * q3 + rx * q2 - ry * q1 + rz * q0;
                double fq = 1.5 - 0.5 * (nw * nw + nx * nx + ny * ny + nz * nz);
                qw[k] = nw * fq;
                qx[k] = nx * fq;
                qy[k] = ny * fq;
                qz[k] = nz * fq;
            }
        } else if (hdrift > 0.0) {
#pragma omp for schedule(static)
            for (int k = 0; k < n; k++) {
                vec3 L = s->L[k], u = two_d ? v3(0.0, 0.0, L.z) : L;
                quat q = {s->qw[k], s->qx[k], s->qy[k], s->qz[k]};
                q = q_renormalize(q_mul(q_exp_scaled(u, ah * s->inv_iner[k]), q));
                s->qw[k] = q.w;
                s->qx[k] = q.x;
                s->qy[k] = q.y;
                s->qz[k] = q.z;
            }
        }
    }
    s->finite = ok;
    if (hdrift > 0.0) s->worst = worst;
}

int sps_finite(const lahar_dem_engine *e) { return e->sph->finite; }

/* The compact state into the body states (and the world vertex = the centre), for the general
 * path. */
void sps_sync(lahar_dem_engine *e)
{
    sp_spheres *s = e->sph;
#pragma omp parallel for schedule(static) num_threads(e->nthr) if (s->n >= SPS_PAR_MIN)
    for (int k = 0; k < s->n; k++) {
        sp_state *st = &e->st[s->body[k]];
        st->x = s->x[k];
        st->v = s->v[k];
        st->L = s->L[k];
        st->w = s->w[k];
        st->q = (quat){s->qw[k], s->qx[k], s->qy[k], s->qz[k]};
        e->vw[s->v0[k]] = s->x[k];
    }
}

/* The body states into the compact state (create, read_restart). */
static void sps_load(lahar_dem_engine *e)
{
    sp_spheres *s = e->sph;
    int ok = 1;
    for (int k = 0; k < s->n; k++) {
        const sp_state *st = &e->st[s->body[k]];
        s->x[k] = s->x0[k] = st->x;
        s->v[k] = st->v;
        s->L[k] = st->L;
        s->w[k] = st->w;
        /* unit length to 1e-8, which the kick's Newton step keeps (normalised here only if not:
         * a restart continues with the same bits) */
        quat q = st->q;
        if (!(fabs(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z - 1.0) <= 1e-8)) q = q_normalize(q);
        s->qw[k] = q.w;
        s->qx[k] = q.x;
        s->qy[k] = q.y;
        s->qz[k] = q.z;
        ok &= state_ok(st->x, st->v, st->w);
    }
    s->finite = ok;
    s->worst = 0.0;
}

void sps_fc(const lahar_dem_engine *e, int i, vec3 *f, vec3 *t)
{
    const sp_spheres *s = e->sph;
    int k = s ? s->of_body[i] : -1;
    if (k >= 0 && s->deferred) {
        sphere_fc(e, s, k, f, t);
    } else {
        *f = e->st[i].fc;
        *t = e->st[i].tc;
    }
}

int sps_needs_sync(const lahar_dem_engine *e)
{
    const sp_spheres *s = e->sph;
    return e->nfree > s->n || s->ngen > 0 || s->nfall > 0;
}

sp_state sps_state(const lahar_dem_engine *e, int i)
{
    const sp_spheres *s = e->sph;
    sp_state st = e->st[i];
    int k = s ? s->of_body[i] : -1;
    if (k < 0) return st;
    st.x = s->x[k];
    st.v = s->v[k];
    st.L = s->L[k];
    st.w = s->w[k];
    st.q = (quat){s->qw[k], s->qx[k], s->qy[k], s->qz[k]};
    if (s->deferred) sphere_fc(e, s, k, &st.fc, &st.tc);
    return st;
}

int sps_ncontact_of(const lahar_dem_engine *e, int i)
{
    const sp_spheres *s = e->sph;
    int k = s ? s->of_body[i] : -1;
    return k >= 0 && s->deferred ? s->scnt[k] : e->ncontact_body[i];
}

/* ---------------------------------------------------------------------------------------------- */
/* Restart: the touching entries (sphere a, partner b, spring) of both lists.                      */

static int hist_write(const sps_list *l, FILE *f)
{
    int n = 0;
    for (int p = 0; p < l->n; p++) n += l->touch[p];
    if (fwrite(&n, sizeof n, 1, f) != 1) return -1;
    for (int p = 0; p < l->n; p++) {
        if (!l->touch[p]) continue;
        int ab[2] = {l->a[p], l->b[p]};
        if (fwrite(ab, sizeof(int), 2, f) != 2 || fwrite(&l->xi[p], sizeof(vec3), 1, f) != 1) return -1;
    }
    return 0;
}

static int hist_read(sps_hist *h, FILE *f, int na, int nb)
{
    int n;
    if (fread(&n, sizeof n, 1, f) != 1 || n < 0 || hist_reserve(h, n)) return -1;
    h->n = n;
    for (int k = 0; k < n; k++) {
        int ab[2];
        if (fread(ab, sizeof(int), 2, f) != 2 || fread(&h->xi[k], sizeof(vec3), 1, f) != 1) return -1;
        if (ab[0] < 0 || ab[0] >= na || ab[1] < 0 || ab[1] >= nb) return -1;
        h->a[k] = ab[0];
        h->b[k] = ab[1];
    }
    return 0;
}

int sps_write_restart(const lahar_dem_engine *e, FILE *f)
{
    const sp_spheres *s = e->sph;
    if (!s) return 0;
    if (fwrite(&s->ncontact, sizeof(int), 1, f) != 1) return -1;
    return hist_write(&s->pl, f) || hist_write(&s->wl, f) ? -1 : 0;
}

int sps_read_restart(lahar_dem_engine *e, FILE *f)
{
    sp_spheres *s = e->sph;
    if (!s) return 0;
    if (fread(&s->ncontact, sizeof(int), 1, f) != 1) return -1;
    if (hist_read(&s->ph, f, s->n, s->n) || hist_read(&s->wh, f, s->n, s->nwall)) return -1;
    s->deferred = 0;
    sps_load(e);
    s->built = 0; /* the next evaluation builds the lists at the restart positions and takes ph/wh */
    return 0;
}
