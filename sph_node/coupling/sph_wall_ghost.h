/* The ghost wall model (sph_wall_ghost.c), private to sph_node/coupling/: what
 * sph_coupling_init and sph_coupling_apply call. Notation and tables: sph_coupling.h. */
#ifndef LAHAR_SPH_WALL_GHOST_H
#define LAHAR_SPH_WALL_GHOST_H
#include "sph_coupling.h"
#include "vec.h"

double sph_ghost_layers(const kernel *k, int dim, double d, double dx);
double sph_ghost_layers_curved(const kernel *k, int dim, double d, double dx, double R);
vec3 sph_ghost_wall_accel(const sph_coupling *c, double p, double pbar, double rho, double d, vec3 n, vec3 u,
                          double *drho);
double sph_ghost_pbar(const sph_coupling *c, const sph_particles *p, int64_t i);
void sph_ghost_soil_sigbar(const sph_coupling *c, const sph_particles *p, int64_t i, double out[SPH_NSTRESS]);
vec3 sph_ghost_soil_accel(const sph_coupling *c, const double si[SPH_NSTRESS], const double sbar[SPH_NSTRESS],
                          double rho, double d, vec3 n, vec3 *A);
vec3 sph_ghost_corner_accel(const sph_coupling *c, double p, double pbar, double rho, double da, vec3 na, double db,
                            vec3 nb, vec3 urel_a, vec3 urel_b, double *drho);

#endif
