/* The particle lattice of a loaded case's blocks (lahar_case_block_lattice): points outside the
 * bodies, the concentric layers around round bodies (sph.body_layers), and the placement checks. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <yaml.h>

#include "case_reader.h"
#include "geometry.h"
#include "vec.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* The bodies a lattice point must stay out of, with the bounding sphere of each about its x to skip
 * the exact test for most points (fixed bodies keep world coordinates with x = 0: the sphere
 * still covers them). A point must also not start inside the coupling's halo eps = dx/2 about a
 * body's surface (sph_coupling.h, Trujillo-Vela et al. 2020 eq. 14): a particle at d < eps starts with an overlap
 * delta = eps - d whose first push, K_n delta with K_n = 0.1 m_min/dt^2 (eq. 15), is an impulse
 * growing as 1/dt: a free body is kicked by it, so that its motion depended on the time step
 * (the boulder pool of `lahar bench`, README "DEM subcycling": kicked up at 0.16 or 0.51 m/s at
 * dt 6.8e-5 or 1.6e-5 s, the runs ended 47 mm apart; with the points moved, 0.06 mm). Such a point
 * of a free body's halo is moved out along the surface normal to d = eps (kept: its fluid belongs
 * next to the body). Fixed and prescribed bodies keep the lattice as it was: their kick goes
 * into the fluid's start-up only, and moving the points there (or dropping them) changed the
 * validated cylinder array's K (2.5 % -> 7.6 % at c = 0.4). A lattice point exactly eps from a
 * surface stays where it is (tolerance 1e-6 dx). */
typedef struct {
    const lahar_case *c;
    double *reach;
    /* the feature grids of the big bodies (a terrain, an STL flume): the inside and halo tests
     * visit only the features within R + eps of the point */
    geom_body_grids grids;
    double eps;
    double zone;  /* sph.body_layers > 0: the lattice leaves out the points within zone = body_layers dx
                     of a round body's surface (case_block_layers fills them); else 0 */
} case_lattice_cut;

/* 1 for a body whose core is one point (a sphere in 3D, a disc in 2D). */
static int case_round_body(const lahar_body *bd)
{
    return bd->shape.nv == 1 && bd->shape.ne == 0 && bd->shape.nf == 0 && bd->shape.radius > 0.0;
}

/* The first round body of the case, or -1. */
int case_first_round_body(const lahar_case *c)
{
    for (int m = 0; m < c->nbody; m++)
        if (case_round_body(&c->bodies[m]))
            return m;
    return -1;
}

/* x - y with the nearest periodic image on the fluid's periodic axes. */
static vec3 case_periodic_sub(const lahar_case *c, const double x[3], vec3 y)
{
    double v[3] = {x[0] - y.x, x[1] - y.y, x[2] - y.z};
    for (int a = 0; a < c->dim; a++)
        if (c->sph.periodic[a]) {
            double L = c->sph.hi[a] - c->sph.lo[a];
            v[a] -= L * floor(v[a] / L + 0.5);
        }
    return v3(v[0], v[1], c->dim == 2 ? 0.0 : v[2]);
}

/* sph.body_layers: the layers of a round body must stay clear of every other round body's layers
 * and of its own periodic images (each point of the zones is filled once). */
void case_check_body_layers(rmap *m, const lahar_case *c)
{
    const double zone = c->sph.body_layers * c->sph_dx;
    for (int i = 0; i < c->nbody; i++) {
        const lahar_body *bi = &c->bodies[i];
        if (!case_round_body(bi))
            continue;
        vec3 xi = geom_world_vertex(&bi->shape, bi->x, bi->q, 0);
        for (int a = 0; a < c->dim; a++)
            if (c->sph.periodic[a] && 2.0 * (bi->shape.radius + zone) > c->sph.hi[a] - c->sph.lo[a]) {
                rmap_fail(m, "body_layers", "the %d layers around body '%s' (radius %g m + %g m) overlap its periodic "
                          "image along %c (period %g m); lower body_layers or dx", c->sph.body_layers, bi->name,
                          bi->shape.radius, zone, "xyz"[a], c->sph.hi[a] - c->sph.lo[a]);
                return;
            }
        for (int j = 0; j < i; j++) {
            const lahar_body *bj = &c->bodies[j];
            if (!case_round_body(bj))
                continue;
            double xj[3];
            v3_store(geom_world_vertex(&bj->shape, bj->x, bj->q, 0), xj);
            if (v3_norm(case_periodic_sub(c, xj, xi)) < bi->shape.radius + bj->shape.radius + 2.0 * zone) {
                rmap_fail(m, "body_layers", "the %d layers around bodies '%s' and '%s' overlap (their surfaces are "
                          "closer than 2 x %g m); lower body_layers or dx", c->sph.body_layers, bj->name, bi->name,
                          zone);
                return;
            }
        }
    }
}

/* 0 if x lies in a body's solid; else 1, with x moved out of any free body's halo it starts in. */
static int case_lattice_outside_bodies(double x[3], void *ctx)
{
    const case_lattice_cut *k = ctx;
    const double tol = 1e-6 * k->c->sph_dx;
    for (int m = 0; m < k->c->nbody && k->zone > 0.0; m++) {
        const lahar_body *bd = &k->c->bodies[m];
        if (case_round_body(bd) &&
            v3_norm(case_periodic_sub(k->c, x, geom_world_vertex(&bd->shape, bd->x, bd->q, 0))) <
                bd->shape.radius + k->zone - tol)
            return 0; /* within the layers of sph.body_layers (case_block_layers) */
    }
    int moved = 0;
    for (int m = 0; m < k->c->nbody; m++) {
        const lahar_body *bd = &k->c->bodies[m];
        double d2 = 0;
        for (int a = 0; a < 3; a++)
            d2 += (x[a] - bd->x[a]) * (x[a] - bd->x[a]);
        if (d2 > k->reach[m] * k->reach[m])
            continue;
        /* inside = lahar_body_contains: core distance < R, or in the core; in a free body's halo:
         * distance < R + eps. Through a grid only the features within R + eps are visited; the
         * distance is the same when one is (the same per-feature tests), and DBL_MAX (neither
         * inside the sweep nor in the halo) when none is. */
        vec3 p = v3_load(x), cp;
        int feat;
        const double R = bd->shape.radius;
        const double dc = geom_body_grids_core(&k->grids, m, &bd->shape, bd->x, bd->q, p, R + k->eps, &cp, &feat);
        if (dc < R || geom_point_in_core(&bd->shape, bd->convex, k->c->dim, bd->x, bd->q, p))
            return 0;
        /* in the halo of a free body: out to d = eps along the normal */
        if (bd->motion == LAHAR_MOTION_FREE && dc - R < k->eps - tol && dc > 0.0) {
            vec3 q = v3_axpy((R + k->eps) / dc, v3_sub(p, cp), cp);
            x[0] = q.x, x[1] = q.y, x[2] = k->c->dim == 2 ? 0.0 : q.z;
            moved = 1;
        }
    }
    /* a point moved out of one body's halo may have landed in another's solid (a point not moved
     * was tested against every body that can hold it above) */
    for (int m = 0; m < k->c->nbody && moved; m++)
        if (lahar_body_contains(&k->c->bodies[m], k->c->dim, x))
            return 0;
    return 1;
}

/* sph.body_layers = N > 0: after the lattice points (which leave out the zone within N dx of every
 * round body's surface), the points of that zone on N layers concentric with each round body, at
 * r_l = R + (l + 1/2) dx, l = 0 .. N - 1, like the rows of fluid a flat wall sees in the lattice (the
 * first at the halo eps = dx/2, Trujillo-Vela et al. 2020 eq. 14, and at the depths of the coupling's ghost layers,
 * sph_coupling.h). Layer l holds the lattice's share of its shell R + l dx .. R + (l + 1) dx,
 * round(volume / dx^D) points (4 pi / 3 ((R + (l+1) dx)^3 - (R + l dx)^3) / dx^3 in 3D,
 * pi ((R + (l+1) dx)^2 - (R + l dx)^2) / dx^2 = 2 pi r_l / dx in 2D; the outermost layer also the
 * lattice's own excess in the zone's ball, below), spread evenly: a spherical Fibonacci lattice in
 * 3D (z_i = 1 - (2 i + 1) / n, azimuth i times the golden angle pi (3 - sqrt 5); Gonzalez 2010,
 * Math. Geosci. 42:49), equal angles in 2D (every other layer turned by half a step). A lattice cut
 * by a curved surface instead leaves the first row at any distance from 0 to ~dx from it, denser
 * or sparser than a row; the near-wall model sees the difference (cases/README.md, "Sphere
 * array"). Initial particle positions that conform to the body surface are what particle-packing
 * methods aim at for the same reason (Colagrossi, Bouscasse, Antuono & Marrone 2012, Comput. Phys.
 * Commun. 183:1641); concentric layers are the direct form of that for a sphere or disc. Points are
 * wrapped into the period on periodic axes and kept when inside the block
 * and outside every body (free bodies' halos as for the lattice). Continues the count `count`. */
static int64_t case_block_layers(const lahar_case *c, int block, case_lattice_cut *k, int64_t count, int64_t most,
                                 double (*out)[3], int64_t cap)
{
    const double dx = c->sph_dx, golden = M_PI * (3.0 - sqrt(5.0));
    for (int m = 0; m < c->nbody; m++) {
        const lahar_body *bd = &c->bodies[m];
        if (!case_round_body(bd))
            continue;
        const vec3 xc = geom_world_vertex(&bd->shape, bd->x, bd->q, 0);
        const double R = bd->shape.radius, rz = R + c->sph.body_layers * dx;
        /* the lattice beyond the zone holds as many points as the lattice's ball of radius rz leaves
         * out, B, not the ball's volume V_b / dx^D: the outermost layer takes the difference B - V_b,
         * so that the layers and the lattice together hold the fluid's volume / dx^D as the plain
         * lattice would (B counted on the block's lattice lo + (i + 1/2) dx continued beyond it) */
        const double *blo = c->blocks[block].lo;
        int64_t inball = 0;
        int lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
        for (int a = 0; a < c->dim; a++) {
            double xa = v3_get(xc, a);
            lo[a] = (int)floor((xa - rz - blo[a]) / dx - 0.5), hi[a] = (int)ceil((xa + rz - blo[a]) / dx - 0.5);
        }
        for (int i = lo[0]; i <= hi[0]; i++)
            for (int j = lo[1]; j <= hi[1]; j++)
                for (int q = lo[2]; q <= hi[2]; q++) {
                    double ex = blo[0] + (i + 0.5) * dx - xc.x, ey = blo[1] + (j + 0.5) * dx - xc.y;
                    double ez = c->dim == 3 ? blo[2] + (q + 0.5) * dx - xc.z : 0.0;
                    inball += ex * ex + ey * ey + ez * ez < rz * rz;
                }
        const double vball = c->dim == 3 ? 4.0 * M_PI / 3.0 * rz * rz * rz / (dx * dx * dx) : M_PI * rz * rz / (dx * dx);
        for (int l = 0; l < c->sph.body_layers; l++) {
            const double r = R + (l + 0.5) * dx, r0 = R + l * dx, r1 = r0 + dx;
            double vol = c->dim == 3 ? 4.0 * M_PI / 3.0 * (r1 * r1 * r1 - r0 * r0 * r0) / (dx * dx * dx)
                                     : M_PI * (r1 * r1 - r0 * r0) / (dx * dx);
            if (l == c->sph.body_layers - 1)
                vol += (double)inball - vball;
            const int64_t n = vol > 0.0 ? llround(vol) : 0;
            for (int64_t i = 0; i < n; i++) {
                double x[3];
                if (c->dim == 3) {
                    double z = 1.0 - (2.0 * (double)i + 1.0) / (double)n, s = sqrt(fmax(0.0, 1.0 - z * z));
                    double ph = golden * (double)i;
                    x[0] = xc.x + r * s * cos(ph), x[1] = xc.y + r * s * sin(ph), x[2] = xc.z + r * z;
                } else {
                    double ph = 2.0 * M_PI * ((double)i + 0.5 * (l % 2)) / (double)n;
                    x[0] = xc.x + r * cos(ph), x[1] = xc.y + r * sin(ph), x[2] = 0.0;
                }
                for (int a = 0; a < c->dim; a++)
                    if (c->sph.periodic[a]) {
                        double L = c->sph.hi[a] - c->sph.lo[a];
                        x[a] -= L * floor((x[a] - c->sph.lo[a]) / L);
                    }
                if (!lahar_particle_block_contains(&c->blocks[block], c->dim, x) || !case_lattice_outside_bodies(x, k))
                    continue;
                if (out && count < cap)
                    memcpy(out[count], x, sizeof x);
                if (++count == most)
                    return count;
            }
        }
    }
    return count;
}

/* As lahar_case_block_lattice; first_only: stop at the first particle (the loader only needs to
 * know a block is not empty). */
static int64_t case_block_lattice(const lahar_case *c, int block, double (*out)[3], int64_t cap, int first_only)
{
    /* the halo is dx/2 (the only value sph.halo accepts) */
    const size_t nb = (size_t)(c->nbody > 0 ? c->nbody : 1);
    case_lattice_cut k = {c, malloc(nb * sizeof(double)), {0}, 0.5 * c->sph_dx, 0.0};
    int64_t count = -1;
    if (!k.reach || geom_body_grids_build(&k.grids, c->bodies, c->nbody) != 0)
        goto done;
    for (int m = 0; m < c->nbody; m++) {
        const lahar_body *bd = &c->bodies[m];
        k.reach[m] = 0.0;
        for (int v = 0; v < bd->shape.nv; v++)
            k.reach[m] = fmax(k.reach[m], v3_norm(v3_sub(geom_world_vertex(&bd->shape, bd->x, bd->q, v), v3_load(bd->x))));
        k.reach[m] += bd->shape.radius + k.eps;
    }
    k.zone = c->sph.body_layers * c->sph_dx;
    count = lahar_particle_block_lattice_keep(&c->blocks[block], c->dim, c->sph_dx, case_lattice_outside_bodies, &k,
                                              first_only ? 1 : -1, out, cap);
    if (k.zone > 0.0 && !(first_only && count > 0)) {
        k.zone = 0.0; /* the layers themselves: only the bodies' solids (and free bodies' halos) cut them */
        count = case_block_layers(c, block, &k, count, first_only ? 1 : -1, out, cap);
    }
done:
    geom_body_grids_free(&k.grids);
    free(k.reach);
    return count;
}

int64_t lahar_case_block_lattice(const lahar_case *c, int block, double (*out)[3], int64_t cap)
{
    return case_block_lattice(c, block, out, cap, 0);
}

/* Blocks must hold particles; on periodic axes they stay inside the period; two boxes must not
 * overlap (their particles would be created twice). */
void case_check_blocks_placement(reader *r, yaml_node_t *bl, lahar_case *c)
{
    const int dim = c->dim;
    const double dx = c->sph_dx;
    for (int i = 0; i < c->nblock && !r->failed; i++) {
        const lahar_particle_block *b = &c->blocks[i];
        char key[KEY_MAX];
        snprintf(key, sizeof key, "sph.blocks[%d]", i);
        yaml_node_t *bn = rd_seq_item(r, bl, i);
        for (int a = 0; a < dim; a++)
            if (c->sph.periodic[a] && (b->lo[a] < c->sph.lo[a] - 1e-9 * dx || b->hi[a] > c->sph.hi[a] + 1e-9 * dx)) {
                rd_fail(r, bn, key, "'%s' reaches outside the period [%g, %g] of axis %c (block [%g, %g]); keep "
                        "blocks inside sph.periodic", b->name, c->sph.lo[a], c->sph.hi[a], "xyz"[a], b->lo[a], b->hi[a]);
                return;
            }
        for (int j = 0; j < i; j++) {
            const lahar_particle_block *o = &c->blocks[j];
            if (b->kind != LAHAR_BLOCK_BOX || o->kind != LAHAR_BLOCK_BOX || b->phase != o->phase)
                continue; /* water may fill the pores of a soil block (Trujillo-Vela et al. 2020 section 2.3) */
            int overlap = 1;
            for (int a = 0; a < dim; a++)
                overlap = overlap && b->lo[a] < o->hi[a] - 1e-9 * dx && o->lo[a] < b->hi[a] - 1e-9 * dx;
            if (overlap) {
                rd_fail(r, bn, key, "'%s' overlaps block '%s' (sph.blocks[%d]); particles would be created twice "
                        "there: make the boxes meet without overlapping", b->name, o->name, j);
                return;
            }
        }
        double size = lahar_particle_block_lattice_size(b, dim, dx);
        if (!(size <= LAHAR_LATTICE_MAX)) {
            rd_fail(r, bn, key, "'%s' spans %g lattice points at dx = %g (more than %g, beyond any machine); check "
                    "its extent and sph.dx", b->name, size, dx, LAHAR_LATTICE_MAX);
            return;
        }
        int64_t np = case_block_lattice(c, i, NULL, 0, 1);
        if (np < 0) {
            rd_fail(r, bn, key, "out of memory");
            return;
        }
        if (np == 0) {
            rd_fail(r, bn, key, "'%s' holds no particle at dx = %g (its region misses every lattice point "
                    "lo + (i + 1/2) dx outside the bodies); enlarge it or lower sph.dx", b->name, dx);
            return;
        }
    }
}
