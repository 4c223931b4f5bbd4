/* The sphere fast path's Verlet lists (README.md "Sphere fast path", head comment of
 * spheropoly_spheres.c): the spheres binned in a dense grid, for each sphere its partners and the
 * walls within the skin, sorted, with each pair's normal-law constants; the spheres split into
 * parts of about equal work for the threads, and the entries across two parts. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "spheropoly_spheres_impl.h"


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
        if (sps_list_reserve(pl, pl->n + m)) return -1;
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
            if (sps_list_reserve(wl, wl->n + 1)) return -1;
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

/* The Verlet lists of the spheres at their current centres (head comment of spheropoly_spheres.c).
 * -1: no memory (a list or scratch could not grow). */
int sps_build_lists(lahar_dem_engine *e)
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
