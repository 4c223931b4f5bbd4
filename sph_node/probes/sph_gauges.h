/* Trackers and control volumes (case sections trackers: and control_volumes:; probes of kinds
 * LAHAR_PROBE_TRACKER and LAHAR_PROBE_CONTROL_VOLUME in common/scene/scene.h), sampled with the probes
 * by sph_probes_sample and written to OUT/gauges.h5 (/trackers/NAME, /control_volumes/NAME).
 *
 * A tracker is a material point: the particle nearest to its position at t = 0 (any phase; the
 * smallest id among equally near ones), followed by its id; a sample is that particle's position
 * and velocity (Trujillo-Vela et al. 2020 section 5.4, points A, B and C of Fig. 16-18 and 25).
 *
 * A control volume is a box [lo, hi). A sample sums over the particles inside it the kinetic
 * energy m |v|^2 / 2 per phase and, for every moving DEM body whose centre is inside, m_B |u_B|^2 / 2:
 * the total is Trujillo-Vela et al. 2020 eq. 39. It also gives the mass of each phase inside and
 * the mean mass flow rate through the box's cross-section normal to `axis`,
 *   q = sum_inside m_i v_i,axis / (hi - lo)_axis,
 * which for a thin box is the flux through the plane (kg/s; kg/(m s) in 2D).
 * Each sample is one pass over the particles (O(N)); a case without trackers and control volumes
 * never calls this module. */
#ifndef LAHAR_SPH_GAUGES_H
#define LAHAR_SPH_GAUGES_H
#include <stdint.h>

#include "scene.h"
#include "sph_fluid.h"

/* The id of the particle nearest to x (ties: the smallest id), -1 without particles. */
int64_t sph_gauges_nearest(const sph_fluid *f, const double x[3]);
/* out[0..6] = x, y, z, vx, vy, vz, id of the particle with this id (z, vz = 0 in 2D); NaN for the
 * position and velocity if no particle has it. */
void sph_gauges_tracker(const sph_fluid *f, int64_t id, double out[7]);
/* out[0..7] = ek, ek_water, ek_soil, ek_bodies, mass_water, mass_soil, flux_water, flux_soil of
 * the control volume p, with the bodies at `states` (nbody entries; NULL: the scene's). */
void sph_gauges_control_volume(const sph_fluid *f, const lahar_probe *p, const lahar_case *c,
                               const lahar_body_state *states, double out[8]);

#endif
