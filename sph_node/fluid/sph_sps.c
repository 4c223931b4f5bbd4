/* WCSPH solver core (sph_fluid.h): SPS turbulence, the gather pass before the pair sums (Canelas et al. 2015, eq. 11). */
#include "sph_fluid.h"
#include "sph_fluid_units.h"
#include <math.h>

/* Velocity gradient, strain rate, nu_t and the SPS stress of particle i (sph_fluid.h, Canelas et al. 2015, eq. 11). */
static inline void fluid_sps_particle(sph_fluid *f, const kernel_kind kind, int64_t i)
{
    const sph_particles *p = &f->p;
    const sph_cells *c = &f->cells;
    const double inv_h = f->k.inv_h, dnorm = f->k.dnorm, s2 = f->k.support * f->k.support;
    const double xi = p->x[i], yi = p->y[i], zi = p->z[i];
    const double vxi = p->vx[i], vyi = p->vy[i], vzi = p->vz[i];
    double g[3][3] = {{0.0}}; /* g[a][b] = d v_a / d x_b */
    SPH_FOR_EACH_NEIGHBOUR(c, p, i, xi, yi, zi, s2, {
        double r = sqrt(r2);
        double fij = r > 0.0 ? dnorm * kernel_dshape(kind, r * inv_h) / r : 0.0;
        double w = p->m[j] / p->rho[j] * fij; /* V_j F_ij; grad_i W_ij = F_ij x_ij */
        double dv[3] = {p->vx[j] - vxi, p->vy[j] - vyi, p->vz[j] - vzi};
        double xr[3] = {rx, ry, rz};
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++)
                g[a][b] += w * dv[a] * xr[b];
    });
    double sxx = g[0][0], syy = g[1][1], szz = g[2][2];
    double sxy = 0.5 * (g[0][1] + g[1][0]), sxz = 0.5 * (g[0][2] + g[2][0]), syz = 0.5 * (g[1][2] + g[2][1]);
    double ss = sxx * sxx + syy * syy + szz * szz + 2.0 * (sxy * sxy + sxz * sxz + syz * syz); /* S:S */
    double smag = sqrt(2.0 * ss), delta = f->prm.dx, csd = f->prm.opt.sps_cs * delta;
    double nut = csd * csd * smag;
    double tr3 = (sxx + syy + szz) / 3.0;
    double iso = 2.0 / 3.0 * SPH_SPS_CI * delta * delta * smag * smag;
    double rho = p->rho[i];
    f->sps_nut[i] = nut;
    f->sps_tau[0][i] = rho * (2.0 * nut * (sxx - tr3) - iso);
    f->sps_tau[1][i] = rho * 2.0 * nut * sxy;
    f->sps_tau[2][i] = rho * 2.0 * nut * sxz;
    f->sps_tau[3][i] = rho * (2.0 * nut * (syy - tr3) - iso);
    f->sps_tau[4][i] = rho * 2.0 * nut * syz;
    f->sps_tau[5][i] = rho * (2.0 * nut * (szz - tr3) - iso);
}

void sph_fluid_sps_pass(sph_fluid *f)
{
    const int64_t n = f->p.n;
    const kernel_kind kind = f->k.kind;
#pragma omp parallel for schedule(dynamic, SPH_OMP_CHUNK) if (n >= SPH_OMP_MIN_HEAVY)
    for (int64_t i = 0; i < n; i++) {
        switch (kind) {
        case KERNEL_QUINTIC: fluid_sps_particle(f, KERNEL_QUINTIC, i); break;
        case KERNEL_WENDLAND2: fluid_sps_particle(f, KERNEL_WENDLAND2, i); break;
        default: fluid_sps_particle(f, KERNEL_CUBIC, i); break;
        }
    }
}
