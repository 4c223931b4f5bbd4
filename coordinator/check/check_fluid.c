/* `lahar check` references of the SPH cases (table in check.c, names and metrics in
 * cases/README.md). Each evaluator reads what it needs from the case (fluid properties from
 * sph:, the driving acceleration gravity + sph.body_force, periods, bodies' geometry) and from
 * the run's output (particles.h5 snapshots, bodies.h5 poses, forces.h5 rows), computes its
 * values and fills the plot panels.
 *
 * Common conventions:
 *  - "Late window": force-stream rows (or snapshots) with t >= t_last - 0.1 (t_last - t_first),
 *    at least the last one. Force averages over it smooth the step-to-step noise of SPH
 *    pressure; the reference is averaged over the same rows.
 *  - Free-surface level: particles are binned in columns of width dx across the horizontal
 *    directions; the level is the mean of the column tops plus dx/2 (a particle stands for a
 *    cell of size dx; the lattice of a block puts its top row dx/2 below the block's top).
 *
 * This file holds what the evaluators share (check_fluid.h); the evaluators live by family:
 * check_fluid_internal.c (poiseuille, lid_driven_cavity, taylor_green), check_fluid_arrays.c
 * (cylinder_array, sphere_array), check_fluid_still.c (hydrostatic, floating_box, sinking_disc),
 * check_fluid_dam_break.c (dam_break). */
#include "check_fluid.h"
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "geometry.h"

/* ---------------------------------------------------------------- helpers --------------- */

/* Acceleration driving the fluid: gravity plus the fluid-only body force. */
vec3 fluid_accel(const lahar_case *c) { return v3_add(v3_load(c->gravity), v3_load(c->sph.body_force)); }

double fluid_dx(const lahar_case *c, const lahar_check_data *d)
{
    return c->sph_dx > 0.0 ? c->sph_dx : (d->particles ? d->particles->dx : 0.0);
}

/* The particles must be there with the fields `need` (LAHAR_PFIELD_* bits). */
int fluid_need(const lahar_check_data *d, unsigned need, const char *who, lahar_check_result *r)
{
    const lahar_check_particles *p = d->particles;
    if (!p || p->nsnap == 0) {
        snprintf(r->err, sizeof r->err, "%s: needs particle snapshots (OUT/particles.h5); did the SPH node write any?",
                 who);
        return -1;
    }
    if ((p->fields & need) != need) {
        snprintf(r->err, sizeof r->err,
                 "%s: particles.h5 lacks the fields it needs (%s%s); add them to output: fields in the case", who,
                 (need & LAHAR_PFIELD_VELOCITY) && !(p->fields & LAHAR_PFIELD_VELOCITY) ? "velocity " : "",
                 (need & LAHAR_PFIELD_PRESSURE) && !(p->fields & LAHAR_PFIELD_PRESSURE) ? "pressure" : "");
        return -1;
    }
    return 0;
}

int fluid_read(const lahar_check_data *d, int64_t k, lahar_check_result *r)
{
    return lahar_check_particles_read(d->particles, k, r->err, sizeof r->err);
}

/* Pose of body j at body snapshot k (fixed bodies: their own world-frame geometry). */
void fluid_pose(const lahar_case *c, const lahar_check_data *d, int j, int64_t k, double x[3], double q[4])
{
    const lahar_body *b = &c->bodies[j];
    if (b->motion == LAHAR_MOTION_FIXED || k < 0 || d->nsnap == 0) {
        memcpy(x, b->x, sizeof b->x), memcpy(q, b->q, sizeof b->q);
        return;
    }
    memcpy(x, d->x + ((size_t)k * (size_t)d->nbody + (size_t)j) * 3, 3 * sizeof(double));
    memcpy(q, d->q + ((size_t)k * (size_t)d->nbody + (size_t)j) * 4, 4 * sizeof(double));
}

/* Distance from p to the core of body j at body snapshot k; *cp the closest core point. */
double fluid_core_dist(const lahar_case *c, const lahar_check_data *d, int j, int64_t k, vec3 p, vec3 *cp)
{
    double x[3], q[4];
    fluid_pose(c, d, j, k, x, q);
    int feature;
    return geom_point_body_core(&c->bodies[j].shape, x, q, p, cp, &feature);
}

/* 1 when p lies inside the closed core of body j at output k (geom_point_in_core). Tells a
 * particle that went deep into a body from one merely far from its surface
 * (geom_point_body_core gives an unsigned distance). */
int fluid_inside_core(const lahar_case *c, const lahar_check_data *d, int j, int64_t k, vec3 p)
{
    double x[3], q[4];
    fluid_pose(c, d, j, k, x, q);
    return geom_point_in_core(&c->bodies[j].shape, c->bodies[j].convex, c->dim, x, q, p);
}

/* How deep p lies inside the swept solid of body j at body snapshot k (negative: outside):
 * R - distance to the core, or R + distance when p is inside a closed convex core. */
double fluid_depth(const lahar_case *c, const lahar_check_data *d, int j, int64_t k, vec3 p)
{
    double dist = fluid_core_dist(c, d, j, k, p, NULL), R = c->bodies[j].shape.radius;
    return fluid_inside_core(c, d, j, k, p) ? R + dist : R - dist;
}

/* fluid_depth(c, d, j, k, p) > level; for a body with a feature grid visiting only the features
 * within R - level of p: the same answer (the nearest feature is among them whenever the depth
 * can exceed the level), for the tests every particle of every snapshot makes against a terrain. */
int fluid_deeper_than(const lahar_case *c, const lahar_check_data *d, int j, int64_t k, vec3 p, double level)
{
    const double R = c->bodies[j].shape.radius;
    if (fluid_inside_core(c, d, j, k, p))
        return fluid_depth(c, d, j, k, p) > level;
    if (!(R - level > 0.0))
        return 0; /* outside the core the depth is R - distance <= R */
    double x[3], q[4];
    fluid_pose(c, d, j, k, x, q);
    const double dist = geom_body_grids_core(&d->grids, j, &c->bodies[j].shape, x, q, p, R - level, NULL, NULL);
    return dist != DBL_MAX && R - dist > level;
}

/* Unit vector "up" (against gravity) and horizontal unit vectors e1 (and e2 in 3D). */
int fluid_frame(const lahar_case *c, vec3 *up, vec3 *e1, vec3 *e2)
{
    vec3 g = v3_load(c->gravity);
    if (v3_norm(g) <= 0.0)
        return -1;
    *up = v3_scale(g, -1.0 / v3_norm(g));
    if (c->dim == 2) {
        *e1 = v3_normalize(v3(up->y, -up->x, 0.0));
        if (e1->x < 0.0)
            *e1 = v3_neg(*e1);
        *e2 = v3(0, 0, 0);
    } else {
        vec3 ax = fabs(up->x) < 0.9 ? v3(1, 0, 0) : v3(0, 1, 0);
        *e1 = v3_normalize(v3_sub(ax, v3_scale(*up, v3_dot(ax, *up))));
        *e2 = v3_cross(*up, *e1);
    }
    return 0;
}

/* Free-surface level of the particles in the buffers (see the top of the file), skipping those
 * whose e1 coordinate lies in [skip_lo, skip_hi] (e.g. under a floating body). Returns the
 * number of columns (0: no particles or out of memory), the level, and min/max of the column
 * tops. */
int fluid_surface(const lahar_check_particles *p, int dim, vec3 up, vec3 e1, vec3 e2, double dx,
                  double skip_lo, double skip_hi, fluid_columns *col, double *level, double *top_min,
                  double *top_max)
{
    double lo1 = INFINITY, hi1 = -INFINITY, lo2 = INFINITY, hi2 = -INFINITY;
    for (int64_t i = 0; i < p->cur_n; i++) {
        vec3 x = fluid_pos(p, i);
        double s1 = v3_dot(x, e1), s2 = dim == 3 ? v3_dot(x, e2) : 0.0;
        lo1 = fmin(lo1, s1), hi1 = fmax(hi1, s1), lo2 = fmin(lo2, s2), hi2 = fmax(hi2, s2);
    }
    if (p->cur_n == 0 || dx <= 0.0)
        return 0;
    /* columns centred on the lowest particle's coordinate: on a lattice the particles sit at the
     * column centres, not on the column edges where rounding would put part of a lattice column
     * into its neighbour and leave a column without its top particle */
    int64_t n1 = (int64_t)floor((hi1 - lo1) / dx + 0.5) + 1, n2 = dim == 3 ? (int64_t)floor((hi2 - lo2) / dx + 0.5) + 1 : 1;
    if ((size_t)(n1 * n2) > col->cap) {
        size_t cap = col->cap ? 2 * col->cap : 1024;
        while (cap < (size_t)(n1 * n2))
            cap *= 2;
        double *t = realloc(col->top, cap * sizeof *t);
        if (!t)
            return 0;
        col->top = t, col->cap = cap;
    }
    double *top = col->top;
    for (int64_t b = 0; b < n1 * n2; b++)
        top[b] = -INFINITY;
    for (int64_t i = 0; i < p->cur_n; i++) {
        vec3 x = fluid_pos(p, i);
        double s1 = v3_dot(x, e1);
        if (s1 >= skip_lo && s1 <= skip_hi)
            continue;
        int64_t b1 = (int64_t)floor((s1 - lo1) / dx + 0.5),
                b2 = dim == 3 ? (int64_t)floor((v3_dot(x, e2) - lo2) / dx + 0.5) : 0;
        b1 = b1 < 0 ? 0 : (b1 >= n1 ? n1 - 1 : b1);
        b2 = b2 < 0 ? 0 : (b2 >= n2 ? n2 - 1 : b2);
        top[b2 * n1 + b1] = fmax(top[b2 * n1 + b1], v3_dot(x, up));
    }
    int nc = 0;
    double sum = 0.0;
    *top_min = INFINITY, *top_max = -INFINITY;
    for (int64_t b = 0; b < n1 * n2; b++) {
        if (top[b] == -INFINITY)
            continue;
        nc++, sum += top[b];
        *top_min = fmin(*top_min, top[b]), *top_max = fmax(*top_max, top[b]);
    }
    if (nc)
        *level = sum / nc + 0.5 * dx;
    return nc;
}

/* Where the late window of the times t[0, n) starts (see the top of the file; n > 0). */
double fluid_late_from(const double *t, int64_t n) { return lahar_check_late_from(t, n, 0.1); }

/* First index of the late window of the times t[0, n): the last one and the run of those before it
 * that are in the window (0 when n = 0). */
static int64_t fluid_late_start(const double *t, int64_t n)
{
    if (n == 0)
        return 0;
    double from = fluid_late_from(t, n);
    int64_t k = n - 1;
    while (k > 0 && t[k - 1] >= from)
        k--;
    return k;
}

/* First row of the late window of the force stream. */
int64_t fluid_late_row(const lahar_check_data *d) { return fluid_late_start(d->ft, d->nrow); }

/* First particle snapshot of the late window. */
int64_t fluid_late_snapshot(const lahar_check_particles *p) { return fluid_late_start(p->t, p->nsnap); }

static double fluid_force(const lahar_check_data *d, int64_t row, int j, vec3 dir)
{
    return v3_dot(v3_load(d->force + ((size_t)row * (size_t)d->nbody + (size_t)j) * 3), dir);
}

/* Mean force on body j along dir over rows [k0, nrow). */
double fluid_force_mean(const lahar_check_data *d, int64_t k0, int j, vec3 dir)
{
    double s = 0.0;
    for (int64_t k = k0; k < d->nrow; k++)
        s += fluid_force(d, k, j, dir);
    return d->nrow > k0 ? s / (double)(d->nrow - k0) : NAN;
}

/* Plot a force history: block means of at most ~600 points, divided by `scale`. */
void fluid_plot_force(lahar_check_result *r, int panel, const lahar_check_data *d, int j, vec3 dir,
                      double scale, const char *label)
{
    if (lahar_check_curve(r, panel, 1, label))
        return;
    int64_t blk = d->nrow / 600 + 1;
    for (int64_t k0 = 0; k0 < d->nrow; k0 += blk) {
        int64_t k1 = k0 + blk < d->nrow ? k0 + blk : d->nrow;
        double s = 0.0, ts = 0.0;
        for (int64_t k = k0; k < k1; k++)
            s += fluid_force(d, k, j, dir), ts += d->ft[k];
        lahar_check_point(r, ts / (double)(k1 - k0), s / (double)(k1 - k0) / scale);
    }
}

/* Index of the body snapshot closest in time to t (-1 when none is within tol). */
int64_t fluid_body_snapshot(const lahar_check_data *d, double t, double tol)
{
    int64_t best = -1;
    double bd = INFINITY;
    for (int64_t k = 0; k < d->nsnap; k++)
        if (fabs(d->t[k] - t) < bd)
            bd = fabs(d->t[k] - t), best = k;
    return bd <= tol ? best : -1;
}

int fluid_first_free(const lahar_case *c)
{
    for (int j = 0; j < c->nbody; j++)
        if (c->bodies[j].motion == LAHAR_MOTION_FREE)
            return j;
    return -1;
}
