/* The table of DEM engines selectable by name (`dem: engine:` in the case). To add an engine,
 * write its lahar_dem_engine_ops and list it here. */
#include <string.h>
#include "dem_engine.h"
#include "spheropoly.h"

static const lahar_dem_engine_ops *const lahar_dem_engines[] = {
    &lahar_dem_spheropoly_ops,
};

const lahar_dem_engine_ops *lahar_dem_engine_find(const char *name)
{
    if (!name || !name[0]) name = "spheropoly"; /* the default engine */
    for (size_t i = 0; i < sizeof lahar_dem_engines / sizeof lahar_dem_engines[0]; i++)
        if (strcmp(lahar_dem_engines[i]->name, name) == 0) return lahar_dem_engines[i];
    return NULL;
}

const char *lahar_dem_engine_names(void) { return "spheropoly"; }
