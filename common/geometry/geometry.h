/* Geometry of sphero-polyhedra, in one place: closest points between features (vertex, edge,
 * face), closest point on a body's surface, distance between two bodies. Used by the DEM
 * contact detection, by the case loader (overlap at t = 0) and by the SPH-DEM coupling
 * (virtual particle at the closest surface point, Trujillo-Vela et al. 2020 eq. 12-14). */
#ifndef LAHAR_GEOMETRY_H
#define LAHAR_GEOMETRY_H
#include "scene.h"
#include "vec.h"

/* Closest point c on segment [a, b] to p; returns |p - c|. */
double geom_point_segment(vec3 p, vec3 a, vec3 b, vec3 *c);

/* Closest points cp on [p0, p1] and cq on [q0, q1]; returns |cp - cq|. Robust for parallel and
 * degenerate (zero-length) segments. */
double geom_segment_segment(vec3 p0, vec3 p1, vec3 q0, vec3 q1, vec3 *cp, vec3 *cq);

/* Squared distance from p to segment [a, b] and the parameter t in [0, 1] of the closest point
 * (inline, no sqrt: for the culling loops of the DEM narrow phase). */
static inline double geom_point_segment_dist2(vec3 p, vec3 a, vec3 b, double *t)
{
    vec3 ab = v3_sub(b, a), ap = v3_sub(p, a);
    double l2 = v3_norm2(ab), s = 0.0;
    if (l2 > 0.0) {
        s = v3_dot(ap, ab) / l2;
        s = s < 0.0 ? 0.0 : (s > 1.0 ? 1.0 : s);
    }
    if (t) *t = s;
    return v3_norm2(v3_sub(ap, v3_scale(ab, s)));
}

/* As geom_point_segment, also returning the parameter t in [0, 1] of c = a + t (b - a). */
double geom_point_segment_param(vec3 p, vec3 a, vec3 b, vec3 *c, double *t);

/* As geom_segment_segment, also returning the parameters s, t in [0, 1] of cp = p0 + s (p1 - p0)
 * and cq = q0 + t (q1 - q0) (the DEM uses them to keep edge-edge contacts interior to both). */
double geom_segment_segment_param(vec3 p0, vec3 p1, vec3 q0, vec3 q1, double *s, double *t,
                                  vec3 *cp, vec3 *cq);

/* Closest point c on the planar convex polygon poly[0..n-1] (counter-clockwise about `normal`)
 * to p; returns |p - c|. *inside = 1 when the projection of p falls inside the polygon. */
double geom_point_polygon(vec3 p, const vec3 *poly, int n, vec3 normal, vec3 *c, int *inside);

/* The inside test of geom_point_polygon alone (n >= 3): 1 when the projection of p on the
 * polygon's plane falls inside it (boundary inclusive), the projection in *proj (may be NULL).
 * No closest point on the boundary when outside: the DEM narrow phase only needs the test. */
int geom_point_polygon_inside(vec3 p, const vec3 *poly, int n, vec3 normal, vec3 *proj);

/* World-frame vertex i of a body at position x and orientation q. */
vec3 geom_world_vertex(const lahar_shape *s, const double x[3], const double q[4], int i);

/* Closest point `c` on the core (vertices, edges, faces) of a body placed at (x, q) to the world
 * point p; returns the distance to the core (subtract shape->radius for the swept surface).
 * *feature receives 0 vertex, 1 edge, 2 face. */
double geom_point_body_core(const lahar_shape *s, const double x[3], const double q[4], vec3 p,
                            vec3 *c, int *feature);

/* Smallest distance between the cores of two placed bodies (all feature pairs); the swept
 * surfaces overlap by (ra + rb) - distance when that is positive. */
double geom_body_core_distance(const lahar_shape *a, const double xa[3], const double qa[4],
                               const lahar_shape *b, const double xb[3], const double qb[4]);

/* Outward unit normal of face f (body frame), from Newell's method. */
vec3 geom_face_normal(const lahar_shape *s, int f);

/* 1 when the +x ray from (px, py) crosses the edge a-b of a polygon in the x-y plane (half-open in
 * y, Franklin's rule, so that a ray through a vertex counts once): the even-odd test of every
 * polygon in lahar (body cores, particle blocks) sums this over the edges. */
static inline int geom_ray_crosses_edge(double ax, double ay, double bx, double by, double px, double py)
{
    return (ay > py) != (by > py) && px < ax + (py - ay) * (bx - ax) / (by - ay);
}

/* 1 when p lies inside the closed core of a shape placed at (x, q): in 3D a convex polyhedron
 * (p behind every face plane; open or non-convex cores give 0), in 2D a closed ring of edges
 * (ne == nv >= 3; even-odd rule in the x-y plane). The swept sphere is not part of it (distance to
 * the core: geom_point_body_core). The one inside test of a body: the case loader's lattice cut,
 * the SPH coupling's deep-inside test and the checks use it. */
int geom_point_in_core(const lahar_shape *s, int convex, int dim, const double x[3], const double q[4], vec3 p);

/* ---- Feature grid: a uniform grid over the features (vertices, edges, faces) of one shape, in
 * its own frame (body frame; world frame for fixed bodies), so that a query near a big terrain or
 * flume surface visits only the nearby features. Built once at setup; queries allocate nothing. */
enum { GEOM_FEATURE_VERTEX = 0, GEOM_FEATURE_EDGE = 1, GEOM_FEATURE_FACE = 2 };

typedef struct {
    double lo[3];   /* body-frame corner of the grid */
    double h;       /* cell size */
    int n[3];       /* cells per axis */
    int nitem[3];   /* features of each type in the body */
    int *start[3];  /* per type: ncell + 1 offsets into items */
    int *items[3];  /* per type: feature indices, each feature in every cell its box touches */
} geom_feature_grid;

/* Scratch space for queries (one per thread). */
typedef struct {
    int *stamp[3];  /* per type: last query id that listed the feature */
    int *out[3];    /* per type: the candidate feature indices */
    int nout[3];
    int cap[3];
    int query;
} geom_feature_query;

/* Shapes with more features (vertices + edges + faces) than this are worth a grid: below it a
 * plain scan of every feature is as fast (boxes, boulders). */
#define GEOM_FEATURE_GRID_MIN 64

/* Build the grid of shape s (features inflated by its sweep radius). Returns 0 or -1 (no memory). */
int geom_feature_grid_build(geom_feature_grid *g, const lahar_shape *s);
void geom_feature_grid_free(geom_feature_grid *g);

/* Scratch able to serve grids with up to nv, ne, nf features. Returns 0 or -1. */
int geom_feature_query_init(geom_feature_query *q, int nv, int ne, int nf);
void geom_feature_query_free(geom_feature_query *q);

/* Features whose inflated box meets the ball (body-frame centre c, radius r), without duplicates,
 * in a deterministic order; results in q->out / q->nout. */
void geom_feature_grid_query(const geom_feature_grid *g, vec3 c, double r, geom_feature_query *q);

/* Closest point of the core like geom_point_body_core, but only among the features whose
 * inflated box lies within max_dist of p (through the grid g of shape s placed at x, q). Returns
 * the distance to the core, or DBL_MAX (c, feature untouched) when no feature is that close.
 * Thread-safe and allocation-free: meant for many points against one big body (SPH particles
 * against a terrain). Faces must have at most 64 vertices. */
double geom_point_body_core_near(const geom_feature_grid *g, const lahar_shape *s, const double x[3],
                                 const double q[4], vec3 p, double max_dist, vec3 *c, int *feature);

/* ---- The feature grids of an array of bodies: a grid for each body with more than
 * GEOM_FEATURE_GRID_MIN features, none for the others. Each user that tests many points against
 * the bodies (the SPH coupling, the lattice cut, lahar check) owns one, built once. */
typedef struct {
    int nbody;
    geom_feature_grid *grid; /* per body; valid where has[b] */
    unsigned char *has;      /* per body: 1 when grid[b] is built */
} geom_body_grids;

/* Build the grids of bodies[0 .. nbody). Returns 0, or -1 (no memory; g is then freed). */
int geom_body_grids_build(geom_body_grids *g, const lahar_body *bodies, int nbody);
void geom_body_grids_free(geom_body_grids *g);

/* Distance from p to the core of body b (shape s placed at x, q), its closest point c and feature:
 * through b's grid when it has one, visiting only the features within reach of p (DBL_MAX, c and
 * feature untouched, when none is that close: geom_point_body_core_near); else every feature at
 * any distance (geom_point_body_core). g NULL or never built: every feature. */
double geom_body_grids_core(const geom_body_grids *g, int b, const lahar_shape *s, const double x[3],
                            const double q[4], vec3 p, double reach, vec3 *c, int *feature);

#endif
