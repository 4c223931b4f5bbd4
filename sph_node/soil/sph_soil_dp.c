/* The Drucker-Prager soil (Trujillo-Vela et al. 2020 eq. 6-7; Bui et al. 2008): the constitutive
 * model "drucker_prager" of sph_soil_model.h. Equations: sph_soil.h. */
#include "sph_soil.h"
#include "sph_soil_model.h"
#include <math.h>

/* component index of the symmetric tensor (xx, xy, xz, yy, yz, zz) */
static const int SYM[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};

void sph_soil_constants(const sph_soil_material *m, double *G, double *K, double *cs, double *alpha_phi,
                        double *kc, double *alpha_psi)
{
    *G = m->young / (2.0 * (1.0 + m->poisson));
    *K = m->young / (3.0 * (1.0 - 2.0 * m->poisson));
    *cs = sqrt((*K + 4.0 / 3.0 * *G) / m->density);
    /* plane-strain match of Drucker-Prager to Mohr-Coulomb (Bui 2008 eq. 20; shared/papers/README.md) */
    double tp = tan(m->phi), tpsi = tan(m->psi);
    double d = sqrt(9.0 + 12.0 * tp * tp);
    *alpha_phi = tp / d;
    *kc = 3.0 * m->cohesion / d;
    *alpha_psi = tpsi / sqrt(9.0 + 12.0 * tpsi * tpsi);
}

static void dp_init(sph_soil *s)
{
    sph_soil_constants(&s->mat, &s->G, &s->K, &s->cs, &s->alpha_phi, &s->kc, &s->alpha_psi);
}

static void dp_return(const sph_soil *s, double sig[SPH_NSTRESS])
{
    const double ap = s->alpha_phi, kc = s->kc;
    double i1 = sig[0] + sig[3] + sig[5];
    /* tension cracking: move the stress along the hydrostatic axis to the apex I1 = k_c / alpha_phi */
    if (ap > 0.0 && -ap * i1 + kc < 0.0) {
        double shift = (i1 - kc / ap) / 3.0;
        sig[0] -= shift, sig[3] -= shift, sig[5] -= shift;
        i1 = sig[0] + sig[3] + sig[5];
    }
    /* return to the yield surface by scaling the deviatoric stress */
    double m = i1 / 3.0;
    double sxx = sig[0] - m, syy = sig[3] - m, szz = sig[5] - m;
    double j2 = 0.5 * (sxx * sxx + syy * syy + szz * szz) + sig[1] * sig[1] + sig[2] * sig[2] + sig[4] * sig[4];
    double rj2 = sqrt(j2), lim = -ap * i1 + kc;
    if (rj2 > lim && rj2 > 0.0) {
        double r = lim > 0.0 ? lim / rj2 : 0.0;
        sig[0] = m + r * sxx, sig[3] = m + r * syy, sig[5] = m + r * szz;
        sig[1] *= r, sig[2] *= r, sig[4] *= r;
    }
}

/* The objective stress rate (Trujillo-Vela et al. 2020, eq. 6-7): Jaumann + elastic - plastic. */
static void dp_stress_rate(const sph_soil *s, const double sig[3][3], const double eps[3][3], const double spin[3][3],
                           double out[SPH_NSTRESS])
{
    const double G = s->G, K = s->K, ap = s->alpha_phi, aps = s->alpha_psi;
    double tre = eps[0][0] + eps[1][1] + eps[2][2];
    double i1 = sig[0][0] + sig[1][1] + sig[2][2], m = i1 / 3.0;
    double dev[3][3], j2 = 0.0, sde = 0.0;
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) {
            dev[a][b] = sig[a][b] - (a == b ? m : 0.0);
            j2 += 0.5 * dev[a][b] * dev[a][b];
            sde += dev[a][b] * eps[a][b];
        }
    double rj2 = sqrt(j2);
    /* plastic multiplier (Trujillo-Vela et al. 2020, eq. 7) on the yield surface, when loading */
    double lam = 0.0;
    double lim = -ap * i1 + s->kc;
    if (rj2 > 0.0 && rj2 >= lim * (1.0 - 1e-9)) {
        lam = (3.0 * ap * K * tre + G / rj2 * sde) / (9.0 * ap * aps * K + G);
        if (lam < 0.0)
            lam = 0.0;
    }
    for (int a = 0; a < 3; a++)
        for (int b = a; b < 3; b++) {
            double jau = 0.0;
            for (int g = 0; g < 3; g++)
                jau += sig[a][g] * spin[b][g] + sig[g][b] * spin[a][g];
            double el = 2.0 * G * (eps[a][b] - (a == b ? tre / 3.0 : 0.0)) + (a == b ? K * tre : 0.0);
            double pl = lam > 0.0 ? lam * ((a == b ? 3.0 * K * aps : 0.0) + G / rj2 * dev[a][b]) : 0.0;
            out[SYM[a][b]] = jau + el - pl; /* Trujillo-Vela et al. 2020, eq. 6 */
        }
}

const sph_soil_model sph_soil_model_drucker_prager = {
    .name = "drucker_prager",
    .init = dp_init,
    .stress_rate = dp_stress_rate,
    .admissible = dp_return,
};
