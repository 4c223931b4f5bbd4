/* The shape builders' private interface: only common/geometry/shape_*.c include it (users include
 * shape_build.h). What the primitives, hulls, STL import and mass properties share, defined once
 * in shape_build.c. */
#ifndef LAHAR_SHAPE_PRIVATE_H
#define LAHAR_SHAPE_PRIVATE_H
#include "scene.h"
#include "vec.h"

static inline vec3 shape_vertex(const lahar_shape *s, int i) { return v3_load(s->v[i]); }

/* Allocate the arrays of a shape (face_start always has nf + 1 entries). */
int shape_alloc(lahar_shape *s, int nv, int ne, int nf, int nfv, double radius);
/* Bounding-box diagonal: the length scale of geometric tolerances. */
double points_scale(const double (*p)[3], int n);
/* Order of edges (i, j) as int[2], for qsort and bsearch. */
int edge_cmp(const void *a, const void *b);
/* Unique undirected edges (i < j, sorted) of all faces; replaces s->e. */
int shape_build_edges(lahar_shape *s);
/* Newell normal of face f (not normalised: its length is twice the face area). */
vec3 face_newell(const lahar_shape *s, int f);
/* A 2D chain of n points in the x-y plane, edges (i, i+1); closed adds the edge n-1 -> 0. */
int shape_make_ring2d(lahar_shape *s, const double (*p)[2], int n, int closed, double radius);

#endif
