/* The kernel table (kernel.h). */
#include "kernel.h"
#include <math.h>
#include <string.h>

static double cubic_f(double q) { return kernel_shape(KERNEL_CUBIC, q); }
static double cubic_df(double q) { return kernel_dshape(KERNEL_CUBIC, q); }
static double quintic_f(double q) { return kernel_shape(KERNEL_QUINTIC, q); }
static double quintic_df(double q) { return kernel_dshape(KERNEL_QUINTIC, q); }
static double wendland2_f(double q) { return kernel_shape(KERNEL_WENDLAND2, q); }
static double wendland2_df(double q) { return kernel_dshape(KERNEL_WENDLAND2, q); }

static const kernel_def kernel_table[KERNEL_COUNT] = {
    {"cubic", KERNEL_CUBIC, 2.0, {10.0 / (7.0 * M_PI), 1.0 / M_PI}, cubic_f, cubic_df},
    {"quintic", KERNEL_QUINTIC, 3.0, {7.0 / (478.0 * M_PI), 1.0 / (120.0 * M_PI)}, quintic_f, quintic_df},
    {"wendland2", KERNEL_WENDLAND2, 2.0, {7.0 / (4.0 * M_PI), 21.0 / (16.0 * M_PI)}, wendland2_f, wendland2_df},
};

const kernel_def *kernel_find(const char *name)
{
    if (!name)
        return NULL;
    for (int i = 0; i < KERNEL_COUNT; i++)
        if (strcmp(kernel_table[i].name, name) == 0)
            return &kernel_table[i];
    return NULL;
}

const kernel_def *kernel_def_of(kernel_kind kind)
{
    return (kind >= 0 && kind < KERNEL_COUNT) ? &kernel_table[kind] : NULL;
}

int kernel_init(kernel *k, const char *name, int dim, double h)
{
    const kernel_def *d = kernel_find(name);
    if (!d || (dim != 2 && dim != 3) || !(h > 0.0))
        return -1;
    k->kind = d->kind;
    k->dim = dim;
    k->h = h;
    k->inv_h = 1.0 / h;
    k->support = d->kappa * h;
    k->norm = d->sigma[dim - 2] / pow(h, dim);
    k->dnorm = k->norm / h;
    return 0;
}

void kernel_line_add(const kernel *k, double rh2, double zj, double v, double z0, double step, int npt,
                     double *phi)
{
    const double S2 = k->support * k->support;
    if (!(rh2 < S2))
        return;
    const double half = sqrt(S2 - rh2);
    int i0 = (int)ceil((zj - half - z0) / step), i1 = (int)floor((zj + half - z0) / step);
    if (i0 < 0)
        i0 = 0;
    if (i1 > npt - 1)
        i1 = npt - 1;
    for (int i = i0; i <= i1; i++) {
        const double dz = z0 + i * step - zj, r2 = rh2 + dz * dz;
        if (r2 < S2)
            phi[i] += v * kernel_w(k, sqrt(r2));
    }
}

double kernel_line_crossing(const double *phi, int npt, double step, double frac, int from_top)
{
    if (npt < 1)
        return from_top ? NAN : 0.0;
    if (!from_top) {
        if (phi[0] < frac)
            return 0.0;
        for (int i = 1; i < npt; i++)
            if (phi[i] < frac)
                return (i - 1 + (phi[i - 1] - frac) / (phi[i - 1] - phi[i])) * step;
        return (npt - 1) * step;
    }
    if (phi[npt - 1] >= frac)
        return NAN;
    for (int i = npt - 2; i >= 0; i--)
        if (phi[i] >= frac)
            return (i + (phi[i] - frac) / (phi[i] - phi[i + 1])) * step;
    return NAN;
}
