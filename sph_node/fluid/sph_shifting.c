/* WCSPH solver core (sph_fluid.h): particle shifting after a step (Lind et al. 2012). */
#include "sph_fluid.h"
#include "sph_fluid_units.h"
#include <math.h>

/* Particle shifting (Lind et al. 2012, J. Comput. Phys. 231:1499, eq. 17-18 with D = A h^2):
 * dr_i = -A h^2 grad C_i, grad C_i = sum_j V_j grad_i W_ij, moves water particles from where they
 * crowd to where they are sparse, against the pairing and clustering that disorder a slow flow.
 * A body's surface has no particles behind it, so grad C points away from it: within the coupling
 * range of a body the part of the shift towards the body (along x_i - x_s of each contact of the
 * last evaluation) is dropped, the particle shifts along the surface only. Lahar detects no free
 * surface: for confined (periodic, closed) flows. The shift is at most 0.1 dx per step. vhx, vhy,
 * vhz (free between steps) hold the shifts: no allocation. */
void sph_fluid_shift(sph_fluid *f)
{
    sph_particles *p = &f->p;
    const sph_cells *c = &f->cells;
    const sph_coupling *cpl = &f->cpl;
    const int64_t n = p->n;
    const kernel *k = &f->k;
    const double s2 = k->support * k->support, coef = -f->prm.opt.shifting * k->h * k->h, cap = 0.1 * f->prm.dx;
    const int d3 = f->prm.dim == 3;
#pragma omp parallel for schedule(dynamic, SPH_OMP_CHUNK) if (n >= SPH_OMP_MIN_HEAVY)
    for (int64_t i = 0; i < n; i++) {
        double gx = 0.0, gy = 0.0, gz = 0.0;
        if (p->phase[i] == 0) {
            SPH_FOR_EACH_NEIGHBOUR(c, p, i, p->x[i], p->y[i], p->z[i], s2, {
                if (p->phase[j] != 0 || !(r2 > 0.0)) /* coincident: no direction (and W'(0)/0) */
                    continue;
                const double r = sqrt(r2), fv = f->vol[j] * kernel_dwdr(k, r) / r;
                gx += fv * rx, gy += fv * ry, gz += fv * rz;
            });
        }
        vec3 d = v3(coef * gx, coef * gy, d3 ? coef * gz : 0.0);
        const int ncontact = cpl->slot_n ? cpl->slot_n[i] : 0; /* no bodies attached: none */
        for (int s = 0; s < ncontact; s++) {
            const sph_contact *ct = &cpl->slot[i * SPH_COUPLING_MAX_PER_PARTICLE + s];
            vec3 nrm = v3(p->x[i] - ct->xs[0], p->y[i] - ct->xs[1], d3 ? p->z[i] - ct->xs[2] : 0.0);
            for (int a = 0; a < 3; a++) /* the particle may be a periodic image away from x_s */
                if (cpl->periodic[a]) {
                    double P = cpl->period[a], u = v3_get(nrm, a);
                    u -= P * floor(u / P + 0.5);
                    if (a == 0) nrm.x = u; else if (a == 1) nrm.y = u; else nrm.z = u;
                }
            double len = v3_norm(nrm), dn = len > 0.0 ? v3_dot(d, nrm) / len : 0.0;
            if (dn < 0.0) /* towards the body */
                d = v3_axpy(-dn / len, nrm, d);
        }
        double dl = v3_norm(d);
        if (dl > cap)
            d = v3_scale(d, cap / dl);
        p->vhx[i] = d.x, p->vhy[i] = d.y, p->vhz[i] = d.z;
    }
    if (f->prm.opt.shifting_density) {
        /* shifting_density: the shift is a displacement the continuity equation (Trujillo-Vela et al. 2020, eq. 1)
         * never saw, so the density takes the change that operator gives a particle moved by dr,
         * drho_i = rho_i sum_j V_j (dr_i - dr_j).grad_i W_ij (the arbitrary-Lagrangian-Eulerian
         * reading of the shift; Lind et al. 2012 correct the fields after the shift as well).
         * It follows the summation density of the moved particles to first order (test_sph_fluid).
         * Without it the densities keep the history of a particle arrangement the shift has
         * undone: in a closed box the total volume sum m/rho fell by 9.6 % in 30 s of the
         * lid-driven cavity (docs/bench/validation.md), with it by < 0.1 %. rhoh is free between steps. */
#pragma omp parallel for schedule(dynamic, SPH_OMP_CHUNK) if (n >= SPH_OMP_MIN_HEAVY)
        for (int64_t i = 0; i < n; i++) {
            double s = 0.0;
            if (p->phase[i] == 0) {
                const double dxi = p->vhx[i], dyi = p->vhy[i], dzi = d3 ? p->vhz[i] : 0.0;
                SPH_FOR_EACH_NEIGHBOUR(c, p, i, p->x[i], p->y[i], p->z[i], s2, {
                    if (p->phase[j] != 0 || !(r2 > 0.0))
                        continue;
                    const double fv = f->vol[j] * kernel_dwdr(k, sqrt(r2)) / sqrt(r2);
                    s += fv * ((dxi - p->vhx[j]) * rx + (dyi - p->vhy[j]) * ry +
                               (d3 ? (dzi - p->vhz[j]) * rz : 0.0));
                });
            }
            p->rhoh[i] = p->rho[i] * (1.0 + s);
        }
#pragma omp parallel for schedule(static) if (n >= SPH_OMP_MIN_LIGHT)
        for (int64_t i = 0; i < n; i++)
            p->rho[i] = p->rhoh[i];
    }
#pragma omp parallel for schedule(static) if (n >= SPH_OMP_MIN_LIGHT)
    for (int64_t i = 0; i < n; i++) {
        p->x[i] += p->vhx[i];
        p->y[i] += p->vhy[i];
        if (d3)
            p->z[i] += p->vhz[i];
    }
}
