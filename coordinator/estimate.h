/* What a case will cost before it runs: particles, bodies, memory and particle-steps, so that
 * `lahar validate` can say it and `lahar run` can refuse a case the machine cannot hold. */
#ifndef LAHAR_ESTIMATE_H
#define LAHAR_ESTIMATE_H
#include <stdint.h>
#include "scene.h"

typedef struct {
    int64_t particles;     /* SPH particles at t = 0 (exact when `exact`, else the blocks' lattice) */
    int exact;             /* 1: counted point by point with the bodies cut out (lahar_case_block_lattice) */
    int64_t soil_particles;
    int64_t inflow_particles; /* room the SPH node reserves for the inlets (sph_inflow_capacity; 0 without) */
    int bodies;
    double bytes;          /* peak memory of the run, estimated (all nodes) */
    double dt;             /* the largest SPH step the CFL limit allows (0: no particles) */
    double steps;          /* steps to t_end at min(dt, time.dt_max): a lower bound */
    double particle_steps; /* particles x steps */
} lahar_estimate;

/* Fills *e for case c, counting the particles point by point (the bodies cut out, as the SPH node
 * fills them) up to count_max lattice points in all; above it the count of the blocks' lattices
 * is given instead, an upper bound (a terrain case's blocks may hold 8 x fewer). Counting costs
 * about 1 us per lattice point (a terrain's features through its grid), so `lahar validate` counts
 * up to LAHAR_ESTIMATE_COUNT_MAX (a few seconds), and `lahar run`, which only needs an upper bound
 * for its memory check, up to LAHAR_ESTIMATE_COUNT_RUN, counting further only before it would
 * refuse a case. */
#define LAHAR_ESTIMATE_COUNT_MAX 4000000.0
#define LAHAR_ESTIMATE_COUNT_RUN 250000.0
void lahar_estimate_case(const lahar_case *c, double count_max, lahar_estimate *e);

/* The machine's physical memory in bytes (0 if unknown). */
double lahar_estimate_machine_bytes(void);
#endif
