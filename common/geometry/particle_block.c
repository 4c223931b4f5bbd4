/* SPH particle regions (lahar_particle_block, declared in shape_build.h): the inside test of a
 * box, polygon or closed STL mesh block, and the lattice of particles the SPH node fills it with
 * and the case loader checks. Separate from the shape builders: a block is a region of fluid,
 * not a body, and shares none of their code. */
#include "shape_build.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "geometry.h"
#include "vec.h"

/* ---- SPH particle regions ------------------------------------------------------------------ */

/* Even-odd rule (crossings of the ray +x from p with the polygon's edges; Franklin's half-open
 * vertex rule so a ray through a vertex counts once). */
static int block_polygon_contains(const lahar_particle_block *b, const double x[3])
{
    int inside = 0;
    for (int i = 0, j = b->nvert - 1; i < b->nvert; j = i++)
        inside ^= geom_ray_crosses_edge(b->vert[i][0], b->vert[i][1], b->vert[j][0], b->vert[j][1], x[0], x[1]);
    return inside;
}

/* The directions of the inside test's rays: skew to every axis and diagonal so that rays from
 * lattice points miss the edges and vertices of meshes built on round coordinates. */
static const double block_ray_dirs[3][3] = {{1.0, 0.3183098861837907, 0.2078795763507619},
                                            {-0.5772156649015329, 1.0, 0.6931471805599453},
                                            {0.2718281828459045, -0.4142135623730951, 1.0}};

/* Does the ray o + s d (s > 0) cross triangle t of mesh block b (Moller-Trumbore)? Returns 1 or 0;
 * sets *ambiguous when the ray passes within 1e-9 (in barycentric terms) of an edge, or starts
 * on the face. */
static int block_ray_crosses_triangle(const lahar_particle_block *b, int t, vec3 o, vec3 d, int *ambiguous)
{
    const double eps = 1e-9;
    vec3 p0 = v3_load(b->vert[b->tri[t][0]]), p1 = v3_load(b->vert[b->tri[t][1]]);
    vec3 p2 = v3_load(b->vert[b->tri[t][2]]);
    vec3 e1 = v3_sub(p1, p0), e2 = v3_sub(p2, p0);
    vec3 pv = v3_cross(d, e2);
    double det = v3_dot(e1, pv);
    if (det == 0.0)
        return 0; /* ray parallel to the triangle's plane */
    double inv = 1.0 / det;
    vec3 tv = v3_sub(o, p0);
    double u = v3_dot(tv, pv) * inv;
    if (u < -eps || u > 1.0 + eps)
        return 0;
    vec3 qv = v3_cross(tv, e1);
    double v = v3_dot(d, qv) * inv;
    if (v < -eps || u + v > 1.0 + eps)
        return 0;
    double s = v3_dot(e2, qv) * inv;
    double scale = sqrt(v3_norm2(e1) + v3_norm2(e2));
    if (fabs(s) <= eps * scale || u < eps || v < eps || u + v > 1.0 - eps) {
        if (s >= -eps * scale)
            *ambiguous = 1; /* (behind the start it is irrelevant) */
        return 0;
    }
    return s > 0.0;
}

/* Parity of the crossings of a ray from x with the triangles, trying the next direction while
 * the ray is ambiguous. Returns 1 inside, 0 outside. */
static int block_mesh_contains(const lahar_particle_block *b, const double x[3])
{
    const vec3 o = v3_load(x);
    int crossings = 0;
    for (int k = 0; k < 3; k++) {
        const vec3 d = v3_normalize(v3_load(block_ray_dirs[k]));
        int ambiguous = 0;
        crossings = 0;
        for (int t = 0; t < b->ntri && !ambiguous; t++)
            crossings += block_ray_crosses_triangle(b, t, o, d, &ambiguous);
        if (!ambiguous)
            break;
    }
    return crossings & 1;
}

/* The triangles of a mesh block binned by their shadow along the first ray direction: a 2D grid
 * in the plane normal to it (axes u, w), each triangle listed in every cell its shadow's box
 * (grown by 1e-6 of its size) meets. A ray from x can only cross, or pass near, the triangles
 * listed in the cell of x's shadow: the others leave it more than 1e-6 (barycentric) outside,
 * far beyond the test's 1e-9, so that the candidates give the same crossings and the same
 * ambiguity as all triangles. For the lattice of a block cut from a large surface (a terrain)
 * this visits a few triangles per point instead of all of them. */
typedef struct {
    vec3 d, u, w;   /* ray direction and the two axes of the shadow plane */
    double lo[2], h;
    int n[2];
    int *start, *items;
} block_ray_grid;

static void block_ray_shadow_box(const lahar_particle_block *b, const block_ray_grid *g, int t, double lo[2], double hi[2])
{
    lo[0] = lo[1] = DBL_MAX;
    hi[0] = hi[1] = -DBL_MAX;
    for (int j = 0; j < 3; j++) {
        vec3 p = v3_load(b->vert[b->tri[t][j]]);
        double c[2] = {v3_dot(p, g->u), v3_dot(p, g->w)};
        for (int a = 0; a < 2; a++) {
            lo[a] = fmin(lo[a], c[a]);
            hi[a] = fmax(hi[a], c[a]);
        }
    }
    double grow = 1e-6 * fmax(hi[0] - lo[0], hi[1] - lo[1]) + 1e-12 * (fabs(lo[0]) + fabs(lo[1]) + fabs(hi[0]) + fabs(hi[1]));
    for (int a = 0; a < 2; a++) {
        lo[a] -= grow;
        hi[a] += grow;
    }
}

static void block_ray_cells(const block_ray_grid *g, const double lo[2], const double hi[2], int c0[2], int c1[2])
{
    for (int a = 0; a < 2; a++) {
        double f0 = floor((lo[a] - g->lo[a]) / g->h), f1 = floor((hi[a] - g->lo[a]) / g->h);
        c0[a] = f0 < 0.0 ? 0 : f0 > g->n[a] - 1 ? g->n[a] - 1 : (int)f0;
        c1[a] = f1 < 0.0 ? 0 : f1 > g->n[a] - 1 ? g->n[a] - 1 : (int)f1;
    }
}

static void block_ray_grid_free(block_ray_grid *g)
{
    free(g->start);
    free(g->items);
    g->start = g->items = NULL;
}

/* Returns 0, 1 when the mesh's extent cannot be binned (then no grid), or -1 when out of memory. */
static int block_ray_grid_build(const lahar_particle_block *b, block_ray_grid *g)
{
    memset(g, 0, sizeof *g);
    g->d = v3_normalize(v3_load(block_ray_dirs[0]));
    /* u: the axis least aligned with d made normal to it; w = d x u */
    g->u = v3_normalize(v3_sub(v3(0.0, 0.0, 1.0), v3_scale(g->d, g->d.z)));
    g->w = v3_cross(g->d, g->u);
    double lo[2] = {DBL_MAX, DBL_MAX}, hi[2] = {-DBL_MAX, -DBL_MAX};
    for (int t = 0; t < b->ntri; t++) {
        double tl[2], th[2];
        block_ray_shadow_box(b, g, t, tl, th);
        for (int a = 0; a < 2; a++) {
            lo[a] = fmin(lo[a], tl[a]);
            hi[a] = fmax(hi[a], th[a]);
        }
    }
    if (!(isfinite(lo[0]) && isfinite(lo[1]) && isfinite(hi[0] - lo[0]) && isfinite(hi[1] - lo[1])))
        return 1; /* extents no grid can bin (coordinates near DBL_MAX): the per-point test */
    /* about one triangle per cell */
    double area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
    g->h = area > 0.0 ? sqrt(area / b->ntri) : fmax(hi[0] - lo[0], hi[1] - lo[1]) + 1.0;
    long ncell = 1;
    for (int a = 0; a < 2; a++) {
        g->lo[a] = lo[a];
        double n = ceil((hi[a] - lo[a]) / g->h);
        g->n[a] = n < 1.0 ? 1 : n > 4096.0 ? 4096 : (int)n;
        ncell *= g->n[a];
    }
    g->h = fmax(g->h, fmax((hi[0] - lo[0]) / g->n[0], (hi[1] - lo[1]) / g->n[1]));
    g->start = calloc((size_t)ncell + 1, sizeof *g->start);
    if (!g->start)
        return -1;
    for (int pass = 0; pass < 2; pass++) {
        for (int t = 0; t < b->ntri; t++) {
            double tl[2], th[2];
            int c0[2], c1[2];
            block_ray_shadow_box(b, g, t, tl, th);
            block_ray_cells(g, tl, th, c0, c1);
            for (int j = c0[1]; j <= c1[1]; j++)
                for (int i = c0[0]; i <= c1[0]; i++) {
                    long c = (long)j * g->n[0] + i;
                    if (pass == 0)
                        g->start[c + 1]++;
                    else
                        g->items[g->start[c]++] = t;
                }
        }
        if (pass == 0) {
            for (long c = 0; c < ncell; c++)
                g->start[c + 1] += g->start[c];
            g->items = malloc((size_t)(g->start[ncell] > 0 ? g->start[ncell] : 1) * sizeof *g->items);
            if (!g->items) {
                block_ray_grid_free(g);
                return -1;
            }
        } else {
            for (long c = ncell; c > 0; c--)
                g->start[c] = g->start[c - 1];
            g->start[0] = 0;
        }
    }
    return 0;
}

/* block_mesh_contains through the grid: the first direction over the candidates; an ambiguous
 * ray falls back to the full test (which finds the same ambiguity and goes on to the next). */
static int block_mesh_contains_grid(const lahar_particle_block *b, const block_ray_grid *g, const double x[3])
{
    const vec3 o = v3_load(x);
    double c[2] = {v3_dot(o, g->u), v3_dot(o, g->w)};
    for (int a = 0; a < 2; a++)
        if (c[a] < g->lo[a] || c[a] > g->lo[a] + g->n[a] * g->h)
            return 0; /* outside every triangle's shadow: no crossing, and not ambiguous */
    int ci[2], cj[2];
    block_ray_cells(g, c, c, ci, cj);
    long cell = (long)ci[1] * g->n[0] + ci[0];
    int ambiguous = 0, crossings = 0;
    for (int k = g->start[cell]; k < g->start[cell + 1] && !ambiguous; k++)
        crossings += block_ray_crosses_triangle(b, g->items[k], o, g->d, &ambiguous);
    return ambiguous ? block_mesh_contains(b, x) : crossings & 1;
}

/* x within the block's bounds [lo, hi) */
static int block_in_bounds(const lahar_particle_block *b, int dim, const double x[3])
{
    for (int a = 0; a < dim; a++)
        if (!(x[a] >= b->lo[a] && x[a] < b->hi[a]))
            return 0;
    return 1;
}

int lahar_particle_block_contains(const lahar_particle_block *b, int dim, const double x[3])
{
    if (!block_in_bounds(b, dim, x))
        return 0;
    switch (b->kind) {
    case LAHAR_BLOCK_BOX: return 1;
    case LAHAR_BLOCK_POLYGON: return b->nvert >= 3 && block_polygon_contains(b, x);
    case LAHAR_BLOCK_MESH: return dim == 3 && b->ntri > 0 && block_mesh_contains(b, x);
    default: return 0;
    }
}

/* Lattice points per axis, as doubles (not finite for a non-finite extent or dx). */
static void block_lattice_dims(const lahar_particle_block *b, int dim, double dx, double n[3])
{
    for (int a = 0; a < 3; a++) {
        n[a] = (a == 2 && dim == 2) ? 1.0 : floor((b->hi[a] - b->lo[a]) / dx + 1e-9);
        if (n[a] < 0.0)
            n[a] = 0.0;
    }
}

double lahar_particle_block_box_filled(const lahar_particle_block *b, int dim, double dx, double filled[3])
{
    double n[3], fraction = 1.0;
    block_lattice_dims(b, dim, dx, n);
    for (int a = 0; a < 3; a++) {
        double side = b->hi[a] - b->lo[a];
        filled[a] = a < dim ? n[a] * dx : side;
        if (a < dim && b->kind == LAHAR_BLOCK_BOX && side > 0.0)
            fraction *= filled[a] / side;
    }
    return fraction;
}

double lahar_particle_block_lattice_size(const lahar_particle_block *b, int dim, double dx)
{
    double n[3];
    block_lattice_dims(b, dim, dx, n);
    double size = n[0] * n[1] * n[2];
    return size == size ? size : INFINITY; /* NaN (an extent of inf / inf) counts as too large */
}

int64_t lahar_particle_block_lattice_keep(const lahar_particle_block *b, int dim, double dx,
                                          int (*keep)(double x[3], void *ctx), void *ctx, int64_t most,
                                          double (*out)[3], int64_t cap)
{
    double nd[3];
    block_lattice_dims(b, dim, dx, nd);
    /* a lattice no run could hold (or whose indices would not fit int64): refused, not walked */
    if (!(lahar_particle_block_lattice_size(b, dim, dx) <= LAHAR_LATTICE_MAX))
        return -1;
    /* an axis without a point: no point at all (and another axis may still be beyond int64, its
     * product with 0 within the bound) */
    if (nd[0] == 0.0 || nd[1] == 0.0 || nd[2] == 0.0)
        return 0;
    int64_t n[3] = {(int64_t)nd[0], (int64_t)nd[1], (int64_t)nd[2]};
    int64_t count = 0;
    block_ray_grid grid;
    int gridded = b->kind == LAHAR_BLOCK_MESH && dim == 3 && b->ntri > GEOM_FEATURE_GRID_MIN;
    if (gridded) {
        int rc = block_ray_grid_build(b, &grid);
        if (rc < 0)
            return -1;
        gridded = rc == 0;
    }
    for (int64_t i = 0; i < n[0]; i++)
        for (int64_t j = 0; j < n[1]; j++)
            for (int64_t k = 0; k < n[2]; k++) {
                double x[3] = {b->lo[0] + ((double)i + 0.5) * dx, b->lo[1] + ((double)j + 0.5) * dx,
                               dim == 2 ? 0.0 : b->lo[2] + ((double)k + 0.5) * dx};
                /* the lattice point of a box is inside by construction (the +1e-9 above may put
                 * the last one a hair past hi) */
                if (gridded ? !(block_in_bounds(b, dim, x) && block_mesh_contains_grid(b, &grid, x))
                            : b->kind != LAHAR_BLOCK_BOX && !lahar_particle_block_contains(b, dim, x))
                    continue;
                if (keep && !keep(x, ctx))
                    continue;
                if (out && count < cap)
                    memcpy(out[count], x, sizeof x);
                if (++count == most)
                    goto done;
            }
done:
    if (gridded)
        block_ray_grid_free(&grid);
    return count;
}

int64_t lahar_particle_block_lattice(const lahar_particle_block *b, int dim, double dx, double (*out)[3], int64_t cap)
{
    return lahar_particle_block_lattice_keep(b, dim, dx, NULL, NULL, -1, out, cap);
}

void lahar_particle_block_bounds(lahar_particle_block *b, int dim)
{
    for (int a = 0; a < 3; a++) {
        b->lo[a] = b->nvert > 0 ? INFINITY : 0.0;
        b->hi[a] = b->nvert > 0 ? -INFINITY : 0.0;
    }
    for (int i = 0; i < b->nvert; i++)
        for (int a = 0; a < 3; a++) {
            b->lo[a] = fmin(b->lo[a], b->vert[i][a]);
            b->hi[a] = fmax(b->hi[a], b->vert[i][a]);
        }
    if (dim == 2)
        b->lo[2] = b->hi[2] = 0.0;
}

void lahar_particle_block_free(lahar_particle_block *b)
{
    free(b->vert);
    free(b->tri);
    b->vert = NULL;
    b->tri = NULL;
    b->nvert = b->ntri = 0;
}
