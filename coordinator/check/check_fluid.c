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
 *    cell of size dx; the lattice of a block puts its top row dx/2 below the block's top). */
#include <inttypes.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "check.h"
#include "geometry.h"
#include "output.h"
#include "vec.h"

/* ---------------------------------------------------------------- helpers --------------- */

/* Acceleration driving the fluid: gravity plus the fluid-only body force. */
static vec3 fluid_accel(const lahar_case *c) { return v3_add(v3_load(c->gravity), v3_load(c->sph.body_force)); }

static double fluid_dx(const lahar_case *c, const lahar_check_data *d)
{
    return c->sph_dx > 0.0 ? c->sph_dx : (d->particles ? d->particles->dx : 0.0);
}

static vec3 fluid_pos(const lahar_check_particles *p, int64_t i) { return v3(p->x[i], p->y[i], p->z[i]); }
static vec3 fluid_vel(const lahar_check_particles *p, int64_t i) { return v3(p->vx[i], p->vy[i], p->vz[i]); }

/* The particles must be there with the fields `need` (LAHAR_PFIELD_* bits). */
static int fluid_need(const lahar_check_data *d, unsigned need, const char *who, lahar_check_result *r)
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

static int fluid_read(const lahar_check_data *d, int64_t k, lahar_check_result *r)
{
    return lahar_check_particles_read(d->particles, k, r->err, sizeof r->err);
}

/* Pose of body j at body snapshot k (fixed bodies: their own world-frame geometry). */
static void fluid_pose(const lahar_case *c, const lahar_check_data *d, int j, int64_t k, double x[3], double q[4])
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
static double fluid_core_dist(const lahar_case *c, const lahar_check_data *d, int j, int64_t k, vec3 p, vec3 *cp)
{
    double x[3], q[4];
    fluid_pose(c, d, j, k, x, q);
    int feature;
    return geom_point_body_core(&c->bodies[j].shape, x, q, p, cp, &feature);
}

/* 1 when p lies inside the closed core of body j at output k (geom_point_in_core). Tells a
 * particle that went deep into a body from one merely far from its surface
 * (geom_point_body_core gives an unsigned distance). */
static int fluid_inside_core(const lahar_case *c, const lahar_check_data *d, int j, int64_t k, vec3 p)
{
    double x[3], q[4];
    fluid_pose(c, d, j, k, x, q);
    return geom_point_in_core(&c->bodies[j].shape, c->bodies[j].convex, c->dim, x, q, p);
}

/* How deep p lies inside the swept solid of body j at body snapshot k (negative: outside):
 * R - distance to the core, or R + distance when p is inside a closed convex core. */
static double fluid_depth(const lahar_case *c, const lahar_check_data *d, int j, int64_t k, vec3 p)
{
    double dist = fluid_core_dist(c, d, j, k, p, NULL), R = c->bodies[j].shape.radius;
    return fluid_inside_core(c, d, j, k, p) ? R + dist : R - dist;
}

/* fluid_depth(c, d, j, k, p) > level; for a body with a feature grid visiting only the features
 * within R - level of p: the same answer (the nearest feature is among them whenever the depth
 * can exceed the level), for the tests every particle of every snapshot makes against a terrain. */
static int fluid_deeper_than(const lahar_case *c, const lahar_check_data *d, int j, int64_t k, vec3 p, double level)
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
static int fluid_frame(const lahar_case *c, vec3 *up, vec3 *e1, vec3 *e2)
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

/* Column tops of fluid_surface, kept across snapshots (grown by doubling, freed by the caller). */
typedef struct {
    double *top;
    size_t cap;
} fluid_columns;

/* Free-surface level of the particles in the buffers (see the top of the file), skipping those
 * whose e1 coordinate lies in [skip_lo, skip_hi] (e.g. under a floating body). Returns the
 * number of columns (0: no particles or out of memory), the level, and min/max of the column
 * tops. */
static int fluid_surface(const lahar_check_particles *p, int dim, vec3 up, vec3 e1, vec3 e2, double dx,
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
static double fluid_late_from(const double *t, int64_t n) { return lahar_check_late_from(t, n, 0.1); }

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
static int64_t fluid_late_row(const lahar_check_data *d) { return fluid_late_start(d->ft, d->nrow); }

/* First particle snapshot of the late window. */
static int64_t fluid_late_snapshot(const lahar_check_particles *p) { return fluid_late_start(p->t, p->nsnap); }

static double fluid_force(const lahar_check_data *d, int64_t row, int j, vec3 dir)
{
    return v3_dot(v3_load(d->force + ((size_t)row * (size_t)d->nbody + (size_t)j) * 3), dir);
}

/* Mean force on body j along dir over rows [k0, nrow). */
static double fluid_force_mean(const lahar_check_data *d, int64_t k0, int j, vec3 dir)
{
    double s = 0.0;
    for (int64_t k = k0; k < d->nrow; k++)
        s += fluid_force(d, k, j, dir);
    return d->nrow > k0 ? s / (double)(d->nrow - k0) : NAN;
}

/* Plot a force history: block means of at most ~600 points, divided by `scale`. */
static void fluid_plot_force(lahar_check_result *r, int panel, const lahar_check_data *d, int j, vec3 dir,
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
static int64_t fluid_body_snapshot(const lahar_check_data *d, double t, double tol)
{
    int64_t best = -1;
    double bd = INFINITY;
    for (int64_t k = 0; k < d->nsnap; k++)
        if (fabs(d->t[k] - t) < bd)
            bd = fabs(d->t[k] - t), best = k;
    return bd <= tol ? best : -1;
}

static int fluid_first_free(const lahar_case *c)
{
    for (int j = 0; j < c->nbody; j++)
        if (c->bodies[j].motion == LAHAR_MOTION_FREE)
            return j;
    return -1;
}

/* ---------------------------------------------------------------- poiseuille ------------ */

/* Series of Morris et al. 1997 eq. 21, terms until the next
 * is below 1e-13 of the steady maximum (the terms decrease monotonically in n). */
double lahar_check_poiseuille_u(double y, double t, double H, double a, double nu)
{
    double u = a / (2.0 * nu) * y * (H - y);
    if (t <= 0.0)
        return 0.0; /* the series sums to the parabola exactly at t = 0 */
    double umax = a * H * H / (8.0 * nu), c = 4.0 * a * H * H / (nu * M_PI * M_PI * M_PI);
    for (int n = 0; n < 200000; n++) {
        double k = 2.0 * n + 1.0, term = c / (k * k * k) * exp(-k * k * M_PI * M_PI * nu * t / (H * H));
        if (term < 1e-13 * umax)
            break;
        u -= term * sin(k * M_PI * y / H);
    }
    return u;
}

/* rho nu du/dy at y = 0 of the same series: rho a H/2 - sum 4 rho a H/(pi^2 (2n+1)^2) e^(...),
 * zero at t = 0 (sum 1/(2n+1)^2 = pi^2/8) and rho a H/2 when steady (Trujillo-Vela et al. 2020 eq. 31-32). */
double lahar_check_poiseuille_wall_stress(double t, double H, double a, double nu, double rho)
{
    double tau = rho * a * H / 2.0;
    if (t <= 0.0)
        return 0.0;
    double c = 4.0 * rho * a * H / (M_PI * M_PI);
    for (int n = 0; n < 200000; n++) {
        double k = 2.0 * n + 1.0, term = c / (k * k) * exp(-k * k * M_PI * M_PI * nu * t / (H * H));
        if (term < 1e-13 * tau)
            break;
        tau -= term;
    }
    return tau;
}

/* Plane Poiseuille flow between two fixed parallel plates (Trujillo-Vela et al. 2020 section 5.1), driven by the
 * acceleration a = |gravity + sph.body_force| along the plates, periodic along the flow.
 *  - H: distance between the plates' swept surfaces, from their geometry (the two fixed bodies
 *    nearest the fluid's centre on opposite sides); y is measured from the lower plate's surface.
 *  - nu = sph.mu / rest density; L = the period along the flow (or the fluid's extent + dx),
 *    W = the period/extent across in 3D (1 in 2D).
 *  - steady_l2_rel_error: at the last snapshot, sqrt(sum (u_i - u(y_i, t))^2 / sum u(y_i, t)^2)
 *    over all particles, u from the transient series at that snapshot's time (the steady
 *    parabola once t >> H^2/nu; info developed_fraction = u_ref max / (a H^2 / 8 nu)).
 *  - transient_l2_rel_error_max: the same, worst over the snapshots where the reference maximum
 *    exceeds 10 % of the steady one.
 *  - plate_force_rel_error: per plate, the late-window mean of the force-stream force along the
 *    flow minus the mean of the series' wall stress tau(t) L W over the same rows, relative to the
 *    steady tau L W = rho a H L W / 2; the worse plate. */

/* What poiseuille measures, step by step (the helpers below fill it in order). */
typedef struct {
    /* the drive and the fluid */
    double a, rho, nu, dx;     /* |gravity + sph.body_force|, density, mu / rho, spacing */
    vec3 ex;                   /* along the flow: the driving acceleration's direction */
    vec3 centre;               /* the fluid's centroid at the first snapshot */
    /* the plates and the channel */
    int lo, hi;                /* the plates' bodies, lo at y = 0 */
    double gap_lo, gap_hi, H;  /* from the centre to each plate's swept surface; H = their sum */
    vec3 ny;                   /* across the channel, from the lower plate up */
    double Lx, W;              /* the period along the flow, the width across (1 in 2D) */
    double umax, tau_s;        /* steady centreline velocity a H^2 / (8 nu), wall stress rho a H / 2 */
    /* the velocity profiles */
    int nb;                    /* bins of about dx across the channel */
    double *bin_u;             /* [nb] sum of u per bin */
    int *bin_n;                /* [nb] particles per bin */
    double l2_last, l2_max, u_meas_max, dev;
    /* the plate forces (NAN without a force stream) */
    double perr, f_lo, f_hi, f_ref;
} poiseuille;

/* The driving acceleration and the fluid's properties: 0, or -1 with r->err. */
static int poiseuille_drive(const lahar_case *c, const lahar_check_data *d, poiseuille *pw, lahar_check_result *r)
{
    if (fluid_need(d, LAHAR_PFIELD_VELOCITY, "poiseuille", r))
        return -1;
    vec3 av = fluid_accel(c);
    double a = v3_norm(av), rho = c->sph_density, mu = c->sph.mu, dx = fluid_dx(c, d);
    if (!(a > 0.0) || !(rho > 0.0) || !(mu > 0.0) || !(dx > 0.0)) {
        snprintf(r->err, sizeof r->err,
                 "poiseuille: needs a driving acceleration (gravity + sph.body_force, got %g), sph.density (%g), "
                 "sph.viscosity mu (%g) and sph.dx (%g) > 0",
                 a, rho, mu, dx);
        return -1;
    }
    pw->a = a, pw->rho = rho, pw->nu = mu / rho, pw->dx = dx;
    pw->ex = v3_scale(av, 1.0 / a);
    return 0;
}

/* The fluid's centroid at the first snapshot (left in the buffers): the plates are found from it. */
static int poiseuille_centre(const lahar_check_data *d, poiseuille *pw, lahar_check_result *r)
{
    const lahar_check_particles *p = d->particles;
    if (fluid_read(d, 0, r))
        return -1;
    vec3 centre = v3(0, 0, 0);
    for (int64_t i = 0; i < p->cur_n; i++)
        centre = v3_add(centre, fluid_pos(p, i));
    pw->centre = v3_scale(centre, 1.0 / (double)(p->cur_n ? p->cur_n : 1));
    return 0;
}

/* The plates: the fixed body nearest the centre, then the nearest one on the opposite side; both
 * parallel to the flow. y = 0 at the plate on the low side of the axes. 0, or -1 with r->err. */
static int poiseuille_plates(const lahar_case *c, const lahar_check_data *d, poiseuille *pw, lahar_check_result *r)
{
    const vec3 centre = pw->centre;
    int lo = -1, hi = -1;
    double gap_lo = INFINITY, gap_hi = INFINITY;
    vec3 ny = v3(0, 0, 0);
    for (int pass = 0; pass < 2; pass++)
        for (int j = 0; j < c->nbody; j++) {
            if (c->bodies[j].motion != LAHAR_MOTION_FIXED)
                continue;
            vec3 cp;
            double gap = fluid_core_dist(c, d, j, -1, centre, &cp) - c->bodies[j].shape.radius;
            vec3 n = v3_normalize(v3_sub(centre, cp));
            if (pass == 0 && gap < gap_lo)
                gap_lo = gap, lo = j, ny = n;
            if (pass == 1 && j != lo && v3_dot(n, ny) < -0.99 && gap < gap_hi)
                gap_hi = gap, hi = j;
        }
    if (lo < 0 || hi < 0 || fabs(v3_dot(ny, pw->ex)) > 1e-6) {
        snprintf(r->err, sizeof r->err,
                 "poiseuille: needs two fixed parallel plates on opposite sides of the fluid, parallel to the driving "
                 "acceleration (found %s%s%s)",
                 lo >= 0 ? c->bodies[lo].name : "none", hi >= 0 ? " and " : "", hi >= 0 ? c->bodies[hi].name : "");
        return -1;
    }
    if (ny.x + ny.y + ny.z < 0.0) { /* y = 0 at the plate on the low side of the axes */
        int tj = lo;
        lo = hi, hi = tj;
        double tg = gap_lo;
        gap_lo = gap_hi, gap_hi = tg;
        ny = v3_neg(ny);
    }
    pw->lo = lo, pw->hi = hi, pw->gap_lo = gap_lo, pw->gap_hi = gap_hi, pw->ny = ny;
    pw->H = gap_lo + gap_hi;
    pw->umax = pw->a * pw->H * pw->H / (8.0 * pw->nu), pw->tau_s = pw->rho * pw->a * pw->H / 2.0;
    return 0;
}

/* The period along the flow and the width across (3D): the periodic box's where an axis lies
 * along them, else the extent of the particles of the first snapshot (in the buffers) + dx. */
static void poiseuille_period(const lahar_case *c, const lahar_check_particles *p, poiseuille *pw)
{
    const vec3 ex = pw->ex, ez = v3_cross(ex, pw->ny);
    double Lx = NAN, W = 1.0;
    for (int ax = 0; ax < 3; ax++) {
        vec3 e = v3(ax == 0, ax == 1, ax == 2);
        if (c->sph.periodic[ax] && fabs(v3_dot(e, ex)) > 0.999)
            Lx = c->sph.hi[ax] - c->sph.lo[ax];
        if (c->dim == 3 && c->sph.periodic[ax] && fabs(v3_dot(e, ez)) > 0.999)
            W = c->sph.hi[ax] - c->sph.lo[ax];
    }
    if (!(Lx > 0.0) || (c->dim == 3 && W == 1.0)) {
        double xlo = INFINITY, xhi = -INFINITY, zlo = INFINITY, zhi = -INFINITY;
        for (int64_t i = 0; i < p->cur_n; i++) {
            vec3 x = fluid_pos(p, i);
            xlo = fmin(xlo, v3_dot(x, ex)), xhi = fmax(xhi, v3_dot(x, ex));
            zlo = fmin(zlo, v3_dot(x, ez)), zhi = fmax(zhi, v3_dot(x, ez));
        }
        if (!(Lx > 0.0))
            Lx = xhi - xlo + pw->dx;
        if (c->dim == 3 && W == 1.0)
            W = zhi - zlo + pw->dx;
    }
    pw->Lx = Lx, pw->W = W;
}

/* The snapshot in the buffers at time t: every particle's velocity along the flow against the
 * series at its height (the relative L2 error, returned) and the profile binned across the
 * channel; on the last snapshot also the largest velocity. */
static double poiseuille_snapshot(const lahar_check_particles *p, double t, int last, poiseuille *pw)
{
    const double H = pw->H;
    const int nb = pw->nb;
    double se = 0.0, sr = 0.0;
    memset(pw->bin_u, 0, (size_t)nb * sizeof *pw->bin_u), memset(pw->bin_n, 0, (size_t)nb * sizeof *pw->bin_n);
    for (int64_t i = 0; i < p->cur_n; i++) {
        vec3 x = fluid_pos(p, i);
        double y = v3_dot(v3_sub(x, pw->centre), pw->ny) + pw->gap_lo, u = v3_dot(fluid_vel(p, i), pw->ex);
        double ur = lahar_check_poiseuille_u(y, t, H, pw->a, pw->nu);
        se += (u - ur) * (u - ur), sr += ur * ur;
        int b = (int)floor(y / H * nb);
        b = b < 0 ? 0 : (b >= nb ? nb - 1 : b);
        pw->bin_u[b] += u, pw->bin_n[b]++;
        if (last)
            pw->u_meas_max = fmax(pw->u_meas_max, u);
    }
    return sr > 0.0 ? sqrt(se / sr) : NAN;
}

/* The binned profile of the last poiseuille_snapshot next to the series at t. */
static void poiseuille_plot_profile(lahar_check_result *r, int pv, const poiseuille *pw, double t)
{
    const double H = pw->H;
    const int nb = pw->nb;
    char label[96];
    snprintf(label, sizeof label, "t = %.4g s", t);
    lahar_check_curve(r, pv, 1, label);
    for (int b = 0; b < nb; b++)
        if (pw->bin_n[b])
            lahar_check_point(r, pw->bin_u[b] / pw->bin_n[b], (b + 0.5) * H / nb);
    snprintf(label, sizeof label, "series t = %.4g s", t);
    lahar_check_curve(r, pv, 0, label);
    for (int s = 0; s <= 100; s++)
        lahar_check_point(r, lahar_check_poiseuille_u(s * H / 100.0, t, H, pw->a, pw->nu), s * H / 100.0);
}

/* The velocity profiles of every snapshot with t > 0 against the transient series (Morris et al.
 * 1997 eq. 21): the steady error at the last snapshot, the worst transient error once the flow
 * has reached 10 % of its steady maximum (before, the relative error divides by ~0), and up to 6
 * profiles spread over the run for the plot (always the last). 0, or -1 with r->err. */
static int poiseuille_profiles(const lahar_check_data *d, poiseuille *pw, lahar_check_result *r)
{
    const lahar_check_particles *p = d->particles;
    const double H = pw->H, umax = pw->umax;
    int nb = (int)lround(H / pw->dx);
    pw->nb = nb = nb < 1 ? 1 : (nb > 400 ? 400 : nb);
    pw->bin_u = calloc((size_t)nb, sizeof *pw->bin_u);
    pw->bin_n = calloc((size_t)nb, sizeof *pw->bin_n);
    if (!pw->bin_u || !pw->bin_n) {
        free(pw->bin_u), free(pw->bin_n);
        snprintf(r->err, sizeof r->err, "out of memory");
        return -1;
    }
    int pv = lahar_check_panel(r, "velocity profiles (markers: lahar, binned by dx; lines: transient series)",
                               "u [m/s]", "y from the lower plate [m]");
    int64_t first = 0;
    while (first < p->nsnap && p->t[first] <= 0.0)
        first++;
    pw->l2_last = NAN, pw->l2_max = 0.0, pw->u_meas_max = 0.0, pw->dev = NAN;
    int nprof = 0, rc = 0;
    for (int64_t k = first; k < p->nsnap; k++) {
        double t = p->t[k], uref_max = lahar_check_poiseuille_u(0.5 * H, t, H, pw->a, pw->nu);
        int last = k == p->nsnap - 1;
        int64_t span = p->nsnap - first, stride = span > 6 ? (span + 5) / 6 : 1;
        int plot = last || ((k - first) % stride == 0 && nprof < 5);
        if (!last && !plot && uref_max < 0.1 * umax)
            continue;
        if (fluid_read(d, k, r)) {
            rc = -1;
            break;
        }
        double l2 = poiseuille_snapshot(p, t, last, pw);
        if (uref_max >= 0.1 * umax)
            pw->l2_max = fmax(pw->l2_max, l2);
        if (last)
            pw->l2_last = l2, pw->dev = uref_max / umax;
        if (plot) {
            poiseuille_plot_profile(r, pv, pw, t);
            nprof++;
        }
    }
    free(pw->bin_u), free(pw->bin_n);
    pw->bin_u = NULL, pw->bin_n = NULL;
    if (rc)
        return -1;
    if (first >= p->nsnap) {
        snprintf(r->err, sizeof r->err, "poiseuille: no particle snapshot after t = 0");
        return -1;
    }
    return 0;
}

/* Each plate's late-window mean force along the flow against the series' wall stress tau(t) L W
 * averaged over the same rows (Trujillo-Vela et al. 2020 eq. 31-32), and their plot; nothing
 * without a force stream. */
static void poiseuille_plate_forces(const lahar_case *c, const lahar_check_data *d, poiseuille *pw,
                                    lahar_check_result *r)
{
    const double H = pw->H, a = pw->a, nu = pw->nu, rho = pw->rho, Lx = pw->Lx, W = pw->W;
    pw->perr = NAN, pw->f_lo = NAN, pw->f_hi = NAN, pw->f_ref = NAN;
    if (d->nrow == 0)
        return;
    int64_t k0 = fluid_late_row(d);
    double LW = Lx * W, sref = 0.0;
    for (int64_t k = k0; k < d->nrow; k++)
        sref += lahar_check_poiseuille_wall_stress(d->ft[k], H, a, nu, rho) * LW;
    pw->f_ref = sref / (double)(d->nrow - k0);
    pw->f_lo = fluid_force_mean(d, k0, pw->lo, pw->ex), pw->f_hi = fluid_force_mean(d, k0, pw->hi, pw->ex);
    pw->perr = fmax(fabs(pw->f_lo - pw->f_ref), fabs(pw->f_hi - pw->f_ref)) / (pw->tau_s * LW);
    int pf = lahar_check_panel(r, "plate force along the flow per unit plate length (= tau W)", "t [s]",
                               "F / L [N/m^2 in 2D, N/m in 3D]");
    char label[96];
    snprintf(label, sizeof label, "%s", c->bodies[pw->lo].name);
    fluid_plot_force(r, pf, d, pw->lo, pw->ex, Lx, label);
    snprintf(label, sizeof label, "%s", c->bodies[pw->hi].name);
    fluid_plot_force(r, pf, d, pw->hi, pw->ex, Lx, label);
    lahar_check_curve(r, pf, 0, "tau(t) W (series), steady rho a H W/2");
    double t0 = d->ft[0], t1 = d->ft[d->nrow - 1];
    for (int s = 0; s <= 200; s++) {
        double t = t0 + (t1 - t0) * s / 200.0;
        lahar_check_point(r, t, lahar_check_poiseuille_wall_stress(t, H, a, nu, rho) * W);
    }
}

/* The metrics and the information values (check.json), the convention, the note and the title. */
static void poiseuille_report(const lahar_case *c, const lahar_check_particles *p, const poiseuille *pw,
                              lahar_check_result *r)
{
    lahar_check_value(r, "steady_l2_rel_error", pw->l2_last);
    lahar_check_value(r, "transient_l2_rel_error_max", pw->l2_max);
    lahar_check_value(r, "plate_force_rel_error", pw->perr);
    lahar_check_value(r, "u_max_measured", pw->u_meas_max);
    lahar_check_value(r, "u_max_steady", pw->umax);
    lahar_check_value(r, "developed_fraction", pw->dev);
    lahar_check_value(r, "plate_force_lower", pw->f_lo);
    lahar_check_value(r, "plate_force_upper", pw->f_hi);
    lahar_check_value(r, "plate_force_reference", pw->f_ref);
    lahar_check_value(r, "plate_force_steady", pw->tau_s * pw->Lx * pw->W);
    lahar_check_value(r, "H", pw->H);
    lahar_check_value(r, "period_L", pw->Lx);
    lahar_check_value(r, "nu", pw->nu);
    lahar_check_value(r, "accel", pw->a);
    lahar_check_value(r, "t_last", p->t[p->nsnap - 1]);
    snprintf(r->convention, sizeof r->convention,
             "u along the driving acceleration, y from the lower plate's surface; plate force per unit plate length "
             "F/L = tau W, tau = rho nu du/dy at the wall");
    snprintf(r->note, sizeof r->note,
             "plates %s (y = 0) and %s; u(y,t): transient series (Morris et al. "
             "1997 eq. 21); plate force: late-window mean along the flow vs tau(t) L W, steady tau = rho a H/2 "
             "(Trujillo-Vela et al. 2020 eq. 31-32)",
             c->bodies[pw->lo].name, c->bodies[pw->hi].name);
    snprintf(r->title, sizeof r->title, "poiseuille: H = %.4g m, a = %.3g m/s^2, nu = %.3g m^2/s", pw->H, pw->a,
             pw->nu);
}

int lahar_check_poiseuille(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r)
{
    poiseuille pw = {0};
    if (poiseuille_drive(c, d, &pw, r) || poiseuille_centre(d, &pw, r) || poiseuille_plates(c, d, &pw, r))
        return -1;
    poiseuille_period(c, d->particles, &pw);
    if (poiseuille_profiles(d, &pw, r))
        return -1;
    poiseuille_plate_forces(c, d, &pw, r);
    poiseuille_report(c, d->particles, &pw, r);
    return 0;
}

/* ---------------------------------------------------------------- cylinder array -------- */

/* Sangani & Acrivos (1982) Table 1, square array . */
static const double sa_c[] = {0.05, 0.10, 0.20, 0.30, 0.40, 0.50, 0.60, 0.70, 0.75};
static const double sa_K[] = {15.56, 24.83, 51.53, 102.90, 217.89, 532.55, 1.763e3, 1.352e4, 1.263e5};
#define SA_N ((int)(sizeof sa_c / sizeof sa_c[0]))

double lahar_check_sangani_acrivos_K(double c)
{
    if (!(c > 0.0) || c > sa_c[SA_N - 1])
        return NAN;
    if (c < sa_c[0]) /* low-c asymptote (Hasimoto 1959, Sangani & Acrivos 1982) */
        return 4.0 * M_PI / (-0.5 * log(c) - 0.738 + c - 0.887 * c * c + 2.038 * c * c * c);
    int i = 0;
    while (i + 2 < SA_N && c > sa_c[i + 1])
        i++;
    double s = (c - sa_c[i]) / (sa_c[i + 1] - sa_c[i]);
    return exp((1.0 - s) * log(sa_K[i]) + s * log(sa_K[i + 1]));
}

/* Periodic square cell with one fixed disc (Trujillo-Vela et al. 2020 section 5.2), flow driven by the
 * acceleration g = |gravity + sph.body_force|: K = rho g L^2 / (mu U_s) with U_s = (1 - c) <u>,
 * <u> the mean particle velocity along g (the particles fill the fluid area uniformly, so it is
 * the fluid-area mean) at the last snapshot, c = pi r^2 / L^2; against Sangani & Acrivos at c. */
int lahar_check_cylinder_array(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r)
{
    if (fluid_need(d, LAHAR_PFIELD_VELOCITY, "cylinder_array", r))
        return -1;
    lahar_check_particles *p = d->particles;
    vec3 gv = fluid_accel(c);
    double g = v3_norm(gv), rho = c->sph_density, mu = c->sph.mu;
    int disc = -1;
    for (int j = 0; j < c->nbody && disc < 0; j++)
        if (c->bodies[j].shape.nv == 1 && c->bodies[j].motion != LAHAR_MOTION_FREE)
            disc = j;
    if (c->dim != 2 || disc < 0 || !c->sph.periodic[0] || !c->sph.periodic[1] || !(g > 0.0) || !(mu > 0.0)) {
        snprintf(r->err, sizeof r->err,
                 "cylinder_array: needs a 2D case periodic in x and y with one fixed disc, a driving acceleration "
                 "(gravity + sph.body_force) and sph.viscosity > 0");
        return -1;
    }
    double Lx = c->sph.hi[0] - c->sph.lo[0], Ly = c->sph.hi[1] - c->sph.lo[1];
    if (fabs(Lx - Ly) > 1e-9 * Lx) {
        snprintf(r->err, sizeof r->err, "cylinder_array: the periodic cell must be square (%g x %g)", Lx, Ly);
        return -1;
    }
    double L = Lx, rad = c->bodies[disc].shape.radius, conc = M_PI * rad * rad / (L * L);
    double K_ref = lahar_check_sangani_acrivos_K(conc);
    if (!isfinite(K_ref)) {
        snprintf(r->err, sizeof r->err, "cylinder_array: solid fraction c = %g outside the table (0, 0.75]", conc);
        return -1;
    }
    vec3 eg = v3_scale(gv, 1.0 / g);
    double Us_ref = rho * g * L * L / (mu * K_ref);
    int pu = lahar_check_panel(r, "superficial velocity U_s = (1 - c) <u>", "t [s]", "U_s [m/s]");
    lahar_check_curve(r, pu, 1, "lahar");
    double Us = NAN, Us_prev = NAN;
    for (int64_t k = 0; k < p->nsnap; k++) {
        if (fluid_read(d, k, r))
            return -1;
        double s = 0.0;
        for (int64_t i = 0; i < p->cur_n; i++)
            s += v3_dot(fluid_vel(p, i), eg);
        Us_prev = Us;
        Us = (1.0 - conc) * s / (double)(p->cur_n ? p->cur_n : 1);
        lahar_check_point(r, p->t[k], Us);
    }
    lahar_check_curve(r, pu, 0, "rho g L^2 / (mu K_SA)");
    lahar_check_point(r, p->t[0], Us_ref);
    lahar_check_point(r, p->t[p->nsnap - 1], Us_ref);
    double K = rho * g * L * L / (mu * Us);
    int pk = lahar_check_panel(r, "K = rho g L^2 / (mu U_s) against Sangani & Acrivos 1982 (square array)",
                               "solid fraction c", "K");
    if (pk >= 0)
        r->panel[pk].ylog = 1;
    lahar_check_curve(r, pk, 0, "Sangani & Acrivos 1982");
    for (int s = 0; s <= 150; s++) {
        double cc = 0.01 + (0.75 - 0.01) * s / 150.0;
        lahar_check_point(r, cc, lahar_check_sangani_acrivos_K(cc));
    }
    lahar_check_curve(r, pk, 1, "lahar");
    lahar_check_point(r, conc, K);
    double F = NAN, F_exp = rho * g * (1.0 - conc) * L * L;
    if (d->nrow > 0)
        F = fluid_force_mean(d, fluid_late_row(d), disc, eg);
    lahar_check_value(r, "K_rel_error", fabs(K - K_ref) / K_ref);
    lahar_check_value(r, "K_measured", K);
    lahar_check_value(r, "K_reference", K_ref);
    lahar_check_value(r, "solid_fraction", conc);
    lahar_check_value(r, "U_superficial", Us);
    lahar_check_value(r, "U_superficial_reference", Us_ref);
    lahar_check_value(r, "U_change_last_snapshot", fabs(Us - Us_prev) / fabs(Us));
    lahar_check_value(r, "disc_force", F);
    lahar_check_value(r, "force_balance_rel_error", fabs(F - F_exp) / F_exp);
    lahar_check_value(r, "K_from_disc_force", F / ((1.0 - conc) * mu * Us));
    snprintf(r->convention, sizeof r->convention,
             "K = rho g L^2 / (mu U_s): F = rho g L^2 (driving force per cell and unit length, body force per fluid "
             "volume times the cell area), U_s = (1 - c) <u>_fluid the superficial velocity (Sangani & Acrivos 1982 "
             "as reproduced by Basilisk)");
    snprintf(r->note, sizeof r->note,
             "disc %s, r = %g m, L = %g m; K interpolated in ln K between tabulated c (low-c asymptote below 0.05); "
             "force balance: at steady state the disc carries the body force on the fluid, rho g (1 - c) L^2",
             c->bodies[disc].name, rad, L);
    snprintf(r->title, sizeof r->title, "cylinder_array: c = %.4g, K = %.4g (Sangani & Acrivos %.4g)", conc, K, K_ref);
    return 0;
}

/* ---------------------------------------------------------------- sphere array ---------- */

/* Zick & Homsy (1982) Table 2, simple cubic array: K = F / (6 pi mu a U) with U the superficial
 * velocity (cases/sphere_array_reference.md). */
static const double zh_c[] = {0.027, 0.064, 0.125, 0.216, 0.343, 0.45, 0.5236};
static const double zh_K[] = {2.008, 2.810, 4.292, 7.442, 15.4, 28.1, 42.1};
#define ZH_N ((int)(sizeof zh_c / sizeof zh_c[0]))

double lahar_check_zick_homsy_K(double c)
{
    if (!(c > 0.0) || c > zh_c[ZH_N - 1])
        return NAN;
    if (c < zh_c[0]) /* dilute series: Hasimoto 1959, Sangani & Acrivos 1982 (K = 2.0087 at 0.027) */
        return 1.0 / (1.0 - 1.7601 * cbrt(c) + c - 1.5593 * c * c);
    int i = 0;
    while (i + 2 < ZH_N && c > zh_c[i + 1])
        i++;
    double s = (c - zh_c[i]) / (zh_c[i + 1] - zh_c[i]);
    return exp((1.0 - s) * log(zh_K[i]) + s * log(zh_K[i + 1]));
}

/* Periodic cubic cell with one fixed sphere, flow driven by the acceleration g = |gravity +
 * sph.body_force| on the fluid: K = rho g L^3 / (6 pi mu a U_s) with U_s = (1 - c) <u>, <u> the
 * mean particle velocity along g at the last snapshot, c = 4 pi a^3 / (3 L^3); against Zick &
 * Homsy (1982) at c. Steady state: U_change_rel = |U_s(t_end) - U_s(3/4 t_end)| / U_s(t_end). */
int lahar_check_sphere_array(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r)
{
    if (fluid_need(d, LAHAR_PFIELD_VELOCITY, "sphere_array", r))
        return -1;
    lahar_check_particles *p = d->particles;
    vec3 gv = fluid_accel(c);
    double g = v3_norm(gv), rho = c->sph_density, mu = c->sph.mu;
    int sph = -1;
    for (int j = 0; j < c->nbody && sph < 0; j++)
        if (c->bodies[j].shape.nv == 1 && c->bodies[j].motion != LAHAR_MOTION_FREE)
            sph = j;
    if (c->dim != 3 || sph < 0 || !c->sph.periodic[0] || !c->sph.periodic[1] || !c->sph.periodic[2] || !(g > 0.0) ||
        !(mu > 0.0)) {
        snprintf(r->err, sizeof r->err,
                 "sphere_array: needs a 3D case periodic in x, y and z with one fixed sphere, a driving acceleration "
                 "(gravity + sph.body_force) and sph.viscosity > 0");
        return -1;
    }
    double L = c->sph.hi[0] - c->sph.lo[0];
    for (int a = 1; a < 3; a++)
        if (fabs(c->sph.hi[a] - c->sph.lo[a] - L) > 1e-9 * L) {
            snprintf(r->err, sizeof r->err, "sphere_array: the periodic cell must be a cube (%g x %g x %g)", L,
                     c->sph.hi[1] - c->sph.lo[1], c->sph.hi[2] - c->sph.lo[2]);
            return -1;
        }
    double rad = c->bodies[sph].shape.radius, conc = 4.0 * M_PI * rad * rad * rad / (3.0 * L * L * L);
    double K_ref = lahar_check_zick_homsy_K(conc);
    if (!isfinite(K_ref)) {
        snprintf(r->err, sizeof r->err, "sphere_array: solid fraction c = %g outside the table (0, 0.5236]", conc);
        return -1;
    }
    vec3 eg = v3_scale(gv, 1.0 / g);
    double drive = rho * g * L * L * L, stokes = 6.0 * M_PI * mu * rad;
    double Us_ref = drive / (stokes * K_ref);
    int pu = lahar_check_panel(r, "superficial velocity U_s = (1 - c) <u>", "t [s]", "U_s [m/s]");
    lahar_check_curve(r, pu, 1, "lahar");
    double Us = NAN, Us_q = NAN, t_end = p->t[p->nsnap - 1], t_q = NAN;
    for (int64_t k = 0; k < p->nsnap; k++) {
        if (fluid_read(d, k, r))
            return -1;
        double s = 0.0;
        for (int64_t i = 0; i < p->cur_n; i++)
            s += v3_dot(fluid_vel(p, i), eg);
        Us = (1.0 - conc) * s / (double)(p->cur_n ? p->cur_n : 1);
        if (p->t[k] <= 0.75 * t_end + 1e-9 * t_end) {
            Us_q = Us;
            t_q = p->t[k];
        }
        lahar_check_point(r, p->t[k], Us);
    }
    lahar_check_curve(r, pu, 0, "rho g L^3 / (6 pi mu a K_ZH)");
    lahar_check_point(r, p->t[0], Us_ref);
    lahar_check_point(r, t_end, Us_ref);
    double K = drive / (stokes * Us);
    int pk = lahar_check_panel(r, "K = rho g L^3 / (6 pi mu a U_s) against Zick & Homsy 1982 (simple cubic)",
                               "solid fraction c", "K");
    if (pk >= 0)
        r->panel[pk].ylog = 1;
    lahar_check_curve(r, pk, 0, "Zick & Homsy 1982 / dilute series (cases/sphere_array_reference.md)");
    for (int s = 0; s <= 150; s++) {
        double cc = 0.002 + (0.5236 - 0.002) * s / 150.0;
        lahar_check_point(r, cc, lahar_check_zick_homsy_K(cc));
    }
    lahar_check_curve(r, pk, 1, "lahar");
    lahar_check_point(r, conc, K);
    double F = NAN, F_exp = drive * (1.0 - conc);
    if (d->nrow > 0)
        F = fluid_force_mean(d, fluid_late_row(d), sph, eg);
    lahar_check_value(r, "K_rel_error", fabs(K - K_ref) / K_ref);
    lahar_check_value(r, "U_change_rel", fabs(Us - Us_q) / fabs(Us));
    lahar_check_value(r, "K_measured", K);
    lahar_check_value(r, "K_reference", K_ref);
    lahar_check_value(r, "solid_fraction", conc);
    lahar_check_value(r, "U_superficial", Us);
    lahar_check_value(r, "U_superficial_reference", Us_ref);
    lahar_check_value(r, "U_change_from_t", t_q);
    lahar_check_value(r, "sphere_force", F);
    lahar_check_value(r, "force_balance_rel_error", fabs(F - F_exp) / F_exp);
    lahar_check_value(r, "K_from_sphere_force", F / ((1.0 - conc) * stokes * Us));
    snprintf(r->convention, sizeof r->convention,
             "K = rho g L^3 / (6 pi mu a U_s): rho g L^3 the driving force per cell (Zick & Homsy's mean pressure "
             "drop), U_s = (1 - c) <u>_fluid the superficial velocity (cases/sphere_array_reference.md)");
    snprintf(r->note, sizeof r->note,
             "sphere %s, a = %g m, L = %g m; K interpolated in ln K between tabulated c; U_change_rel: relative "
             "change of U_s over the last quarter of the run (steady state); force balance: at steady state the "
             "sphere carries the body force on the fluid, rho g (1 - c) L^3",
             c->bodies[sph].name, rad, L);
    snprintf(r->title, sizeof r->title, "sphere_array: c = %.4g, K = %.4g (Zick & Homsy %.4g)", conc, K, K_ref);
    return 0;
}

/* ---------------------------------------------------------------- hydrostatic ----------- */

/* Water at rest in a tank of fixed DEM bodies (2D or 3D), over the late window of the particle
 * snapshots and of the force stream:
 *  - floor: the fixed body under the lowest particle; its surface height y_f. Depth h = free
 *    surface level (mean over the window) - y_f.
 *  - wall_force_rel_error: for every side wall (fixed body other than the floor whose normal
 *    towards the fluid is horizontal and that the fluid reaches, within 2 dx), |F - rho g h^2 W/2|
 *    / (rho g h^2 W/2), F the late-window mean force pushing the wall outwards, W = 1 in 2D or the
 *    fluid's extent along the wall + dx in 3D; the worst wall. The tank's side walls must be
 *    bodies of their own (one body holding floor and walls gets horizontal forces that cancel).
 *  - pressure_l2_rel_error: particle pressures averaged over the window in rows of dx (row mean
 *    p_b at mean height y_b, n_b samples), sqrt(sum n_b (p_b - rho g (level - y_b))^2 /
 *    sum n_b (rho g (level - y_b))^2); pressure_l2_rel_error_interior the same over the rows at
 *    least 3 dx from the floor and from the surface (where kernels are not cut by them).
 *  - free_surface_spread_rel: (highest - lowest column top) / h, mean over the window;
 *    max_speed_rel: largest particle speed at the last snapshot / sqrt(g h) (nothing drifts). */

/* What hydrostatic measures, step by step (the helpers below fill it in order). */
typedef struct {
    double rho, dx, g;
    vec3 up, e1, e2;           /* against gravity; the horizontal directions */
    int64_t kl;                /* the last snapshot */
    vec3 centre;               /* the fluid's centroid at the last snapshot */
    int floor_j;               /* the fixed body under the lowest particle */
    double y_floor;            /* its surface's height */
    fluid_columns cols;
    double tmax;               /* the highest column top at the last snapshot */
    /* the late window: pressures in rows of dx above the floor */
    int nb;
    double *bp, *by;           /* [nb] sums of the pressures and the heights of a row's samples */
    int64_t *bn;               /* [nb] its samples */
    double level_sum, spread_sum, vmax;
    int nwin;
    double level, h;           /* the window's mean free-surface level, the depth above the floor */
    double se, sr, sei, sri;   /* sums of the pressure errors and references (all rows, interior) */
    /* the side walls */
    double werr, wforce, wref; /* the worst wall's relative error, its force and reference per width */
    int nwall;
} hydrostatic;

static void hydrostatic_free(hydrostatic *hs)
{
    free(hs->bp), free(hs->by), free(hs->bn), free(hs->cols.top);
    hs->bp = hs->by = NULL, hs->bn = NULL, hs->cols.top = NULL;
}

/* The fields, gravity's frame and dx: 0, or -1 with r->err. */
static int hydrostatic_frame(const lahar_case *c, const lahar_check_data *d, hydrostatic *hs, lahar_check_result *r)
{
    if (fluid_need(d, LAHAR_PFIELD_PRESSURE, "hydrostatic", r))
        return -1;
    hs->rho = c->sph_density, hs->dx = fluid_dx(c, d), hs->g = v3_norm(v3_load(c->gravity));
    if (fluid_frame(c, &hs->up, &hs->e1, &hs->e2) || !(hs->dx > 0.0)) {
        snprintf(r->err, sizeof r->err, "hydrostatic: needs gravity and sph.dx > 0");
        return -1;
    }
    return 0;
}

/* At the last snapshot (left in the buffers): the fluid's centroid, the floor (the fixed body
 * whose surface faces up under the lowest particle) and the height of the free surface's highest
 * column, which sizes the rows. 0, or -1 with r->err. */
static int hydrostatic_floor(const lahar_case *c, const lahar_check_data *d, hydrostatic *hs, lahar_check_result *r)
{
    const lahar_check_particles *p = d->particles;
    const vec3 up = hs->up;
    hs->kl = p->nsnap - 1;
    if (fluid_read(d, hs->kl, r))
        return -1;
    if (p->cur_n == 0) {
        snprintf(r->err, sizeof r->err, "hydrostatic: no particles in the last snapshot");
        return -1;
    }
    int64_t ilow = 0;
    vec3 centre = v3(0, 0, 0);
    for (int64_t i = 0; i < p->cur_n; i++) {
        if (v3_dot(fluid_pos(p, i), up) < v3_dot(fluid_pos(p, ilow), up))
            ilow = i;
        centre = v3_add(centre, fluid_pos(p, i));
    }
    hs->centre = v3_scale(centre, 1.0 / (double)p->cur_n);
    int floor_j = -1;
    double best = INFINITY, y_floor = 0.0;
    for (int j = 0; j < c->nbody; j++) {
        if (c->bodies[j].motion != LAHAR_MOTION_FIXED)
            continue;
        vec3 cp, x = fluid_pos(p, ilow);
        double gap = fluid_core_dist(c, d, j, -1, x, &cp) - c->bodies[j].shape.radius;
        vec3 n = v3_normalize(v3_sub(x, cp));
        if (v3_dot(n, up) > 0.9 && gap < best)
            best = gap, floor_j = j, y_floor = v3_dot(v3_axpy(c->bodies[j].shape.radius, n, cp), up);
    }
    hs->floor_j = floor_j, hs->y_floor = y_floor;
    double level = 0.0, tmin = 0.0;
    hs->tmax = 0.0;
    if (floor_j < 0 ||
        !fluid_surface(p, c->dim, up, hs->e1, hs->e2, hs->dx, INFINITY, -INFINITY, &hs->cols, &level, &tmin,
                       &hs->tmax)) {
        snprintf(r->err, sizeof r->err, "hydrostatic: no fixed floor under the fluid");
        return -1;
    }
    return 0;
}

/* The snapshot k in the buffers: its particles' pressures and heights into the rows; on the last
 * snapshot also the largest speed (when the velocities are there). */
static void hydrostatic_bin_snapshot(const lahar_check_particles *p, int64_t k, hydrostatic *hs)
{
    for (int64_t i = 0; i < p->cur_n; i++) {
        double y = v3_dot(fluid_pos(p, i), hs->up);
        int b = (int)floor((y - hs->y_floor) / hs->dx);
        b = b < 0 ? 0 : (b >= hs->nb ? hs->nb - 1 : b);
        hs->bp[b] += p->pressure[i], hs->by[b] += y, hs->bn[b]++;
        if (p->vx && k == hs->kl)
            hs->vmax = fmax(hs->vmax, v3_norm(fluid_vel(p, i)));
    }
}

/* Late-window snapshots (latest first): the mean level and its spread, and the pressures binned
 * by height (rows of dx above the floor) and averaged over the window, so that the column's
 * start-up oscillation averages out as it does in the wall force. 0, or -1 with r->err. */
static int hydrostatic_window(const lahar_case *c, const lahar_check_data *d, hydrostatic *hs,
                              lahar_check_result *r)
{
    const lahar_check_particles *p = d->particles;
    int nb = (int)ceil((hs->tmax - hs->y_floor) / hs->dx) + 4;
    hs->nb = nb = nb < 1 ? 1 : (nb > 4000 ? 4000 : nb);
    hs->bp = calloc((size_t)nb, sizeof *hs->bp), hs->by = calloc((size_t)nb, sizeof *hs->by);
    hs->bn = calloc((size_t)nb, sizeof *hs->bn);
    if (!hs->bp || !hs->by || !hs->bn) {
        snprintf(r->err, sizeof r->err, "out of memory");
        return -1;
    }
    const int64_t k0 = fluid_late_snapshot(p);
    double level = 0.0, tmin = 0.0, tmax = 0.0;
    for (int64_t k = hs->kl; k >= k0; k--) {
        if (fluid_read(d, k, r))
            return -1;
        if (!fluid_surface(p, c->dim, hs->up, hs->e1, hs->e2, hs->dx, INFINITY, -INFINITY, &hs->cols, &level, &tmin,
                           &tmax))
            continue;
        hs->level_sum += level, hs->spread_sum += tmax - tmin, hs->nwin++;
        hydrostatic_bin_snapshot(p, k, hs);
    }
    hs->level = hs->level_sum / (hs->nwin ? hs->nwin : 1);
    hs->h = hs->level - hs->y_floor;
    return 0;
}

/* The rows' mean pressures against rho g (level - y): over every row, and over the interior rows
 * at least 3 dx from the floor and from the surface (where the kernels are not cut by them). */
static void hydrostatic_pressure_profile(hydrostatic *hs, lahar_check_result *r)
{
    const double rho = hs->rho, g = hs->g, level = hs->level, y_floor = hs->y_floor, dx = hs->dx;
    double se = 0.0, sr = 0.0, sei = 0.0, sri = 0.0;
    int pp = lahar_check_panel(r, "pressure, late-window mean per row of dx", "p [Pa]", "height above the floor [m]");
    lahar_check_curve(r, pp, 1, "lahar");
    for (int b = 0; b < hs->nb; b++) {
        if (!hs->bn[b])
            continue;
        const double n = (double)hs->bn[b];
        double pm = hs->bp[b] / n, ym = hs->by[b] / n, pr = rho * g * (level - ym);
        se += n * (pm - pr) * (pm - pr), sr += n * pr * pr;
        if (ym - y_floor >= 3.0 * dx && level - ym >= 3.0 * dx)
            sei += n * (pm - pr) * (pm - pr), sri += n * pr * pr;
        lahar_check_point(r, pm, ym - y_floor);
    }
    lahar_check_curve(r, pp, 0, "rho g (h - y)");
    lahar_check_point(r, rho * g * hs->h, 0.0);
    lahar_check_point(r, 0.0, hs->h);
    hs->se = se, hs->sr = sr, hs->sei = sei, hs->sri = sri;
}

/* Side wall j at the last snapshot (in the buffers): its outward horizontal normal and its width
 * W (1 in 2D, the fluid's extent along it + dx in 3D) into *n, *W; 0 when j is no side wall (its
 * normal towards the fluid is not horizontal, or the fluid does not reach it within 2 dx). */
static int hydrostatic_side_wall(const lahar_case *c, const lahar_check_data *d, const hydrostatic *hs, int j,
                                 vec3 *n_out, double *W)
{
    const lahar_check_particles *p = d->particles;
    const vec3 up = hs->up;
    vec3 cp;
    fluid_core_dist(c, d, j, -1, hs->centre, &cp);
    vec3 n = v3_normalize(v3_sub(hs->centre, cp));
    if (fabs(v3_dot(n, up)) > 0.1)
        return 0;
    n = v3_normalize(v3_sub(n, v3_scale(up, v3_dot(n, up))));
    double near = INFINITY, tlo = INFINITY, thi = -INFINITY;
    vec3 et = v3_cross(up, n);
    for (int64_t i = 0; i < p->cur_n; i++) {
        vec3 x = fluid_pos(p, i);
        near = fmin(near, fluid_core_dist(c, d, j, -1, x, NULL) - c->bodies[j].shape.radius);
        tlo = fmin(tlo, v3_dot(x, et)), thi = fmax(thi, v3_dot(x, et));
    }
    if (near > 2.0 * hs->dx)
        return 0;
    *n_out = n;
    *W = c->dim == 3 ? thi - tlo + hs->dx : 1.0;
    return 1;
}

/* Every side wall's late-window mean force pushing it outwards against rho g h^2 W / 2; the worst
 * wall is kept. 0, or -1 with r->err when there is none (no force stream, or the walls are not
 * bodies of their own: one body holding floor and walls gets horizontal forces that cancel). */
static int hydrostatic_side_walls(const lahar_case *c, const lahar_check_data *d, hydrostatic *hs,
                                  lahar_check_result *r)
{
    if (fluid_read(d, hs->kl, r))
        return -1;
    const double rho = hs->rho, g = hs->g, h = hs->h;
    hs->werr = NAN, hs->wforce = NAN, hs->wref = NAN, hs->nwall = 0;
    if (d->nrow > 0) {
        int64_t k0 = fluid_late_row(d);
        int pw = lahar_check_panel(r, "side wall force per unit width", "t [s]", "F / W [N/m]");
        for (int j = 0; j < c->nbody; j++) {
            vec3 n;
            double W;
            if (j == hs->floor_j || c->bodies[j].motion != LAHAR_MOTION_FIXED ||
                !hydrostatic_side_wall(c, d, hs, j, &n, &W))
                continue;
            double ref = 0.5 * rho * g * h * h * W;
            double F = fluid_force_mean(d, k0, j, v3_neg(n)), e = fabs(F - ref) / ref;
            if (hs->nwall == 0 || e > hs->werr)
                hs->werr = e, hs->wforce = F / W, hs->wref = ref / W;
            hs->nwall++;
            fluid_plot_force(r, pw, d, j, v3_neg(n), W, c->bodies[j].name);
        }
        if (hs->nwall > 0) {
            lahar_check_curve(r, pw, 0, "rho g h^2 / 2");
            lahar_check_point(r, d->ft[0], hs->wref);
            lahar_check_point(r, d->ft[d->nrow - 1], hs->wref);
        }
    }
    if (hs->nwall == 0) {
        snprintf(r->err, sizeof r->err,
                 "hydrostatic: no side wall force: needs forces.h5 and side walls as fixed bodies of their own that "
                 "the water touches");
        return -1;
    }
    return 0;
}

/* The metrics and the information values (check.json), the note and the title. */
static void hydrostatic_report(const lahar_case *c, const lahar_check_particles *p, const hydrostatic *hs,
                               lahar_check_result *r)
{
    const double h = hs->h;
    lahar_check_value(r, "wall_force_rel_error", hs->werr);
    lahar_check_value(r, "pressure_l2_rel_error", hs->sr > 0.0 ? sqrt(hs->se / hs->sr) : NAN);
    lahar_check_value(r, "pressure_l2_rel_error_interior", hs->sri > 0.0 ? sqrt(hs->sei / hs->sri) : NAN);
    lahar_check_value(r, "free_surface_spread_rel", hs->spread_sum / (hs->nwin ? hs->nwin : 1) / h);
    if (p->vx)
        lahar_check_value(r, "max_speed_rel", hs->vmax / sqrt(hs->g * h));
    lahar_check_value(r, "depth", h);
    lahar_check_value(r, "wall_force_per_width", hs->wforce);
    lahar_check_value(r, "wall_force_reference", hs->wref);
    lahar_check_value(r, "side_walls", hs->nwall);
    lahar_check_value(r, "t_last", p->t[hs->kl]);
    snprintf(r->note, sizeof r->note,
             "floor %s; h from the free-surface level (mean column top + dx/2); wall force: late-window mean, worst "
             "side wall, reference rho g h^2/2 per unit width",
             c->bodies[hs->floor_j].name);
    snprintf(r->title, sizeof r->title, "hydrostatic: h = %.4g m, worst wall force error %.3g %%", h,
             100.0 * hs->werr);
}

int lahar_check_hydrostatic(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r)
{
    hydrostatic hs = {0};
    if (hydrostatic_frame(c, d, &hs, r) || hydrostatic_floor(c, d, &hs, r) || hydrostatic_window(c, d, &hs, r)) {
        hydrostatic_free(&hs);
        return -1;
    }
    hydrostatic_pressure_profile(&hs, r);
    hydrostatic_free(&hs);
    if (hydrostatic_side_walls(c, d, &hs, r))
        return -1;
    hydrostatic_report(c, d->particles, &hs, r);
    return 0;
}

/* ---------------------------------------------------------------- floating box ---------- */

/* A free box floating in water: draft = free-surface level -
 * lowest point of the box's swept surface, averaged over the late window of the snapshots;
 * reference rho_b h / rho_f with rho_b the box material's density, h its height along gravity
 * (core extent + 2 sweep radius; rounded corners of radius R change the displaced area by
 * (4 - pi) R^2, ignored). The free surface is the level where the water's pressure is zero,
 * extrapolated by a least-squares line p(height) through the particles clear of every body (3 dx)
 * and of the surface and floor (3 dx): Archimedes' draft is the depth at which the hydrostatic
 * pressure carries the box, p = rho_f g d. The column tops + dx/2 (fluid_surface) are reported as
 * draft_columns: on a disordered surface a column without its top particle, and the rows against
 * the walls, move that level by up to dx/4, 2.5 % of this draft at dx = 10 mm.
 * draft_spread_rel: (largest - smallest draft) / reference over the window, how far the heave
 * has settled. */
/* Level where a least-squares line p(height) through the particles of the buffers at least 3 dx
 * from every body (snapshot kb), 3 dx below `level` and 3 dx above the lowest particle, reaches
 * zero; the slope over rho_f g into *gradient. Returns 0, or -1 with fewer than 10 particles. */
static int fluid_pressure_zero_level(const lahar_case *c, const lahar_check_data *d, int64_t kb, vec3 up,
                                     double dx, double level, double *zero, double *gradient)
{
    const lahar_check_particles *p = d->particles;
    double hmin = INFINITY;
    for (int64_t i = 0; i < p->cur_n; i++)
        hmin = fmin(hmin, v3_dot(fluid_pos(p, i), up));
    double sh = 0.0, sp = 0.0, shh = 0.0, shp = 0.0;
    int64_t n = 0;
    for (int64_t i = 0; i < p->cur_n; i++) {
        vec3 x = fluid_pos(p, i);
        double hgt = v3_dot(x, up);
        if (hgt < hmin + 3.0 * dx || hgt > level - 3.0 * dx)
            continue;
        int near = 0;
        for (int j = 0; j < c->nbody && !near; j++)
            near = fluid_deeper_than(c, d, j, c->bodies[j].motion == LAHAR_MOTION_FIXED ? -1 : kb, x, -3.0 * dx);
        if (near)
            continue;
        sh += hgt, sp += p->pressure[i], shh += hgt * hgt, shp += hgt * p->pressure[i], n++;
    }
    double den = n * shh - sh * sh;
    if (n < 10 || !(den > 0.0))
        return -1;
    double a = (n * shp - sh * sp) / den, b = (sp - a * sh) / n; /* p = a h + b */
    if (!(a < 0.0))
        return -1;
    *zero = -b / a;
    *gradient = -a / (c->sph_density * v3_norm(v3_load(c->gravity)));
    return 0;
}

int lahar_check_floating_box(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r)
{
    if (fluid_need(d, LAHAR_PFIELD_PRESSURE, "floating_box", r))
        return -1;
    lahar_check_particles *p = d->particles;
    vec3 up, e1, e2;
    int b = fluid_first_free(c);
    double dx = fluid_dx(c, d), rho_f = c->sph_density;
    if (b < 0 || fluid_frame(c, &up, &e1, &e2) || !(dx > 0.0) || c->bodies[b].shape.nv < 2) {
        snprintf(r->err, sizeof r->err, "floating_box: needs gravity, sph.dx > 0 and a free polygonal body");
        return -1;
    }
    const lahar_body *box = &c->bodies[b];
    int m = box->material;
    double rho_b = m >= 0 && m < c->nmaterial ? c->materials[m].density : NAN, R = box->shape.radius;
    double t0 = p->t[0], t1 = p->t[p->nsnap - 1], from = fluid_late_from(p->t, p->nsnap);
    double tol = c->output_interval > 0.0 ? 0.25 * c->output_interval : 1e-9;
    int pd = lahar_check_panel(r, "draft of the box", "t [s]", "draft [m]");
    lahar_check_curve(r, pd, 1, box->name);
    double sum = 0.0, hb = NAN, d_last = NAN, tilt = 0.0, wmin = INFINITY, wmax = -INFINITY;
    double sum_cols = 0.0, sum_grad = 0.0;
    int nwin = 0;
    fluid_columns cols = {NULL, 0};
    for (int64_t k = 0; k < p->nsnap; k++) {
        int64_t kb = fluid_body_snapshot(d, p->t[k], tol);
        if (kb < 0)
            continue;
        double x[3], q[4];
        fluid_pose(c, d, b, kb, x, q);
        double bot = INFINITY, top = -INFINITY, slo = INFINITY, shi = -INFINITY;
        for (int i = 0; i < box->shape.nv; i++) {
            vec3 v = geom_world_vertex(&box->shape, x, q, i);
            bot = fmin(bot, v3_dot(v, up)), top = fmax(top, v3_dot(v, up));
            slo = fmin(slo, v3_dot(v, e1)), shi = fmax(shi, v3_dot(v, e1));
        }
        if (fluid_read(d, k, r)) {
            free(cols.top);
            return -1;
        }
        double level, tmin, tmax, zero, grad;
        if (!fluid_surface(p, c->dim, up, e1, e2, dx, slo - R - dx, shi + R + dx, &cols, &level, &tmin,
                           &tmax) ||
            fluid_pressure_zero_level(c, d, kb, up, dx, level, &zero, &grad) != 0)
            continue;
        double draft = zero - (bot - R);
        hb = top - bot + 2.0 * R;
        d_last = draft;
        /* rotation angle of the body (2D: about z) */
        tilt = 2.0 * atan2(sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3]), fabs(q[0])) * 180.0 / M_PI;
        lahar_check_point(r, p->t[k], draft);
        if (p->t[k] >= from) {
            sum += draft, nwin++, wmin = fmin(wmin, draft), wmax = fmax(wmax, draft);
            sum_cols += level - (bot - R), sum_grad += grad;
        }
    }
    free(cols.top);
    if (nwin == 0) {
        snprintf(r->err, sizeof r->err,
                 "floating_box: no particle snapshot matches a body snapshot in time (same output interval?) or no "
                 "water beside the box");
        return -1;
    }
    double draft = sum / nwin, d_ref = rho_b * hb / rho_f;
    lahar_check_curve(r, pd, 0, "Archimedes rho_b h / rho_f");
    lahar_check_point(r, t0, d_ref);
    lahar_check_point(r, t1, d_ref);
    lahar_check_value(r, "draft_rel_error", fabs(draft - d_ref) / d_ref);
    lahar_check_value(r, "draft_measured", draft);
    lahar_check_value(r, "draft_last", d_last);
    lahar_check_value(r, "draft_spread_rel", (wmax - wmin) / d_ref);
    lahar_check_value(r, "draft_columns", sum_cols / nwin);
    lahar_check_value(r, "draft_columns_rel_error", fabs(sum_cols / nwin - d_ref) / d_ref);
    lahar_check_value(r, "pressure_gradient_over_rho_g", sum_grad / nwin);
    lahar_check_value(r, "draft_reference", d_ref);
    lahar_check_value(r, "box_height", hb);
    lahar_check_value(r, "box_density", rho_b);
    lahar_check_value(r, "tilt_deg", tilt);
    snprintf(r->note, sizeof r->note,
             "box %s; draft averaged over the snapshots of the last 10 %% of the run (%d); free surface: where the "
             "pressure of the water 3 dx clear of every body extrapolates to zero (draft_columns: mean column top + "
             "dx/2 instead)",
             box->name, nwin);
    snprintf(r->title, sizeof r->title, "floating_box: draft %.4g m (Archimedes %.4g m)", draft, d_ref);
    return 0;
}

/* ---------------------------------------------------------------- sinking disc ---------- */

/* A dense free disc (or sphere) sinking through viscous fluid onto a fixed floor (the fixed body
 * whose surface is under the body's final position).
 *  - floor_penetration [m]: the deepest any particle centre gets inside the floor's swept solid
 *    (R_f - distance to the floor's core, or deeper inside a closed convex core), or the disc's
 *    surface beyond the floor's core (its soft-contact overlap larger than the floor's sweep
 *    radius); 0 in a correct run.
 *  - particle_disc_penetration [m]: the deepest any particle centre gets inside the disc.
 *  - final_speed_rel: speed at the last snapshot / largest speed during the run (at rest: ~0).
 *  - rest_gap_rel: |gap between disc and floor surfaces| / disc radius at the last snapshot (on
 *    the floor: the small contact overlap). Informative: sink_distance, max_speed, rotation_deg
 *    (integral of |omega| dt), max_angular_speed. */
int lahar_check_sinking_disc(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r)
{
    if (fluid_need(d, 0, "sinking_disc", r))
        return -1;
    lahar_check_particles *p = d->particles;
    vec3 up, e1, e2;
    int b = fluid_first_free(c);
    if (b < 0 || fluid_frame(c, &up, &e1, &e2) || d->nsnap < 2) {
        snprintf(r->err, sizeof r->err, "sinking_disc: needs gravity, a free body and >= 2 body snapshots");
        return -1;
    }
    const lahar_body *disc = &c->bodies[b];
    int64_t kl = d->nsnap - 1;
    vec3 xl = v3_load(d->x + ((size_t)kl * (size_t)d->nbody + (size_t)b) * 3);
    int fl = -1;
    double best = INFINITY;
    for (int j = 0; j < c->nbody; j++) {
        if (c->bodies[j].motion != LAHAR_MOTION_FIXED)
            continue;
        vec3 cp;
        double dist = fluid_core_dist(c, d, j, -1, xl, &cp);
        if (v3_dot(v3_normalize(v3_sub(xl, cp)), up) > 0.7 && dist < best)
            best = dist, fl = j;
    }
    if (fl < 0) {
        snprintf(r->err, sizeof r->err, "sinking_disc: no fixed floor under body %s", disc->name);
        return -1;
    }
    const lahar_body *floor_b = &c->bodies[fl];
    double Rf = floor_b->shape.radius, Rd = disc->shape.radius;
    /* the disc's surface: distance of its core to the floor's core minus both radii */
    int pg = lahar_check_panel(r, "gap between the disc and the floor surfaces", "t [s]", "gap [m]");
    lahar_check_curve(r, pg, 1, disc->name);
    double pen = 0.0, vmax = 0.0, wmax = 0.0, rot = 0.0, gap = NAN;
    for (int64_t k = 0; k < d->nsnap; k++) {
        double x[3], q[4];
        fluid_pose(c, d, b, k, x, q);
        double core = geom_body_core_distance(&disc->shape, x, q, &floor_b->shape, floor_b->x, floor_b->q);
        if (disc->shape.nv == 1 && fluid_inside_core(c, d, fl, -1, v3_load(x)))
            core = -fluid_core_dist(c, d, fl, -1, v3_load(x), NULL); /* centre inside the floor's core */
        gap = core - Rd - Rf;
        pen = fmax(pen, Rd - core); /* the disc's surface past the floor's core */
        lahar_check_point(r, d->t[k], gap);
        vec3 v = v3_load(d->v + ((size_t)k * (size_t)d->nbody + (size_t)b) * 3);
        vec3 w = v3_load(d->w + ((size_t)k * (size_t)d->nbody + (size_t)b) * 3);
        vmax = fmax(vmax, v3_norm(v)), wmax = fmax(wmax, v3_norm(w));
        if (k > 0) {
            vec3 w0 = v3_load(d->w + ((size_t)(k - 1) * (size_t)d->nbody + (size_t)b) * 3);
            rot += 0.5 * (v3_norm(w) + v3_norm(w0)) * (d->t[k] - d->t[k - 1]);
        }
    }
    lahar_check_curve(r, pg, 0, "resting on the floor (gap 0)");
    lahar_check_point(r, d->t[0], 0.0);
    lahar_check_point(r, d->t[kl], 0.0);
    double disc_pen = pen, part_pen = 0.0, part_disc = 0.0;
    double tol = c->output_interval > 0.0 ? 0.25 * c->output_interval : 1e-9;
    for (int64_t k = 0; k < p->nsnap; k++) {
        if (fluid_read(d, k, r))
            return -1;
        int64_t kb = fluid_body_snapshot(d, p->t[k], tol);
        for (int64_t i = 0; i < p->cur_n; i++) {
            vec3 x = fluid_pos(p, i);
            part_pen = fmax(part_pen, fluid_depth(c, d, fl, -1, x));
            if (kb >= 0)
                part_disc = fmax(part_disc, fluid_depth(c, d, b, kb, x));
        }
    }
    vec3 v_last = v3_load(d->v + ((size_t)kl * (size_t)d->nbody + (size_t)b) * 3);
    vec3 x0 = v3_load(d->x + (size_t)b * 3);
    lahar_check_value(r, "floor_penetration", fmax(disc_pen, fmax(part_pen, 0.0)));
    lahar_check_value(r, "particle_disc_penetration", part_disc);
    lahar_check_value(r, "final_speed_rel", vmax > 0.0 ? v3_norm(v_last) / vmax : NAN);
    lahar_check_value(r, "rest_gap_rel", fabs(gap) / Rd);
    lahar_check_value(r, "disc_floor_gap", gap);
    lahar_check_value(r, "sink_distance", v3_dot(v3_sub(x0, xl), up));
    lahar_check_value(r, "max_speed", vmax);
    lahar_check_value(r, "max_angular_speed", wmax);
    lahar_check_value(r, "rotation_deg", rot * 180.0 / M_PI);
    lahar_check_value(r, "t_last", d->t[kl]);
    snprintf(r->note, sizeof r->note,
             "body %s on floor %s; penetration: particle centres inside the floor's swept layer, or the body past the "
             "floor's core",
             disc->name, floor_b->name);
    snprintf(r->title, sizeof r->title, "sinking_disc: %s sank %.4g m, final gap %.3g m", disc->name,
             v3_dot(v3_sub(x0, xl), up), gap);
    return 0;
}

/* ---------------------------------------------------------------- dam break ------------- */

/* Martin & Moyce (1952), "An experimental study of the collapse of liquid columns on a rigid
 * horizontal plane", Phil. Trans. R. Soc. Lond. A 244:312-324, Figure 3: surge front Z = z/a
 * (z from the column's back wall, a the column's initial width) against T = t sqrt(2 g / a) for
 * a column of height n^2 a with n^2 = 2, a = 2.25 in. Not in shared/reference: the values are
 * those digitised from the figure in PySPH (github.com/pypr/pysph, pysph/examples/db_exp_data.py,
 * mm_data_2, commit 483e4449f50719350fc2857e8163ea3aae637cc7). */
static const double mm_T[] = {0.832, 1.219, 1.997, 2.547, 3.345, 4.034, 4.418, 5.091,
                              5.685, 6.306, 6.822, 7.439, 8.031, 8.633, 9.237};
static const double mm_Z[] = {1.217, 1.474, 2.292, 2.995, 4.134, 4.944, 5.881, 6.980,
                              7.945, 8.966, 9.986, 10.963, 11.977, 13.005, 13.970};
#define MM_N ((int)(sizeof mm_T / sizeof mm_T[0]))

/* Linear interpolation of the Martin & Moyce front at T (NAN outside the data). */
static double fluid_martin_moyce(double T)
{
    if (T < mm_T[0] || T > mm_T[MM_N - 1])
        return NAN;
    int i = 0;
    while (i + 2 < MM_N && T > mm_T[i + 1])
        i++;
    double s = (T - mm_T[i]) / (mm_T[i + 1] - mm_T[i]);
    return (1.0 - s) * mm_Z[i] + s * mm_Z[i + 1];
}

/* A water column collapsing in a tank of fixed bodies. Metrics that every correct run has:
 *  - mass_change: max over snapshots of |N - N_0| / N_0 (particles have constant mass).
 *  - escaped_particles: the most particles in one snapshot that are inside a body (centre within
 *    a body's swept layer, or inside a closed convex core) or more than dx outside the box around
 *    all fixed bodies, except above it (left the tank; a splash may rise above the walls).
 *  - front_regression: the front (furthest particle along the flow direction: horizontal, from
 *    the column towards the tank's far side) must advance until it reaches its furthest
 *    position; the largest step back before that, in units of dx.
 *  - front_rel_error (only for a column of height 2 x width, Martin & Moyce's n^2 = 2, within
 *    5 %): the largest |Z - Z_MM| / Z_MM over the snapshots inside the data's T range before the
 *    front reaches its furthest position, Z = (front + dx/2 - back of the column at t = 0) / a,
 *    the water's edge being dx/2 beyond the furthest particle (lattice) and the back dx/2 behind
 *    the hindmost one, a the column's initial width (extent + dx).
 *    The experiment's gate opening delays its early front; SPH fronts usually lead slightly.
 * Informative: front_speed_ritter_ratio, the mean front speed until the front has covered half
 * its run, over the Ritter (1892) dry-bed shallow-water front speed 2 sqrt(g H0) (an upper
 * bound for a real front; H0 the initial column height). */

/* What dam_break measures, step by step (the helpers below fill it in order). */
typedef struct {
    double dx, g;
    vec3 up, e1, e2;           /* against gravity; the horizontal directions */
    double blo[3], bhi[3];     /* the box around the fixed bodies' swept surfaces (the tank) */
    /* the column at t = 0 */
    int64_t n0;
    double H0, a_col, back;    /* height, width (extents + dx), the back of the column along ef */
    vec3 ef;                   /* the flow direction: horizontal, from the column to the tank's far side */
    double Tscale;             /* sqrt(2 g / a): Martin & Moyce's time scale */
    /* the snapshots */
    double *front;             /* [nsnap] the furthest particle along ef */
    int64_t escaped;
    double mass;
    /* the front's run */
    double fmaxv, regress, ritter, c_r;
    int64_t khit;              /* the first snapshot where the front is within 2 dx of its furthest */
    int mm;                    /* 1: a column of Martin & Moyce's n^2 = 2 */
    double mm_err;
} dam_break;

/* Gravity's frame and dx: 0, or -1 with r->err. */
static int dam_break_frame(const lahar_case *c, const lahar_check_data *d, dam_break *db, lahar_check_result *r)
{
    if (fluid_need(d, 0, "dam_break", r))
        return -1;
    db->dx = fluid_dx(c, d), db->g = v3_norm(v3_load(c->gravity));
    if (fluid_frame(c, &db->up, &db->e1, &db->e2) || !(db->dx > 0.0)) {
        snprintf(r->err, sizeof r->err, "dam_break: needs gravity and sph.dx > 0");
        return -1;
    }
    return 0;
}

/* The box around the fixed bodies (the tank): 0, or -1 with r->err when there is none. */
static int dam_break_tank(const lahar_case *c, dam_break *db, lahar_check_result *r)
{
    for (int a = 0; a < 3; a++)
        db->blo[a] = INFINITY, db->bhi[a] = -INFINITY;
    int nfixed = 0;
    for (int j = 0; j < c->nbody; j++) {
        const lahar_body *fb = &c->bodies[j];
        if (fb->motion != LAHAR_MOTION_FIXED)
            continue;
        nfixed++;
        for (int i = 0; i < fb->shape.nv; i++) {
            vec3 v = geom_world_vertex(&fb->shape, fb->x, fb->q, i);
            for (int a = 0; a < 3; a++)
                db->blo[a] = fmin(db->blo[a], v3_get(v, a) - fb->shape.radius),
                db->bhi[a] = fmax(db->bhi[a], v3_get(v, a) + fb->shape.radius);
        }
    }
    if (nfixed == 0) {
        snprintf(r->err, sizeof r->err, "dam_break: no fixed bodies (the tank)");
        return -1;
    }
    return 0;
}

/* The column at the first snapshot: its particles, height, the flow direction (towards the
 * tank's centre), its width and back along it. The water's edge is dx/2 beyond the outermost
 * particles (a lattice). 0, or -1 with r->err. */
static int dam_break_column(const lahar_case *c, const lahar_check_data *d, dam_break *db, lahar_check_result *r)
{
    const lahar_check_particles *p = d->particles;
    const double dx = db->dx;
    if (fluid_read(d, 0, r))
        return -1;
    int64_t n0 = p->cur_n;
    vec3 cen = v3(0, 0, 0);
    double ylo = INFINITY, yhi = -INFINITY;
    for (int64_t i = 0; i < n0; i++) {
        vec3 x = fluid_pos(p, i);
        cen = v3_add(cen, x);
        ylo = fmin(ylo, v3_dot(x, db->up)), yhi = fmax(yhi, v3_dot(x, db->up));
    }
    cen = v3_scale(cen, 1.0 / (double)(n0 ? n0 : 1));
    double H0 = yhi - ylo + dx, elo = INFINITY, ehi = -INFINITY;
    const double *blo = db->blo, *bhi = db->bhi;
    vec3 tank_c = v3(0.5 * (blo[0] + bhi[0]), 0.5 * (blo[1] + bhi[1]), c->dim == 3 ? 0.5 * (blo[2] + bhi[2]) : 0.0);
    vec3 ef = v3_dot(v3_sub(tank_c, cen), db->e1) >= 0.0 ? db->e1 : v3_neg(db->e1);
    for (int64_t i = 0; i < n0; i++) {
        double s = v3_dot(fluid_pos(p, i), ef);
        elo = fmin(elo, s), ehi = fmax(ehi, s);
    }
    db->n0 = n0, db->H0 = H0, db->ef = ef;
    db->a_col = ehi - elo + dx, db->back = elo - 0.5 * dx, db->Tscale = sqrt(2.0 * db->g / db->a_col);
    return 0;
}

/* 1 when the particle at x has escaped: more than dx outside the tank's box except above it (the
 * tank is open at the top: splashes may rise above it), or inside a body (fixed, or free at body
 * snapshot kb; -1: none matches the particle snapshot). */
static int dam_break_escaped(const lahar_case *c, const lahar_check_data *d, const dam_break *db, int64_t kb,
                             vec3 x)
{
    const double dx = db->dx;
    int out = 0;
    for (int a = 0; a < c->dim; a++) {
        double ua = v3_get(db->up, a);
        out |= (ua < 0.9 && v3_get(x, a) > db->bhi[a] + dx) || (ua > -0.9 && v3_get(x, a) < db->blo[a] - dx);
    }
    for (int j = 0; j < c->nbody && !out; j++) {
        int fixed = c->bodies[j].motion == LAHAR_MOTION_FIXED;
        if (!fixed && kb < 0)
            continue;
        out |= fluid_deeper_than(c, d, j, fixed ? -1 : kb, x, 0.0);
    }
    return out;
}

/* Every snapshot: the front, the most particles escaped in one snapshot and the largest change of
 * the particle count. 0, or -1 with r->err (the caller frees the front). */
static int dam_break_snapshots(const lahar_case *c, const lahar_check_data *d, dam_break *db, lahar_check_result *r)
{
    const lahar_check_particles *p = d->particles;
    const int64_t n0 = db->n0;
    double tol = c->output_interval > 0.0 ? 0.25 * c->output_interval : 1e-9;
    db->mass = 0.0, db->front = malloc((size_t)p->nsnap * sizeof *db->front);
    db->escaped = 0;
    if (!db->front) {
        snprintf(r->err, sizeof r->err, "out of memory");
        return -1;
    }
    for (int64_t k = 0; k < p->nsnap; k++) {
        if (fluid_read(d, k, r))
            return -1;
        int64_t kb = fluid_body_snapshot(d, p->t[k], tol), esc = 0;
        double fr = -INFINITY;
        for (int64_t i = 0; i < p->cur_n; i++) {
            vec3 x = fluid_pos(p, i);
            fr = fmax(fr, v3_dot(x, db->ef));
            esc += dam_break_escaped(c, d, db, kb, x);
        }
        db->escaped = esc > db->escaped ? esc : db->escaped;
        db->mass = fmax(db->mass, fabs((double)(p->cur_n - n0)) / (double)(n0 ? n0 : 1));
        db->front[k] = fr;
    }
    return 0;
}

/* The front's run: its furthest position, the first snapshot near it (khit), the largest step
 * back before (in dx), and the mean speed until it has covered half its run over Ritter's (1892)
 * dry-bed front speed 2 sqrt(g H0). */
static void dam_break_front_run(const lahar_check_particles *p, dam_break *db)
{
    const double *front = db->front, dx = db->dx;
    double fmaxv = -INFINITY;
    for (int64_t k = 0; k < p->nsnap; k++)
        fmaxv = fmax(fmaxv, front[k]);
    double regress = 0.0, run = -INFINITY, ritter = NAN;
    int64_t khit = p->nsnap - 1;
    for (int64_t k = 0; k < p->nsnap; k++)
        if (front[k] >= fmaxv - 2.0 * dx) {
            khit = k;
            break;
        }
    for (int64_t k = 0; k <= khit; k++) {
        run = fmax(run, front[k]);
        regress = fmax(regress, (run - front[k]) / dx);
    }
    double c_r = 2.0 * sqrt(db->g * db->H0);
    for (int64_t k = 1; k <= khit; k++)
        if (front[k] - front[0] >= 0.5 * (fmaxv - front[0]) && p->t[k] > p->t[0]) {
            ritter = (front[k] - front[0]) / (p->t[k] - p->t[0]) / c_r;
            break;
        }
    db->fmaxv = fmaxv, db->khit = khit, db->regress = regress, db->c_r = c_r, db->ritter = ritter;
}

/* For a column of height 2 x width (n^2 = 2, within 5 %): the front Z = z / a against Martin &
 * Moyce's at T = t sqrt(2 g / a) until it reaches its furthest position, and its panel. */
static void dam_break_martin_moyce(const lahar_check_particles *p, dam_break *db, lahar_check_result *r)
{
    const double *front = db->front, dx = db->dx, back = db->back, a_col = db->a_col, Tscale = db->Tscale;
    db->mm = fabs(db->H0 / a_col - 2.0) <= 0.1;
    db->mm_err = NAN;
    if (!db->mm)
        return;
    db->mm_err = 0.0;
    for (int64_t k = 0; k < db->khit; k++) {
        double zr = fluid_martin_moyce((p->t[k] - p->t[0]) * Tscale);
        if (isfinite(zr))
            db->mm_err = fmax(db->mm_err, fabs((front[k] + 0.5 * dx - back) / a_col - zr) / zr);
    }
    int pm = lahar_check_panel(r, "surge front against Martin & Moyce 1952 (n^2 = 2, a = 2.25 in)",
                               "T = t sqrt(2 g / a)", "Z = z / a");
    lahar_check_curve(r, pm, 1, "lahar");
    for (int64_t k = 0; k < p->nsnap; k++)
        lahar_check_point(r, (p->t[k] - p->t[0]) * Tscale, (front[k] + 0.5 * dx - back) / a_col);
    lahar_check_curve(r, pm, 0, "Martin & Moyce 1952 Fig. 3 (as digitised in PySPH)");
    for (int i = 0; i < MM_N; i++)
        lahar_check_point(r, mm_T[i], mm_Z[i]);
}

/* The front's advance next to Ritter's front (an upper bound, capped at the front's run). */
static void dam_break_plot_front(const lahar_check_particles *p, const dam_break *db, lahar_check_result *r)
{
    const double *front = db->front;
    int pf = lahar_check_panel(r, "surge front (furthest particle along the flow)", "t [s]", "front advance [m]");
    lahar_check_curve(r, pf, 1, "lahar");
    for (int64_t k = 0; k < p->nsnap; k++)
        lahar_check_point(r, p->t[k], front[k] - front[0]);
    lahar_check_curve(r, pf, 0, "Ritter 1892 dry bed: 2 sqrt(g H0) t (upper bound)");
    for (int64_t k = 0; k < p->nsnap; k++)
        lahar_check_point(r, p->t[k], fmin(db->c_r * (p->t[k] - p->t[0]), db->fmaxv - front[0]));
}

/* The metrics and the information values (check.json), the note and the title. */
static void dam_break_report(const lahar_check_particles *p, const dam_break *db, lahar_check_result *r)
{
    lahar_check_value(r, "escaped_particles", (double)db->escaped);
    lahar_check_value(r, "mass_change", db->mass);
    lahar_check_value(r, "front_regression", db->regress);
    lahar_check_value(r, "front_speed_ritter_ratio", db->ritter);
    if (db->mm)
        lahar_check_value(r, "front_rel_error", db->mm_err);
    lahar_check_value(r, "column_width", db->a_col);
    lahar_check_value(r, "column_height", db->H0);
    lahar_check_value(r, "particles", (double)db->n0);
    lahar_check_value(r, "t_last", p->t[p->nsnap - 1]);
    snprintf(r->note, sizeof r->note,
             "metrics: particle count conservation, no particle inside a body or out of the tank, a front that only "
             "advances%s; Ritter's 2 sqrt(g H0) is shown as an upper bound",
             db->mm ? ", front vs Martin & Moyce 1952 Fig. 3 n^2 = 2 (values digitised in PySPH db_exp_data.py, not in "
                      "shared/reference)"
                    : "; no Martin & Moyce comparison (needs a column of height 2 x width)");
    snprintf(r->title, sizeof r->title, "dam_break: %" PRId64 " particles, H0 = %.4g m", db->n0, db->H0);
}

int lahar_check_dam_break(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r)
{
    dam_break db = {0};
    if (dam_break_frame(c, d, &db, r) || dam_break_tank(c, &db, r) || dam_break_column(c, d, &db, r))
        return -1;
    if (dam_break_snapshots(c, d, &db, r)) {
        free(db.front);
        return -1;
    }
    dam_break_front_run(d->particles, &db);
    dam_break_martin_moyce(d->particles, &db, r);
    dam_break_plot_front(d->particles, &db, r);
    free(db.front);
    dam_break_report(d->particles, &db, r);
    return 0;
}

/* ---------------------------------------------------------------- lid-driven cavity ----- */

/* Ghia, Ghia & Shin 1982 (J. Comput. Phys. 48:387-411), Re = 100: Table I, u/U along the vertical
 * centreline at heights y/L; Table II, v/U along the horizontal centreline at x/L. The interior
 * points only (the end points are the boundary conditions). Source and the full table:
 * docs/reference/ghia_1982_re100.txt. */
static const double ghia_y[] = {0.9766, 0.9688, 0.9609, 0.9531, 0.8516, 0.7344, 0.6172, 0.5000,
                                0.4531, 0.2813, 0.1719, 0.1016, 0.0703, 0.0625, 0.0547};
static const double ghia_u[] = {0.84123, 0.78871, 0.73722, 0.68717, 0.23151, 0.00332, -0.13641, -0.20581,
                                -0.21090, -0.15662, -0.10150, -0.06434, -0.04775, -0.04192, -0.03717};
static const double ghia_x[] = {0.9688, 0.9609, 0.9531, 0.9453, 0.9063, 0.8594, 0.8047, 0.5000,
                                0.2344, 0.2266, 0.1563, 0.0938, 0.0781, 0.0703, 0.0625};
static const double ghia_v[] = {-0.05906, -0.07391, -0.08864, -0.10313, -0.16914, -0.22445, -0.24533, 0.05454,
                                0.17527, 0.17507, 0.16077, 0.12317, 0.10890, 0.10091, 0.09233};
#define GHIA_NU ((int)(sizeof ghia_y / sizeof ghia_y[0]))
#define GHIA_NV ((int)(sizeof ghia_x / sizeof ghia_x[0]))
#define CAVITY_NPROF 81 /* plotted profile points per centreline */
/* The sample points: Ghia's (u, then v), then the plotted profiles (u, then v). */
#define CAVITY_NPT (GHIA_NU + GHIA_NV + 2 * CAVITY_NPROF)
#define CAVITY_PROF_U (GHIA_NU + GHIA_NV)            /* first point of the plotted u profile */
#define CAVITY_PROF_V (CAVITY_PROF_U + CAVITY_NPROF) /* first point of the plotted v profile */

/* Lid-driven square cavity (2D): the fluid fills a square of side L (the particles' extent at the
 * first snapshot plus dx/2 each side) closed by fixed walls and a lid, the prescribed body moving
 * along +x above it at U = |v|; Re = rho U L / mu must be 100 (within 1 %), Ghia's tables.
 *  - u_max_error / u_l2_error: the velocity u/U along x = L/2 at Ghia's interior heights
 *    (Table I), max and root mean square of |u - u_Ghia| / U; v_max_error / v_l2_error the same
 *    for v/U along y = L/2 (Table II). The particle velocities are sampled at each point by a
 *    Shepard mean with the weight exp(-(r/dx)^2), r < 2 dx, summed over the late window's
 *    snapshots (t >= t_last - 0.1 (t_last - t_first)): the steady state, with the particle noise
 *    averaged out.
 *  - volume_drift: |<V>/V(0) - 1|, <V> the late window's mean of V = sum_i m_i/rho_i with m_i = rho0
 *    dx^2 (the lattice's mass without a hydrostatic start): in a closed box the particles fill the
 *    same area all along, so the total volume their densities claim must stay. Information:
 *    volume_deviation_max, max over the snapshots of |V(t)/V(0) - 1| (the lid's impulsive start
 *    compresses the fluid by a few 1e-3 for about a second: a sound wave, not a drift).
 *  - information: the Reynolds number, V at the end over the box area L^2, mean and max rho/rho0
 *    at the end, the mean u/U of the particles within dx of the lid in its middle half at the end. */

/* What lid_driven_cavity measures, step by step (the helpers below fill it in order). */
typedef struct {
    double dx, rho0, U;        /* spacing, rest density, the lid's speed */
    int lid;                   /* the moving prescribed body */
    double x0, x1, y0, y1, L, Re; /* the box the fluid fills at t = 0, its side, rho0 U L / mu */
    /* the sample points and their Shepard sums over the late window */
    double px[CAVITY_NPT], py[CAVITY_NPT], su[CAVITY_NPT], sw[CAVITY_NPT];
    double val[CAVITY_NPT];    /* the sampled velocity component / U (NAN: no particle within 2 dx) */
    /* the volume sum m/rho over the snapshots, the state at the end */
    double V0, V, dev, Vwin, rho_mean, rho_max, ulid;
    int nwin;
    /* the centreline errors against Ghia's points */
    double umax, u2, vmax, v2;
} cavity;

/* The fields, the lid (moving along +x) and the fluid's properties: 0, or -1 with r->err. */
static int cavity_lid(const lahar_case *c, const lahar_check_data *d, cavity *cv, lahar_check_result *r)
{
    if (fluid_need(d, LAHAR_PFIELD_VELOCITY, "lid_driven_cavity", r))
        return -1;
    if (!(d->particles->fields & LAHAR_PFIELD_DENSITY)) {
        snprintf(r->err, sizeof r->err, "lid_driven_cavity: particles.h5 lacks the density; add density to output: fields");
        return -1;
    }
    cv->dx = fluid_dx(c, d), cv->rho0 = c->sph_density;
    int lid = -1;
    for (int j = 0; j < c->nbody && lid < 0; j++)
        if (c->bodies[j].motion == LAHAR_MOTION_PRESCRIBED && v3_norm(v3_load(c->bodies[j].v)) > 0.0)
            lid = j;
    if (c->dim != 2 || lid < 0 || !(cv->dx > 0.0) || !(c->sph.mu > 0.0) ||
        c->sph.initial_pressure != LAHAR_SPH_INITIAL_PRESSURE_NONE) {
        snprintf(r->err, sizeof r->err,
                 "lid_driven_cavity: needs a 2D case with a moving prescribed body (the lid), sph.viscosity > 0 and "
                 "no hydrostatic start");
        return -1;
    }
    const double *lv = c->bodies[lid].v;
    cv->lid = lid, cv->U = fabs(lv[0]);
    if (!(lv[0] > 0.0) || fabs(lv[1]) > 1e-9 * cv->U) {
        snprintf(r->err, sizeof r->err, "lid_driven_cavity: the lid '%s' must move along +x (velocity %g, %g)",
                 c->bodies[lid].name, lv[0], lv[1]);
        return -1;
    }
    return 0;
}

/* The square the fluid fills at the first snapshot (the particles' extent plus dx/2 each side)
 * under the lid, and its Reynolds number, which Ghia's tables fix at 100. 0, or -1 with r->err. */
static int cavity_box(const lahar_case *c, const lahar_check_data *d, cavity *cv, lahar_check_result *r)
{
    const lahar_check_particles *p = d->particles;
    const double dx = cv->dx;
    if (fluid_read(d, 0, r))
        return -1;
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    for (int64_t i = 0; i < p->cur_n; i++) {
        x0 = fmin(x0, p->x[i]), x1 = fmax(x1, p->x[i]);
        y0 = fmin(y0, p->y[i]), y1 = fmax(y1, p->y[i]);
    }
    x0 -= 0.5 * dx, x1 += 0.5 * dx, y0 -= 0.5 * dx, y1 += 0.5 * dx;
    const double L = x1 - x0, Re = cv->rho0 * cv->U * L / c->sph.mu;
    cv->x0 = x0, cv->x1 = x1, cv->y0 = y0, cv->y1 = y1, cv->L = L, cv->Re = Re;
    if (!(fabs(y1 - y0 - L) < dx) || !(c->bodies[cv->lid].x[1] > y1)) {
        snprintf(r->err, sizeof r->err,
                 "lid_driven_cavity: the fluid must fill a square (%g x %g m) under the lid '%s'", L, y1 - y0,
                 c->bodies[cv->lid].name);
        return -1;
    }
    if (fabs(Re - 100.0) > 1.0) {
        snprintf(r->err, sizeof r->err,
                 "lid_driven_cavity: Ghia et al.'s tables here are for Re = 100; rho U L / mu = %g (U = %g m/s, L = "
                 "%g m)",
                 Re, cv->U, L);
        return -1;
    }
    return 0;
}

/* The sample points: Ghia's interior heights on x = L/2 and abscissae on y = L/2, then the
 * plotted profiles along both centrelines (from dx/2 to L - dx/2); their sums start at 0. */
static void cavity_sample_points(cavity *cv)
{
    const double x0 = cv->x0, y0 = cv->y0, L = cv->L, dx = cv->dx;
    int np = 0;
    for (int k = 0; k < GHIA_NU; k++, np++)
        cv->px[np] = x0 + 0.5 * L, cv->py[np] = y0 + ghia_y[k] * L;
    for (int k = 0; k < GHIA_NV; k++, np++)
        cv->px[np] = x0 + ghia_x[k] * L, cv->py[np] = y0 + 0.5 * L;
    for (int k = 0; k < 2 * CAVITY_NPROF; k++, np++) {
        double s = (0.5 * dx + (L - dx) * (k % CAVITY_NPROF) / (CAVITY_NPROF - 1.0));
        cv->px[np] = k < CAVITY_NPROF ? x0 + 0.5 * L : x0 + s;
        cv->py[np] = k < CAVITY_NPROF ? y0 + s : y0 + 0.5 * L;
    }
    for (int k = 0; k < CAVITY_NPT; k++)
        cv->su[k] = cv->sw[k] = 0.0;
}

/* The snapshot k in the buffers: the volume V = sum m/rho (m = rho0 dx^2, the lattice's mass) and
 * its largest deviation from V(0) so far; the mean and largest density and the mean u/U within dx
 * under the lid's middle half (kept from the last snapshot). */
static void cavity_volume(const lahar_check_particles *p, int64_t k, cavity *cv)
{
    const double m = cv->rho0 * cv->dx * cv->dx, x0 = cv->x0, L = cv->L;
    double s = 0.0, sr = 0.0, rmax = 0.0, sl = 0.0;
    int nl = 0;
    for (int64_t i = 0; i < p->cur_n; i++) {
        s += m / p->density[i];
        sr += p->density[i];
        rmax = fmax(rmax, p->density[i]);
        if (p->y[i] > cv->y1 - cv->dx && fabs(p->x[i] - x0 - 0.5 * L) < 0.25 * L)
            sl += p->vx[i], nl++;
    }
    cv->V = s;
    if (k == 0)
        cv->V0 = cv->V;
    cv->dev = fmax(cv->dev, fabs(cv->V / cv->V0 - 1.0));
    cv->rho_mean = sr / (double)(p->cur_n ? p->cur_n : 1) / cv->rho0;
    cv->rho_max = rmax / cv->rho0;
    cv->ulid = nl ? sl / nl / cv->U : NAN;
}

/* The snapshot in the buffers into the Shepard sums of every sample point (weight exp(-(r/dx)^2),
 * r < 2 dx): u at Ghia's u points and on the plotted u profile, v at the others. */
static void cavity_sample(const lahar_check_particles *p, cavity *cv)
{
    const double dx = cv->dx, R2 = 4.0 * dx * dx;
    for (int64_t i = 0; i < p->cur_n; i++)
        for (int q = 0; q < CAVITY_NPT; q++) {
            const double ddx = p->x[i] - cv->px[q], ddy = p->y[i] - cv->py[q], r2 = ddx * ddx + ddy * ddy;
            if (r2 >= R2)
                continue;
            const double w = exp(-r2 / (dx * dx));
            cv->su[q] += w * (q < GHIA_NU || (q >= CAVITY_PROF_U && q < CAVITY_PROF_V) ? p->vx[i] : p->vy[i]);
            cv->sw[q] += w;
        }
}

/* Every snapshot: the volume (plotted) and the state at the end; the late window's snapshots
 * also into the sample points' sums, the steady state with the particle noise averaged out.
 * 0, or -1 with r->err. */
static int cavity_snapshots(const lahar_check_data *d, cavity *cv, lahar_check_result *r)
{
    const lahar_check_particles *p = d->particles;
    const double twin = fluid_late_from(p->t, p->nsnap);
    cv->V0 = NAN, cv->V = NAN, cv->dev = 0.0, cv->Vwin = 0.0, cv->rho_mean = NAN, cv->rho_max = NAN, cv->ulid = NAN;
    cv->nwin = 0;
    int pv = lahar_check_panel(r, "total volume sum m/rho over the box area L^2", "t [s]", "V / L^2");
    lahar_check_curve(r, pv, 1, "lahar");
    for (int64_t k = 0; k < p->nsnap; k++) {
        if (fluid_read(d, k, r))
            return -1;
        cavity_volume(p, k, cv);
        lahar_check_point(r, p->t[k], cv->V / (cv->L * cv->L));
        if (p->t[k] < twin)
            continue;
        cv->nwin++;
        cv->Vwin += cv->V;
        cavity_sample(p, cv);
    }
    return 0;
}

/* The sampled velocities / U against Ghia et al.'s Tables I and II: max and sums of squares of
 * the errors. 0, or -1 with r->err when a centreline point had no particle near. */
static int cavity_centrelines(cavity *cv, lahar_check_result *r)
{
    for (int q = 0; q < CAVITY_NPT; q++)
        cv->val[q] = cv->sw[q] > 0.0 ? cv->su[q] / cv->sw[q] / cv->U : NAN;
    double umax = 0.0, u2 = 0.0, vmax = 0.0, v2 = 0.0;
    for (int k = 0; k < GHIA_NU; k++) {
        double e = fabs(cv->val[k] - ghia_u[k]);
        umax = fmax(umax, e), u2 += e * e;
    }
    for (int k = 0; k < GHIA_NV; k++) {
        double e = fabs(cv->val[GHIA_NU + k] - ghia_v[k]);
        vmax = fmax(vmax, e), v2 += e * e;
    }
    cv->umax = umax, cv->u2 = u2, cv->vmax = vmax, cv->v2 = v2;
    if (!isfinite(umax + vmax)) {
        snprintf(r->err, sizeof r->err, "lid_driven_cavity: a centreline point has no particle within 2 dx");
        return -1;
    }
    return 0;
}

/* The two centreline profiles next to Ghia's points. */
static void cavity_plot_profiles(const cavity *cv, lahar_check_result *r)
{
    const double x0 = cv->x0, y0 = cv->y0, L = cv->L;
    int pu = lahar_check_panel(r, "u / U along the vertical centreline x = L/2", "u / U", "y / L");
    lahar_check_curve(r, pu, 0, "Ghia, Ghia & Shin 1982, Table I (Re = 100)");
    for (int k = 0; k < GHIA_NU; k++)
        lahar_check_point(r, ghia_u[k], ghia_y[k]);
    lahar_check_curve(r, pu, 1, "lahar (late-window mean)");
    for (int k = 0; k < CAVITY_NPROF; k++)
        lahar_check_point(r, cv->val[CAVITY_PROF_U + k], (cv->py[CAVITY_PROF_U + k] - y0) / L);
    int pw = lahar_check_panel(r, "v / U along the horizontal centreline y = L/2", "x / L", "v / U");
    lahar_check_curve(r, pw, 0, "Ghia, Ghia & Shin 1982, Table II (Re = 100)");
    for (int k = 0; k < GHIA_NV; k++)
        lahar_check_point(r, ghia_x[k], ghia_v[k]);
    lahar_check_curve(r, pw, 1, "lahar (late-window mean)");
    for (int k = 0; k < CAVITY_NPROF; k++)
        lahar_check_point(r, (cv->px[CAVITY_PROF_V + k] - x0) / L, cv->val[CAVITY_PROF_V + k]);
}

/* The metrics and the information values (check.json), the convention, the note and the title. */
static void cavity_report(const lahar_case *c, const cavity *cv, lahar_check_result *r)
{
    const double L = cv->L, Re = cv->Re;
    lahar_check_value(r, "u_max_error", cv->umax);
    lahar_check_value(r, "v_max_error", cv->vmax);
    lahar_check_value(r, "u_l2_error", sqrt(cv->u2 / GHIA_NU));
    lahar_check_value(r, "v_l2_error", sqrt(cv->v2 / GHIA_NV));
    lahar_check_value(r, "volume_drift", fabs(cv->Vwin / cv->nwin / cv->V0 - 1.0));
    lahar_check_value(r, "volume_deviation_max", cv->dev);
    lahar_check_value(r, "volume_end_over_box", cv->V / (L * L));
    lahar_check_value(r, "density_mean_end", cv->rho_mean);
    lahar_check_value(r, "density_max_end", cv->rho_max);
    lahar_check_value(r, "u_under_lid_end", cv->ulid);
    lahar_check_value(r, "reynolds", Re);
    lahar_check_value(r, "window_snapshots", cv->nwin);
    snprintf(r->convention, sizeof r->convention,
             "errors in units of the lid speed U at Ghia et al.'s interior points (docs/reference/"
             "ghia_1982_re100.txt); volume V = sum rho0 dx^2 / rho_i");
    snprintf(r->note, sizeof r->note,
             "lid %s at U = %g m/s, L = %g m, Re = %.4g; profiles: Shepard mean (weight exp(-(r/dx)^2), r < 2 dx) "
             "over %d late-window snapshots",
             c->bodies[cv->lid].name, cv->U, L, Re, cv->nwin);
    snprintf(r->title, sizeof r->title, "lid_driven_cavity: Re = %.4g, max |u - u_Ghia| = %.3g U, max |v - v_Ghia| = %.3g U",
             Re, cv->umax, cv->vmax);
}

int lahar_check_lid_driven_cavity(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r)
{
    cavity cv = {0};
    if (cavity_lid(c, d, &cv, r) || cavity_box(c, d, &cv, r))
        return -1;
    cavity_sample_points(&cv);
    if (cavity_snapshots(d, &cv, r) || cavity_centrelines(&cv, r))
        return -1;
    cavity_plot_profiles(&cv, r);
    cavity_report(c, &cv, r);
    return 0;
}

/* taylor_green: the 2D Taylor-Green vortex on the periodic square [lo, lo + L)^2 (both axes
 * periodic with the same period L, no bodies):
 *   u = -U cos(2 pi x'/L) sin(2 pi y'/L) e^{-8 pi^2 nu t/L^2},  v = U sin(2 pi x'/L) cos(2 pi y'/L) e^{...},
 * x' = x - lo, nu = mu / rho0. The kinetic energy decays as e^{-16 pi^2 nu t / L^2}. Measured at
 * every snapshot: E = rho0 dx^D / 2 sum |v|^2 (the particles' mass taken as rho0 dx^D: the initial
 * pressure changes masses by p/c0^2, below 1e-2 here); U from the first snapshot, U^2 = 2 <|v|^2>.
 * Metrics:
 *   energy_decay_rel_error = |k / k_exact - 1|, k the least-squares slope of -ln(E/E0) over all
 *     snapshots (a line through the origin), k_exact = 16 pi^2 nu / L^2;
 *   velocity_l2_rel_error = sqrt(sum |v - v_exact|^2 / sum |v_exact|^2) at the last snapshot;
 *   density_mean_rel_change = max over snapshots of |mean rho / rho0 - 1|;
 *   volume_rel_change = max over snapshots of |sum (rho0 dx^D / rho_i) / L^2 - 1| (sum m/rho against
 *     the box). */
int lahar_check_taylor_green(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r)
{
    lahar_check_particles *p = d->particles;
    if (fluid_need(d, LAHAR_PFIELD_VELOCITY | LAHAR_PFIELD_DENSITY, "taylor_green", r) != 0)
        return -1;
    const double L = c->sph.hi[0] - c->sph.lo[0];
    if (c->dim != 2 || !c->sph.periodic[0] || !c->sph.periodic[1] || fabs(c->sph.hi[1] - c->sph.lo[1] - L) > 1e-12 * L ||
        p->nsnap < 3 || !p->density) {
        snprintf(r->err, sizeof r->err, "taylor_green: needs a 2D case periodic on x and y with the same period, "
                 ">= 3 snapshots and the fields velocity and density");
        return -1;
    }
    const double rho0 = c->sph_density, nu = c->sph.mu / rho0, dx = fluid_dx(c, d), m0 = rho0 * dx * dx;
    const double k_exact = 16.0 * M_PI * M_PI * nu / (L * L), tw = 2.0 * M_PI / L;
    double E0 = 0.0, U = 0.0, stt = 0.0, sty = 0.0, dmax = 0.0, vmax = 0.0, l2 = 0.0;
    for (int64_t k = 0; k < p->nsnap; k++) {
        if (fluid_read(d, k, r) != 0)
            return -1;
        const double t = p->t[k], dec = exp(-8.0 * M_PI * M_PI * nu * t / (L * L));
        double v2 = 0.0, rho = 0.0, vol = 0.0, e2 = 0.0, x2 = 0.0;
        for (int64_t i = 0; i < p->cur_n; i++) {
            const double vx = p->vx[i], vy = p->vy[i];
            v2 += vx * vx + vy * vy;
            rho += p->density[i];
            vol += m0 / p->density[i];
            if (k == p->nsnap - 1) {
                const double xs = p->x[i] - c->sph.lo[0], ys = p->y[i] - c->sph.lo[1];
                const double ue = -U * cos(tw * xs) * sin(tw * ys) * dec, ve = U * sin(tw * xs) * cos(tw * ys) * dec;
                e2 += (vx - ue) * (vx - ue) + (vy - ve) * (vy - ve);
                x2 += ue * ue + ve * ve;
            }
        }
        const double n = (double)(p->cur_n > 0 ? p->cur_n : 1), E = 0.5 * m0 * v2;
        if (k == 0) {
            E0 = E;
            U = sqrt(2.0 * v2 / n);
        }
        if (!(E0 > 0.0)) {
            snprintf(r->err, sizeof r->err, "taylor_green: the first snapshot has no kinetic energy (initial velocity?)");
            return -1;
        }
        if (k == p->nsnap - 1)
            l2 = x2 > 0.0 ? sqrt(e2 / x2) : INFINITY;
        const double y = -log(E / E0);
        stt += t * t, sty += t * y;
        dmax = fmax(dmax, fabs(rho / n / rho0 - 1.0));
        vmax = fmax(vmax, fabs(vol / (L * L) - 1.0));
        if (r->nseries < LAHAR_CHECK_MAX_SERIES) {
            r->series_t[r->nseries] = t;
            r->series_measured[r->nseries] = E / E0;
            r->series_reference[r->nseries] = exp(-k_exact * t);
            r->nseries++;
        }
    }
    const double k_fit = stt > 0.0 ? sty / stt : 0.0;
    lahar_check_value(r, "energy_decay_rel_error", fabs(k_fit / k_exact - 1.0));
    lahar_check_value(r, "velocity_l2_rel_error", l2);
    lahar_check_value(r, "density_mean_rel_change", dmax);
    lahar_check_value(r, "volume_rel_change", vmax);
    lahar_check_value(r, "energy_decay_rate", k_fit);
    lahar_check_value(r, "energy_decay_rate_exact", k_exact);
    lahar_check_value(r, "reynolds", U * L / nu);
    lahar_check_value(r, "t_last", p->t[p->nsnap - 1]);
    snprintf(r->title, sizeof r->title, "Taylor-Green vortex, Re = %.4g, %lld particles", U * L / nu,
             (long long)p->n[0]);
    snprintf(r->xlabel, sizeof r->xlabel, "t (s)");
    snprintf(r->ylabel, sizeof r->ylabel, "E / E0");
    snprintf(r->convention, sizeof r->convention, "E = rho0 dx^2/2 sum |v|^2; rate fitted over all snapshots, "
             "exact 16 pi^2 nu / L^2; L2 error at t = %.3g s", p->t[p->nsnap - 1]);
    return 0;
}
