/* Weakly compressible SPH water (Trujillo-Vela et al. 2020 section 2.1, Canelas et al. 2015 section 3), the solver core the
 * SPH node drives. Equations (x_ij = x_i - x_j, v_ij = v_i - v_j, r = |x_ij|, F_ij = W'(r)/r so
 * that grad_i W_ij = F_ij x_ij, eta^2 = 0.01 h^2, V_j = m_j / rho_j):
 *
 *   continuity (Trujillo-Vela et al. 2020, eq. 1, first term; Canelas et al. 2015, eq. 9 in the rho_i V_j form):
 *     drho_i/dt = rho_i sum_j V_j v_ij . grad_i W_ij
 *   delta-SPH density diffusion (Molteni & Colagrossi 2009; Trujillo-Vela et al. 2020, eq. 1, second term):
 *     + 2 delta h c0 sum_j V_j [(rho_i - rho_j) - rho0 b.x_ij / c0^2] F_ij r^2 / (r^2 + eta^2)
 *     Trujillo-Vela et al. 2020 print (rho_j - rho_i) x_ij with eta^2 = 0.1 h^2; Molteni & Colagrossi write
 *     (rho_j - rho_i) x_ji. With x_ij the sign must be (rho_i - rho_j) for the term to be
 *     Brookshaw's Laplacian delta h c0 lap(rho), which diffuses a bump (test_sph_fluid.c checks
 *     the rate of a sine mode against -delta h c0 k^2); eta^2 = 0.01 h^2 as their text says.
 *     The hydrostatic part rho0 b.x_ij/c0^2 (b = body force along the non-periodic axes) is not
 *     diffused (Fourtakas et al. 2019, DualSPHysics "DDT 2"): the plain Molteni term drives a
 *     column at rest away from hydrostatics (Canelas et al. 2015, section 3.3 says so; measured here: wall force
 *     -4.6 % on a 20-particle column), the corrected one leaves it hydrostatic.
 *   momentum (Trujillo-Vela et al. 2020, eq. 2, Canelas et al. 2015, eq. 10):
 *     dv_i/dt = g - sum_j m_j (p_i/rho_i^2 + p_j/rho_j^2 + Pi_ij) grad_i W_ij         (symmetric)
 *             + sum_j m_j (mu_i + mu_j)/(rho_i rho_j) F_ij r^2/(r^2 + eta^2) v_ij     (Morris 1997)
 *             + (coupling forces of DEM bodies, sph_coupling.h) / m_i
 *     Trujillo-Vela et al. 2020, eq. 2 prints the laminar term without x_ij . grad W / r^2; the complete Morris (1997)
 *     form is used (equal to Lo & Shao's 4 (mu_i + mu_j)/(rho_i + rho_j)^2 at equal densities).
 *     Pi_ij = -alpha c0 mu_ij / rho_ij, mu_ij = h v_ij.x_ij/(r^2 + eta^2) when v_ij.x_ij < 0
 *     (Monaghan 1992), rho_ij the mean density; off when alpha = 0.
 *   EOS: linear p = c0^2 (rho - rho0) (Trujillo-Vela et al. 2020, eq. 3) or Tait p = rho0 c0^2/gamma ((rho/rho0)^gamma - 1)
 *     (Canelas et al. 2015, eq. 19). c0 is the constant numerical speed of sound.
 *
 *   Background pressure p_b (prm.opt.background_pressure, default 0): without the transport velocity
 *     the momentum equation uses p_i + p_b (p.p and the snapshots keep the EOS pressure); with it,
 *     p_b enters the transport velocity only (Adami et al. 2013, below).
 *   Transport velocity (prm.opt.transport_velocity; Adami, Hu & Adams 2013, J. Comput. Phys.
 *     241:292-307, section 2; fully periodic water-only flows, the loader rejects the rest):
 *       b_i = -p_b sum_j m_j (1/rho_i^2 + 1/rho_j^2) grad_i W_ij   (the uniform p_b, same symmetric form)
 *       drift x += dt v~, v~ = v(t + dt/2) + dt/2 b (b of the last evaluation); tv = v~ - v kept
 *       per particle (permuted by the sort) for
 *       dv_i/dt += sum_j m_j (A_i/rho_i^2 + A_j/rho_j^2) . grad_i W_ij,  A = rho v (x) (v~ - v)
 *       (the extra stress of the momentum transported with v~; v = the predicted velocity of the
 *       evaluation); density by summation rho_i = m_i sum_j W_ij (j includes i; continuity and
 *       delta-SPH unused, drho = 0); the laminar viscosity is Adami et al.'s shear term
 *       mu (V_i^2 + V_j^2) F_ij v_ij, Morris's without the eta^2 = 0.01 h^2 of its denominator.
 *       Adami et al. write the pair terms with (V_i^2 + V_j^2): equal to these for equal masses.
 *       Off: no arrays, the pair loop's branch is never taken.
 *   Shepard filter (Canelas et al. 2015, eq. 5, optional, every N steps): rho_i = sum_j m_j W_ij / sum_j V_j W_ij
 *     (j includes i), which removes the particle-scale pressure noise of WCSPH without the
 *     hydrostatic bias that delta-SPH has (Canelas et al. 2015, section 3.3; test_sph_hydrostatic.c).
 *
 * Riemann scheme (case key sph.scheme: riemann; Zhang, Hu & Adams 2017, J. Comput. Phys.
 *   335:605-620, section 3), instead of delta-SPH and Monaghan's viscosity (both must be 0): with
 *   the pair's interface state U*, P* of sph_riemann.h (e_ij = -x_ij/r, U_L - U_R = -v_ij.x_ij/r),
 *     drho_i/dt = 2 rho_i sum_j V_j (v_i - v*_ij) . grad_i W_ij,  v*_ij = v-bar_ij + (U* - U-bar) e_ij
 *               = rho_i sum_j V_j F_ij (v_ij.x_ij + (p_i - p_j - rho0 b.x_ij) r / (rhobar c0))
 *     dv_i/dt  = -2 sum_j m_j P*_ij / (rho_i rho_j) grad_i W_ij   (+ viscosity, SPS, coupling as above)
 *   c = c0 for both EOS. The hydrostatic part rho0 b.x_ij of p_i - p_j is not diffused (as for
 *   delta-SPH, Fourtakas et al. 2019; Zhang et al. 2017 have no gravity term in U*): otherwise the
 *   term drives a column at rest off hydrostatics. The ghost walls (LAHAR_SPH_WALL_PRESSURE_GHOST) keep
 *   their terms: with the mirrored ghost state of Zhang et al. 2017 section 3.4 (rho_g = rho_i,
 *   the wall's velocity, p_g extrapolated hydrostatically) the interface state without
 *   dissipation is the symmetric pressure (p_i + p_g)/2 and the wall's velocity, which are the
 *   ghost terms, plus the wall's limited dissipation: p_i + p_g becomes p_i + p_g + rho_i beta dU,
 *   dU = -2 u_rel.n along the wall's normal (sph_riemann_wall_dissipation). The penalty force of
 *   eq. 15 stays.
 *
 * Time integration: kick-drift-kick leapfrog, second order, one neighbour pass per step:
 *   v_h = v + dt/2 a;  rho_h = rho + dt/2 D;  x += dt v_h;
 *   predict v = v_h + dt/2 a, rho = rho_h + dt/2 D;  sort;  evaluate a, D at (x, v, rho);
 *   v = v_h + dt/2 a;  rho = rho_h + dt/2 D.
 * Step proposal (Canelas et al. 2015, eq. 20 split in its three parts, plus the viscous limit):
 *   dt = min(C_cfl h/(c0 + |v|max), C_f sqrt(h/|a|max), C_v h^2/(nu + nu_t,max)),
 *   nu_t,max the largest SPS eddy viscosity (0 without SPS).
 * The water's particle-particle sums are symmetric: each pair (i, j) is evaluated once, from the
 * particle that comes first in the forward half of the cell stencil, and its terms are added to
 * both (the momentum terms as the pair force m_i m_j (...) with +F to i and -F to j, so momentum is
 * conserved to round-off; the continuity and delta-SPH terms each with their own V and rho). The
 * threads take blocks of cell rows, a colour at a time (sph_cells_blocks), so no two add to one
 * particle at once, and each particle receives its terms in an order fixed by the blocks: bitwise
 * the same result for any number of threads (sph_fluid.c fluid_pass). The other loops over particles (SPS, Shepard,
 * shifting, soil) gather: each particle sums over its own neighbours in cell order. */
#ifndef LAHAR_SPH_FLUID_H
#define LAHAR_SPH_FLUID_H
#include <stdint.h>
#include "kernel.h"
#include "scene.h"
#include "sph_coupling.h"
#include "sph_particles.h"
#include "sph_soil.h"


/* The solver's parameters: the case's sph: section as the loader filled it (every default set from
 * the key table, common/io/case_keys.c) and what the solver derives from the rest of the case.
 * Programs without a case file start from sph_params_default. */
typedef struct {
    lahar_sph_options opt;  /* the sph: keys (common/scene/scene.h documents each) */
    int dim;
    double dx;              /* initial particle spacing (sph.dx) */
    double rho0;            /* rest density (sph.density) */
    double body_force[3];   /* m/s^2 acting on the water: gravity + sph.body_force */
    int soil;               /* 1: the particles include soil (phase 1, sph_soil.h) of material soil_mat */
    sph_soil_material soil_mat;
} sph_params;

typedef struct {
    sph_params prm;
    kernel k;
    sph_particles p;
    sph_cells cells;
    sph_coupling cpl;
    int has_bodies;
    int primed;             /* rates of the current state are in p.ax.. */
    double t;
    int64_t step;
    double vmax, amax;      /* of the last evaluation */
    int64_t crossings;      /* of the last step */
    int begun;              /* sph_fluid_step_begin done, sph_fluid_step_end due */
    /* SPS only (NULL when prm.opt.sps is off): per particle, in the sorted order of the last
     * evaluation, the eddy viscosity nu_t and the SPS stress tau (Canelas et al. 2015, eq. 11, with density:
     * xx, xy, xz, yy, yz, zz) */
    double *sps_nut;
    double nut_max;         /* largest nu_t of the last evaluation (viscous step limit), 0 without SPS */
    double *sps_tau[6];
    /* per particle, in the sorted order of the last evaluation, filled with the EOS so that the
     * pair loop divides nothing per pair: p_i / rho_i^2 and the volume m_i / rho_i */
    double *prho2, *vol;
    /* transport velocity only (NULL otherwise): the background-pressure acceleration b of the
     * last evaluation, in its sorted order (sph_fluid.h "Transport velocity") */
    double *tv_bx, *tv_by, *tv_bz;
    /* soil (prm.soil only; sph_soil.h): its passes run after the water pass, which then skips soil
     * particles and soil neighbours; sigma is integrated in the same leapfrog as v and rho */
    int has_soil;
    sph_soil soil;
    /* Work counters (cumulative since init; read by the SPH node for its STATUS work fields):
     * particle-particle passes, and the neighbours (i, j), j != i, within the kernel support that
     * the water pass summed over: ordered pairs, so each pair evaluated counts twice, (i, j) and
     * (j, i), as in the soil passes, which gather. The count is a register increment in the pair
     * loop summed by the pass's reduction: integer, so the same for any thread count. */
    int64_t work_passes;
    int64_t work_neighbours_fluid;
    int64_t work_neighbours_soil;       /* soil pass: soil neighbours of soil particles */
    int64_t work_neighbours_fluid_soil; /* seepage: water neighbours of soil + soil neighbours of water */
} sph_fluid;

/* prm with every sph: key at the key table's default (lahar_sph_options_default), body_force
 * zero, no soil. */
void sph_params_default(sph_params *prm);
/* Set up for up to cap particles (add them with sph_particles_add / _add_box on f->p before the
 * first step). Returns 0, or -1 with a one-line reason in err. */
int sph_fluid_init(sph_fluid *f, const sph_params *prm, int64_t cap, char *err, int errlen);
/* Couple with DEM bodies (borrowed, must outlive f). Call after adding the particles (their
 * smallest mass enters K_n, eq. 15). Returns 0 or -1 (out of memory). */
int sph_fluid_attach_bodies(sph_fluid *f, int nbody, const lahar_body *bodies);
void sph_fluid_free(sph_fluid *f);

/* Pressure from density by the EOS of the parameters. */
double sph_fluid_pressure(const sph_params *prm, double rho);
/* The density whose EOS pressure is p (the inverse of sph_fluid_pressure). */
double sph_fluid_density_of_pressure(const sph_params *prm, double p);

/* SPS turbulence (Canelas et al. 2015, eq. 10-11, Dalrymple & Rogers 2006), when prm.opt.sps is on. Before the
 * particle-particle sums, one gather pass takes the velocity gradient
 *   (grad v)_ab,i = sum_j V_j (v_j - v_i)_a (grad_i W_ij)_b,
 * the strain rate S = (grad v + grad v^T)/2, |S| = sqrt(2 S:S), the eddy viscosity
 * nu_t = (C_s Delta)^2 |S| with Delta = dx, and the SPS stress (Canelas et al. 2015, eq. 11; the delta term of the
 * printed equation is the trace S_kk)
 *   tau_i / rho_i = 2 nu_t (S - tr(S)/3 I) - 2/3 C_I Delta^2 |S|^2 I,   C_I = 0.0066.
 * The momentum equation gains the symmetric term of Canelas et al. 2015, eq. 10:
 *   dv_i/dt += sum_j m_j (tau_i / rho_i^2 + tau_j / rho_j^2) . grad_i W_ij.
 * Off: no pass, no arrays, and the pair loop is compiled without the term. The largest nu_t joins
 * the viscous limit of the step proposal. */
#define SPH_SPS_CI 0.0066

/* Evaluate the rates (p.ax, ay, az, drho) at the current state: EOS, the particle-particle sums
 * and, with bodies, the coupling for a step dt with bodies at `states` (NULL: their own fields).
 * Particles must be sorted (sph_cells_sort). Returns crossings, or -1 (out of memory). */
int64_t sph_fluid_rates(sph_fluid *f, const lahar_body_state *states, double dt);

/* One step of length dt; bodies at `states` at the end of the step (NULL: their own fields).
 * Returns the number of particles that crossed a body surface in this step (0 normally), or -1
 * (out of memory). */
int64_t sph_fluid_step(sph_fluid *f, double dt, const lahar_body_state *states);

/* The same step in two parts, so that a caller can do the particle work while it waits for the
 * body states: sph_fluid_step(f, dt, s) is bitwise sph_fluid_step_begin(f, dt) followed by
 * sph_fluid_step_end(f, dt, s) (tests/test_sph_split.c).
 * step_begin: kick (half), drift, predict, sort, EOS, SPS and the particle-particle sums at the
 *   end of the step. On a state whose rates were never evaluated it first evaluates them with the
 *   bodies at their own fields (sph_fluid_step primes with its `states` instead). Returns 0 or -1
 *   (out of memory).
 * step_end: the coupling with the bodies at `states` (the end of the step; NULL: their own
 *   fields), vmax/amax, the second half kick, the Shepard filter when due. Returns the crossings
 *   of sph_fluid_step, or -1 (out of memory, or no step_begin before). */
int sph_fluid_step_begin(sph_fluid *f, double dt);
int64_t sph_fluid_step_end(sph_fluid *f, double dt, const lahar_body_state *states);

/* Apply the Shepard density filter now (particles sorted, cells valid). */
void sph_fluid_shepard(sph_fluid *f);

/* The step this state allows (see above; with soil also C_cfl h / (c_s + |v|max), sph_soil.h).
 * Call after a step (or sph_fluid_rates). */
double sph_fluid_dt(const sph_fluid *f);

#endif
