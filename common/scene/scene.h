/* The in-memory description of a case: what the case loader produces, what the coordinator
 * sends to the nodes (lcm_types/scene_t.lcm mirrors it) and what the engines are built from.
 * SI units throughout. 2D scenes live in the x-y plane (z = 0, rotation about z only) and
 * their masses and forces are per unit thickness (kg/m, N/m). */
#ifndef LAHAR_SCENE_H
#define LAHAR_SCENE_H
#include <stdint.h>
#include "inflow.h"

#define LAHAR_NAME_MAX 64
#define LAHAR_EXPR_MAX 256 /* an initial-field expression of a particle block (case key velocity:, pressure:) */

typedef enum { LAHAR_MOTION_FREE = 0, LAHAR_MOTION_FIXED = 1, LAHAR_MOTION_PRESCRIBED = 2 } lahar_motion;
typedef enum { LAHAR_CONTACT_LINEAR = 0, LAHAR_CONTACT_HERTZ = 1, LAHAR_CONTACT_SOIL = 2 } lahar_contact_model;

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
    double friction;    /* Coulomb coefficient mu >= 0; soil: mu_phi against DEM surfaces (Trujillo-Vela et al. 2020 eq. 24) */
    lahar_contact_model model; /* LAHAR_CONTACT_SOIL: an SPH soil (model: soil), not a DEM contact law */
    /* soil only (model: soil; sph_node/soil/sph_soil.h): elastic-perfectly plastic Drucker-Prager matched
     * to Mohr-Coulomb; young and poisson above are its elastic constants */
    double friction_angle;  /* phi, radians (case: degrees) */
    double cohesion;        /* c, Pa */
    double dilatancy;       /* psi, radians (case: degrees) */
    double permeability;    /* k_h, Darcy hydraulic conductivity, m/s (0: no seepage) */
    double damping;         /* c_d, 1/s: velocity damping -c_d v of the soil (quasi-static start; 0 = off) */
    double av_alpha, av_beta; /* Monaghan artificial viscosity of the soil (Trujillo-Vela et al. 2020 section 5.3: 1, 1) */
    int constitutive;       /* soil: the constitutive model, the index of its name in the choices of
                               materials.NAME.constitutive (common/io/case_keys.c; 0 drucker_prager) */
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
    int record_contacts;  /* 1: write every fluid contact point and its force for this body
                             (pressure along a wall); case key record_contacts, default 0 */
} lahar_body;

/* A region of SPH particles created on a lattice of spacing dx (sph.dx). The lattice of a block
 * has its points at lo + (i + 1/2) dx, i = 0 .. floor((hi - lo)/dx) - 1 per axis (z = 0, one
 * layer in 2D); a point becomes a particle when it lies inside the region
 * (lahar_particle_block_contains, common/geometry/shape_build.h). For a box the region is [lo, hi); for a
 * polygon or a closed mesh lo/hi are its bounding box (the loader computes them). */
typedef enum {
    LAHAR_BLOCK_BOX = 0,     /* axis-aligned box [lo, hi), 2D or 3D */
    LAHAR_BLOCK_POLYGON = 1, /* 2D simple polygon vert[0..nvert), either orientation, may be non-convex */
    LAHAR_BLOCK_MESH = 2,    /* 3D closed triangulated surface (from an STL file): vert + tri */
} lahar_block_kind;

typedef struct {
    char name[LAHAR_NAME_MAX];
    lahar_block_kind kind;
    double lo[3], hi[3];  /* box, or the bounding box of the polygon / mesh */
    double v[3];          /* initial velocity */
    /* per-particle initial fields (case keys velocity: / pressure: as expressions in x, y, z,
     * evaluated by libmatheval at each particle when the SPH node fills the block; "" = none):
     * vexpr[a] replaces v[a]; pexpr gives the pressure, whose inverse EOS is the density */
    char vexpr[3][LAHAR_EXPR_MAX];
    char pexpr[LAHAR_EXPR_MAX];
    /* or from an HDF5 file (case key initial: {file: F.h5}, the path made absolute by the loader;
     * "" = none): datasets vx, vy (, vz) and/or pressure, one value per particle of the block in
     * the order of lahar_case_block_lattice */
    char init_file[1024];
    int nvert;            /* polygon / mesh vertices, world frame (z = 0 in 2D) */
    double (*vert)[3];
    int ntri;             /* mesh triangles (vertex indices, outward orientation not required) */
    int (*tri)[3];
    char source[256];     /* mesh: the STL file as written in the case, for messages */
    int phase;            /* 0 water (default), 1 soil (case: phase: soil) */
    int material;         /* soil: index into lahar_case.materials (a model: soil material), else -1 */
} lahar_particle_block;

/* Weakly compressible SPH and the SPH-DEM coupling (section sph: of a case; every key is
 * documented in cases/dem_drop_3d.yaml). Together with lahar_case.sph_dx (particle spacing) and
 * lahar_case.sph_density (rest density) this is everything the SPH node needs: the solver's
 * sph_params (sph_node/fluid/sph_fluid.h) holds this struct as it is. The loader fills every
 * default from the key table (common/io/case_keys.c), so a loaded case has final values;
 * lahar_sph_options_default gives the same defaults without a case. */
typedef enum { LAHAR_SPH_EOS_LINEAR = 0, LAHAR_SPH_EOS_TAIT = 1 } lahar_sph_eos;
typedef enum { LAHAR_SPH_WALL_HALFSPACE = 0, LAHAR_SPH_WALL_PAPER = 1 } lahar_sph_wall_viscous;
typedef enum { LAHAR_SPH_INITIAL_PRESSURE_NONE = 0, LAHAR_SPH_INITIAL_PRESSURE_HYDROSTATIC = 1 } lahar_sph_initial_pressure;
typedef enum { LAHAR_SPH_WALL_PRESSURE_PENALTY = 0, LAHAR_SPH_WALL_PRESSURE_GHOST = 1 } lahar_sph_wall_pressure;
typedef enum { LAHAR_SPH_PENALTY_STEP = 0, LAHAR_SPH_PENALTY_ACOUSTIC = 1 } lahar_sph_penalty_stiffness;
typedef enum { LAHAR_SPH_SCHEME_DELTA = 0, LAHAR_SPH_SCHEME_RIEMANN = 1 } lahar_sph_scheme;

typedef struct {
    char kernel[LAHAR_NAME_MAX]; /* "cubic" (default), "quintic", "wendland2" (common/kernels/kernel.h) */
    double h_over_dx;      /* smoothing length h = h_over_dx dx (default 1.3) */
    double c0;             /* m/s, numerical speed of sound (default 10 U_ref, see the example) */
    lahar_sph_eos eos;     /* default linear (Trujillo-Vela et al. 2020 eq. 3); tait: Canelas et al. 2015 eq. 19 */
    double gamma;          /* Tait exponent (default 7) */
    double mu;             /* Pa s, dynamic viscosity (default 1e-3, water) */
    double alpha;          /* Monaghan artificial viscosity (default 0 = off) */
    double delta;          /* delta-SPH coefficient (default 0.1; 0 = off) */
    double cfl, cfl_force, cfl_visc; /* step factors (defaults 0.25, 0.25, 0.125) */
    double body_force[3];  /* m/s^2 acting on the fluid only, added to gravity (default 0) */
    int periodic[3];       /* 1: axis periodic with period [lo[a], hi[a]) */
    double lo[3], hi[3];   /* the periods (only meaningful on periodic axes) */
    int shepard_interval;  /* steps between Shepard density filters, 0 = off (default) */
    int sps;               /* 1: Smagorinsky SPS turbulence (Canelas et al. 2015); default 0 */
    double sps_cs;         /* Smagorinsky constant (default 0.12) */
    double halo;           /* m, coupling halo eps (Trujillo-Vela et al. 2020 eq. 14; default dx/2) */
    double kappa;          /* coupling range in units of h (default: the kernel's support radius) */
    lahar_sph_wall_viscous wall_viscous; /* wall viscous model (sph_node/coupling/sph_coupling.h) */
    lahar_sph_initial_pressure initial_pressure; /* block densities at t = 0: rest (none, default) or
                                                   hydrostatic per block (lahar_sph_node_fill) */
    lahar_sph_wall_pressure wall_pressure; /* wall pressure term: penalty only (default, Trujillo-Vela et al. 2020
                                              eq. 15) or ghost layers (sph_node/coupling/sph_coupling.h) */
    lahar_sph_penalty_stiffness penalty_stiffness; /* K_n = 0.1 m_min / dt^2 of Trujillo-Vela et al. 2020 eq. 15 with the
                                              step's dt (step, default) or the acoustic step
                                              cfl h / c0 (acoustic: independent of the step) */
    lahar_sph_wall_pressure soil_wall_stress; /* the soil's wall term: penalty + friction spring only
                                                 (default, Trujillo-Vela et al. 2020 eq. 15, 22-27) or ghost layers
                                                 carrying the soil stress (sph_node/coupling/sph_coupling.h) */
    double shifting;       /* particle shifting A: dr = -A h^2 grad C per step (Lind et al. 2012),
                              confined flows only; default 0 = off (sph_node/fluid/sph_fluid.c) */
    int shifting_density;  /* 1: the shift changes the density as the continuity equation would (keeps
                              the total volume of a closed box); default 0 (sph_node/fluid/sph_fluid.c) */
    double background_pressure; /* Pa, p_b: default 0. Without transport_velocity it is added to the
                              EOS pressure in the momentum equation; with it, it drives the transport
                              velocity only (Adami et al. 2013); sph_node/fluid/sph_fluid.h */
    int transport_velocity; /* 1: transport-velocity formulation (Adami, Hu & Adams 2013), confined
                              water-only flows without bodies; default 0 */
    int body_layers;       /* N > 0: the particles within N dx of every sphere (3D) or disc (2D) body's
                              surface are placed on N layers concentric with it at (k + 1/2) dx
                              instead of the lattice (lahar_case_block_lattice); default 0 */
    lahar_sph_scheme scheme; /* water's pressure and continuity terms: delta (default: delta-SPH +
                              Monaghan viscosity) or riemann (Zhang, Hu & Adams 2017;
                              sph_node/fluid/sph_riemann.h) */
    double riemann_limiter; /* eta of the riemann scheme's dissipation limiter (default 3; 0 = none) */
} lahar_sph_options;

/* A probe (section probes: of a case; sph_node/probes/sph_probes.h samples it, OUT/gauges.h5).
 * kind LAHAR_PROBE_LEVEL: a water-level gauge, the vertical line (the last axis, along gravity)
 * from x (the floor under the gauge: x[dim - 1] = floor) up to `top`; it reads the height of the
 * free surface above the floor (sph_probes.h). The other fields are for pressure probes:
 * body < 0: a point in the fluid, pressure by Shepard interpolation of the water particles.
 * body >= 0: a point on that body's swept surface (the loader projects x onto it and stores the
 * outward normal n), pressure by Adami, Hu & Adams 2012 eq. 27 at the surface point; with size > 0
 * the mean over a segment (2D) or disc (3D) of that diameter on the surface. */
enum { LAHAR_PROBE_PRESSURE = 0, LAHAR_PROBE_LEVEL = 1, LAHAR_PROBE_TRACKER = 2, LAHAR_PROBE_CONTROL_VOLUME = 3 };
/* Trackers (case section trackers:) and control volumes (control_volumes:) travel as probes of
 * these kinds (sph_node/probes/sph_gauges.h): a tracker follows the particle nearest to x at t = 0; a
 * control volume is the box [x, hi) with its flux axis. Values per sample, in gauges.h5 order:
 * pressure p; level h; tracker x, y, z, vx, vy, vz, id; control volume ek, ek_water, ek_soil,
 * ek_bodies, mass_water, mass_soil, flux_water, flux_soil. */
#define LAHAR_PROBE_MAX_VALUES 8
static inline int lahar_probe_nvalues(int kind)
{
    return kind == LAHAR_PROBE_TRACKER ? 7 : kind == LAHAR_PROBE_CONTROL_VOLUME ? 8 : 1;
}

typedef struct {
    char name[LAHAR_NAME_MAX];
    int kind;              /* LAHAR_PROBE_PRESSURE (default) or LAHAR_PROBE_LEVEL */
    double x[3];           /* world point at the scene pose (on the surface when body >= 0; level
                              gauges: the foot of the line on the floor) */
    double top;            /* level gauges: vertical coordinate of the line's top (m) */
    double n[3];           /* body probes: outward surface normal at x (world, scene pose) */
    int body;              /* index into lahar_case.bodies, or -1 */
    double size;           /* sensor diameter, m (0: the point) */
    double rate;           /* samples per second (0: every step) */
    double hi[3];          /* control volumes: the box's upper corner (x is the lower one) */
    int axis;              /* control volumes: the flux direction (0 x, 1 y, 2 z) */
} lahar_probe;

typedef struct {
    int enabled;           /* 1 if the case has a check: section */
    char reference[256];   /* name of the reference the check compares against */
    int nmetric;
    struct {
        char name[LAHAR_NAME_MAX];
        double bound;      /* the metric passes when value <= bound */
    } metric[16];
} lahar_check;

/* Instability checks (section stability: of a case, see common/protocol/instability.h and cases/README.md).
 * The loader fills every default. */
typedef struct {
    double density_band[2]; /* SPH: every particle keeps rho / rho0 in [lo, hi] (default [0.5, 2]) */
    double max_overlap;     /* DEM: a body-body overlap above this fraction of the smaller sweep
                               radius stops the run (default 0.5; the normal is lost at 1) */
    double dt_collapse;     /* coordinator: a step below this fraction of the first step stops the
                               run (default 1e-3; 0 = only time.dt_min) */
} lahar_stability;

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

    /* SPH */
    double sph_dx;         /* particle spacing, m */
    double sph_density;    /* rest density, kg/m^3 */
    lahar_sph_options sph; /* everything else about the fluid and the coupling */
    int nblock;
    lahar_particle_block *blocks;

    /* DEM engine options */
    char dem_engine[LAHAR_NAME_MAX]; /* "spheropoly" by default */
    int dem_engine_line;             /* line of `dem.engine` in the case file (0: not given), for messages */
    double dem_dt_safety;  /* fraction of the contact period used as the DEM step, default 0.02 */

    int nprobe;            /* pressure probes (probes: section; 0 = none, no gauges.h5) */
    lahar_probe *probes;

    /* open boundaries of the SPH fluid (sections inlets:, outlets:, domain:; common/scene/inflow.h,
     * sph_node/inflow/sph_inflow.h); none by default: a case without them runs exactly as before */
    int ninlet;
    lahar_inlet *inlets;
    int noutlet;
    lahar_outlet *outlets;
    int has_domain;        /* 1: particles outside [domain_lo, domain_hi] are removed */
    double domain_lo[3], domain_hi[3];

    lahar_check check;
    lahar_stability stability; /* instability checks (stability: section) */

    /* output: section. output_fields: particle fields to write, bits in the order of the names
     * velocity, density, pressure, phase, id (= LAHAR_PFIELD_* in output.h); default all.
     * output_forces: 1 = write the per-body force stream (default), 0 = not.
     * output_in_place: 1 = snapshots written into particles.h5, bodies.h5, contacts.h5 in place
     * (output.twins: false); 0 (default) = through their twins (common/io/output_h5.h). */
    unsigned output_fields;
    int output_forces;
    int output_in_place;

    /* checkpoint: section (coordinator/README.md "Checkpoints"): every checkpoint_interval s of
     * simulated time (0: none) the nodes write their whole state to OUT/checkpoints/NNNNNN/;
     * the newest checkpoint_keep are kept (default 2). */
    double checkpoint_interval;
    int checkpoint_keep;

    /* Not case keys: set by `lahar resume` (and carried by the scene). resume = 1: the run
     * continues from the checkpoint in resume_dir, the state of step resume_step; the output
     * files are appended to, not created. */
    int resume;
    int64_t resume_step;
    char resume_dir[1024];
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
    double energy[3]; /* E_P, E_K, E_R at the end of the step (lahar_body_energy, common/geometry/energy.h) */
} lahar_body_report;

#endif
