/* Open boundaries of the SPH fluid (case sections inlets:, outlets:, domain:): what the case
 * loader fills, the scene message carries (lcm_types/inlet_t.lcm, outlet_t.lcm) and the SPH node
 * runs (sph_node/inflow/sph_inflow.h). The inflow hydrograph is evaluated here, once for everyone.
 *
 * An inlet is a line segment (2D) or a rectangle (3D) with an inward unit normal n: the section
 * through which water enters. Behind it (against n) lies its buffer zone of `layers` rows of
 * particles that move with the prescribed velocity u(t) n; the water below the prescribed level h
 * (depth above the section's lowest point, measured against gravity) enters. Velocity u(t):
 *   constant:  u = velocity
 *   gumbel:    u = a_G/beta_G exp(-(t - mu_G)/beta_G) exp(-exp(-(t - mu_G)/beta_G))
 *              (Trujillo-Vela et al. 2020, eq. 36; a_G = 35, beta_G = 2, mu_G = 3 in their section 6)
 *   table:     a CSV hydrograph, rows t,u (m/s) or t,Q (discharge: m^2/s per unit width in 2D,
 *              m^3/s in 3D), linear between rows, the end values outside;
 * all multiplied by 0 outside the active window [start, end). A discharge Q is turned into the
 * velocity u = Q / A with A the wetted area of the section's lattice (slots below the level times
 * dx^(D-1)), so the particles delivered carry Q exactly up to one row (sph_inflow.c). The level h
 * is a constant or a CSV table t,h (level_hydrograph): a new buffer row fills the slots below
 * h(t) at its creation, and the buffer's hydrostatic density follows h(t). */
#ifndef LAHAR_INFLOW_H
#define LAHAR_INFLOW_H
#include <stdint.h>

#define LAHAR_INFLOW_NAME_MAX 64

typedef enum {
    LAHAR_HYDRO_CONSTANT = 0,
    LAHAR_HYDRO_GUMBEL = 1,
    LAHAR_HYDRO_TABLE_U = 2, /* CSV t,u */
    LAHAR_HYDRO_TABLE_Q = 3, /* CSV t,Q */
    LAHAR_HYDRO_TABLE_H = 4  /* CSV t,h: a level table (level_hydrograph), not a velocity */
} lahar_hydro_kind;

typedef struct {
    char name[LAHAR_INFLOW_NAME_MAX];
    double x0[3];       /* one end of the line (2D) or a corner of the rectangle (3D) */
    double e1[3], e2[3]; /* edges: the section is x0 + a e1 (+ b e2), a, b in [0, 1]; 2D: e2 = 0 */
    double n[3];        /* inward unit normal (perpendicular to the edges) */
    double level;       /* water depth above the section's lowest point, m (with a level table: its
                           largest value, which sets the slots of the section's lattice) */
    int nlevel;         /* level table rows (0: the level is constant) */
    double *level_t, *level_h; /* t (s, increasing) and h (m): h(t) linear between rows, the end
                                  values outside (not limited to [t_start, t_end)) */
    int layers;         /* rows of buffer particles behind the section (>= kernel support / dx) */
    int kind;           /* lahar_hydro_kind */
    double velocity;    /* constant: m/s */
    double gumbel[3];   /* a_G (m), beta_G (s), mu_G (s) */
    double t_start, t_end; /* active window, s (u = 0 outside) */
    int ntable;         /* table rows */
    double *table_t, *table_v; /* t (s, increasing) and u (m/s) or Q */
    int64_t max_particles; /* most particles this inlet may create (buffer included) */
} lahar_inlet;

/* An outlet: particles beyond the line/rectangle (x0, e1, e2) along its outward normal n, within
 * its extent (and at most `depth` beyond it), are removed and counted. */
typedef struct {
    char name[LAHAR_INFLOW_NAME_MAX];
    double x0[3], e1[3], e2[3], n[3];
    double depth;       /* how far beyond the section the removal zone reaches, m */
} lahar_outlet;

/* The value of the inlet's hydrograph at t: u (m/s) for constant, gumbel and t,u tables; Q for
 * t,Q tables; 0 outside [t_start, t_end). */
double lahar_inlet_hydrograph(const lahar_inlet *in, double t);

/* The inlet's level at t: the constant level, or the level table at t. */
double lahar_inlet_level(const lahar_inlet *in, double t);

/* Read a CSV hydrograph: a header line `t,u`, `t,Q` or `t,h` (kind LAHAR_HYDRO_TABLE_U / _Q / _H), then rows
 * of two numbers, t strictly increasing; blank lines and lines starting with # are skipped.
 * Allocates *t and *v (free both). Returns the number of rows, or -1 with "line N: what to do" in
 * err. */
int lahar_hydrograph_read_csv(const char *path, int *kind, double **t, double **v, char *err, int errlen);

#endif
