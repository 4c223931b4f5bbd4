/* The in-memory description of a case: what the case loader produces, what the coordinator
 * sends to the nodes (lcm_types/scene_t.lcm mirrors it) and what the engines are built from.
 * SI units throughout. 2D scenes live in the x-y plane (z = 0, rotation about z only) and
 * their masses and forces are per unit thickness (kg/m, N/m). */
#ifndef LAHAR_SCENE_H
#define LAHAR_SCENE_H
#include <stdint.h>

#define LAHAR_NAME_MAX 64

typedef enum { LAHAR_MOTION_FREE = 0, LAHAR_MOTION_FIXED = 1, LAHAR_MOTION_PRESCRIBED = 2 } lahar_motion;
typedef enum { LAHAR_CONTACT_LINEAR = 0, LAHAR_CONTACT_HERTZ = 1 } lahar_contact_model;

/* Contact properties of a material. A pair of materials combines them (see dem_node/README.md):
 * E* and R* as in Hertz theory, restitution and friction as the minimum of the two. */
typedef struct {
    char name[LAHAR_NAME_MAX];
    double density;     /* kg/m^3 (used for mass properties of bodies) */
    double young;       /* Pa, Hertz model */
    double poisson;     /* -, Hertz model */
    double kn;          /* N/m (3D) or N/m per m (2D), linear model normal stiffness */
    double kt_ratio;    /* tangential/normal stiffness ratio, default 2/7 */
    double restitution; /* normal coefficient of restitution e in (0, 1] */
    double friction;    /* Coulomb coefficient mu >= 0 */
    lahar_contact_model model;
} lahar_material;

/* A sphero-polyhedron: a convex (or, for fixed bodies, any) set of vertices, edges and faces
 * swept by a sphere of radius `radius`. Coordinates are in the body frame: origin at the centre
 * of mass, axes along the principal axes of inertia (so the inertia tensor is diagonal).
 * Fixed bodies keep world-frame geometry with identity orientation. */
typedef struct {
    int nv;
    double (*v)[3];
    int ne;
    int (*e)[2];
    int nf;
    int *face_start; /* nf + 1 entries; face f uses face_v[face_start[f] .. face_start[f+1]) */
    int *face_v;     /* vertex indices, counter-clockwise seen from outside (outward normal) */
    double radius;   /* sweep radius R > 0 */
} lahar_shape;

typedef struct {
    char name[LAHAR_NAME_MAX];
    int material;         /* index into lahar_case.materials */
    lahar_motion motion;
    int convex;           /* 1 if the core is convex (required for free bodies) */
    lahar_shape shape;
    double mass;          /* kg (kg/m in 2D) */
    double inertia[3];    /* principal moments about body axes */
    double x[3];          /* centre of mass, world frame */
    double q[4];          /* orientation (w, x, y, z): body frame -> world */
    double v[3];          /* linear velocity (prescribed bodies keep it) */
    double w[3];          /* angular velocity, world frame (prescribed bodies keep it) */
} lahar_body;

/* A block of SPH particles created on a lattice of spacing dx (SPH issue extends this). */
typedef struct {
    char name[LAHAR_NAME_MAX];
    double lo[3], hi[3];  /* axis-aligned box filled with particles */
    double v[3];          /* initial velocity */
} lahar_particle_block;

typedef struct {
    int enabled;           /* 1 if the case has a check: section */
    char reference[256];   /* name of the reference the check compares against */
    int nmetric;
    struct {
        char name[LAHAR_NAME_MAX];
        double bound;      /* the metric passes when value <= bound */
    } metric[16];
} lahar_check;

typedef struct {
    char path[1024];       /* case file, for messages */
    int dim;               /* 2 or 3 */
    double gravity[3];     /* m/s^2 */
    double t_end;          /* s */
    double dt_max;         /* s, upper limit for the coordinator step */
    double dt_min;         /* s, a step below this stops the run (dt collapse) */
    double output_interval;       /* s, snapshot interval */
    double forces_interval;       /* s, 0 = every step */

    int nmaterial;
    lahar_material *materials;
    int nbody;
    lahar_body *bodies;

    /* SPH (issue 3 grows this) */
    double sph_dx;         /* particle spacing, m */
    double sph_density;    /* rest density, kg/m^3 */
    int nblock;
    lahar_particle_block *blocks;

    /* DEM engine options */
    char dem_engine[LAHAR_NAME_MAX]; /* "spheropoly" by default */
    double dem_dt_safety;  /* fraction of the contact period used as the DEM step, default 0.02 */

    lahar_check check;

    /* output: section. output_fields: particle fields to write, bits in the order of the names
     * velocity, density, pressure, phase, id (= LAHAR_PFIELD_* in output.h); default all.
     * output_forces: 1 = write the per-body force stream (default), 0 = not. */
    unsigned output_fields;
    int output_forces;
} lahar_case;

/* Per-body state as exchanged with the other nodes (body_state_t). */
typedef struct {
    double x[3], q[4], v[3], w[3];
} lahar_body_state;

/* External load on a body for one coordinator step (from the SPH node). Constant during the
 * step; zero for bodies nobody touches. */
typedef struct {
    double force[3];  /* N, world frame */
    double torque[3]; /* N m about the centre of mass, world frame */
} lahar_body_load;

/* What the engine reports per body for the force stream (forces.h5). */
typedef struct {
    double force[3];  /* total contact + external force over the last step, N (time average over substeps) */
    double torque[3]; /* about the centre of mass, N m */
    int ncontacts;    /* active contact points at the end of the step */
} lahar_body_report;

#endif
