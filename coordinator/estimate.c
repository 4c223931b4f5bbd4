/* Cost of a case before it runs (estimate.h). The memory figures are measured peak resident
 * memory of in-process runs (/usr/bin/time, one thread, 80,000-344,000 particles): 18.5 MB of
 * libraries and buffers plus about 250 B per 2D water particle, 310 B per 3D one and 720 B per
 * soil particle (stress, artificial stress and the soil's neighbour list); rounded up here so the
 * estimate errs on the high side. */
#include "estimate.h"
#include <math.h>
#include <unistd.h>
#include "case.h"
#include "sph_inflow.h"
#include "sph_node.h"

#define BASE_BYTES 20.0e6
#define WATER_BYTES_2D 300.0
#define WATER_BYTES_3D 360.0
#define SOIL_BYTES 850.0
#define BODY_BYTES 20.0e3 /* shapes, display meshes, contact lists per body (small next to particles) */

static double block_lattice_points(const lahar_particle_block *b, int dim, double dx)
{
    double n = 1.0;
    for (int a = 0; a < dim; a++)
        n *= floor((b->hi[a] - b->lo[a]) / dx + 1e-9);
    return n > 0.0 ? n : 0.0;
}

/* The fastest sound speed of the scene's soils: P-wave speed sqrt(E (1 - nu) / (rho (1 + nu) (1 - 2 nu))). */
static double soil_sound_speed(const lahar_case *c)
{
    double cs = 0.0;
    for (int b = 0; b < c->nblock; b++) {
        if (c->blocks[b].phase != 1 || c->blocks[b].material < 0)
            continue;
        const lahar_material *m = &c->materials[c->blocks[b].material];
        double nu = m->poisson, den = m->density * (1.0 + nu) * (1.0 - 2.0 * nu);
        if (den > 0.0)
            cs = fmax(cs, sqrt(m->young * (1.0 - nu) / den));
    }
    return cs;
}

void lahar_estimate_case(const lahar_case *c, double count_max, lahar_estimate *e)
{
    *e = (lahar_estimate){.bodies = c->nbody, .exact = 1};
    double lattice = 0.0;
    for (int b = 0; b < c->nblock; b++)
        lattice += block_lattice_points(&c->blocks[b], c->dim, c->sph_dx);
    e->exact = lattice <= count_max;
    for (int b = 0; b < c->nblock; b++) {
        int64_t n = e->exact ? lahar_case_block_lattice(c, b, NULL, 0)
                             : (int64_t)block_lattice_points(&c->blocks[b], c->dim, c->sph_dx);
        if (n < 0) /* out of memory counting: fall back to the lattice */
            n = (int64_t)block_lattice_points(&c->blocks[b], c->dim, c->sph_dx);
        e->particles += n;
        if (c->blocks[b].phase == 1)
            e->soil_particles += n;
    }
    /* open boundaries: the room the SPH node reserves for what the inlets create (the memory is
     * allocated at set-up, so it counts in full) */
    sph_params prm;
    sph_inflow fl = {0};
    char err[256];
    if (sph_inflow_case_wanted(c) && lahar_sph_node_params(c, &prm, err, sizeof err) == 0 &&
        sph_inflow_setup_case(&fl, c, &prm, err, (int)sizeof err) == 0)
        e->inflow_particles = sph_inflow_capacity(&fl);
    if (sph_inflow_case_wanted(c))
        sph_inflow_free(&fl);
    double water = (double)(e->particles - e->soil_particles + e->inflow_particles);
    e->bytes = BASE_BYTES + BODY_BYTES * c->nbody + water * (c->dim == 3 ? WATER_BYTES_3D : WATER_BYTES_2D) +
               (double)e->soil_particles * SOIL_BYTES;
    if (e->particles > 0 && c->sph_dx > 0.0) {
        double h = c->sph.h_over_dx * c->sph_dx, speed = fmax(e->soil_particles < e->particles ? c->sph.c0 : 0.0,
                                                              soil_sound_speed(c));
        e->dt = speed > 0.0 ? c->sph.cfl * h / speed : c->dt_max;
        double dt = fmin(e->dt, c->dt_max > 0.0 ? c->dt_max : e->dt);
        e->steps = dt > 0.0 ? ceil(c->t_end / dt) : 0.0;
        e->particle_steps = e->steps * (double)e->particles;
    }
}

double lahar_estimate_machine_bytes(void)
{
    long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGESIZE);
    return pages > 0 && size > 0 ? (double)pages * (double)size : 0.0;
}
