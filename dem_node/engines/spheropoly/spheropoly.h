/* The sphero-polyhedra DEM engine ("spheropoly"), reached through lahar_dem_engine_find(). */
#ifndef LAHAR_SPHEROPOLY_H
#define LAHAR_SPHEROPOLY_H
#include "dem_engine.h"

extern const lahar_dem_engine_ops lahar_dem_spheropoly_ops;

#endif
