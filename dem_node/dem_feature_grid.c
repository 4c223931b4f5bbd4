/* Body-frame feature grid (see dem_feature_grid.h). */
#include "dem_feature_grid.h"
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static void feature_box(const lahar_shape *s, int type, int i, double lo[3], double hi[3])
{
    int nvtx = 1, base = 0;
    const int *ids = &i;
    int pair[2];
    if (type == DEM_FEATURE_EDGE) {
        pair[0] = s->e[i][0];
        pair[1] = s->e[i][1];
        ids = pair;
        nvtx = 2;
    } else if (type == DEM_FEATURE_FACE) {
        base = s->face_start[i];
        nvtx = s->face_start[i + 1] - base;
        ids = s->face_v + base;
    }
    for (int k = 0; k < 3; k++) {
        lo[k] = DBL_MAX;
        hi[k] = -DBL_MAX;
    }
    for (int j = 0; j < nvtx; j++)
        for (int k = 0; k < 3; k++) {
            double x = s->v[ids[j]][k];
            if (x < lo[k]) lo[k] = x;
            if (x > hi[k]) hi[k] = x;
        }
    for (int k = 0; k < 3; k++) {
        lo[k] -= s->radius;
        hi[k] += s->radius;
    }
}

static int clampi(int x, int lo, int hi) { return x < lo ? lo : (x > hi ? hi : x); }

static void cell_range(const dem_feature_grid *g, const double lo[3], const double hi[3], int c0[3], int c1[3])
{
    for (int k = 0; k < 3; k++) {
        c0[k] = clampi((int)floor((lo[k] - g->lo[k]) / g->h), 0, g->n[k] - 1);
        c1[k] = clampi((int)floor((hi[k] - g->lo[k]) / g->h), 0, g->n[k] - 1);
    }
}

int dem_feature_grid_build(dem_feature_grid *g, const lahar_shape *s)
{
    memset(g, 0, sizeof *g);
    int count[3] = {s->nv, s->ne, s->nf};
    double blo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, bhi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
    double size_sum = 0.0;
    int nfeat = 0;
    for (int t = 0; t < 3; t++)
        for (int i = 0; i < count[t]; i++) {
            double lo[3], hi[3], m = 0.0;
            feature_box(s, t, i, lo, hi);
            for (int k = 0; k < 3; k++) {
                if (lo[k] < blo[k]) blo[k] = lo[k];
                if (hi[k] > bhi[k]) bhi[k] = hi[k];
                if (hi[k] - lo[k] > m) m = hi[k] - lo[k];
            }
            if (t != DEM_FEATURE_VERTEX) { /* vertices are points; edges/faces set the scale */
                size_sum += m;
                nfeat++;
            }
        }
    /* cell about the mean feature size, so that a feature touches a few cells; grown until the
     * grid has at most ~8 cells per feature */
    double h = nfeat > 0 ? size_sum / nfeat : 2.0 * s->radius;
    if (!(h > 0.0)) h = 1.0;
    long ncell;
    int total = s->nv + s->ne + s->nf;
    for (;;) {
        ncell = 1;
        for (int k = 0; k < 3; k++) {
            g->n[k] = (int)ceil((bhi[k] - blo[k]) / h);
            if (g->n[k] < 1) g->n[k] = 1;
            ncell *= g->n[k];
        }
        if (ncell <= 8L * total + 64) break;
        h *= 1.5;
    }
    g->h = h;
    for (int k = 0; k < 3; k++) g->lo[k] = blo[k];
    for (int t = 0; t < 3; t++) {
        g->nitem[t] = count[t];
        g->start[t] = calloc((size_t)ncell + 1, sizeof(int));
        if (!g->start[t]) return -1;
        for (int pass = 0; pass < 2; pass++) {
            for (int i = 0; i < count[t]; i++) {
                double lo[3], hi[3];
                int c0[3], c1[3];
                feature_box(s, t, i, lo, hi);
                cell_range(g, lo, hi, c0, c1);
                for (int z = c0[2]; z <= c1[2]; z++)
                    for (int y = c0[1]; y <= c1[1]; y++)
                        for (int x = c0[0]; x <= c1[0]; x++) {
                            long c = ((long)z * g->n[1] + y) * g->n[0] + x;
                            if (pass == 0) g->start[t][c + 1]++;
                            else g->items[t][g->start[t][c]++] = i;
                        }
            }
            if (pass == 0) {
                for (long c = 0; c < ncell; c++) g->start[t][c + 1] += g->start[t][c];
                g->items[t] = malloc(sizeof(int) * (size_t)(g->start[t][ncell] > 0 ? g->start[t][ncell] : 1));
                if (!g->items[t]) return -1;
            } else {
                /* the fill advanced each start to the next cell's start: shift back */
                for (long c = ncell; c > 0; c--) g->start[t][c] = g->start[t][c - 1];
                g->start[t][0] = 0;
            }
        }
    }
    return 0;
}

void dem_feature_grid_free(dem_feature_grid *g)
{
    for (int t = 0; t < 3; t++) {
        free(g->start[t]);
        free(g->items[t]);
        g->start[t] = g->items[t] = NULL;
    }
}

int dem_feature_query_init(dem_feature_query *q, int nv, int ne, int nf)
{
    memset(q, 0, sizeof *q);
    int n[3] = {nv, ne, nf};
    for (int t = 0; t < 3; t++) {
        q->cap[t] = n[t] > 0 ? n[t] : 1;
        q->stamp[t] = calloc((size_t)q->cap[t], sizeof(int));
        q->out[t] = malloc(sizeof(int) * (size_t)q->cap[t]);
        if (!q->stamp[t] || !q->out[t]) return -1;
    }
    return 0;
}

void dem_feature_query_free(dem_feature_query *q)
{
    for (int t = 0; t < 3; t++) {
        free(q->stamp[t]);
        free(q->out[t]);
        q->stamp[t] = q->out[t] = NULL;
    }
}

void dem_feature_grid_query(const dem_feature_grid *g, vec3 c, double r, dem_feature_query *q)
{
    double lo[3] = {c.x - r, c.y - r, c.z - r}, hi[3] = {c.x + r, c.y + r, c.z + r};
    q->query++;
    if (q->query == 0x7fffffff) { /* wrap: clear the stamps (once per 2^31 queries) */
        for (int t = 0; t < 3; t++) memset(q->stamp[t], 0, sizeof(int) * (size_t)q->cap[t]);
        q->query = 1;
    }
    for (int t = 0; t < 3; t++) q->nout[t] = 0;
    for (int k = 0; k < 3; k++)
        if (hi[k] < g->lo[k] || lo[k] > g->lo[k] + g->n[k] * g->h) return;
    int c0[3], c1[3];
    cell_range(g, lo, hi, c0, c1);
    for (int z = c0[2]; z <= c1[2]; z++)
        for (int y = c0[1]; y <= c1[1]; y++)
            for (int x = c0[0]; x <= c1[0]; x++) {
                long cell = ((long)z * g->n[1] + y) * g->n[0] + x;
                for (int t = 0; t < 3; t++)
                    for (int k = g->start[t][cell]; k < g->start[t][cell + 1]; k++) {
                        int i = g->items[t][k];
                        if (q->stamp[t][i] != q->query) {
                            q->stamp[t][i] = q->query;
                            q->out[t][q->nout[t]++] = i;
                        }
                    }
            }
}
