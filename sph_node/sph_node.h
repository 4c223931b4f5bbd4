/* The SPH node's process loop (minimal for now: particles on a lattice falling under gravity, no
 * forces). Joins a run, creates the particles of the scene's blocks and answers each STEP of the
 * coordinator (protocol in lcm_types/README.md). Used by lahar-sph and `lahar run --in-process`. */
#ifndef LAHAR_SPH_NODE_H
#define LAHAR_SPH_NODE_H
#include <stdint.h>
#include "scene.h"

typedef struct {
    const char *lcm_url; /* udpm://... or memq:// */
    int64_t run_id;      /* 0: join the first run announced */
    int threads;         /* OpenMP threads; 0 = OpenMP default */
    double join_wait_s;  /* how long to wait for the coordinator's HELLO */
} lahar_sph_node_options;

/* Particles: the solver core's structure of arrays (sph_particles.h). Until the node steps them
 * with the WCSPH core, they only fall under gravity. */
#include "sph_particles.h"

/* Allocate and fill the lattice of spacing dx in every block (sph_particles_add_box: centres at
 * lo + (i + 1/2) dx, floor((hi - lo)/dx) per axis, one layer at z = 0 in 2D). Returns the number
 * of particles, or -1 when out of memory. */
int64_t lahar_sph_node_fill(sph_particles *p, int dim, double dx, double rest_density, int nblock,
                            const lahar_particle_block *blocks);
/* Semi-implicit Euler under gravity only: v += g dt, then x += v dt. */
void lahar_sph_node_fall(sph_particles *p, const double g[3], double dt);
/* CFL-like step of a free fall: 0.25 dx / (|v|max + sqrt(|g| dx)). */
double lahar_sph_node_fall_dt(const sph_particles *p, const double g[3], double dx);

int lahar_sph_node_run(const lahar_sph_node_options *o);

#endif
