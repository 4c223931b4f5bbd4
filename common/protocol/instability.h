/* A numerical instability caught by a node or the coordinator: WHAT went wrong, WHERE (a particle
 * or a body: id, name, position) and WHEN (step, time), with the offending value and its limit.
 *
 * The checks (see README.md "Stability limits" and cases/README.md `stability:`):
 *   SPH node   non-finite particle state, density outside stability.density_band, a particle
 *              through a DEM surface (the coupling's crossing count)
 *   DEM node   non-finite or runaway body state, a body-body overlap beyond
 *              stability.max_overlap x the smaller sweep radius (the engine's fault report)
 *   coordinator the step the nodes allow falls below time.dt_min or below
 *              stability.dt_collapse x the first step
 *
 * A node reports one in its STATUS message (status_t.message, 512 bytes) as one line
 *   UNSTABLE|what|kind|id|name|x|y|z|step|t|value|limit|text
 * (lahar_instability_encode); the coordinator recognises the prefix (lahar_instability_decode),
 * ends the run with exit status 1 and status "unstable" in summary.json, with these fields under
 * "instability", and prints `text`, a sentence that says all of it in words. */
#ifndef LAHAR_INSTABILITY_H
#define LAHAR_INSTABILITY_H
#include <stddef.h>
#include <stdint.h>

#define LAHAR_INSTABILITY_PREFIX "UNSTABLE|"

typedef struct {
    char what[48];       /* "non-finite state", "density out of band", "crossing", "overlap",
                            "runaway", "dt collapse" */
    char kind[16];       /* "particle", "body" or "" (dt collapse: no place) */
    int64_t id;          /* particle id or body index; -1 when none */
    char name[64];       /* body name ("" for particles) */
    double x[3];         /* where: particle position, body centre or contact point */
    int64_t step;        /* the coordinator step in which it was caught */
    double t;            /* s, time at the end of that step (the state of the final snapshot) */
    double value, limit; /* the offending quantity and its bound (what-dependent; NaN if none) */
    char text[400];      /* the whole report in words */
} lahar_instability;

/* Write u into msg as the single line above (fields cut to fit n, text last). */
void lahar_instability_encode(const lahar_instability *u, char *msg, size_t n);
/* 1 and u filled when msg is an encoded instability, 0 otherwise (u untouched). */
int lahar_instability_decode(const char *msg, lahar_instability *u);

#endif
