/* The water's pair terms, one function per physical model, inlined into the pair loop of
 * sph_fluid.c (fluid_pairs) where they are hot. Notation of sph_fluid.h: x_ij = x_i - x_j,
 * v_ij = v_i - v_j, r = |x_ij|, F_ij = W'(r)/r, V_j = m_j/rho_j, eta^2 = 0.01 h^2,
 * rsoft = r^2/(r^2 + eta^2), ieta = 1/(r^2 + eta^2). Each returns the scalar that multiplies its
 * pair's vector (x_ij or v_ij) or adds its vector term to the pair force; the caller keeps the
 * order of the sums (bitwise results, -ffp-contract=off). The Riemann scheme's interface state
 * is sph_riemann.h; the equation of state is sph_eos.h. */
#ifndef LAHAR_SPH_PAIR_TERMS_H
#define LAHAR_SPH_PAIR_TERMS_H

/* delta-SPH density diffusion of the pair (Molteni & Colagrossi 2009; Trujillo-Vela et al. 2020,
 * eq. 1 second term, sign corrected: sph_fluid.h) without its hydrostatic part (Fourtakas et
 * al. 2019): ddelta = 2 delta h c0, hydro_x = rho0 b.x_ij / c0^2. drho_i/dt gains
 * V_j F_ij times the result, drho_j/dt loses V_i F_ij times it. */
static inline double sph_delta_diffusion(double ddelta, double rhoi, double rhoj, double hydro_x, double rsoft)
{
    return ddelta * ((rhoi - rhoj) - hydro_x) * rsoft;
}

/* Monaghan (1992) artificial viscosity Pi_ij rho-scaled for the pressure term: with
 * av = 2 alpha c0 h, the value av v_ij.x_ij/(r^2 + eta^2)/(rho_i + rho_j) = -Pi_ij when the pair
 * approaches (v_ij.x_ij < 0), else 0; the pressure term uses p_i/rho_i^2 + p_j/rho_j^2 - it. */
static inline double sph_monaghan_viscosity(double av, double vdotr, double ieta, double rhoi, double rhoj)
{
    return vdotr < 0.0 ? av * vdotr * ieta / (rhoi + rhoj) : 0.0;
}

/* Laminar viscosity (Morris, Fox & Zhu 1997): the pair force's v_ij coefficient
 * m_i m_j (mu_i + mu_j)/(rho_i rho_j) F_ij rsoft = 2 mu V_i V_j F_ij rsoft; visci = 2 mu V_i.
 * With rsoft = 1 it is Adami et al. 2013's shear term (the transport velocity's; sph_fluid.h). */
static inline double sph_morris_viscosity(double visci, double volj, double fij, double rsoft)
{
    return visci * volj * fij * rsoft;
}

/* SPS stress (Canelas et al. 2015, eq. 10 third term): adds
 * m_i m_j (tau_i/rho_i^2 + tau_j/rho_j^2) . grad_i W_ij to F. ti = tau_i/rho_i^2 (xx, xy, xz, yy,
 * yz, zz), tj = tau_j, irj2 = 1/rho_j^2, mf = m_i m_j F_ij. */
static inline void sph_sps_pair(const double ti[6], const double tj[6], double irj2, double mf, double rx, double ry,
                                double rz, int dim, double *Fx, double *Fy, double *Fz)
{
    const double txx = ti[0] + tj[0] * irj2, txy = ti[1] + tj[1] * irj2, txz = ti[2] + tj[2] * irj2;
    const double tyy = ti[3] + tj[3] * irj2, tyz = ti[4] + tj[4] * irj2, tzz = ti[5] + tj[5] * irj2;
    *Fx += mf * (txx * rx + txy * ry + txz * rz);
    *Fy += mf * (txy * rx + tyy * ry + tyz * rz);
    if (dim == 3)
        *Fz += mf * (txz * rx + tyz * ry + tzz * rz);
}

/* Transport velocity (Adami, Hu & Adams 2013, section 2): the extra stress A = rho v (x) (v~ - v),
 * 1/rho div A in symmetric form, m_i m_j (A_i/rho_i^2 + A_j/rho_j^2) . grad_i W_ij, where
 * (A/rho^2 . grad W)_a = v_a ((v~ - v) . grad W)/rho; si, sj = (v~ - v).x_ij / rho of i and j,
 * mf = m_i m_j F_ij. */
static inline void sph_transport_pair(double mf, double si, double sj, double vxi, double vyi, double vzi,
                                      double vxj, double vyj, double vzj, int dim, double *Fx, double *Fy, double *Fz)
{
    *Fx += mf * (vxi * si + vxj * sj);
    *Fy += mf * (vyi * si + vyj * sj);
    if (dim == 3)
        *Fz += mf * (vzi * si + vzj * sj);
}

/* Background pressure in the transport velocity (Adami et al. 2013): the pair's coefficient of
 * x_ij, -m_i m_j p_b (1/rho_i^2 + 1/rho_j^2) F_ij. */
static inline double sph_background_pair(double mi, double mj, double pb, double rhoi, double rhoj, double fij)
{
    return -mi * mj * pb * (1.0 / (rhoi * rhoi) + 1.0 / (rhoj * rhoj)) * fij;
}

#endif
