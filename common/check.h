/* `lahar check`: compare a finished run's output with the reference named in the case's check:
 * section, write OUT/check.json and OUT/check.png (plot through tools/plot_check.py).
 *
 * check.json: {"pass": bool, "reference": name,
 *              "metrics": {name: {"value": v, "bound": b, "pass": bool}},
 *              "info": {...measured and reference quantities...},
 *              "plot": {"title", "xlabel", "ylabel", "t": [...], "measured": [...], "reference": [...]}}
 * A metric passes when value <= bound. Metrics computed but not named in the case go to "info";
 * a case without metrics gets the reference's default metric and bound.
 * The plot runs `$LAHAR_PYTHON` (default python3) on tools/plot_check.py; LAHAR_CHECK_NO_PLOT=1
 * skips it. */
#ifndef LAHAR_CHECK_H
#define LAHAR_CHECK_H
#include <stddef.h>
#include <stdint.h>
#include "scene.h"

/* Returns 0 if every metric passes, 1 if any fails, 2 on error (missing output, unknown
 * reference or metric, not enough data); messages on stderr. */
int lahar_check_evaluate(const lahar_case *c, const char *outdir);

/* What the evaluators get: the body snapshots of OUT/bodies.h5 and the force stream of
 * OUT/forces.h5 (nrow = 0 when it is missing). Arrays are [snapshot][body][3]. */
typedef struct {
    int nbody;
    int64_t nsnap;
    double *t;
    int64_t *step;
    double *x, *v, *w;
    int64_t nrow;
    double *ft;
    int32_t *ncontacts; /* [row][body] */
} lahar_check_data;

#define LAHAR_CHECK_MAX_VALUES 16
#define LAHAR_CHECK_MAX_SERIES 4096

/* What an evaluator produces: named values (metrics and informative quantities alike, the case
 * decides which are metrics), and a measured/reference series for the plot. */
typedef struct {
    int nvalue;
    struct {
        char name[64];
        double value;
    } value[LAHAR_CHECK_MAX_VALUES];
    char note[256];            /* e.g. "rolling" / "sliding", the body used */
    char title[128], xlabel[64], ylabel[64];
    int nseries;
    double *series_t, *series_measured, *series_reference; /* LAHAR_CHECK_MAX_SERIES each */
    char err[512];             /* set with a non-zero return */
} lahar_check_result;

typedef int (*lahar_check_evaluator)(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r);

/* The table of references (name -> evaluator); the SPH issue adds Poiseuille etc. here. */
typedef struct {
    const char *name;
    const char *description;
    const char *default_metric;
    double default_bound;
    lahar_check_evaluator evaluate;
} lahar_check_reference;

const lahar_check_reference *lahar_check_find(const char *name);
/* Comma-separated reference names for messages. */
const char *lahar_check_names(void);

/* Load / free the evaluator input from OUT (used by lahar_check_evaluate; exposed for tests). */
int lahar_check_data_load(const char *outdir, lahar_check_data *d, char *err, size_t n);
void lahar_check_data_free(lahar_check_data *d);

#endif
