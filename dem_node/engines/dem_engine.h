/* The contract every DEM engine fulfils (a table of function pointers, as PETSc and LAMMPS do
 * for their implementations). The DEM node drives an engine only through this table, so another
 * engine can be plugged in by writing one more `lahar_dem_engine_ops` and registering it in
 * dem_engine_registry.c. */
#ifndef LAHAR_DEM_ENGINE_H
#define LAHAR_DEM_ENGINE_H
#include <stdio.h>
#include "scene.h"

typedef struct lahar_dem_engine lahar_dem_engine; /* opaque, owned by the implementation */

/* An instability of the bodies that made advance() fail (the DEM node turns it into the
 * report of common/protocol/instability.h: what, which body, where, when). */
typedef struct {
    char what[48];        /* "non-finite state", "runaway", "overlap" */
    int body, other;      /* the body (the first of a pair), the other one or -1 */
    double x[3];          /* the body's centre, or the contact point of an overlap */
    double value, limit;  /* overlap and its limit (m); |x| and its limit for a runaway; NaN otherwise */
    long substep;         /* engine substep since creation */
} lahar_dem_fault;

typedef struct {
    const char *name;    /* selected by `dem: engine:` in the case */
    const char *version;
    /* Build from the scene (copies what it needs). Returns NULL and fills err on failure. */
    lahar_dem_engine *(*create)(const lahar_case *scene, char *err, size_t errlen);
    /* Optional (NULL: the engine takes every case the loader accepts). Whether this engine can run
     * the case: 0, or -1 with a message naming the body or section and what to do. `lahar validate`
     * and `lahar run` call it before any node starts, so each engine validates what is its own. */
    int (*check_case)(const lahar_case *scene, char *err, size_t errlen);
    /* Largest stable step of the engine itself (a fraction of the smallest contact period). */
    double (*stable_dt)(const lahar_dem_engine *e);
    /* Advance all bodies by dt, subcycling with n = ceil(dt / stable_dt) equal substeps when
     * needed. `loads` has one entry per body (NULL = none). Returns the number of substeps, or -1
     * on an instability (message in err: which body, which step). No allocation here in the
     * steady state. */
    int (*advance)(lahar_dem_engine *e, double dt, const lahar_body_load *loads, char *err, size_t errlen);
    int (*nbody)(const lahar_dem_engine *e);
    void (*get_state)(const lahar_dem_engine *e, int body, lahar_body_state *out);
    void (*get_report)(const lahar_dem_engine *e, int body, lahar_body_report *out);
    int (*ncontacts)(const lahar_dem_engine *e);
    double (*kinetic_energy)(const lahar_dem_engine *e);
    /* Work counter: body-body contacts summed over every force evaluation since create (one per
     * substep; not part of a restart). Optional (NULL: the node reports 0). */
    long long (*contacts_evaluated)(const lahar_dem_engine *e);
    /* Restart: everything needed to continue bit for bit (states, contact history). */
    int (*write_restart)(const lahar_dem_engine *e, FILE *f);
    int (*read_restart)(lahar_dem_engine *e, FILE *f);
    void (*destroy)(lahar_dem_engine *e);
    /* After advance() returned -1: 1 with *out filled when the bodies went unstable, 0 when the
     * failure was something else (out of memory, a bad dt). NULL: the engine has no such report. */
    int (*fault)(const lahar_dem_engine *e, lahar_dem_fault *out);
} lahar_dem_engine_ops;

/* Look an engine up by name; NULL if unknown. */
const lahar_dem_engine_ops *lahar_dem_engine_find(const char *name);
/* Comma-separated list of the registered names, for error messages. */
const char *lahar_dem_engine_names(void);

#endif
