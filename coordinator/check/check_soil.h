/* The soil evaluators' private interface: only coordinator/check/check_soil*.c include it (the
 * driver includes check.h). check_soil.c holds soil_geostatic, soil_slide, darcy and what they
 * share; check_soil_collapse.c granular_collapse; check_soil_impact.c granular_impact. */
#ifndef LAHAR_CHECK_SOIL_H
#define LAHAR_CHECK_SOIL_H
#include "check.h"

/* The soil material of the case (the first soil block's), or NULL. */
const lahar_material *soil_material(const lahar_case *c);

#endif
