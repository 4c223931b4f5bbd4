/* The constitutive models of the SPH soil (sph_soil_model.h), by name. */
#include "sph_soil_model.h"
#include <string.h>

extern const sph_soil_model sph_soil_model_drucker_prager; /* sph_soil_dp.c */

static const sph_soil_model *const models[] = {&sph_soil_model_drucker_prager, NULL};

const sph_soil_model *sph_soil_model_find(const char *name)
{
    for (int i = 0; name && models[i]; i++)
        if (strcmp(models[i]->name, name) == 0)
            return models[i];
    return NULL;
}
