/* The fluid evaluators' private interface: only coordinator/check/check_fluid*.c include it (the
 * driver includes check.h). The helpers every family of fluid references shares, defined once in
 * check_fluid.c (what each does and the conventions they follow: there). */
#ifndef LAHAR_CHECK_FLUID_H
#define LAHAR_CHECK_FLUID_H
#include <stddef.h>
#include <stdint.h>
#include "check.h"
#include "output.h"
#include "vec.h"

/* A particle's position and velocity in the snapshot in the buffers (inlined: every loop over the
 * particles calls them). */
static inline vec3 fluid_pos(const lahar_check_particles *p, int64_t i) { return v3(p->x[i], p->y[i], p->z[i]); }
static inline vec3 fluid_vel(const lahar_check_particles *p, int64_t i) { return v3(p->vx[i], p->vy[i], p->vz[i]); }

/* the case and the particle snapshots */
vec3 fluid_accel(const lahar_case *c);
double fluid_dx(const lahar_case *c, const lahar_check_data *d);
int fluid_need(const lahar_check_data *d, unsigned need, const char *who, lahar_check_result *r);
int fluid_read(const lahar_check_data *d, int64_t k, lahar_check_result *r);

/* the bodies: pose, distance to the core, depth inside the swept solid */
void fluid_pose(const lahar_case *c, const lahar_check_data *d, int j, int64_t k, double x[3], double q[4]);
double fluid_core_dist(const lahar_case *c, const lahar_check_data *d, int j, int64_t k, vec3 p, vec3 *cp);
int fluid_inside_core(const lahar_case *c, const lahar_check_data *d, int j, int64_t k, vec3 p);
double fluid_depth(const lahar_case *c, const lahar_check_data *d, int j, int64_t k, vec3 p);
int fluid_deeper_than(const lahar_case *c, const lahar_check_data *d, int j, int64_t k, vec3 p, double level);
int64_t fluid_body_snapshot(const lahar_check_data *d, double t, double tol);
int fluid_first_free(const lahar_case *c);

/* gravity's frame and the free-surface level */
int fluid_frame(const lahar_case *c, vec3 *up, vec3 *e1, vec3 *e2);
/* fluid_surface's work space, kept across snapshots (grown by doubling; fluid_columns_free). */
typedef struct {
    double *top, *bot;     /* [column] highest and lowest particle along up */
    int64_t *start, *order; /* [column + 1], [particle]: the particles sorted by column */
    double *phi;           /* a gauge's line */
    size_t cap_col, cap_bot, cap_start, cap_n, cap_phi;
} fluid_columns;
void fluid_columns_free(fluid_columns *col);
int fluid_surface(const lahar_case *c, const lahar_check_particles *p, vec3 up, vec3 e1, vec3 e2, double dx,
                  double skip_lo, double skip_hi, fluid_columns *col, double *level, double *lmin, double *lmax);

/* the late window and the force stream */
double fluid_late_from(const double *t, int64_t n);
int64_t fluid_late_row(const lahar_check_data *d);
int64_t fluid_late_snapshot(const lahar_check_particles *p);
double fluid_force_mean(const lahar_check_data *d, int64_t k0, int j, vec3 dir);
void fluid_plot_force(lahar_check_result *r, int panel, const lahar_check_data *d, int j, vec3 dir, double scale,
                      const char *label);

#endif
