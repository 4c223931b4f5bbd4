/* `lahar check`: compare a finished run's output with the reference named in the case's check:
 * section, write OUT/check.json and OUT/check.png (plot through tools/plot_check.py).
 *
 * check.json: {"pass": bool, "reference": name, "convention": "..." (some references),
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
#include "geometry.h"
#include "scene.h"

/* Returns 0 if every metric passes, 1 if any fails, 2 on error (missing output, unknown
 * reference or metric, not enough data); messages on stderr. */
int lahar_check_evaluate(const lahar_case *c, const char *outdir);

/* Particle snapshots of OUT/particles.h5, read one at a time (lahar_check_particles_read) into
 * buffers sized for the largest snapshot: a 3D run's particles need not fit in memory at once. */
typedef struct {
    int dim;
    unsigned fields;           /* LAHAR_PFIELD_* bits the file holds (output.h) */
    double dx, rest_density;   /* header attributes */
    int64_t nsnap;
    double *t;                 /* [nsnap] */
    int64_t *n;                /* [nsnap] particle count of each snapshot */
    int64_t nmax;
    int64_t cur;               /* snapshot in the buffers (-1: none) */
    int64_t cur_n;
    double *x, *y, *z, *vx, *vy, *vz, *density, *pressure; /* [nmax]; NULL for fields not stored */
    int32_t *phase;            /* [nmax]; NULL when not stored */
    double *stress;            /* [nmax][6] soil stress (xx, xy, xz, yy, yz, zz); NULL when not stored */
    int64_t file;              /* hid_t of the open file */
} lahar_check_particles;

/* What the evaluators get: the body snapshots of OUT/bodies.h5, the force stream of
 * OUT/forces.h5 (nrow = 0 when it is missing) and the particles of OUT/particles.h5 (NULL when
 * missing). Arrays are [snapshot][body][3] (q: [4]), force [row][body][3]. */
typedef struct {
    int nbody;
    int64_t nsnap;
    double *t;
    int64_t *step;
    double *x, *q, *v, *w;
    int64_t nrow;
    double *ft;
    int32_t *ncontacts; /* [row][body] */
    double *force;      /* [row][body][3], N (N/m in 2D) */
    lahar_check_particles *particles;
    /* the feature grids of the case's big bodies (a terrain, an STL flume), so that a particle's
     * distance test visits only the features near it (lahar_check_evaluate builds them; never
     * built: every feature is scanned) */
    geom_body_grids grids;
} lahar_check_data;

/* Read particle snapshot k into p's buffers (no-op when it is already there). Returns 0, or -1
 * with a message in err. */
int lahar_check_particles_read(lahar_check_particles *p, int64_t k, char *err, size_t n);

#define LAHAR_CHECK_MAX_VALUES 24
#define LAHAR_CHECK_MAX_SERIES 4096
#define LAHAR_CHECK_MAX_PANELS 4
#define LAHAR_CHECK_MAX_CURVES 32
#define LAHAR_CHECK_MAX_POINTS 65536

/* What an evaluator produces: named values (metrics and informative quantities alike, the case
 * decides which are metrics), and for the plot either one measured/reference series over t
 * (series_*) or panels of labelled curves (lahar_check_panel/_curve/_point), e.g. velocity
 * profiles at several times next to the analytic ones and a force history next to its
 * reference line. */
typedef struct {
    int nvalue;
    struct {
        char name[64];
        double value;
    } value[LAHAR_CHECK_MAX_VALUES];
    char note[512];            /* e.g. "rolling" / "sliding", the body used */
    char convention[256];      /* how the compared quantities are defined, when it matters */
    char title[128], xlabel[64], ylabel[64];
    int nseries;
    double *series_t, *series_measured, *series_reference; /* LAHAR_CHECK_MAX_SERIES each */
    int npanel;
    struct {
        char title[160], xlabel[64], ylabel[64];
        int ylog;              /* 1: logarithmic y axis */
    } panel[LAHAR_CHECK_MAX_PANELS];
    int ncurve;
    struct {
        int panel;
        int measured;          /* 1: markers (lahar), 0: line (reference) */
        char label[96];
        int start, n;          /* points [start, start + n) of px/py */
    } curve[LAHAR_CHECK_MAX_CURVES];
    int npoint;
    double *px, *py;           /* LAHAR_CHECK_MAX_POINTS each */
    char err[512];             /* set with a non-zero return */
} lahar_check_result;

/* Evaluator helpers. A value name longer than 63 characters or beyond LAHAR_CHECK_MAX_VALUES is
 * dropped; points beyond the pool are dropped (the plot is then shorter, the metrics are not
 * affected). */
void lahar_check_value(lahar_check_result *r, const char *name, double v);
/* Start of the late window of the times t[0, n) (n >= 1): the last `fraction` of the span
 * t[n-1] - t[0], where an evaluator averages a steady state (water: 0.1, soil: 0.25). */
double lahar_check_late_from(const double *t, int64_t n, double fraction);
/* Grow *buf (elements of size sz, capacity *cap) to hold n, doubling from 1024: 0, or -1 out of
 * memory (buffers kept across snapshots). */
int lahar_check_grow(void **buf, size_t *cap, size_t n, size_t sz);
/* A level gauge's line (common/kernels/kernel.h kernel_line_add, kernel_line_crossing): the
 * points `step` apart from low up to a kernel support above top, zeroed in *phi (grown as needed,
 * *cap its capacity). Returns their number, or -1 out of memory. */
int lahar_check_gauge_line(double **phi, size_t *cap, double low, double top, double support, double step);
/* Start a panel; returns its index (or -1 when there are LAHAR_CHECK_MAX_PANELS already). */
int lahar_check_panel(lahar_check_result *r, const char *title, const char *xlabel, const char *ylabel);
/* Start a curve in panel `panel`; following lahar_check_point calls add to it. Returns 0 or -1. */
int lahar_check_curve(lahar_check_result *r, int panel, int measured, const char *label);
void lahar_check_point(lahar_check_result *r, double x, double y);

typedef int (*lahar_check_evaluator)(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r);

/* The table of references (name -> evaluator). */
typedef struct {
    const char *name;
    const char *description;
    const char *default_metric;
    double default_bound;
    lahar_check_evaluator evaluate;
} lahar_check_reference;

const lahar_check_reference *lahar_check_find(const char *name);

/* The DEM references (coordinator/check/check_dem.c). */
int lahar_check_restitution(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r);
int lahar_check_incline_roll(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r);

/* The SPH references (coordinator/check/check_fluid_*.c, one file per family, table in
 * coordinator/check/README.md; what each computes is documented there and in cases/README.md). */
int lahar_check_poiseuille(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r);
int lahar_check_cylinder_array(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r);
int lahar_check_sphere_array(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r);
int lahar_check_hydrostatic(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r);
int lahar_check_floating_box(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r);
int lahar_check_sinking_disc(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r);
int lahar_check_dam_break(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r);
int lahar_check_lid_driven_cavity(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r);
int lahar_check_taylor_green(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r);
/* The soil references (coordinator/check/check_soil*.c; documented there and in cases/README.md). */
int lahar_check_soil_geostatic(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r);
int lahar_check_soil_slide(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r);
int lahar_check_granular_collapse(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r);
int lahar_check_granular_impact(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r);
int lahar_check_darcy(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r);
/* open boundaries: discharge, mass balance, outflow, depth (coordinator/check/check_inflow.c) */
int lahar_check_inflow(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r);
/* A soil mass sliding down a 2D terrain (coordinator/check/check_landslide.c; cases/README.md). */
int lahar_check_landslide(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r);

/* Dimensionless drag K = F/(mu U) of a square array of cylinders at solid fraction c (Sangani &
 * Acrivos 1982 Table 1: ln K interpolated linearly in c between tabulated
 * points, the low-c asymptote below c = 0.05); NAN outside (0, 0.75]. */
double lahar_check_sangani_acrivos_K(double c);
/* Zick & Homsy (1982) Table 2, simple cubic array of spheres (dilute series below c = 0.027); NAN outside (0, 0.5236]. */
double lahar_check_zick_homsy_K(double c);

/* Transient plane Poiseuille flow from rest (Morris et al. 1997 eq. 21
 * ): velocity at distance y from the lower wall of a channel of width H driven by
 * the acceleration a, kinematic viscosity nu, time t; and the shear force per unit wall area on
 * one wall, rho nu du/dy at the wall (steady value rho a H / 2, Trujillo-Vela et al. 2020 eq. 31-32). */
double lahar_check_poiseuille_u(double y, double t, double H, double a, double nu);
double lahar_check_poiseuille_wall_stress(double t, double H, double a, double nu, double rho);
/* Comma-separated reference names for messages. */
const char *lahar_check_names(void);

/* Load / free the evaluator input from OUT (used by lahar_check_evaluate; exposed for tests). */
int lahar_check_data_load(const char *outdir, lahar_check_data *d, char *err, size_t n);
void lahar_check_data_free(lahar_check_data *d);

#endif
