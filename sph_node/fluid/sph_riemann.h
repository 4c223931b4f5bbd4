/* The pair interface state of the Riemann-solver WCSPH of Zhang, Hu & Adams (2017, J. Comput.
 * Phys. 335:605-620, "A weakly compressible SPH method based on a low-dissipation Riemann
 * solver"), the water's alternative to delta-SPH + artificial viscosity (case key sph.scheme:
 * riemann; sph_fluid.h "Riemann scheme").
 *
 * Between particles i (left) and j (right), along e_ij = (x_j - x_i)/r, the states are
 * (rho_L, U_L = v_i.e_ij, P_L = p_i) and (rho_R, U_R = v_j.e_ij, P_R = p_j). The linearised
 * (acoustic) Riemann solver with the averaged impedance rhobar c (rhobar = (rho_L + rho_R)/2)
 * gives the interface state (Zhang et al. 2017, section 3.1, the acoustic solver with
 * rho_L c_L = rho_R c_R = rhobar c):
 *   U* = (U_L + U_R)/2 + (P_L - P_R) / (2 rhobar c)
 *   P* = (P_L + P_R)/2 + rhobar c (U_L - U_R) / 2
 * and the low-dissipation limiter (Zhang et al. 2017, section 3.2) replaces c in the pressure's
 * dissipation by
 *   beta = min(eta max(U_L - U_R, 0), c),   eta = 3 in the paper,
 * so that no dissipation acts on expanding pairs and only rhobar eta dU^2/2 (not the acoustic
 * rhobar c dU/2) on slowly approaching ones: P* = (P_L + P_R)/2 + rhobar beta (U_L - U_R)/2.
 * The continuity equation keeps the unlimited U* (its P_L - P_R term is the scheme's density
 * diffusion). Both are symmetric in i and j (swapping L and R reverses e_ij), so the pair terms
 * built on them are antisymmetric and conserve momentum and mass. tests/test_sph_riemann.c checks
 * them against the exact acoustic interface state of a pair. */
#ifndef LAHAR_SPH_RIEMANN_H
#define LAHAR_SPH_RIEMANN_H

/* Interface pressure P* with the limiter (eta <= 0: no limiter, beta = c: the plain acoustic
 * solver). du = U_L - U_R (> 0 approaching). */
static inline double sph_riemann_pstar(double pl, double pr, double rhobar, double c, double du, double eta)
{
    double beta = c;
    if (eta > 0.0) {
        const double b = eta * (du > 0.0 ? du : 0.0);
        beta = b < c ? b : c;
    }
    return 0.5 * (pl + pr) + 0.5 * rhobar * beta * du;
}

/* Interface velocity U* along e_ij (acoustic, not limited). */
static inline double sph_riemann_ustar(double ul, double ur, double pl, double pr, double rhobar, double c)
{
    return 0.5 * (ul + ur) + (pl - pr) / (2.0 * rhobar * c);
}

/* The wall's share (Zhang et al. 2017, section 3.4): the ghost behind the wall mirrors particle i
 * (rho_g = rho_i, p_g extrapolated from it, the normal velocity mirrored about the wall's), so
 * along the wall's normal n (into the fluid) U_L - U_R = -2 u_rel.n, u_rel the particle's velocity
 * relative to the wall. The interface pressure is 2 P* = p_i + p_g + rho_i beta (U_L - U_R): this
 * returns the dissipation rho_i beta (U_L - U_R) added to p_i + p_g in the ghost terms
 * (sph_coupling.c). */
static inline double sph_riemann_wall_dissipation(double rho, double un, double c, double eta)
{
    const double du = -2.0 * un;
    double beta = c;
    if (eta > 0.0) {
        const double b = eta * (du > 0.0 ? du : 0.0);
        beta = b < c ? b : c;
    }
    return rho * beta * du;
}

#endif
