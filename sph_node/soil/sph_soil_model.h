/* The constitutive model of the SPH soil behind one interface: what is specific to one stress-strain
 * law. The rest of the soil (kernel sums, artificial stress, momentum, seepage, the integrator's
 * stress updates; sph_soil.c) is the same for every model. A model is a table of these functions in
 * a file of its own (sph_soil_dp.c: Drucker-Prager) and one entry of sph_soil_models.c; a case
 * selects it by name (materials.NAME.constitutive, whose choices in common/io/case_keys.c list the
 * same names in the same order). */
#ifndef LAHAR_SPH_SOIL_MODEL_H
#define LAHAR_SPH_SOIL_MODEL_H
#include "sph_soil.h"

typedef struct sph_soil_model {
    const char *name;
    /* the model's constants of s->mat into s (the elastic moduli G, K, the P-wave speed cs and
     * its own constants) */
    void (*init)(sph_soil *s);
    /* the objective stress rate of a particle with stress sig, strain rate eps and spin (3 x 3),
     * into out (xx, xy, xz, yy, yz, zz) */
    void (*stress_rate)(const sph_soil *s, const double sig[3][3], const double eps[3][3], const double spin[3][3],
                        double out[SPH_NSTRESS]);
    /* a stress brought back to the admissible set after an update, in place */
    void (*admissible)(const sph_soil *s, double sig[SPH_NSTRESS]);
} sph_soil_model;

/* The model of that name, or NULL. */
const sph_soil_model *sph_soil_model_find(const char *name);

#endif
