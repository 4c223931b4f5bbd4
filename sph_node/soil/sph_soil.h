/* SPH soil (Trujillo-Vela et al. 2020 section 2.2; Bui, Fukagawa, Sako & Ohno 2008, "Bui 2008" below): particles of
 * phase 1 carry an effective stress sigma (tension positive, the SoA arrays p->sig of
 * sph_particles.h, allocated only when a scene has soil) and follow an elastic-perfectly plastic
 * Drucker-Prager law matched to Mohr-Coulomb in plane strain. Equations (x_ij = x_i - x_j,
 * v_ij = v_i - v_j, grad_i W_ij = F_ij x_ij, V_j = m_j / rho_j; sums over soil neighbours j):
 *
 *   velocity gradient  L_ab = sum_j V_j (v_j - v_i)_a (grad_i W_ij)_b;  strain rate eps = (L + L^T)/2,
 *                      spin w = (L - L^T)/2 (2D: the out-of-plane rows stay 0, plane strain)
 *   stress rate (Trujillo-Vela et al. 2020, eq. 6, Bui 2008 eq. 23-24; Jaumann):
 *     dsigma_ab/dt = sigma_ac w_bc + sigma_cb w_ac + 2 G e_ab + K eps_cc delta_ab
 *                    - lambda' (3 K alpha_psi delta_ab + G / sqrt(J2) s_ab)
 *     e = eps - tr(eps)/3 I, s = sigma - tr(sigma)/3 I, J2 = s:s/2, G = E/(2(1+nu)),
 *     K = E/(3(1-2nu)).
 *   plastic multiplier (Trujillo-Vela et al. 2020, eq. 7), only on the yield surface f = alpha_phi I1 + sqrt(J2) - k_c = 0
 *   and when loading (lambda' > 0):
 *     lambda' = (3 alpha_phi K eps_cc + G / sqrt(J2) s:eps) / (9 alpha_phi alpha_psi K + G)
 *     Trujillo-Vela et al. 2020 print 9 K sin(psi) and 27 alpha_phi K sin(psi), i.e. alpha_psi = 3 sin(psi); the
 *     plastic potential g = alpha_psi I1 + sqrt(J2) with the same plane-strain match as the
 *     yield function is used (Bui 2008 eq. 21): both forms vanish at psi = 0.
 *   Drucker-Prager matched to Mohr-Coulomb in plane strain (shared/papers/README.md):
 *     alpha_phi = tan(phi) / sqrt(9 + 12 tan^2 phi),  k_c = 3 c / sqrt(9 + 12 tan^2 phi),
 *     alpha_psi = tan(psi) / sqrt(9 + 12 tan^2 psi).
 *   after every stress update (Bui 2008 section 3.3):
 *     tension cracking: if -alpha_phi I1 + k_c < 0, sigma_aa -= (I1 - k_c / alpha_phi) / 3
 *     return to the yield surface: if -alpha_phi I1 + k_c < sqrt(J2), s *= (-alpha_phi I1 + k_c) / sqrt(J2)
 *   continuity (Trujillo-Vela et al. 2020, section 2.2: eq. 1 without the delta term):
 *     drho_i/dt = rho_i sum_j V_j v_ij . grad_i W_ij
 *   momentum (Trujillo-Vela et al. 2020, eq. 5 with tension-positive stress; Bui 2008 eq. 31):
 *     dv_i/dt = g + sum_j m_j (sigma_i/rho_i^2 + sigma_j/rho_j^2 + (R_i + R_j) f_ij^n - Pi_ij I) . grad_i W_ij
 *     Pi_ij = (-alpha c_s mu_ij + beta mu_ij^2) / rho_ij, mu_ij = h v_ij.x_ij / (r^2 + 0.01 h^2) when
 *     v_ij.x_ij < 0 (Monaghan 1992), c_s = sqrt((K + 4G/3) / rho_s) the P-wave speed.
 *     Artificial stress (Monaghan 2000; Gray, Monaghan & Swift 2001; Bui 2008 eq. 32-35): in the
 *     principal frame of sigma_i, R'_aa = -eps_as sigma'_aa / rho_i^2 where sigma'_aa > 0 (tension),
 *     else 0, rotated back; f_ij = W(r_ij) / W(dx), n = 2.55, eps_as = 0.3.
 *     Optional velocity damping -c_d v (material key damping, 0 by default): the dynamic
 *     relaxation used to bring a soil to its geostatic state (Bui & Fukagawa 2013), which the
 *     conservative equations above would otherwise reach only after their elastic waves die out.
 *   The mean pressure -tr(sigma)/3 goes to p->p of soil particles (for output).
 * Water particles are not neighbours of soil particles in these sums (and the water pass skips
 * soil neighbours). Water and soil interact (Trujillo-Vela et al. 2020 section 2.3) when the soil has k_h > 0:
 *   seepage force (eq. 10): f_ij = (mu / k) (u_f - u_s) = (rho_w g / k_h) (u_f - u_s), since
 *     k = k_h mu / (rho_w g) (rho_w the water's rest density, g = |gravity|, 9.81 without gravity)
 *   on soil particle s (eq. 9):  a_s += sum_f m_f / (rho_f rho_s) [f_sf W_sf - p_f grad_s W_sf]
 *   on water particle f (eq. 8, the reaction, equal and opposite pair by pair):
 *                                a_f -= sum_s m_s / (rho_f rho_s) [f_sf W_sf + p_f grad_f W_fs]
 *   eq. 8 prints the water's term with the same sign as the soil's; pair by pair the forces must
 *   cancel (Newton's third law), which fixes it. In a soil filling the space (sum_s V_s W = 1)
 *   the water then obeys a = b - (g / k_h) (u_f - u_s): Darcy, u = k_h i for b = g i.
 *   The drag rate g / k_h joins the step limit: dt <= 0.25 k_h / g.
 * Time integration: sigma in the same kick-drift-kick leapfrog as v and rho (sph_fluid.h); step
 * limit C_cfl h / (c_s + |v|max).
 * Every pass is a gather over the particle's own neighbours: bitwise the same for any thread count. */
#ifndef LAHAR_SPH_SOIL_H
#define LAHAR_SPH_SOIL_H
#include <stdint.h>
#include "kernel.h"
#include "sph_particles.h"

#define SPH_SOIL_PHASE 1
#define SPH_SOIL_AS_EPS 0.3     /* artificial stress coefficient (Gray et al. 2001) */
#define SPH_SOIL_AS_N 2.55      /* its exponent n of f_ij^n */

typedef struct {
    double density;        /* kg/m^3, rest density of the soil particles */
    double young, poisson; /* Pa, - */
    double phi, cohesion, psi; /* friction angle (rad), cohesion (Pa), dilatancy (rad) */
    double kh;             /* Darcy hydraulic conductivity, m/s (0: none) */
    double mu_phi;         /* soil-DEM friction coefficient (Trujillo-Vela et al. 2020 eq. 24) */
    double damping;        /* c_d, 1/s: dv/dt += -c_d v (0 = off) */
    double av_alpha, av_beta; /* Monaghan artificial viscosity (Bui 2008 section 4.1; the case's
                               * defaults 0.1, 0; Trujillo-Vela et al. 2020 section 5.3 uses 1, 1) */
    double g_ref;          /* g of k = k_h mu / (rho_w g), m/s^2 */
    double gravity[3];     /* m/s^2: the soil's body force (sph.body_force drives the water only) */
    double rho_water;      /* rho_w of the same, kg/m^3 */
    const struct sph_soil_model *model; /* the constitutive model (sph_soil_model.h); NULL: Drucker-Prager */
} sph_soil_material;

typedef struct sph_soil {
    sph_soil_material mat;
    const struct sph_soil_model *model; /* the constitutive model in use (never NULL after init) */
    int dim;
    double G, K, cs;               /* shear and bulk modulus, P-wave speed */
    double alpha_phi, kc, alpha_psi; /* the model's constants (Drucker-Prager's plane-strain match) */
    double w_dx;                   /* W(dx), the artificial stress's reference */
    int64_t cap;
    double *dsig[SPH_NSTRESS];     /* stress rate of the last evaluation (sorted order) */
    double *rart[SPH_NSTRESS];     /* artificial stress R_i (already divided by rho_i^2) */
    double *sig_rho2[SPH_NSTRESS]; /* sigma_i / rho_i^2 of the last evaluation (pass 1 for pass 2) */
    int nb_stride;                 /* room per particle in nb_j */
    int32_t *nb_n;                 /* soil neighbours of each soil particle found by pass 1 (-1: more
                                    * than nb_stride; 0 where pass 1 did not record) */
    int32_t *nb_j;                 /* their indices, nb_stride per particle, in the walk's order:
                                    * pass 2 sums over them instead of walking the cells again */
    unsigned char *tensile;        /* 1 where R_i != 0 (a principal stress in tension): the pairs
                                    * where neither particle has one skip f_ij^n */
    double seep;                   /* rho_w g / k_h (kg/(m^3 s)), 0 without seepage (k_h = 0) */
    double *grad[9];               /* sph_soil_keep_gradient only (else NULL): the soil neighbours'
                                    * velocity gradient L_ab (index 3a + b) of the last pass 1 */
} sph_soil;

/* Derived constants (G, K, c_s, alpha_phi, k_c, alpha_psi) of a Drucker-Prager material
 * (sph_soil_dp.c). */
void sph_soil_constants(const sph_soil_material *m, double *G, double *K, double *cs, double *alpha_phi,
                        double *kc, double *alpha_psi);

/* Set up for cap particles and allocate the stress arrays of p. Returns 0 or -1 (out of memory). */
int sph_soil_init(sph_soil *s, const sph_soil_material *m, int dim, const kernel *k, double dx, sph_particles *p);
void sph_soil_free(sph_soil *s);

/* Pass 1 (before the momentum pass): per soil particle, the stress rate, the artificial stress and
 * p = -tr(sigma)/3. Particles sorted, cells valid; vol[j] = m_j / rho_j of every particle (the
 * fluid's, filled with its EOS). */
void sph_soil_stress_rates(sph_soil *s, sph_particles *p, const sph_cells *c, const kernel *k, const double *vol);
/* Pass 2: per soil particle, drho/dt and dv/dt (with the material's gravity) into p->drho, ax, ay,
 * az. Water particles are left alone. Returns the soil neighbours (i, j) within the support summed
 * over (work counter, each soil-soil pair twice) and the water neighbours of the soil particles in
 * *water_neighbours (0 without seepage). */
int64_t sph_soil_momentum(const sph_soil *s, sph_particles *p, const sph_cells *c, const kernel *k,
                          int64_t *water_neighbours);

/* Keep each particle's velocity gradient of pass 1 (9 doubles per particle) so that
 * sph_soil_wall_gradient can add a wall's share to it. Returns 0 or -1 (out of memory). */
int sph_soil_keep_gradient(sph_soil *s);
/* After pass 1 (sph_soil_keep_gradient on): the stress rate of soil particle i again, from its
 * neighbours' velocity gradient plus Lw (index 3a + b), the share of the ghost layers of a wall
 * (sph_coupling.h, sph_coupling_set_soil_wall). */
void sph_soil_wall_gradient(sph_soil *s, const sph_particles *p, int64_t i, const double Lw[9]);

/* The model's return to its admissible stresses (Drucker-Prager: tension cracking and the return
 * to the yield surface, Bui 2008 section 3.3) of one stress (xx, xy, xz, yy, yz, zz), in place. */
void sph_soil_return(const sph_soil *s, double sig[SPH_NSTRESS]);

/* Seepage (sph_soil.h, Trujillo-Vela et al. 2020 eq. 8-10) on the water particles: their reaction to every soil
 * neighbour, added to p->ax.. after the water pass. No-op when s->seep is 0. */
int64_t sph_soil_water_seepage(const sph_soil *s, sph_particles *p, const sph_cells *c, const kernel *k);
/* (returns the soil neighbours of the water particles summed over: work counter, 0 without seepage) */

/* The integrator's stress updates of soil particle i (the other phases are skipped by the
 * caller): begin: sigh = sig + hdt dsig, predicted sig = sigh + hdt dsig; end: sig = sigh + hdt dsig;
 * each followed by sph_soil_return. */
void sph_soil_kick_begin(const sph_soil *s, sph_particles *p, int64_t i, double hdt);
void sph_soil_kick_end(const sph_soil *s, sph_particles *p, int64_t i, double hdt);

#endif
