/* The equations of state (sph_eos.h). */
#include "sph_eos.h"
#include <math.h>
#include <stddef.h>

/* Trujillo-Vela et al. 2020, eq. 3: p = c0^2 (rho - rho0) */
static double linear_pressure(double rho, double rho0, double c0, double gamma)
{
    (void)gamma;
    return c0 * c0 * (rho - rho0);
}

static double linear_density(double p, double rho0, double c0, double gamma)
{
    (void)gamma;
    return rho0 + p / (c0 * c0);
}

/* Canelas et al. 2015, eq. 19: p = rho0 c0^2 / gamma ((rho / rho0)^gamma - 1) */
static double tait_pressure(double rho, double rho0, double c0, double gamma)
{
    return rho0 * c0 * c0 / gamma * (pow(rho / rho0, gamma) - 1.0);
}

static double tait_density(double p, double rho0, double c0, double gamma)
{
    return rho0 * pow(1.0 + gamma * p / (rho0 * (c0 * c0)), 1.0 / gamma);
}

static const sph_eos_ops eos_table[] = {
    [LAHAR_SPH_EOS_LINEAR] = {"linear", linear_pressure, linear_density},
    [LAHAR_SPH_EOS_TAIT] = {"tait", tait_pressure, tait_density},
};

const sph_eos_ops *sph_eos_get(lahar_sph_eos kind)
{
    if ((int)kind < 0 || (size_t)kind >= sizeof eos_table / sizeof eos_table[0])
        return &eos_table[LAHAR_SPH_EOS_LINEAR];
    return &eos_table[kind];
}
