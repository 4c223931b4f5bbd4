/* Equations of state of the water, one table behind the case key sph.eos (a swappable unit, as
 * the kernels are): pressure from density and its inverse. Adding one: a row in sph_eos.c and a
 * name in scene.h's lahar_sph_eos and the key table (common/io/case_keys.c). */
#ifndef LAHAR_SPH_EOS_H
#define LAHAR_SPH_EOS_H
#include "scene.h"

typedef struct {
    const char *name;
    double (*pressure)(double rho, double rho0, double c0, double gamma);
    double (*density)(double p, double rho0, double c0, double gamma); /* the inverse */
} sph_eos_ops;

/* The equation of state `kind` (LAHAR_SPH_EOS_*); the linear one for an unknown kind. */
const sph_eos_ops *sph_eos_get(lahar_sph_eos kind);

#endif
