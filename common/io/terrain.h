/* Terrain input (case section terrain:, and the sph.blocks[i].between: option): 2D ground
 * profiles (polylines, inline or from a CSV file of x,y) and 3D heightmaps (ESRI ASCII grid, .asc),
 * turned into the geometry the rest of lahar already knows: a fixed sphero-polyhedron body (a
 * chain of segments in 2D, two triangles per grid cell in 3D) and the particle region between the
 * terrain and an upper surface (a polygon block in 2D, a closed triangulated mesh block in 3D).
 *
 * Errors name the file and line ("path:line: problem; what to do") and leave nothing allocated. */
#ifndef LAHAR_TERRAIN_H
#define LAHAR_TERRAIN_H
#include <stddef.h>

#include "scene.h"

/* A heightmap read from an ESRI ASCII grid. Node (i, j) (i = 0 the southern row, j = 0 the western
 * column) sits at the cell centre x = x0 + j cellsize, y = y0 + i cellsize (x0 = xllcorner +
 * cellsize/2, or xllcenter) with elevation z[i * ncols + j]; NODATA nodes hold `nodata`. */
typedef struct {
    int ncols, nrows;
    double x0, y0, cellsize, nodata;
    double *z;
} lahar_heightmap;

/* Read an .asc file: header keys ncols, nrows, xllcorner|xllcenter, yllcorner|yllcenter, cellsize,
 * optional NODATA_value (default -9999), any order and case; then nrows x ncols numbers, the
 * northern row first. 0, or -1 with "path:line: ..." in err. */
int lahar_heightmap_read_asc(const char *path, lahar_heightmap *h, char *err, size_t errlen);
void lahar_heightmap_free(lahar_heightmap *h);
/* 1 if node (i, j) has data. */
int lahar_heightmap_valid(const lahar_heightmap *h, int i, int j);

/* The fixed terrain surface: the nodes with data as vertices, two triangles per grid cell whose
 * four nodes have data (counter-clockwise seen from above: outward normal up), swept by radius.
 * 0, or -1 with a message (no complete cell, out of memory). */
int lahar_heightmap_shape(const lahar_heightmap *h, double radius, lahar_shape *s, char *err, size_t errlen);

/* The closed region between the terrain `bot` and the upper surface `top` (same grid): top
 * triangles, bottom triangles and side walls around the grid's boundary, as a mesh block
 * (LAHAR_BLOCK_MESH: vert, tri, bounds). The terrain is raised by `lift` along its normal
 * (lift sqrt(1 + |grad z|^2) vertically at each node: the sweep radius plus the particles'
 * clearance dx/2). A top node below the raised terrain counts as on it (no soil there); a NODATA
 * top node also. The mesh covers only the window of nodes around those with the top above the raised
 * terrain (one node more on each side), so a small region on a large grid has a small bounding box
 * (the lattice is cut from it). Every bottom node must have data. 0, or -1 with a message naming
 * top_path. */
int lahar_heightmap_block(const lahar_heightmap *bot, const lahar_heightmap *top, const char *top_path, double lift,
                          lahar_particle_block *pb, char *err, size_t errlen);

/* A 2D profile from a CSV file: one point "x,y" per line (also ';', tab or space separated), '#'
 * comments and blank lines skipped, one optional header line of text. At least 2 points. The
 * points get z = 0. 0, or -1 with "path:line: ..." in err. */
int lahar_profile_read_csv(const char *path, double (**p)[3], int *n, char *err, size_t errlen);

/* Elevation of a polyline whose x increases strictly, at x (linear; clamped to the ends). */
double lahar_profile_height(const double (*p)[3], int n, double x);

/* The polygon between the ground polyline g (x strictly increasing) and the upper profile t (x
 * strictly increasing, within g's x range): t from left to right, then the ground back from t's
 * right end to its left end. The ground is raised by `lift` normal to each of its segments (the
 * terrain's sweep radius plus the particles' clearance dx/2: no particle starts closer than dx/2
 * to the terrain's surface); where t is below it the region is empty (t is raised to it).
 * Consecutive duplicate points are dropped. 0, or -1 with a message (out of range, not
 * increasing, empty region). *poly is malloc'ed. */
int lahar_profile_between(const double (*g)[3], int ng, const double (*t)[3], int nt, double lift,
                          double (**poly)[3], int *np, char *err, size_t errlen);

#endif
