/* Probes (case section probes:, lahar_probe in common/scene/scene.h): pressure probes and water-level
 * gauges, sampled by the SPH node after each step, written to OUT/gauges.h5 (common/io/output.h).
 *
 * A level gauge (kind: level) reads the height above the floor of the water column standing on the
 * floor along a vertical line, as a wire (resistance or capacitance) wave gauge does, with the
 * dry rule of DualSPHysics' MeasureTool (Crespo et al. 2015, Comput. Phys. Commun. 187:204): the
 * water's kernel fraction phi(z) = sum_j V_j W(x - x_j), V_j = m_j / rho_j, is evaluated at points
 * dx/8 apart from the floor to the top of the line, each particle within the kernel's support of
 * the floor also counted at its mirror image below the floor (the half space the floor cuts off,
 * so phi is ~1 on a wetted floor), and the level is the first z going up from the floor where phi
 * falls to 1/2 (linear between the points), minus the floor; 0 when phi < 1/2 on the floor. phi
 * is 1 inside the water and, the kernel being symmetric, 1/2 on the plane surface of a half space,
 * so a lattice of spacing dx filled to depth h (top particles at h - dx/2) reads h. Jets and
 * spray above an air gap (a wall jet falling back over the gauge) are not counted. One walk over
 * the cells of the column within the kernel's support of the line per sample; each particle adds
 * to the points within its support.
 *
 * A probe in the fluid reads the Shepard interpolation of the water particles' pressure
 *   p(x) = sum_j p_j V_j W(x - x_j) / sum_j V_j W(x - x_j),
 * the "MeasureTool" practice of DualSPHysics (Crespo et al. 2015, Comput. Phys. Commun. 187:204),
 * with its dry rule: when sum_j V_j W < 0.5 (its `kclimit`) the point is out of the water and
 * reads 0 (its `kcdummy`).
 *
 * A probe on a body's surface reads the wall pressure of Adami, Hu & Adams 2012 (J. Comput. Phys.
 * 231:7057) eq. 27 at the surface point x_w itself:
 *   p_w = [sum_f p_f W_wf + b . sum_f rho_f (x_w - x_f) W_wf] / sum_f W_wf,
 * b the fluid's body force (gravity + sph.body_force; the body's own acceleration a_w of eq. 27 is
 * not known on the SPH node and is left out: exact for fixed bodies). The water particles are
 * the f. Only the fluid side holds particles, so a wetted wall point has sum_f V_f W_wf near 1/2
 * (near 1/4 in a 90 degree corner: a sensor 3 mm above a floor); below 0.1 the point is dry and
 * reads 0 (corner probes in a tank at rest read rho g (h - y) within 0.6 % of rho g h).
 * A sensor of diameter `size` > 0 averages the value over points at most dx/4 apart across a
 * segment (2D) or a disc (3D) of that diameter in the surface's tangent plane, each projected onto
 * the surface at setup. Points and normals are kept in the body frame and follow moving bodies.
 *
 * Sampling: every step (rate 0), or the first step at or after each multiple of 1/rate (the value
 * at that step, not an average over the interval). Costs one cell walk per sample point of the
 * probes due; a case without probes never calls this module. */
#ifndef LAHAR_SPH_PROBES_H
#define LAHAR_SPH_PROBES_H
#include <stdint.h>

#include "scene.h"
#include "sph_fluid.h"

#define SPH_PROBE_MAX_POINTS 256 /* sample points per sensor (a disc in 3D) */

typedef struct {
    int n;                 /* probes */
    int npts;              /* sample points of all probes */
    int *pt0;              /* n + 1: probe k's points are pt0[k] .. pt0[k + 1] - 1 */
    int *body;             /* per probe: body index or -1 */
    double *rate;          /* per probe: samples per second, 0 = every step */
    int64_t *next_slot;    /* per probe: the next multiple of 1/rate to record */
    double (*xl)[3];       /* per point: body frame (body probes) or world (fluid probes) */
    double (*nl)[3];       /* per point: outward normal in the body frame (body probes) */
    int *kind;             /* per probe: LAHAR_PROBE_PRESSURE or LAHAR_PROBE_LEVEL */
    int *l0;               /* n + 1: level gauge k's line points are l0[k] .. l0[k + 1] - 1 */
    double *lphi;          /* per line point: sum_j V_j W (work space of the last sample) */
    double *lstep;         /* per probe: spacing of its line points (level gauges) */
    int *v0;               /* n + 1: probe k's values are value[v0[k] .. v0[k + 1]) (lahar_probe_nvalues) */
    double *value;         /* the last sample: Pa (pressure), m (level), trackers and control
                              volumes as sph_gauges.h */
    int64_t *target;       /* per probe: the particle id a tracker follows (-1: not chosen yet) */
    int *due;              /* per probe: 1 if sampled by the last sph_probes_sample */
} sph_probes;

/* Sample points of the case's probes (c->nprobe >= 1), with the bodies at their scene pose.
 * Returns 0, or -1 (out of memory). */
int sph_probes_init(sph_probes *pr, const lahar_case *c);
void sph_probes_free(sph_probes *pr);
/* Sample the probes due at time t (after a step: the state of f at t) with the bodies at
 * `states` (nbody entries; NULL: the scene poses of c). Fills pr->value and pr->due; returns the
 * number of probes sampled. Trackers and control volumes (sph_gauges.h) are sampled here too; a
 * tracker without a target takes the particle nearest its position now (t = 0). The particles must be sorted into f's cells (they are after a step). */
int sph_probes_sample(sph_probes *pr, const sph_fluid *f, const lahar_case *c, const lahar_body_state *states,
                      double t);
/* The level of the water at the vertical line from the world point foot (on the floor) upward:
 * npt points `step` apart, phi (npt values) the work space. m above foot, 0 when dry. */
double sph_probes_level(const sph_fluid *f, const double foot[3], int npt, double step, double *phi);
/* The pressure at one world point: wall = 0 Shepard (fluid probe), 1 Adami eq. 27 (wall point). */
double sph_probes_point(const sph_fluid *f, const double x[3], int wall);

#endif
