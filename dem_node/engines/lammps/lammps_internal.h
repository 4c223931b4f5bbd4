/* The LAMMPS engine's private interface: only lammps_engine.c (the step, the queries, the
 * function table) and lammps_create.c (the checks of the scene and the building of the LAMMPS
 * instance) include it. What the engine is and its conventions: lammps_engine.c. */
#ifndef LAHAR_LAMMPS_INTERNAL_H
#define LAHAR_LAMMPS_INTERNAL_H
#include <float.h>
#include <stddef.h>
#include <stdint.h>
#include "dem_contact.h"
#include "lammps_engine.h"

#include "vec.h"

#define LMP_MAX_TYPES 256 /* atom types (contact classes); pair coefficients grow with the square */
/* a coupling step within LMP_CLOCK_EPS x t_next of n x the current substep is the same step: twice
 * the round-off 2 eps t_next of dt = t_next - t (lmp_advance) */
#define LMP_CLOCK_EPS (4.0 * DBL_EPSILON)

typedef struct {
    int body;        /* index in the scene */
    double p[3], n[3]; /* the contact surface: a point (the face moved out by the sweep radius) and the normal */
    double radius;   /* sweep radius of the wall */
    double c[3];     /* the body's reference point (torques of its report are about it) */
    int material;
} lmp_wall;

struct lahar_dem_engine {
    void *lmp;
    int dim, nbody, nfree, nwall, ntype;
    int *free_of_body;  /* body -> index among the free bodies (tag - 1), -1 for walls */
    int *body_of_free;  /* tag - 1 -> body */
    int *type_of_free;  /* atom type (1-based) */
    double *mass, *radius, *inertia; /* per free body (I = 2/5 m r^2 sphere, 1/2 m r^2 disc) */
    lmp_wall *walls;
    lahar_body_state *st;            /* every body, refreshed after each advance */
    double (*load_f)[3], (*load_t)[3]; /* per free body, constant over the coupling step */
    double (*acc_f)[3], (*acc_t)[3];   /* contact + external, summed over the substeps */
    double (*rep_f)[3], (*rep_t)[3];   /* the report of the last step (time average) */
    double (*last_f)[3], (*last_t)[3]; /* contact force and torque of the last substep */
    /* walls (per body, 0 for free bodies): the contact force the free bodies exert on them, summed
     * over the substeps, the SPH load of the step and the report (time average + load), as
     * spheropoly reports its fixed bodies */
    double (*wacc_f)[3], (*wacc_t)[3], (*wload_f)[3], (*wload_t)[3], (*wrep_f)[3], (*wrep_t)[3];
    int nwfix;            /* wall fixes (one per wall and atom type), made with `contacts` */
    char (*wfix_id)[32];  /* their IDs, for lammps_extract_fix */
    int *wfix_wall;       /* their wall */
    int have_last;
    /* fixes made again before every init after the first (see lmp_advance): the Hertz walls
     * and, after them, the stateless fixes that must follow the walls in post_force order */
    int nrefix, caprefix;
    char (*refix_id)[32];
    char (*refix_cmd)[1024];
    int *ncontact_body, ncontacts;
    double dt_stable, h_last, max_overlap;
    double t_req, lag; /* time the engine was asked to reach; that minus LAMMPS' time (see lmp_advance) */
    int64_t step_start;
    long substep;
    int initialized;
    long long contacts_evaluated;
    int has_fault;
    lahar_dem_fault fault;
    char cmd[1024];
};

/* lammps_engine.c: commands to LAMMPS, the contact law's coefficients, the step's callback and fixes */
void lmp_cmd(lahar_dem_engine *e, const char *fmt, ...);
void lmp_keep_fix(lahar_dem_engine *e, const char *id, const char *fmt, ...);
int lmp_is_sphere(const lahar_shape *s);
int lmp_law_coeffs(const dem_pair_law *law, double mstar, char *out, size_t n, char *err, size_t errlen,
                   const char *what);
void lmp_callback(void *ptr, int64_t step, int nlocal, int *ids, double **x, double **fext);
void lmp_refix(lahar_dem_engine *e);
/* lammps_create.c: create (start = 1) or only check (lmp_check_case) the scene, and destroy */
lahar_dem_engine *lmp_create(const lahar_case *c, char *err, size_t errlen);
int lmp_check_case(const lahar_case *c, char *err, size_t errlen);
void lmp_destroy(lahar_dem_engine *e);

#endif
