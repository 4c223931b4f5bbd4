/* Energies of a DEM body (Trujillo-Vela et al. 2020 eq. 37-38), written per body and step to the
 * force stream (forces.h5 dataset energy) and summed over the bodies in a control volume
 * (eq. 39, sph_node/probes/sph_gauges.h). */
#ifndef LAHAR_ENERGY_H
#define LAHAR_ENERGY_H
#include "scene.h"

/* e[0] = E_P = -m g . x (eq. 37: m g y_B with gravity (0, -g) in 2D, m g z_B in 3D; zero at the
 * origin), e[1] = E_K = m |v|^2 / 2 (eq. 38, translational), e[2] = E_R = w . I w / 2 (rotational,
 * principal moments in the body frame). Fixed bodies (mass 0): all 0. Per unit thickness in 2D. */
void lahar_body_energy(const lahar_body *b, const lahar_body_state *s, const double gravity[3], double e[3]);

#endif
