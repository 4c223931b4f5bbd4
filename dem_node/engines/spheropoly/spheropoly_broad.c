/* The broad phase of the spheropoly engine (README.md "Contact detection"): free bodies binned by
 * centre in uniform grids of cell >= their bounding diameter (one level per factor 2 of size; dense
 * over the bodies' box or hashed), so that neighbours are within the 27 surrounding cells, half of
 * them visited in a body's own level; fixed and prescribed bodies (few, possibly huge) are tested
 * against every free body by box. O(N) per step. */
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <string.h>
#include "spheropoly_impl.h"

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
    if (e->npair == e->pair_cap && spp_grow((void **)&e->pairs, &e->pair_cap, e->npair + 1, sizeof(int[2]))) return -1;
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
        if (spp_grow((void **)&e->bucket_start, &cap, nb + 1, sizeof(int))) return -1;
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
int spp_broad_phase(lahar_dem_engine *e)
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
