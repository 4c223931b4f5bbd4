/* A uniform grid over the features (vertices, edges, faces) of one body, in its body frame, so
 * that a small body near a big terrain/flume surface tests only the nearby features instead of all
 * of them. Built once at setup; queries allocate nothing. */
#ifndef LAHAR_DEM_FEATURE_GRID_H
#define LAHAR_DEM_FEATURE_GRID_H
#include "scene.h"
#include "vec.h"

enum { DEM_FEATURE_VERTEX = 0, DEM_FEATURE_EDGE = 1, DEM_FEATURE_FACE = 2 };

typedef struct {
    double lo[3];   /* body-frame corner of the grid */
    double h;       /* cell size */
    int n[3];       /* cells per axis */
    int nitem[3];   /* features of each type in the body */
    int *start[3];  /* per type: ncell + 1 offsets into items */
    int *items[3];  /* per type: feature indices, each feature in every cell its box touches */
} dem_feature_grid;

/* Scratch space for queries (one per thread). */
typedef struct {
    int *stamp[3];  /* per type: last query id that listed the feature */
    int *out[3];    /* per type: the candidate feature indices */
    int nout[3];
    int cap[3];
    int query;
} dem_feature_query;

/* Build the grid of shape s (features inflated by its sweep radius). Returns 0 or -1 (no memory). */
int dem_feature_grid_build(dem_feature_grid *g, const lahar_shape *s);
void dem_feature_grid_free(dem_feature_grid *g);

/* Scratch able to serve grids with up to nv, ne, nf features. Returns 0 or -1. */
int dem_feature_query_init(dem_feature_query *q, int nv, int ne, int nf);
void dem_feature_query_free(dem_feature_query *q);

/* Features whose inflated box meets the ball (body-frame centre c, radius r), without duplicates,
 * in a deterministic order; results in q->out / q->nout. */
void dem_feature_grid_query(const dem_feature_grid *g, vec3 c, double r, dem_feature_query *q);

#endif
