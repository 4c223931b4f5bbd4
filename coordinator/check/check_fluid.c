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
 *  - Free-surface level: level gauges on vertical lines at the centres of dx-wide columns, a
 *    kernel support clear of the side walls (the middle column(s) where the water is narrower
 *    than two supports): where the kernel-summed volume fraction sum_j dx^D W(x - x_j) (the
 *    case's kernel and h) falls to 1/2 coming down from above (KERNEL_SURFACE_FRACTION,
 *    common/kernels/kernel.h; the rule of the SPH node's level probes).
 *    On a lattice it reads the top row + dx/2 (a particle stands for a cell of size dx) within
 *    1e-3 dx; where a column lacks its top particle it drops dx/2, not dx as the column's top
 *    particle would, and it reads no column against a wall, where the support is cut (the
 *    surface rows there sit lower by up to dx/4). dx^D for m/rho: the particles near the
 *    surface are at the rest density within (c0 / sqrt(g h))^-2. The level is the gauges' mean,
 *    the spread their range.
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
#include "kernel.h"

/* ---------------------------------------------------------------- helpers --------------- */

static int64_t fluid_clamp(int64_t b, int64_t n) { return b < 0 ? 0 : (b >= n ? n - 1 : b); }

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

void fluid_columns_free(fluid_columns *col)
{
    free(col->top), free(col->bot), free(col->start), free(col->order), free(col->phi);
    *col = (fluid_columns){0};
}

/* The columns of fluid_surface: dx wide along e1 (and e2 in 3D), centred on the lowest particle's
 * coordinate so that on a lattice the particles sit on the column centres, under the gauges. */
typedef struct {
    int dim;
    vec3 up, e1, e2;
    double dx, lo[2], hi[2]; /* the particles' extent along e1, e2 */
    int64_t n[2];            /* columns along e1, e2 (1 in 2D) */
} fluid_grid;

static int64_t fluid_column(const fluid_grid *g, vec3 x)
{
    int64_t b1 = fluid_clamp((int64_t)floor((v3_dot(x, g->e1) - g->lo[0]) / g->dx + 0.5), g->n[0]);
    int64_t b2 = g->dim == 3 ? fluid_clamp((int64_t)floor((v3_dot(x, g->e2) - g->lo[1]) / g->dx + 0.5), g->n[1]) : 0;
    return b2 * g->n[0] + b1;
}

/* The particles of the buffers sorted by column (counting sort into col->start, col->order) with
 * each column's highest and lowest particle along up (col->top, col->bot; -inf/+inf when empty).
 * 0, or -1 out of memory. */
static int fluid_sort_columns(const lahar_check_particles *p, fluid_grid *g, fluid_columns *col)
{
    g->lo[0] = g->lo[1] = INFINITY, g->hi[0] = g->hi[1] = -INFINITY;
    for (int64_t i = 0; i < p->cur_n; i++) {
        vec3 x = fluid_pos(p, i);
        double s1 = v3_dot(x, g->e1), s2 = g->dim == 3 ? v3_dot(x, g->e2) : 0.0;
        g->lo[0] = fmin(g->lo[0], s1), g->hi[0] = fmax(g->hi[0], s1);
        g->lo[1] = fmin(g->lo[1], s2), g->hi[1] = fmax(g->hi[1], s2);
    }
    g->n[0] = (int64_t)floor((g->hi[0] - g->lo[0]) / g->dx + 0.5) + 1;
    g->n[1] = g->dim == 3 ? (int64_t)floor((g->hi[1] - g->lo[1]) / g->dx + 0.5) + 1 : 1;
    const int64_t ncol = g->n[0] * g->n[1];
    if (lahar_check_grow((void **)&col->top, &col->cap_col, (size_t)ncol, sizeof *col->top) ||
        lahar_check_grow((void **)&col->bot, &col->cap_bot, (size_t)ncol, sizeof *col->bot) ||
        lahar_check_grow((void **)&col->start, &col->cap_start, (size_t)ncol + 1, sizeof *col->start) ||
        lahar_check_grow((void **)&col->order, &col->cap_n, (size_t)p->cur_n, sizeof *col->order))
        return -1;
    double *top = col->top, *bot = col->bot;
    int64_t *start = col->start;
    for (int64_t b = 0; b <= ncol; b++)
        start[b] = 0;
    for (int64_t b = 0; b < ncol; b++)
        top[b] = -INFINITY, bot[b] = INFINITY;
    for (int64_t i = 0; i < p->cur_n; i++) {
        vec3 x = fluid_pos(p, i);
        int64_t b = fluid_column(g, x);
        start[b + 1]++;
        top[b] = fmax(top[b], v3_dot(x, g->up)), bot[b] = fmin(bot[b], v3_dot(x, g->up));
    }
    for (int64_t b = 0; b < ncol; b++)
        start[b + 1] += start[b];
    for (int64_t i = 0; i < p->cur_n; i++)
        col->order[start[fluid_column(g, fluid_pos(p, i))]++] = i;
    for (int64_t b = ncol; b > 0; b--) /* back to the first index of each column */
        start[b] = start[b - 1];
    start[0] = 0;
    return 0;
}

/* The level gauge at the centre of column (b1, b2): the kernel-summed volume fraction of the
 * particles of the columns within a support, on the vertical line from their lowest particle to
 * a support above their highest, read from the top. The level along up, NAN when the line finds
 * no surface, -INFINITY out of memory. */
static double fluid_gauge(const lahar_check_particles *p, const fluid_grid *g, const kernel *k, fluid_columns *col,
                          int64_t b1, int64_t b2)
{
    const double S = k->support, dx = g->dx, vol = pow(dx, g->dim), step = 0.1 * dx;
    const double g1 = g->lo[0] + (double)b1 * dx, g2 = g->lo[1] + (double)b2 * dx;
    const int64_t reach = (int64_t)ceil(S / dx), n1 = g->n[0];
    const int64_t a1 = b1 - reach < 0 ? 0 : b1 - reach, z1 = b1 + reach >= n1 ? n1 - 1 : b1 + reach;
    const int64_t a2 = b2 - reach < 0 ? 0 : b2 - reach, z2 = b2 + reach >= g->n[1] ? g->n[1] - 1 : b2 + reach;
    double zt = -INFINITY, zb = INFINITY;
    for (int64_t m2 = a2; m2 <= z2; m2++)
        for (int64_t m1 = a1; m1 <= z1; m1++)
            zt = fmax(zt, col->top[m2 * n1 + m1]), zb = fmin(zb, col->bot[m2 * n1 + m1]);
    const int npt = lahar_check_gauge_line(&col->phi, &col->cap_phi, zb, zt, S, step);
    if (npt < 0)
        return -INFINITY;
    double *phi = col->phi;
    for (int64_t m2 = a2; m2 <= z2; m2++)
        for (int64_t m1 = a1; m1 <= z1; m1++)
            for (int64_t q = col->start[m2 * n1 + m1]; q < col->start[m2 * n1 + m1 + 1]; q++) {
                vec3 x = fluid_pos(p, col->order[q]);
                const double d1 = v3_dot(x, g->e1) - g1, d2 = g->dim == 3 ? v3_dot(x, g->e2) - g2 : 0.0;
                kernel_line_add(k, d1 * d1 + d2 * d2, v3_dot(x, g->up), vol, zb, step, npt, phi);
            }
    return zb + kernel_line_crossing(phi, npt, step, KERNEL_SURFACE_FRACTION, 1);
}

/* Free-surface level of the particles in the buffers (see the top of the file). Gauges stand at
 * the centres of the dx-wide columns, skipping those within a kernel support of the fluid's
 * horizontal extent (the side walls, where the support is cut; the middle column(s) where the
 * fluid is narrower than two supports) or of [skip_lo, skip_hi] along e1 (e.g. a floating body).
 * Returns the number of gauges that found a surface (0: none, out of memory, or no valid
 * sph.kernel), their mean level and its extremes. */
int fluid_surface(const lahar_case *c, const lahar_check_particles *p, vec3 up, vec3 e1, vec3 e2, double dx,
                  double skip_lo, double skip_hi, fluid_columns *col, double *level, double *lmin, double *lmax)
{
    fluid_grid g = {.dim = c->dim, .up = up, .e1 = e1, .e2 = e2, .dx = dx};
    kernel k;
    if (p->cur_n == 0 || !(dx > 0.0) || kernel_init(&k, c->sph.kernel, c->dim, c->sph.h_over_dx * dx) ||
        fluid_sort_columns(p, &g, col))
        return 0;
    const double S = k.support;
    /* the gauges' clearance from the fluid's sides: a support, or where the fluid is narrower
     * than two supports its middle column(s) (a lattice 5 dx wide reads the same there as a wide
     * one within 2e-5 dx: quintic, h = dx, 3D) */
    double m[2];
    for (int a = 0; a < 2; a++)
        m[a] = fmin(S, 0.5 * (g.hi[a] - g.lo[a]) - 1e-6 * dx);
    int ng = 0;
    double sum = 0.0;
    *lmin = INFINITY, *lmax = -INFINITY;
    for (int64_t b2 = 0; b2 < g.n[1]; b2++)
        for (int64_t b1 = 0; b1 < g.n[0]; b1++) {
            const double g1 = g.lo[0] + (double)b1 * dx, g2 = g.lo[1] + (double)b2 * dx;
            if (col->top[b2 * g.n[0] + b1] == -INFINITY || g1 - g.lo[0] + 0.5 * dx < m[0] ||
                g.hi[0] - g1 + 0.5 * dx < m[0] || (g1 > skip_lo - S && g1 < skip_hi + S) ||
                (g.dim == 3 && (g2 - g.lo[1] + 0.5 * dx < m[1] || g.hi[1] - g2 + 0.5 * dx < m[1])))
                continue;
            const double z = fluid_gauge(p, &g, &k, col, b1, b2);
            if (z == -INFINITY)
                return 0;
            if (isnan(z))
                continue;
            ng++, sum += z;
            *lmin = fmin(*lmin, z), *lmax = fmax(*lmax, z);
        }
    if (ng)
        *level = sum / ng;
    return ng;
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
