/* The SPH node's process loop: joins a run, fills the scene's particle blocks, builds the WCSPH
 * solver core (sph_fluid.h) coupled with the scene's DEM bodies (sph_coupling.h) and answers each
 * STEP of the coordinator, exchanging LOADS and BODY_STATE with the DEM node (protocol and exchange
 * order in lcm_types/README.md). Used by lahar-sph and `lahar run --in-process`. */
#ifndef LAHAR_SPH_NODE_H
#define LAHAR_SPH_NODE_H
#include <stdint.h>
#include "scene.h"

#include "node_cli.h"

/* The node's options: the command line every node takes (common/protocol/node_cli.h). */
typedef lahar_node_options lahar_sph_node_options;

#include <stddef.h>
#include "sph_fluid.h"
#include "sph_particles.h"

/* The solver parameters of a case (lahar_case.sph, sph_dx, sph_density, gravity added to the
 * fluid's body force). Returns 0, or -1 with a message for options the solver core does not
 * implement yet (SPS, a halo other than dx/2, a coupling range other than the kernel support). */
int lahar_sph_node_params(const lahar_case *c, sph_params *prm, char *err, size_t errlen);

/* Allocate and fill the particles of the case's blocks (lahar_case_block_lattice: centres at
 * lo + (i + 1/2) dx, one layer at z = 0 in 2D, points inside bodies left out), mass rho0 dx^D,
 * density rho0, or with sph.initial_pressure: hydrostatic the EOS inverse of
 * rho0 |g| (h_free - height) per block, h_free half a spacing above the block's top particle.
 * Returns the number of particles, or -1 when out of memory. */
int64_t lahar_sph_node_fill(sph_particles *p, const lahar_case *c);

int lahar_sph_node_run(const lahar_sph_node_options *o);

#endif
