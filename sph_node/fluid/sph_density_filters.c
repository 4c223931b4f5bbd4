/* WCSPH solver core (sph_fluid.h): densities by kernel sums: the Shepard filter (Canelas et al. 2015, eq. 5) and the
 * summation density of the transport-velocity formulation (Adami et al. 2013). */
#include "sph_fluid.h"
#include "sph_fluid_units.h"
#include <math.h>

void sph_fluid_shepard(sph_fluid *f)
{
    sph_particles *p = &f->p;
    const sph_cells *c = &f->cells;
    const int64_t n = p->n;
    const kernel *k = &f->k;
    const double s2 = k->support * k->support, w0 = kernel_w(k, 0.0);
    /* new densities into rhoh (free outside a step), then copied: gather, no races */
#pragma omp parallel for schedule(dynamic, SPH_OMP_CHUNK) if (n >= SPH_OMP_MIN_HEAVY)
    for (int64_t i = 0; i < n; i++) {
        double num = p->m[i] * w0, den = p->m[i] / p->rho[i] * w0;
        SPH_FOR_EACH_NEIGHBOUR(c, p, i, p->x[i], p->y[i], p->z[i], s2, {
            double w = kernel_w(k, sqrt(r2));
            num += p->m[j] * w;
            den += p->m[j] / p->rho[j] * w;
        });
        p->rhoh[i] = num / den;
    }
#pragma omp parallel for schedule(static) if (n >= SPH_OMP_MIN_LIGHT)
    for (int64_t i = 0; i < n; i++)
        p->rho[i] = p->rhoh[i];
}

/* Summation density of the transport-velocity formulation (Adami et al. 2013, sph_fluid.h):
 * rho_i = m_i sum_j W_ij (j includes i), into rho and rhoh (the integrator's half-step density;
 * drho is zeroed after the pass, so the density stays this value through the step). Gather. */
void sph_fluid_summation_density(sph_fluid *f)
{
    sph_particles *p = &f->p;
    const sph_cells *c = &f->cells;
    const int64_t n = p->n;
    const kernel *k = &f->k;
    const double s2 = k->support * k->support, w0 = kernel_w(k, 0.0);
#pragma omp parallel for schedule(dynamic, SPH_OMP_CHUNK) if (n >= SPH_OMP_MIN_HEAVY)
    for (int64_t i = 0; i < n; i++) {
        double sw = w0;
        SPH_FOR_EACH_NEIGHBOUR(c, p, i, p->x[i], p->y[i], p->z[i], s2, { sw += kernel_w(k, sqrt(r2)); });
        p->rho[i] = p->rhoh[i] = p->m[i] * sw;
    }
}
