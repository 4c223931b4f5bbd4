/* The solver's optional units, each in its own file, called from the step in sph_fluid.c. Private
 * to sph_node/fluid/: users drive the solver through sph_fluid.h. */
#ifndef LAHAR_SPH_FLUID_UNITS_H
#define LAHAR_SPH_FLUID_UNITS_H
#include "sph_fluid.h"

/* sph_sps.c: nu_t and the SPS stress tau of every particle (sps: true) */
void sph_fluid_sps_pass(sph_fluid *f);
/* sph_shifting.c: shift the water particles after a step (shifting > 0) */
void sph_fluid_shift(sph_fluid *f);
/* sph_density_filters.c: rho_i = m_i sum_j W_ij (transport_velocity: true); the Shepard filter is
 * public (sph_fluid_shepard, sph_fluid.h) */
void sph_fluid_summation_density(sph_fluid *f);

#endif
