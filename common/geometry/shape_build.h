/* Building sphero-polyhedra (lahar_shape, scene.h): primitive shapes, convex hulls, polyhedra
 * from vertices + faces, STL import, convexity, and mass properties of the swept solid
 * (shape_build.c, shape_hull.c, shape_stl.c, shape_mass.c; common/geometry/README.md).
 *
 * Conventions:
 * - 3D shapes carry vertices, edges and faces (faces counter-clockwise seen from outside).
 * - 2D shapes (disc, 2D box, polygon, polyline, 2D segment) lie in the x-y plane (z = 0) and carry
 *   vertices and edges only (nf = 0): contacts in 2D are vertex/edge features in the plane.
 * - Every constructor returns 0 on success; on failure it returns -1, leaves *s empty (all
 *   pointers NULL) and, where it takes `err`, writes a one-line reason without the file prefix.
 * - A shape owns its arrays; release with lahar_shape_free (safe on an empty/zeroed shape). */
#ifndef LAHAR_SHAPE_BUILD_H
#define LAHAR_SHAPE_BUILD_H
#include <stddef.h>
#include "scene.h"

/* Sphere (3D) or disc (2D): one vertex at the origin, swept by `radius`. */
int lahar_shape_make_sphere(lahar_shape *s, double radius);
/* Segment a-b swept by radius (a capsule in 3D, a stadium in 2D): 2 vertices, 1 edge. */
int lahar_shape_make_segment(lahar_shape *s, const double a[3], const double b[3], double radius);
/* Box centred at the origin whose CORE has half-extents `half` (the outer half-size of the swept
 * box is half + radius): 8 vertices, 12 edges, 6 quad faces. The case file's `size` is the outer
 * size; the loader passes half = size/2 - radius. */
int lahar_shape_make_box(lahar_shape *s, const double half[3], double radius);
/* 2D rectangle (core half-extents half[0], half[1]) in the x-y plane: 4 vertices, 4 edges. */
int lahar_shape_make_box2d(lahar_shape *s, const double half[2], double radius);
/* Finite one-sided rectangle: centre c, outward unit normal n, side lengths size[0] along the
 * in-plane axis closest to world x (world y when n is along x) and size[1] along n x that axis.
 * 4 vertices, 4 edges, 1 face. */
int lahar_shape_make_plane(lahar_shape *s, const double c[3], const double n[3], const double size[2],
                           double radius);
/* 2D chain of n >= 2 points (z ignored, set to 0); closed adds the edge n-1 -> 0. */
int lahar_shape_make_polyline(lahar_shape *s, const double (*p)[3], int n, int closed, double radius,
                              char *err, size_t errlen);
/* 2D convex hull of n points (x, y) as a counter-clockwise polygon. Fails if the points are all
 * collinear (degenerate). */
int lahar_shape_make_polygon_hull(lahar_shape *s, const double (*p)[3], int n, double radius, char *err,
                                  size_t errlen);
/* 3D convex hull of n >= 4 points; coplanar triangles are merged into polygonal faces and points
 * inside the hull or on its faces/edges are dropped. Fails (degenerate) if all points are
 * coplanar. Exact supporting-plane enumeration, O(n^3): meant for rocks (at most 512 points;
 * 200 points take 0.1 s). */
int lahar_shape_make_hull(lahar_shape *s, const double (*p)[3], int n, double radius, char *err, size_t errlen);
/* Polyhedron from vertices and faces (face f = face_v[face_start[f] .. face_start[f+1])), which
 * must be counter-clockwise seen from outside. Edges are built from the faces. Checks indices,
 * faces with < 3 vertices and zero-area faces. Convexity is NOT required here (see is_convex). */
int lahar_shape_make_polyhedron(lahar_shape *s, const double (*v)[3], int nv, const int *face_start,
                                const int *face_v, int nf, double radius, char *err, size_t errlen);
/* ASCII or binary STL (binary when the size is 84 + 50 n bytes). Vertices with identical
 * coordinates are merged, triangles that collapse after merging are dropped, edges are built.
 * The surface may be open and non-convex (fixed terrain, flumes). */
int lahar_shape_read_stl(lahar_shape *s, const char *path, double radius, char *err, size_t errlen);

int lahar_shape_copy(lahar_shape *dst, const lahar_shape *src);
void lahar_shape_free(lahar_shape *s);

/* 1 if every vertex lies on the inner side of every face plane (tolerance tol, metres); 2D
 * shapes: of every edge line of a closed CCW polygon. Spheres, segments are convex. */
int lahar_shape_is_convex(const lahar_shape *s, int dim, double tol);
/* Signed volume of the core polyhedron (3D, faces closed and outward) - used to detect inverted
 * face orientation. */
double lahar_shape_core_volume(const lahar_shape *s);

/* Apply x -> R (scale x) + t to every vertex (R row-major 3x3, may be NULL for identity). */
void lahar_shape_transform(lahar_shape *s, const double R[3][3], const double t[3], double scale);

/* Mass properties of the swept solid with unit density, computed EXACTLY (to rounding) by
 * decomposing the Minkowski sum core + ball(R) into: the core polyhedron, one prism per face,
 * one cylindrical wedge per edge (opening angle = angle between the adjacent face normals) and
 * one spherical sector per vertex (its normal cone, solid angle = the vertex angle defect).
 * 2D (per unit thickness): core polygon, one rectangle per edge, one circular sector per vertex.
 * Valid for convex cores (and for the degenerate convex cores: point, segment, 2D polygons). */
typedef struct {
    double volume;        /* m^3 (area m^2 in 2D) */
    double com[3];        /* centre of mass in the shape's frame */
    double inertia[3];    /* principal moments per unit density about the axes below; 2D:
                             [int y'^2, int x'^2, int (x'^2 + y'^2)] over the figure's area */
    double axes[3][3];    /* columns = principal axes in the shape's frame, det = +1 */
} lahar_mass_props;
int lahar_shape_mass_properties(const lahar_shape *s, int dim, lahar_mass_props *mp, char *err, size_t errlen);
/* Move a shape into its principal frame: v -> axes^T (v - com). */
void lahar_shape_to_principal(lahar_shape *s, const lahar_mass_props *mp);

/* Symmetric 3x3 eigen-decomposition by cyclic Jacobi rotations: a = V diag(d) V^T, V columns =
 * eigenvectors, det V = +1 (a product of rotations). Not sorted: an already diagonal matrix gives
 * V = identity, so symmetric shapes keep the axes the user wrote. Deterministic. */
void lahar_sym3_eigen(const double a[3][3], double d[3], double V[3][3]);

/* ---- SPH particle regions (lahar_particle_block, scene.h; particle_block.c) -------------------
 * The SPH node fills a block with the lattice points that lie inside it; the loader uses the same
 * functions to check a case (particles inside bodies, empty blocks) before a run. */
#include <stdint.h>

/* 1 if x lies inside block b: box [lo, hi); polygon (2D): even-odd rule against the polygon's
 * edges (simple polygons, either orientation, convex or not); mesh (3D, closed surface):
 * parity of the crossings of a ray from x in a fixed skew direction (no lattice point lies on
 * a face for an axis-aligned grid of faces). Points outside [lo, hi] are outside. */
int lahar_particle_block_contains(const lahar_particle_block *b, int dim, const double x[3]);

/* The lattice points of block b at spacing dx (lo + (i + 1/2) dx, floor((hi - lo)/dx + 1e-9)
 * per axis, z = 0 in 2D; the order of sph_particles_add_box: x outermost, z innermost) that lie
 * inside it. Writes the first `cap` of them to out (out may be NULL to count) and returns how
 * many lie inside (which may exceed cap). */
int64_t lahar_particle_block_lattice(const lahar_particle_block *b, int dim, double dx, double (*out)[3], int64_t cap);
/* As lahar_particle_block_lattice, keeping only the points for which keep(x, ctx) is non-zero
 * (keep may be NULL; it may move the point it keeps: the moved x is written) and stopping after
 * `most` points (-1: no limit). Both return -1 when the block's lattice has more than
 * LAHAR_LATTICE_MAX points (lahar_particle_block_lattice_size). */
int64_t lahar_particle_block_lattice_keep(const lahar_particle_block *b, int dim, double dx,
                                          int (*keep)(double x[3], void *ctx), void *ctx, int64_t most,
                                          double (*out)[3], int64_t cap);

/* Points of the lattice of b's bounding box [lo, hi] at spacing dx (inside the block or not), as a
 * double: +inf when an extent or dx is not finite. The case loader refuses a block above
 * LAHAR_LATTICE_MAX (2^53, where doubles stop counting exactly; no machine holds that many). */
#define LAHAR_LATTICE_MAX 9007199254740992.0
double lahar_particle_block_lattice_size(const lahar_particle_block *b, int dim, double dx);

/* The extent a box block's lattice fills: floor(side / dx) whole spacings per axis, n dx <= side,
 * into filled[] (the side itself on the axes beyond dim). Returns the fraction of the box's volume
 * the particles stand for (1 for polygons and meshes: their lattice is not a whole box). A box
 * whose sides are not multiples of dx holds less than it says (0.55 m at dx 0.04: 13 layers,
 * 0.52 m); the command line says so before a run. */
double lahar_particle_block_box_filled(const lahar_particle_block *b, int dim, double dx, double filled[3]);

/* lo/hi of a polygon or mesh block from its vertices (z = 0 .. 0 in 2D). */
void lahar_particle_block_bounds(lahar_particle_block *b, int dim);

/* Release the arrays a block owns (vert, tri); the block keeps its other fields. */
void lahar_particle_block_free(lahar_particle_block *b);

#endif
