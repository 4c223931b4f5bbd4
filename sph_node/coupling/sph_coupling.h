/* SPH-DEM coupling through virtual particles (Trujillo-Vela et al. 2020 section 4, eq. 12-21).
 *
 * For every SPH particle i within the kernel support kappa h of the swept surface of a DEM body:
 *   c    closest point of the body's core (vertex, edge or face; geom_point_body_core)
 *   n    unit normal from the core to the particle (eq. 12: n = (x_i - x_dem)/|...|, generalised
 *        from a sphere's centre to the closest core point)
 *   x_s  = c + R n, the virtual particle on the swept surface (eq. 12)
 *   d    = |x_i - c| - R, signed distance to the surface (eq. 13; negative inside the sweep)
 *   delta = eps - d, eps = dx/2 the halo (eq. 14)
 *   F_n  = K_n delta n when delta > 0, K_n = 0.1 m_min / dt^2 (eq. 15)
 *   u_rel = u_i - v_dem - w_dem x (x_s - x_dem) (eq. 16; the surface velocity of the body)
 *   F_t  = m_i a_tau, the viscous force of the virtual particle (eq. 17-18, see lahar_sph_wall_viscous)
 *   F on the particle = F_n + F_t (eq. 19), on the body -F (eq. 20) at x_s, torque
 *   (x_s - x_dem) x (-F) (eq. 21, printed F x r: the usual r x F is used).
 * A particle closer to the core than R, or inside a closed convex core, has crossed the body's
 * surface: it is counted (crossings) and the first one is named.
 * Body forces are summed serially in particle order after the parallel per-particle pass, so the
 * result is bitwise the same for any thread count. */
#ifndef LAHAR_SPH_COUPLING_H
#define LAHAR_SPH_COUPLING_H
#include <stdint.h>
#include "geometry.h"
#include "kernel.h"
#include "scene.h"
#include "sph_particles.h"

/* The wall viscous force (virtual particle term), lahar_sph_wall_viscous (common/scene/scene.h):
 * LAHAR_SPH_WALL_HALFSPACE (default): the Morris (1997) viscous operator summed over ghost layers
 *   behind the body's surface, at depths s_k = (k + 1/2) dx (the mirror image of the fluid
 *   lattice), with the no-slip ghost velocity extrapolated as in Morris et al. (1997):
 *   u_ghost - u_wall = -(s/d)(u_i - u_wall). Then
 *     a_tau = (2 mu_i / rho_i) G(d) u_rel,
 *     G(d) = sum_k (1 + s_k/d) dx int_layer W'(r)/r r^2/(r^2 + eta^2) dA
 *   which is the "readjusted normalising constant" idea of eq. 18 made exact for a flat wall:
 *   the single virtual particle carries the whole missing neighbourhood. G is tabulated at setup
 *   over d in [eps/2, kappa h] (d is clamped to eps/2 below).
 * LAHAR_SPH_WALL_PAPER: eq. 17 as printed: a_tau = 4 m_i/(3 h^D) (2 mu_i)/(2 rho_i)^2 u_rel/d
 *   W'(d)/W(0, h). Its factor disagrees with eq. 18 (2/(3 h^D W(0,h))) and neither gives the wall
 *   shear of a Poiseuille flow (tests/test_sph_poiseuille.c reports its error): kept for comparison. */

/* The wall pressure term, lahar_sph_wall_pressure (common/scene/scene.h): what, besides the penalty
 * force of eq. 15, holds the fluid off a body.
 * PENALTY (default): Trujillo-Vela et al. 2020 as printed, K_n delta n only. A particle in the second row from a
 *   wall (d > eps) misses the kernel neighbours behind the wall and nothing replaces them, so the
 *   first rows carry it with a pressure rise: hydrostatic pressures near a floor read 4-6 % high.
 * GHOST: the penalty force plus the pressure and continuity terms of Trujillo-Vela et al. 2020, eq. 1-2 summed over
 *   ghost layers behind the surface, the same layers as LAHAR_SPH_WALL_HALFSPACE (depths
 *   s_k = (k + 1/2) dx, continuous along the wall, moving with it). The ghost pressure is
 *   extrapolated hydrostatically (Adami, Hu & Adams 2012, eq. 27, wall at rest) from pbar_i, the
 *   Shepard mean of the pressures around particle i carried to x_i:
 *     p_g = pbar_i + rho_i b.(x_g - x_i),  b the fluid's body force,
 *   and ghosts stand only where p_g > 0 (none beside the fluid above its free surface). Mirroring
 *   p_i itself instead of pbar_i is unstable: a particle's own pressure would push it off the
 *   wall into the fluid, which compresses it further. The sums (sph_coupling.c, "GHOST") are
 *   tabulated at setup in the distance and the height of the cut. At a concave corner of two
 *   perpendicular bodies (|n1.n2| < 0.1) the quadrant behind both is in both sets of layers:
 *   half of each body's layers behind the other is taken off again, so the corner counts once;
 *   of what stays, the push along each body's normal is that body's reaction (at a 3D corner of
 *   three bodies the octant then counts zero times instead of once: a few particles). The
 *   reactions go to the bodies with the penalty force (eq. 20). Body accelerations are not
 *   known here: moving bodies are extrapolated as if at rest; b is taken along the non-periodic axes
 *   only (sph_fluid.c), and a body force along a wall that drives a flow instead of holding a
 *   pressure gradient is outside this model (validated: tanks at rest only). Measured (tests/
 *   test_sph_hydrostatic.c, cases/README.md): tank at rest, wall force and pressure L2 within
 *   0.7 % in 2D and 3D, against 1-6 % and 3-15 % with the penalty alone. */
#define SPH_COUPLING_WTAB 48
#define SPH_COUPLING_QTAB 24

/* One particle-body contact of the last evaluation: force ON THE BODY at the virtual particle. */
typedef struct {
    double xs[3];        /* virtual particle (surface point), world */
    double force[3];     /* N (N/m in 2D), on the body: eq. 20 */
    double delta;        /* halo overlap eps - d (m), <= 0 when only the viscous term acts */
    int64_t particle_id; /* sph_particles.id */
} sph_contact;

#define SPH_COUPLING_MAX_PER_PARTICLE 4
#define SPH_COUPLING_GTAB 512

typedef struct {
    int dim, nbody;
    const lahar_body *bodies;  /* borrowed: shapes, motion */
    double *bound;             /* per body: max |core vertex - x| (body frame) + R */
    double (*box)[6];          /* per fixed body: world box of the swept shape (lo, hi) */
    geom_body_grids grids;     /* feature grids of the big shapes (terrain, flumes) */
    kernel k;
    double eps;                /* halo thickness, dx/2 (eq. 14) */
    double m_min;              /* eq. 15 */
    double kn;                 /* K_n of the last evaluation */
    double mu;                 /* fluid dynamic viscosity */
    lahar_sph_wall_viscous viscous;
    double gtab[SPH_COUPLING_GTAB + 1], gtab_d0, gtab_dd; /* G(d) on d = d0 + k dd */
    double **gtab_body;        /* per body: G(d) of a disc/sphere (one core point), layers curved
                                  with its surface; NULL entries (and NULL): the flat gtab */
    lahar_sph_wall_pressure pressure;  /* sph_coupling_set_wall_pressure; default penalty only */
    double kn_dt;                /* > 0: K_n = 0.1 m_min / kn_dt^2 whatever the step (sph.penalty_stiffness:
                                    acoustic, kn_dt = cfl h / c0); 0 (default): the step's dt, eq. 15
                                    as printed. With the step's dt the penalty spring's period stays
                                    ~20 steps, so a smaller step (dt_max, a DEM-limited coordinator
                                    step) makes it stiffer: each particle's bounce becomes a shorter,
                                    higher spike (peak ~ m v sqrt(0.1)/dt) and the wall force a train
                                    of spikes and zeros. A stiffness set by a velocity scale, not by
                                    the step, is what Monaghan-type boundary forces use (Monaghan
                                    1994, J. Comput. Phys. 110:399; Monaghan & Kajtar 2009, Comput.
                                    Phys. Commun. 180:1811: constants from c0^2 or g H) */
    double body_force[3];        /* b of the ghost pressure extrapolation */
    int riemann;                 /* GHOST with the water's Riemann scheme: the wall's dissipation
                                    (sph_riemann.h) joins the ghost pressure; set by sph_fluid_init */
    double riemann_c0, riemann_eta;
    double *wtab, wtab_dd;       /* GHOST: wall table (sph_coupling.c) on d = gtab_d0 + k wtab_dd */
    double *qtab, qtab_dd;       /* GHOST: corner table on d = gtab_d0 + k qtab_dd */
    const sph_cells *cells;      /* GHOST: the fluid's cells (borrowed), for the ghosts' pressure */
    lahar_sph_wall_pressure soil_pressure; /* sph_coupling_set_soil_wall; default penalty + spring only */
    double soil_g[3];            /* the soil's gravity (its ghost stress extrapolation) */
    double (*soil_lw)[9];        /* soil GHOST: per particle, the ghosts' share of the velocity
                                    gradient (L_ab at 3a + b) of the last evaluation */
    unsigned char *soil_lw_on;   /* 1 where soil_lw is set (the particle had ghosts) */
    /* per-particle slots of the parallel pass */
    int64_t pcap;
    int *slot_n;
    uint32_t *near;            /* per particle: bit b set when body b may be within the support
                                  (sph_coupling_mark; bodies < 32, no periodic axis) */
    int near_valid;            /* near[] is for the particles as they are now (reset by apply) */
    int *slot_body;
    sph_contact *slot;
    /* results of the last evaluation, per body */
    double (*force)[3], (*torque)[3];
    int64_t *body_start;       /* nbody + 1: contacts of body b are contacts[body_start[b] ..) */
    sph_contact *contacts;
    int64_t ncontacts, contacts_cap;
    int64_t *body_fill;
    /* crossings in the last evaluation */
    int64_t crossings;
    int cross_body;            /* first crossing (lowest particle index): body, particle id, depth */
    int64_t cross_particle_id;
    double cross_depth;        /* how far inside the swept surface (m, > 0) */
    /* periodic axes of the fluid (sph_coupling_set_periodic; none after init) */
    int periodic[3];
    double period[3];          /* hi - lo on the periodic axes */
    double period_lo[3];       /* lo on the periodic axes */
    /* soil-DEM friction (sph_coupling_enable_soil; NULL/0 without soil): per particle id, up to
     * SPH_COUPLING_MAX_PER_PARTICLE (body, delta_tau) pairs of the last evaluation */
    double mu_phi;
    int *soil_hist_body;       /* -1: empty slot */
    double (*soil_hist_d)[3];
} sph_coupling;

/* Set up the coupling with nbody bodies (borrowed; shapes must stay valid), halo eps = dx/2,
 * m_min = min(particle mass m_sph, masses of free bodies) (eq. 15), dynamic viscosity mu, for
 * particle_cap particles. Returns 0 or -1 (out of memory). */
int sph_coupling_init(sph_coupling *c, int dim, int nbody, const lahar_body *bodies, const kernel *k, double dx,
                      double m_sph, double mu, lahar_sph_wall_viscous viscous, int64_t particle_cap);
void sph_coupling_free(sph_coupling *c);

/* Add the coupling forces (eq. 19) to the particle accelerations p->ax.. (divided by the
 * particle mass) for a step of length dt (K_n = 0.1 m_min/dt^2), with the moving bodies at
 * `states` (NULL: the poses and velocities stored in the bodies; fixed bodies always use theirs). Fills the per-body resultants, the
 * contact list and the crossing count. Returns the number of crossings, or -1 when the contact
 * list cannot grow (out of memory). */
int64_t sph_coupling_apply(sph_coupling *c, sph_particles *p, const lahar_body_state *states, double dt);

/* Periodic axes of the fluid: axis a with periodic[a] repeats with period [lo[a], hi[a]). A particle
 * then interacts with every periodic image of every body (the body shifted by whole periods) whose
 * swept surface is within the kernel support, so a body near (or across) a periodic boundary acts
 * on the particles on the other side of it, as the fluid's own neighbour sums do. Contacts,
 * forces and torques stay per body: an image's contact point is mapped back onto the body itself
 * (the particle is shifted, not the body). A body at least as long as the period along an axis
 * (fixed: its world box; moving: its bounding sphere's diameter) spans that axis, like the walls
 * of a periodic channel, and has no images along it; so has a body entirely outside the period
 * (and the support around it) along an axis: it is outside the fluid's domain (a marker body
 * parked far away stays inert). z is ignored in 2D. */
void sph_coupling_set_periodic(sph_coupling *c, const int periodic[3], const double lo[3], const double hi[3]);
/* Soil-DEM friction (Trujillo-Vela et al. 2020 section 4.2, eq. 22-27) for the soil particles (phase != 0): instead
 * of the water's viscous term, a tangential spring with a history per (particle, body) pair, kept
 * by particle id (so it survives the sort):
 *   u_tau = u_rel - (u_rel . n) n                                        (eq. 22)
 *   delta_tau = P_n(delta_tau) + dt u_tau                                (eq. 23; the old spring is
 *               projected onto the current tangent plane, P_n = I - n n^T, as the contact turns)
 *   delta_tau* = mu_phi |F_n| / K_n  delta_tau / |delta_tau|  when longer (eq. 24; stick below)
 *   F on the particle = F_n - K_n delta_tau*                             (eq. 25)
 *   F on the body = -F (eq. 26) at x_s, torque (x_s - x_dem) x (-F)     (eq. 27 as r x F)
 * A pair exists while the particle is inside the halo (delta > 0, F_n > 0); when it leaves, the
 * spring is released. The spring is advanced once per evaluation (sph_coupling_apply), i.e. once
 * per step; the extra evaluations at t_0 add dt u_tau of the initial state. Allocates the
 * history for the particle cap of the coupling. Returns 0 or -1 (out of memory). */
int sph_coupling_enable_soil(sph_coupling *c, double mu_phi);

/* Choose the wall pressure term (default LAHAR_SPH_WALL_PRESSURE_PENALTY) with the fluid's body force b
 * (m/s^2) and the particle spacing dx; GHOST tabulates its integrals here (a fraction of a second
 * in 3D). Returns 0 or -1 (out of memory). */
int sph_coupling_set_wall_pressure(sph_coupling *c, lahar_sph_wall_pressure mode, const double body_force[3], double dx);

/* The soil's wall term (default LAHAR_SPH_WALL_PRESSURE_PENALTY: the penalty force of eq. 15 and the
 * friction spring of eq. 22-27 only). GHOST: the ghost layers of LAHAR_SPH_WALL_PRESSURE_GHOST (the same
 * tables) carry a stress for the soil particles too, in the spirit of Bui et al. (2008, section
 * 4.2, boundary particles whose stress is the soil's) and Adami, Hu & Adams (2012, eq. 27):
 *   sigma_g = sigmabar_i - rho_i g.(x_g - x_i) I,
 *   sigmabar_i = sum_j V_j W_ij (sigma_j - rho_j g.(x_i - x_j) I) / sum_j V_j W_ij
 * (Shepard mean over i and its soil neighbours, carried to x_i with the weight term; g the soil's
 * gravity). Trujillo-Vela et al. 2020, eq. 5 summed over the ghosts (m_g = rho_i V_g, rho_g = rho_i) then reads
 *   a = -(sigma_i + sigmabar_i) . A / rho_i + B g    (A, B the tables of the water's ghosts)
 * with the shear across the wall, (sigma_i + sigmabar_i)_nt, set to zero, and only the component
 * along n kept (free slip: on a full flat wall the rest vanishes; where the ghosts are cut, along
 * a side wall, it would push along the wall with the soil's vertical stress, which does not
 * vanish where the normal stress does). The wall friction stays with the spring of eq. 22-27, whose
 * cap mu_phi |F_n| then takes F_n = the penalty force plus the ghosts' push along n, and which
 * acts while that total is > 0). Ghosts stand where the extrapolated normal stress is
 * compressive (the water's cut with p = -sigmabar_nn). Without them, the one-sided kernel of the
 * rows on a floor makes the stress divergence carry the weight with too large a stress: the
 * soil row resting on a DEM floor reads ~20 % high in sigma_v (cases/soil_geostatic_2d.yaml).
 * The ghosts also take part in the soil's velocity gradient (Adami, Hu & Adams 2012: the wall's
 * velocity for the ghosts in the continuity and velocity-gradient sums; Bui et al. 2008 section
 * 4.2: boundary particles in the strain-rate sum), free slip: the ghosts move with the wall along
 * n and with the particle along the wall, v_g - v_i = -(u_rel.n) n, so that
 *   L_ab += sum_g V_g (v_g - v_i)_a (grad_i W_ig)_b = (u_rel.n) n_a A_b
 * with A the ghost table's vector of the stress term (sph_soil_wall_gradient redoes the stress
 * rate of the particle with it after this pass). Without this term a collapsing column blew up
 * within 0.1 s: a particle of the floor row at the toe, its neighbours missing to the right and
 * above-right but the ghosts standing under it to the right as well, is pushed up by its own
 * compressive stress; moving up, its one-sided velocity gradient (neighbours above only) reads a
 * compression (L_yy = -0.45 u/dx on a lattice), which raises that stress and the push: a positive
 * feedback (sigma_yy -1.3 kPa to -21 kPa in 0.01 s at dx 10 mm, 0.4 m/s up). With the ghosts'
 * share a particle displaced alone reads no strain (tests/test_sph_soil.c), and the columns come
 * to rest inside the run-out band (cases/README.md, "Soil"). A field v_n = G y vanishing on the
 * wall reads 0.73 G in the first row (the ghosts move with the wall, they do not extrapolate the
 * field; the mirrored velocity 2 v_w - v_i, tried, would read about 0.96 G but leaves the a = 1
 * column moving: E_k end / peak 0.055 at dx 10 mm, 0.031 at 5 mm). The soil's continuity takes no
 * ghost term (tried, -rho_i (u_rel.n) A.n: L_99 -3 % and +2 % at a = 1, dx 10 and 5 mm, -8 % at
 * a = 2, dx 10 mm, no change at rest: not kept), and the concave-corner correction of the water
 * is not applied to the soil (the quadrant behind floor and wall counts twice).
 * Returns 0 or -1 (out of memory). */
int sph_coupling_set_soil_wall(sph_coupling *c, lahar_sph_wall_pressure mode, const double gravity[3], double dx);

/* Before sph_coupling_apply, with the cells sorted for the particles' current positions: marks,
 * per particle, the bodies whose box (fixed: the world box of the swept shape; moving: the
 * bounding sphere's box at `states`), widened by the kernel support, overlaps the particle's
 * cell, so that apply skips the others without testing them (a particle outside that box is
 * farther than the support from the body: results unchanged). Does nothing (apply tests every
 * body) with 32 bodies or more or a periodic axis. One apply uses the marks, then they lapse. */
void sph_coupling_mark(sph_coupling *c, const sph_cells *cells, int64_t n, const lahar_body_state *states);

/* G(d) of the half-space wall model (see LAHAR_SPH_WALL_HALFSPACE), for tests. */
double sph_coupling_halfspace_factor(const sph_coupling *c, double d);
/* The same for body b: its curved table when it is a disc or sphere, else the flat one. */
double sph_coupling_body_halfspace_factor(const sph_coupling *c, int b, double d);

#endif
