/* Trackers and control volumes (sph_gauges.h). */
#include "sph_gauges.h"

#include <math.h>
#include <stddef.h>

#include "energy.h"

int64_t sph_gauges_nearest(const sph_fluid *f, const double x[3])
{
    const sph_particles *p = &f->p;
    const int dim = f->cells.dim;
    int64_t best = -1;
    double bd = INFINITY;
    for (int64_t i = 0; i < p->n; i++) {
        double dx = p->x[i] - x[0], dy = p->y[i] - x[1], dz = dim == 3 ? p->z[i] - x[2] : 0.0;
        double d = dx * dx + dy * dy + dz * dz;
        if (d < bd || (d == bd && p->id[i] < best)) {
            bd = d;
            best = p->id[i];
        }
    }
    return best;
}

void sph_gauges_tracker(const sph_fluid *f, int64_t id, double out[7])
{
    const sph_particles *p = &f->p;
    const int dim = f->cells.dim;
    for (int k = 0; k < 6; k++)
        out[k] = NAN;
    out[6] = (double)id;
    for (int64_t i = 0; i < p->n; i++)
        if (p->id[i] == id) {
            out[0] = p->x[i], out[1] = p->y[i], out[2] = dim == 3 ? p->z[i] : 0.0;
            out[3] = p->vx[i], out[4] = p->vy[i], out[5] = dim == 3 ? p->vz[i] : 0.0;
            return;
        }
}

void sph_gauges_control_volume(const sph_fluid *f, const lahar_probe *pr, const lahar_case *c,
                               const lahar_body_state *states, double out[8])
{
    const sph_particles *p = &f->p;
    const int dim = c->dim, ax = pr->axis;
    const double *lo = pr->x, *hi = pr->hi;
    double ek[2] = {0.0, 0.0}, mass[2] = {0.0, 0.0}, mom[2] = {0.0, 0.0};
    for (int64_t i = 0; i < p->n; i++) {
        const double xi[3] = {p->x[i], p->y[i], dim == 3 ? p->z[i] : 0.0};
        int in = 1;
        for (int a = 0; a < dim; a++)
            in &= xi[a] >= lo[a] && xi[a] < hi[a];
        if (!in)
            continue;
        const double v[3] = {p->vx[i], p->vy[i], dim == 3 ? p->vz[i] : 0.0};
        const int ph = p->phase[i] != 0;
        ek[ph] += 0.5 * p->m[i] * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        mass[ph] += p->m[i];
        mom[ph] += p->m[i] * v[ax];
    }
    double ekb = 0.0;
    for (int b = 0; b < c->nbody; b++) {
        const lahar_body *bd = &c->bodies[b];
        if (bd->motion == LAHAR_MOTION_FIXED)
            continue;
        lahar_body_state s0;
        const lahar_body_state *s = states ? &states[b] : NULL;
        if (!s) {
            for (int k = 0; k < 3; k++)
                s0.x[k] = bd->x[k], s0.v[k] = bd->v[k], s0.w[k] = bd->w[k];
            for (int k = 0; k < 4; k++)
                s0.q[k] = bd->q[k];
            s = &s0;
        }
        int in = 1;
        for (int a = 0; a < dim; a++)
            in &= s->x[a] >= lo[a] && s->x[a] < hi[a];
        if (!in)
            continue;
        double e[3];
        lahar_body_energy(bd, s, c->gravity, e);
        ekb += e[1]; /* 1/2 m_B |u_B|^2 of eq. 39 */
    }
    const double len = hi[ax] - lo[ax];
    out[0] = ek[0] + ek[1] + ekb;
    out[1] = ek[0], out[2] = ek[1], out[3] = ekb;
    out[4] = mass[0], out[5] = mass[1];
    out[6] = mom[0] / len, out[7] = mom[1] / len;
}
