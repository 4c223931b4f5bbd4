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
