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
 * sps_state. */
#include <float.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>
#include "spheropoly_impl.h"
#include "soa_alloc.h"

/* Skin: this fraction of the smallest sphere radius (LAMMPS's bench uses 0.1 d). */
#define SPS_SKIN_FRACTION 0.2
/* Parallel loops from this many spheres on: below, a team's fork/join per loop costs more than the
 * loop (512 spheres on 2 threads took twice the CPU time of 1 thread; 10,000 gained, dem_speed.md). */
enum { SPS_PAR_MIN = 2048 };

typedef struct {
    int n, cap;
    int *a, *b;           /* sphere a, and sphere b > a (sphere list) or wall index (wall list) */
    vec3 *xi;             /* tangential spring */
    unsigned char *touch; /* in contact at the last evaluation (xi is its spring, else 0) */
    unsigned char *fall;  /* wall list: the centre is beyond the face's rim, general path */
    unsigned char *deep;  /* wall list: the centre was farther than the skin inside the face's rim at the build */
    vec3 *f, *ta, *tb;    /* force on b (wall list: on the sphere), torque on a and on b; sphere list:
                             only the entries across two parts of the threaded loop */
    double *delta;        /* wall list: overlap */
    int *ci;              /* sphere list: scratch of the force loop (the entries in contact) */
    dem_pair_consts *pc;  /* normal-law constants of the pair (m*, R* fixed) */
} sps_list;

typedef struct {
    int n, cap;
    int *a, *b;
    vec3 *xi;
} sps_hist; /* the touching entries of a list, sorted: carried over a rebuild or a restart */

struct sp_spheres {
    int n;                /* free spheres */
    int *body;            /* body of sphere k, ascending */
    int *of_body;         /* per body: sphere index, or -1 */
    int *wall_of_body;    /* per body: wall index, or -1 */
    int nwall, *wall_body;
    int ngen, *gen_large; /* fixed/prescribed bodies that are not fast walls (general path) */
    double *rad, *mass;
    int *mat;             /* material */
    double *iner;         /* moment of inertia (3D: the equal moments; 2D: about z) */
    double *inv_iner;     /* 1 / iner */
    int *v0;              /* index of the sphere's vertex in e->vw */
    /* the spheres' state (SoA by field, contiguous by sphere): the body states in e->st are stale
     * (sps_sync writes them, sps_state reads the state) */
    vec3 *x, *v, *w, *L;
    double *qw, *qx, *qy, *qz; /* orientation, unit quaternion by component */
    int nfall;            /* wall entries of the last evaluation beyond the face's rim (general path) */
    int finite;           /* every centre, velocity and angular velocity finite, |x| <= 1e12 m */
    double worst;         /* largest squared displacement of a centre since the list build */
    double skin, rmax;
    vec3 *x0;             /* centres at the last build */
    int built;
    sps_list pl, wl;      /* sphere-sphere and sphere-wall lists */
    sps_hist ph, wh;      /* history hand-over */
    int *bcount;          /* n + 1 counters of the list build */
    int *wstart;          /* per sphere its wall entries [wstart[k], wstart[k+1]) */
    int *pstart;          /* per sphere a its sphere-sphere entries as a: [pstart[a], pstart[a+1]) */
    vec3 *wunit;          /* per wall its unit normal (the one geom_point_polygon_inside uses) */
    vec3 *wnrm, *wp0;     /* per wall its face normal and first vertex (world) */
    double *wrad;         /* per wall its sweep radius */
    /* the force loop in parts of consecutive spheres [part[t], part[t+1]) of about equal work, one
     * per thread; xpair[xstart[t] .. xstart[t+1]) are the entries of part t whose partner is in a
     * later part (npart = 1: no thread team, no such entry); xin[xinstart[t] .. xinstart[t+1]) the
     * entries whose partner b is in part t from earlier parts, by (b, a) */
    int npart, *part, *xstart, *xpair, *xinstart, *xin, xcap;
    vec3 *sf, *st;        /* per sphere: fast-path force and torque */
    int *scnt;
    /* build grid */
    int *cell_start, *cell_of, *order, ncell_cap;
    int *cand, cand_cap;
    int ncontact;
    int deferred;         /* the spheres' forces are in sf/st/scnt only (no general contact on a
                             sphere), not in the body states */
};

/* ---------------------------------------------------------------------------------------------- */

static int list_reserve(sps_list *l, int need)
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
static int hist_take(sps_hist *h, const sps_list *l)
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
static void hist_give(const sps_hist *h, sps_list *l)
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
    if (list_reserve(&s->pl, 8 * s->n + 64) || list_reserve(&s->wl, 2 * s->n + 64) ||
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
/* List build                                                                                      */

static int cmp_int(const void *a, const void *b) { return (*(const int *)a > *(const int *)b) - (*(const int *)a < *(const int *)b); }

/* A dense grid over the spheres' box whose cell holds the largest listed distance of centres, so
 * that a sphere's partners lie in its own and the adjacent cells. Leaves the spheres by cell
 * (ascending index within a cell) in order/cell_start, their centres of this build in x0, and the
 * cells per axis in dn. */
static void bin_spheres(const lahar_dem_engine *e, sp_spheres *s, long long dn[3])
{
    const int n = s->n;
    double cs = 2.0 * s->rmax + s->skin;
    vec3 lo = v3(DBL_MAX, DBL_MAX, DBL_MAX), hi = v3(-DBL_MAX, -DBL_MAX, -DBL_MAX);
    for (int k = 0; k < n; k++) {
        vec3 x = s->x[k];
        lo = v3(fmin(lo.x, x.x), fmin(lo.y, x.y), fmin(lo.z, x.z));
        hi = v3(fmax(hi.x, x.x), fmax(hi.y, x.y), fmax(hi.z, x.z));
    }
    for (;;) { /* coarser cells until the grid fits its pre-sized arrays (a long flume) */
        dn[0] = (long long)floor((hi.x - lo.x) / cs) + 1;
        dn[1] = (long long)floor((hi.y - lo.y) / cs) + 1;
        dn[2] = e->dim == 3 ? (long long)floor((hi.z - lo.z) / cs) + 1 : 1;
        if ((double)dn[0] * (double)dn[1] * (double)dn[2] <= (double)(s->ncell_cap - 1)) break;
        cs *= 1.5;
    }
    int nc = (int)(dn[0] * dn[1] * dn[2]);
    memset(s->cell_start, 0, sizeof(int) * (size_t)(nc + 1));
    for (int k = 0; k < n; k++) {
        vec3 x = s->x[k];
        long long cx = (long long)((x.x - lo.x) / cs), cy = (long long)((x.y - lo.y) / cs);
        long long cz = e->dim == 3 ? (long long)((x.z - lo.z) / cs) : 0;
        cx = cx < dn[0] ? cx : dn[0] - 1;
        cy = cy < dn[1] ? cy : dn[1] - 1;
        cz = cz < dn[2] ? cz : dn[2] - 1;
        s->cell_of[k] = (int)((cz * dn[1] + cy) * dn[0] + cx);
        s->cell_start[s->cell_of[k] + 1]++;
        s->x0[k] = x;
    }
    for (int c = 0; c < nc; c++) s->cell_start[c + 1] += s->cell_start[c];
    for (int k = 0; k < n; k++) s->order[s->cell_start[s->cell_of[k]]++] = k; /* ascending k per cell */
    for (int c = nc; c > 0; c--) s->cell_start[c] = s->cell_start[c - 1];
    s->cell_start[0] = 0;
}

/* The spheres b > a whose surfaces are closer than the skin to sphere a's, from a's cell and the
 * adjacent ones, into s->cand (in cell order; grown when full). Returns their number, or -1 (no
 * memory). */
static int find_partners(sp_spheres *s, int a, const long long dn[3], int zr)
{
    int c = s->cell_of[a];
    long long cx = c % dn[0], cy = (c / dn[0]) % dn[1], cz = c / (dn[0] * dn[1]);
    vec3 xa = s->x0[a];
    int m = 0;
    for (long long z = cz - zr; z <= cz + zr; z++)
        for (long long y = cy - 1; y <= cy + 1; y++)
            for (long long x = cx - 1; x <= cx + 1; x++) {
                if (x < 0 || y < 0 || z < 0 || x >= dn[0] || y >= dn[1] || z >= dn[2]) continue;
                int cc = (int)((z * dn[1] + y) * dn[0] + x);
                for (int q = s->cell_start[cc]; q < s->cell_start[cc + 1]; q++) {
                    int b = s->order[q];
                    if (b <= a) continue;
                    double r = s->rad[a] + s->rad[b] + s->skin;
                    if (v3_norm2(v3_sub(s->x0[b], xa)) >= r * r) continue;
                    if (m == s->cand_cap) {
                        int *p = realloc(s->cand, sizeof(int) * (size_t)(2 * s->cand_cap));
                        if (!p) return -1;
                        s->cand = p;
                        s->cand_cap *= 2;
                    }
                    s->cand[m++] = b;
                }
            }
    return m;
}

/* Sphere-sphere: for each a (ascending) the partners b > a within the skin, ascending, so that the
 * sums of a sphere's contacts come in partner order whenever the list was built (restarts continue
 * bit for bit); each entry carries its pair's normal-law constants (m*, R* are fixed). */
static int list_sphere_pairs(lahar_dem_engine *e, sp_spheres *s, const long long dn[3])
{
    const int n = s->n;
    sps_list *pl = &s->pl;
    pl->n = 0;
    int zr = e->dim == 3 ? 1 : 0;
    for (int a = 0; a < n; a++) {
        s->pstart[a] = pl->n;
        int m = find_partners(s, a, dn, zr);
        if (m < 0) return -1;
        if (m > 1) qsort(s->cand, (size_t)m, sizeof(int), cmp_int);
        if (list_reserve(pl, pl->n + m)) return -1;
        for (int q = 0; q < m; q++) {
            int b = s->cand[q];
            double ma = s->mass[a], mb = s->mass[b], ra = s->rad[a], rb = s->rad[b];
            pl->a[pl->n] = a;
            pl->b[pl->n] = b;
            pl->pc[pl->n] = dem_pair_consts_make(&e->laws[s->mat[a] * e->nmat + s->mat[b]], ma * mb / (ma + mb),
                                                 ra * rb / (ra + rb));
            pl->n++;
        }
    }
    s->pstart[n] = pl->n;
    return 0;
}

/* Per wall, what the force loop reads of it (face normal, unit normal, first vertex, sweep
 * radius), by wall index. */
static void cache_walls(const lahar_dem_engine *e, sp_spheres *s)
{
    for (int w = 0; w < s->nwall; w++) {
        const sp_geo *g = &e->geo[s->wall_body[w]];
        s->wnrm[w] = e->nw[g->f0];
        s->wunit[w] = v3_normalize(s->wnrm[w]);
        s->wp0[w] = e->fw[e->fstart[g->fs0]];
        s->wrad[w] = g->radius;
    }
}

/* The centre x, projected on the plane of the m-gon poly (unit normal nn), lies farther than the
 * skin inside every edge's line: it stays inside the face until the next build, so wall_force
 * skips the polygon test. */
static int deep_inside(const sp_spheres *s, vec3 x, vec3 nn, const vec3 *poly, int m)
{
    vec3 pp = v3_axpy(-v3_dot(v3_sub(x, poly[0]), nn), nn, x);
    int deep = 1;
    for (int i = 0; i < m && deep; i++) {
        vec3 ab = v3_sub(poly[i + 1 < m ? i + 1 : 0], poly[i]);
        deep = v3_dot(v3_cross(ab, v3_sub(pp, poly[i])), nn) > s->skin * v3_norm(ab);
    }
    return deep;
}

/* Sphere-wall: for each sphere (ascending) the walls whose plane is within the skin of its
 * surface, in wall order (a sphere sums its walls after its partners, always in this order). */
static int list_sphere_walls(lahar_dem_engine *e, sp_spheres *s)
{
    const int n = s->n;
    sps_list *wl = &s->wl;
    wl->n = 0;
    for (int a = 0; a < n; a++) {
        s->wstart[a] = wl->n;
        for (int w = 0; w < s->nwall; w++) {
            const sp_geo *g = &e->geo[s->wall_body[w]];
            const vec3 *poly = e->fw + e->fstart[g->fs0];
            int m = e->fstart[g->fs0 + 1] - e->fstart[g->fs0];
            double dpl = v3_dot(v3_sub(s->x0[a], poly[0]), e->nw[g->f0]);
            if (fabs(dpl) >= s->rad[a] + g->radius + s->skin) continue;
            if (list_reserve(wl, wl->n + 1)) return -1;
            wl->a[wl->n] = a;
            wl->b[wl->n] = w;
            /* vertex-face: m* = the sphere's mass, R* = its radius (README, contact laws) */
            wl->pc[wl->n] = dem_pair_consts_make(&e->laws[s->mat[a] * e->nmat + g->material], s->mass[a], s->rad[a]);
            wl->deep[wl->n] = (unsigned char)deep_inside(s, s->x0[a], s->wunit[w], poly, m);
            wl->n++;
        }
    }
    s->wstart[n] = wl->n;
    return 0;
}

/* Parts of consecutive spheres of about equal work (entries as a, walls, the sphere itself), one
 * per thread of the force loop. */
static void split_into_parts(sp_spheres *s)
{
    const int n = s->n;
    const sps_list *pl = &s->pl, *wl = &s->wl;
    double total = (double)pl->n + (double)wl->n + (double)n, acc = 0.0;
    int t = 1;
    s->part[0] = 0;
    for (int k = 0; k < n && t < s->npart; k++) {
        acc += (double)(s->pstart[k + 1] - s->pstart[k]) + (double)(s->wstart[k + 1] - s->wstart[k]) + 1.0;
        while (t < s->npart && acc >= total * t / s->npart) s->part[t++] = k + 1;
    }
    while (t <= s->npart) s->part[t++] = n;
}

/* The entries whose partner lies in a later part: they are computed first (phase 1) so that
 * every thread writes only its own spheres; xpair lists them by part, xin the same entries by
 * partner b (a ascending within b), where they enter b's sum. -1: no memory. */
static int list_cross_entries(sp_spheres *s)
{
    const int n = s->n;
    const sps_list *pl = &s->pl;
    int nx = 0;
    for (int t = 0; t < s->npart; t++) {
        s->xstart[t] = nx;
        for (int p = s->pstart[s->part[t]]; p < s->pstart[s->part[t + 1]]; p++) {
            if (pl->b[p] < s->part[t + 1]) continue;
            if (nx == s->xcap) {
                int *q = realloc(s->xpair, sizeof(int) * (size_t)(2 * s->xcap));
                if (q) s->xpair = q;
                int *r = realloc(s->xin, sizeof(int) * (size_t)(2 * s->xcap));
                if (r) s->xin = r;
                if (!q || !r) return -1;
                s->xcap *= 2;
            }
            s->xpair[nx++] = p;
        }
    }
    s->xstart[s->npart] = nx;
    /* the same entries by partner b, stable (a ascending within b): counting sort */
    int *cnt = s->bcount;
    memset(cnt, 0, sizeof(int) * (size_t)(n + 1));
    for (int q = 0; q < nx; q++) cnt[pl->b[s->xpair[q]] + 1]++;
    for (int k = 0; k < n; k++) cnt[k + 1] += cnt[k];
    for (int t = 0; t <= s->npart; t++) s->xinstart[t] = cnt[s->part[t]];
    for (int q = 0; q < nx; q++) s->xin[cnt[pl->b[s->xpair[q]]]++] = s->xpair[q];
    return 0;
}

/* The Verlet lists of the spheres at their current centres (the file's head comment). -1: no
 * memory (a list or scratch could not grow). */
static int build_lists(lahar_dem_engine *e)
{
    sp_spheres *s = e->sph;
    long long dn[3];
    bin_spheres(e, s, dn);
    if (list_sphere_pairs(e, s, dn)) return -1;
    cache_walls(e, s);
    if (list_sphere_walls(e, s)) return -1;
    if (s->npart > 1) {
        split_into_parts(s);
        if (list_cross_entries(s)) return -1;
    } else {
        s->part[0] = 0;
        s->part[1] = s->n;
    }
    s->built = 1;
    return 0;
}

/* ---------------------------------------------------------------------------------------------- */
/* Forces                                                                                          */

/* The spring of the last step onto the tangent plane of normal n, magnitude kept: the series of
 * the scale 1/sqrt(1 - u), u = (xi.n)^2/|xi|^2, for u <= 1e-5 (truncation < 3e-21; as the pair's),
 * else the square root. */
static inline vec3 spring_onto(vec3 xi, vec3 n)
{
    double m0 = v3_norm2(xi);
    if (m0 == 0.0) return xi;
    double pn = v3_dot(xi, n), p2 = pn * pn;
    vec3 r = v3_axpy(-pn, n, xi);
    if (p2 <= 1e-5 * m0) {
        double u = p2 / m0;
        return v3_scale(r, 1.0 + u * (0.5 + u * (0.375 + u * 0.3125)));
    }
    double m1 = v3_norm2(r);
    return m1 > 0.0 ? v3_scale(r, sqrt(m0 / m1)) : r;
}

/* Sphere a of a pair: its state and radius (loaded once per run of a's entries). */
typedef struct {
    vec3 x, v, w;
    double r;
} sps_side;

static inline __attribute__((always_inline)) void contact_kernel(const sps_side *A, vec3 dx, double d2, vec3 vb, vec3 wb,
                                                                 double rb, const dem_pair_law *law,
                                                                 const dem_pair_consts *pc, unsigned char *touch, vec3 *xip,
                                                                 double h, double maxov, vec3 *f, vec3 *ta, vec3 *tb,
                                                                 int *bad);

/* The force between sphere a and sphere b (b's state, the pair's law and constants, its spring and
 * contact flag) at the current positions: 1 in contact with the force on b in *f and the torques on
 * a and b in *ta, *tb (a gets -f), 0 out of contact. Updates the spring and the contact flag;
 * *bad |= the overlap exceeds maxov x the smaller radius. */
static inline __attribute__((always_inline)) int pair_kernel(const sps_side *A, vec3 xb, vec3 vb, vec3 wb, double rb,
                                                             const dem_pair_law *law, const dem_pair_consts *pc,
                                                             unsigned char *touch, vec3 *xip, double h, double maxov,
                                                             vec3 *f, vec3 *ta, vec3 *tb, int *bad)
{
    double rs = A->r + rb;
    vec3 dx = v3_sub(xb, A->x);
    double d2 = v3_norm2(dx);
    if (d2 >= rs * rs) {
        *touch = 0;
        return 0;
    }
    contact_kernel(A, dx, d2, vb, wb, rb, law, pc, touch, xip, h, maxov, f, ta, tb, bad);
    return 1;
}

/* pair_kernel's force for a pair in contact (d2 = |dx|^2 < (ra + rb)^2, dx = xb - xa). */
static inline __attribute__((always_inline)) void contact_kernel(const sps_side *A, vec3 dx, double d2, vec3 vb, vec3 wb,
                                                                 double rb, const dem_pair_law *law,
                                                                 const dem_pair_consts *pc, unsigned char *touch, vec3 *xip,
                                                                 double h, double maxov, vec3 *f, vec3 *ta, vec3 *tb,
                                                                 int *bad)
{
    double ra = A->r, rs = ra + rb;
    double d = sqrt(d2);
    double delta = rs - d;
    /* the spring onto the new tangent plane, magnitude kept: xi - (xi.n) n scaled by |xi| / |r|
     * = 1/sqrt(1 - u), u = (xi.n)^2 / |xi|^2. One division gives 1/d = d/d^2 and 1/|xi|^2 (it
     * needs no d, so it runs beside the square root); for u <= 1e-5
     * (the normal turned by < 0.2 degrees since the last step) the scale is the series
     * 1 + u/2 + 3u^2/8 + 5u^3/16 (truncation < 3e-21): no square root on the way to the force */
    vec3 xi = *xip, n;
    double m0 = *touch ? v3_norm2(xi) : 0.0;
    if (!(d > 1e-12 * rs)) {
        n = v3(0.0, 0.0, 1.0);
        xi = m0 > 0.0 ? spring_onto(xi, n) : v3(0.0, 0.0, 0.0);
    } else if (m0 > 1e-200) {
        double r = 1.0 / (d2 * m0);
        n = v3_scale(dx, d * (r * m0));
        double pn = v3_dot(xi, n), u = pn * pn * (r * d2);
        vec3 rx = v3_axpy(-pn, n, xi);
        if (u <= 1e-5) {
            xi = v3_scale(rx, 1.0 + u * (0.5 + u * (0.375 + u * 0.3125)));
        } else {
            double m1 = v3_norm2(rx);
            xi = m1 > 0.0 ? v3_scale(rx, sqrt(m0 / m1)) : rx;
        }
    } else {
        n = v3_scale(dx, 1.0 / d);
        xi = m0 > 0.0 ? spring_onto(xi, n) : v3(0.0, 0.0, 0.0);
    }
    /* contact point in the middle of the overlap: cp = xa + la n = xb - lb n */
    double la = ra - 0.5 * delta, lb = rb - 0.5 * delta;
    /* v_b(cp) - v_a(cp) = vb - va - (lb wb + la wa) x n */
    vec3 vr = v3_sub(v3_sub(vb, A->v), v3_cross(v3_axpy(la, A->w, v3_scale(wb, lb)), n));
    double vn = v3_dot(vr, n);
    vec3 vt = v3_axpy(-vn, n, vr);
    double ks, cn;
    double fn = dem_normal_force_pc(law, pc, delta, -vn, 1.0, &ks, &cn);
    xi = v3_axpy(h, vt, xi);
    vec3 ft = dem_tangential_force(law, &xi, vt, fn, ks, cn);
    /* torques about the centres: (cp - xa) x (-f) = -la n x ft, (cp - xb) x f = -lb n x ft */
    vec3 c = v3_cross(n, ft);
    *touch = 1;
    *xip = xi;
    *bad |= delta > maxov * (ra < rb ? ra : rb);
    *f = v3_axpy(fn, n, ft);
    *ta = v3_scale(c, -la);
    *tb = v3_scale(c, -lb);
}

/* pair_kernel for listed pair p. */
static inline int pair_force(const lahar_dem_engine *e, sp_spheres *s, int p, double h, vec3 *f, vec3 *ta, vec3 *tb,
                             int *bad)
{
    sps_list *l = &s->pl;
    int a = l->a[p], b = l->b[p];
    sps_side A = {s->x[a], s->v[a], s->w[a], s->rad[a]};
    return pair_kernel(&A, s->x[b], s->v[b], s->w[b], s->rad[b], &e->laws[s->mat[a] * e->nmat + s->mat[b]], &l->pc[p],
                       &l->touch[p], &l->xi[p], h, e->max_overlap, f, ta, tb, bad);
}

/* Sphere a against wall w, the centre within the sum of the radii of the face's plane
 * (dpl: signed distance along the wall's normal): vertex-face when the centre projects inside the
 * face, else the pair goes to the general narrow phase (edges and corners of the face; fall = 1,
 * returns 0). An entry whose centre was deep inside the face at the list build (`deep`: farther
 * than the skin from every edge) stays inside until the next build (a centre moves less than
 * skin/2), so the polygon test is skipped. The normal is the face's unit normal, towards the
 * sphere. Force on the sphere. */
static int wall_force(const lahar_dem_engine *e, sp_spheres *s, int p, double dpl, double h)
{
    sps_list *l = &s->wl;
    int a = l->a[p], w = l->b[p], wb = s->wall_body[w];
    const sp_geo *gw = &e->geo[wb];
    const vec3 xa = s->x[a];
    double ra = s->rad[a], rs = ra + gw->radius;
    vec3 nn = s->wunit[w], c = v3_axpy(-v3_dot(v3_sub(xa, s->wp0[w]), nn), nn, xa);
    if (!l->deep[p]) {
        int b0 = e->fstart[gw->fs0], m = e->fstart[gw->fs0 + 1] - b0;
        if (!geom_point_polygon_inside(xa, e->fw + b0, m, e->nw[gw->f0], &c)) {
            l->touch[p] = 0;
            l->fall[p] = 1;
            return 0;
        }
    }
    double d = fabs(dpl);
    vec3 n = dpl >= 0.0 ? nn : v3_neg(nn); /* from the wall to the sphere */
    vec3 cp = v3_scale(v3_add(v3_axpy(gw->radius, n, c), v3_axpy(-ra, n, xa)), 0.5);
    vec3 xi = l->touch[p] ? spring_onto(l->xi[p], n) : v3(0.0, 0.0, 0.0);
    vec3 rpa = v3_sub(cp, xa);
    vec3 vr = v3_add(s->v[a], v3_cross(s->w[a], rpa)); /* the wall is fixed */
    double vn = v3_dot(vr, n);
    vec3 vt = v3_axpy(-vn, n, vr);
    const dem_pair_law *law = &e->laws[s->mat[a] * e->nmat + gw->material];
    double ks, cn, delta = rs - d;
    double fn = dem_normal_force_pc(law, &l->pc[p], delta, -vn, 1.0, &ks, &cn);
    xi = v3_axpy(h, vt, xi);
    vec3 ft = dem_tangential_force(law, &xi, vt, fn, ks, cn);
    vec3 f = v3_axpy(fn, n, ft);
    l->touch[p] = 1;
    l->xi[p] = xi;
    l->f[p] = f;
    l->ta[p] = v3_cross(rpa, f);
    l->tb[p] = v3_cross(v3_sub(cp, e->st[wb].x), v3_neg(f));
    l->delta[p] = delta;
    return 1;
}

static int overlap_fault(lahar_dem_engine *e, int a, int b, double delta, double rmin, vec3 cp, char *err, size_t errlen)
{
    snprintf(err, errlen,
             "spheropoly: overlap %.3g m between bodies %d '%s' and %d '%s' exceeds %g x the smaller sweep radius %.3g m "
             "at substep %ld (time step too large or bodies interpenetrating)",
             delta, a, e->names[a], b, e->names[b], e->max_overlap, rmin, e->step);
    e->fault = (lahar_dem_fault){.body = a, .other = b, .value = delta, .limit = e->max_overlap * rmin, .substep = e->step};
    snprintf(e->fault.what, sizeof e->fault.what, "overlap");
    v3_store(cp, e->fault.x);
    e->has_fault = 1;
    return -1;
}

/* Phase 1 of part t (threaded only): the entries of its spheres whose partner belongs to a later
 * part, forces kept in the entry for the two sums. */
static void forces_cross(const lahar_dem_engine *e, sp_spheres *s, int t, double h, int *cnt, int *bad)
{
    sps_list *l = &s->pl;
    int c = 0, bd = 0;
    for (int q = s->xstart[t]; q < s->xstart[t + 1]; q++) {
        int p = s->xpair[q];
        c += pair_force(e, s, p, h, &l->f[p], &l->ta[p], &l->tb[p], &bd);
    }
    *cnt += c;
    *bad |= bd;
}

/* Phase 2 of part t: the sums of its spheres [k0, k1), each in ascending partner order (the
 * entries of earlier parts first, as their partners are smaller), then its walls. The sums of a
 * are kept in registers over its run of entries. */
static void forces_own(const lahar_dem_engine *e, sp_spheres *s, int t, double h, int *cnt, int *bad, int *nfall)
{
    sps_list *l = &s->pl, *wl = &s->wl;
    const int k0 = s->part[t], k1 = s->part[t + 1];
    memset(s->sf + k0, 0, sizeof(vec3) * (size_t)(k1 - k0));
    memset(s->st + k0, 0, sizeof(vec3) * (size_t)(k1 - k0));
    memset(s->scnt + k0, 0, sizeof(int) * (size_t)(k1 - k0));
    for (int q = s->xinstart[t]; q < s->xinstart[t + 1]; q++) { /* by (b, a): each b's sum in ascending a */
        int p = s->xin[q];
        if (!l->touch[p]) continue;
        int b = l->b[p];
        s->sf[b] = v3_add(s->sf[b], l->f[p]);
        s->st[b] = v3_add(s->st[b], l->tb[p]);
        s->scnt[b]++;
    }
    int c = 0, bd = 0;
    /* locals: the stores into the sums cannot alias them */
    const vec3 *x = s->x, *v = s->v, *w = s->w;
    const double *rad = s->rad, maxov = e->max_overlap;
    const int *bl = l->b, *pstart = s->pstart, *mat = s->mat, nmat = e->nmat;
    const dem_pair_consts *pc = l->pc;
    unsigned char *touch = l->touch;
    vec3 *xi = l->xi, *sf = s->sf, *st = s->st;
    int *scnt = s->scnt;
    const int *al = l->a;
    int *ci = l->ci;
    /* blocks of spheres: first the entries in contact, without a branch (the contact test is
     * data-dependent: a mispredicted branch per pair), then their forces */
    for (int a0 = k0; a0 < k1; a0 += 64) {
        const int a1 = a0 + 64 < k1 ? a0 + 64 : k1, p0 = pstart[a0], p1 = pstart[a1];
        int nc = p0;
        for (int p = p0; p < p1; p++) {
            int a = al[p], b = bl[p];
            double rs = rad[a] + rad[b];
            int in = v3_norm2(v3_sub(x[b], x[a])) < rs * rs, cross = b >= k1;
            unsigned char tp = touch[p];
            touch[p] = cross ? tp : (unsigned char)(tp & in); /* cross: phase 1 set it */
            ci[nc] = p;
            nc += cross ? tp : in;
        }
        for (int q = p0; q < nc; q++) {
            int p = ci[q], a = al[p], b = bl[p];
            if (b >= k1) { /* computed in phase 1 */
                scnt[a]++;
                sf[a] = v3_sub(sf[a], l->f[p]);
                st[a] = v3_add(st[a], l->ta[p]);
                continue;
            }
            const sps_side A = {x[a], v[a], w[a], rad[a]};
            vec3 dx = v3_sub(x[b], A.x), f, ta, tb;
            contact_kernel(&A, dx, v3_norm2(dx), v[b], w[b], rad[b], e->laws + mat[a] * nmat + mat[b], &pc[p], &touch[p],
                           &xi[p], h, maxov, &f, &ta, &tb, &bd);
            c++;
            scnt[a]++;
            sf[a] = v3_sub(sf[a], f);
            st[a] = v3_add(st[a], ta);
            sf[b] = v3_add(sf[b], f);
            st[b] = v3_add(st[b], tb);
            scnt[b]++;
        }
    }
    /* walls: the entries within reach of the plane first (no branch), then their forces */
    int nf = 0, nw = s->wstart[k0];
    int *wci = wl->ci;
    double *wd = wl->delta; /* scratch: the signed distances to the plane, overwritten by the overlaps */
    for (int p = s->wstart[k0]; p < s->wstart[k1]; p++) {
        int a = wl->a[p], w = wl->b[p];
        double dpl = v3_dot(v3_sub(x[a], s->wp0[w]), s->wnrm[w]);
        int in = fabs(dpl) < rad[a] + s->wrad[w];
        wl->touch[p] = (unsigned char)(wl->touch[p] & in);
        wl->fall[p] = 0;
        wd[p] = dpl;
        wci[nw] = p;
        nw += in;
    }
    for (int q = s->wstart[k0]; q < nw; q++) {
        int p = wci[q];
        if (!wall_force(e, s, p, wd[p], h)) {
            nf++;
            continue;
        }
        int a = wl->a[p];
        double ra = s->rad[a], rb = e->geo[s->wall_body[wl->b[p]]].radius;
        c++;
        bd |= wl->delta[p] > e->max_overlap * (ra < rb ? ra : rb);
        s->sf[a] = v3_add(s->sf[a], wl->f[p]);
        s->st[a] = v3_add(s->st[a], wl->ta[p]);
        s->scnt[a]++;
    }
    *cnt += c;
    *bad |= bd;
    *nfall += nf;
}

int sps_forces(lahar_dem_engine *e, double h, char *err, size_t errlen)
{
    sp_spheres *s = e->sph;
    /* rebuild when a sphere moved more than skin/2 since the last build (the drift keeps the
     * largest squared displacement) */
    double lim2 = 0.25 * s->skin * s->skin;
    if (!s->built || s->worst > lim2) {
        /* hand the springs over (after a restart the history is already in ph/wh) */
        if (s->built && (hist_take(&s->ph, &s->pl) || hist_take(&s->wh, &s->wl))) goto oom;
        if (build_lists(e)) goto oom;
        hist_give(&s->ph, &s->pl);
        hist_give(&s->wh, &s->wl);
        s->worst = 0.0;
    }
    sps_list *pl = &s->pl, *wl = &s->wl;
    int cnt = 0, bad = 0, nfall = 0;
    const int np = s->npart;
    if (np == 1) {
        forces_own(e, s, 0, h, &cnt, &bad, &nfall);
    } else {
#pragma omp parallel num_threads(np) reduction(+ : cnt, nfall) reduction(| : bad)
        {
            /* a team smaller than asked for takes several parts per thread */
            int id = omp_get_thread_num(), nt = omp_get_num_threads();
            for (int t = id; t < np; t += nt) forces_cross(e, s, t, h, &cnt, &bad);
#pragma omp barrier
            for (int t = id; t < np; t += nt) forces_own(e, s, t, h, &cnt, &bad, &nfall);
        }
    }
    /* the overlap limit: the first offender in list order is reported */
    for (int p = 0; bad && p < pl->n; p++) {
        if (!pl->touch[p]) continue;
        int a = pl->a[p], b = pl->b[p];
        double rmin = fmin(s->rad[a], s->rad[b]);
        double delta = s->rad[a] + s->rad[b] - sqrt(v3_norm2(v3_sub(s->x[b], s->x[a])));
        if (delta > e->max_overlap * rmin) {
            vec3 xa = s->x[a], xb = s->x[b];
            return overlap_fault(e, s->body[a], s->body[b], delta, rmin, v3_scale(v3_add(xa, xb), 0.5), err, errlen);
        }
    }
    for (int p = 0; bad && p < wl->n; p++) {
        if (!wl->touch[p]) continue;
        int a = wl->a[p], wb = s->wall_body[wl->b[p]];
        double rmin = fmin(s->rad[a], e->geo[wb].radius);
        if (wl->delta[p] > e->max_overlap * rmin)
            return overlap_fault(e, s->body[a], wb, wl->delta[p], rmin, s->x[a], err, errlen);
    }
    s->ncontact = cnt;
    s->nfall = nfall;
    e->contacts_evaluated += cnt;
    return 0;
oom:
    snprintf(err, errlen, "spheropoly: out of memory for the sphere neighbour list");
    return -1;
}

int sps_fallback_pairs(lahar_dem_engine *e, int (*add)(lahar_dem_engine *, int, int))
{
    sp_spheres *s = e->sph;
    if (s->nfall == 0) return 0;
    for (int p = 0; p < s->wl.n; p++)
        if (s->wl.fall[p] && add(e, s->body[s->wl.a[p]], s->wall_body[s->wl.b[p]])) return -1;
    return 0;
}

void sps_defer(lahar_dem_engine *e) { e->sph->deferred = 1; }

void sps_accumulate(lahar_dem_engine *e)
{
    sp_spheres *s = e->sph;
    s->deferred = 0;
#pragma omp parallel for schedule(static) num_threads(e->nthr) if (s->n >= SPS_PAR_MIN)
    for (int k = 0; k < s->n; k++) {
        sp_state *st = &e->st[s->body[k]];
        st->fc = s->sf[k];
        st->tc = s->st[k];
        e->ncontact_body[s->body[k]] = s->scnt[k];
    }
}

void sps_accumulate_walls(lahar_dem_engine *e)
{
    sp_spheres *s = e->sph;
    /* the walls feel the reaction, summed in list order */
    const sps_list *wl = &s->wl;
    for (int p = 0; p < wl->n; p++) {
        if (!wl->touch[p]) continue;
        int wb = s->wall_body[wl->b[p]];
        e->st[wb].fc = v3_sub(e->st[wb].fc, wl->f[p]);
        e->st[wb].tc = v3_add(e->st[wb].tc, wl->tb[p]);
        e->ncontact_body[wb]++;
    }
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
