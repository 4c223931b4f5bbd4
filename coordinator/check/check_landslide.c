/* landslide: a 2D soil mass sliding down a terrain profile (case section terrain:) and
 * depositing on it (Trujillo-Vela et al. 2020 section 5.4, the Yangbaodi landslide; cases/yangbaodi_2d.yaml).
 *
 * The terrain is the fixed body named "terrain" (a polyline whose x increases); its core line
 * y_g(x) (the polyline) and surface y_g(x) + R / cos(slope) (R its sweep radius) come from the case.
 * Metrics and information:
 *   escaped_particles   soil particles below the terrain's core line (through the terrain) at any
 *                       snapshot (bound 0)
 *   mass_change         |n_end - n_0| / n_0, soil particles (equal masses) (bound 0)
 *   deposit_length_m    horizontal extent of the deposit at the end, between the x below which 1 %
 *                       and the x below which 99 % of the soil lies (single particles sprayed
 *                       ahead or left behind do not count), deposit_length_rel_diff its signed
 *                       relative difference to the field's 140 m (Trujillo-Vela et al. 2020 section 5.4)
 *                       and deposit_length_rel_error its absolute value (a metric: the bound is the
 *                       case's; the paper's SPH overestimates the run-out)
 *   runout_m            how far the front (99 % quantile of x) moved; front_x_m where it stopped
 *   deposit_thickness_max_m, deposit_thickness_mean_m  vertical thickness at the end, per column of
 *                       width dx (the highest particle + dx/2 above the terrain's surface), max and
 *                       mean over the columns between the 1 % and 99 % quantiles; the field: 1-5 m;
 *                       deposit_thickness_outside_field_m = max(0, 1 m - mean, max - 5 m) (a metric)
 *   kinetic_energy_rel  kinetic energy of the soil at the end / its largest value (settled: small)
 *   speed_max_m_s       the largest particle speed over the snapshots
 * The deposit's surface against the terrain and the initial mass is drawn in check.png. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "case.h"
#include "check.h"

#define LANDSLIDE_FIELD_LENGTH 140.0 /* m, the Yangbaodi deposit (Trujillo-Vela et al. 2020 section 5.4) */
#define LANDSLIDE_FIELD_THICK_LO 1.0 /* m, its thickness: 1-5 m */
#define LANDSLIDE_FIELD_THICK_HI 5.0

static double terrain_y(const lahar_shape *s, double x)
{
    const int n = s->nv;
    if (x <= s->v[0][0])
        return s->v[0][1];
    for (int i = 1; i < n; i++)
        if (x <= s->v[i][0])
            return s->v[i - 1][1] + (x - s->v[i - 1][0]) / (s->v[i][0] - s->v[i - 1][0]) * (s->v[i][1] - s->v[i - 1][1]);
    return s->v[n - 1][1];
}

/* the terrain's surface above x: the core line raised by R / cos(slope of the segment there) */
static double terrain_surface(const lahar_shape *s, double x)
{
    const int n = s->nv;
    int i = 1;
    while (i < n - 1 && x > s->v[i][0])
        i++;
    double sl = (s->v[i][1] - s->v[i - 1][1]) / (s->v[i][0] - s->v[i - 1][0]);
    return terrain_y(s, x) + s->radius * sqrt(1.0 + sl * sl);
}

static int cmp_d(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double quantile(const double *xs, int64_t n, double q)
{
    double k = q * (double)(n - 1);
    int64_t k0 = (int64_t)floor(k), k1 = k0 + 1 < n ? k0 + 1 : k0;
    return xs[k0] + (k - (double)k0) * (xs[k1] - xs[k0]);
}

/* soil x positions of the snapshot in p's buffers, sorted; returns the count (xs has room for cur_n) */
static int64_t soil_xs(const lahar_check_particles *p, double *xs)
{
    int64_t m = 0;
    for (int64_t i = 0; i < p->cur_n; i++)
        if (p->phase[i] == 1)
            xs[m++] = p->x[i];
    qsort(xs, (size_t)m, sizeof *xs, cmp_d);
    return m;
}

/* What landslide measures, step by step (the helpers below fill it in order). */
typedef struct {
    /* the set-up */
    const lahar_shape *ts;     /* the terrain's polyline (x increasing) */
    double dx;                 /* spacing: the width of a column of the surfaces */
    double *xs;                /* [nmax] the soil's x of the snapshot read, sorted (soil_xs) */
    int pl;                    /* the deposit panel */
    /* the initial mass */
    int64_t n0;                /* soil particles at t = 0 */
    double front0;             /* its front: the 99 % quantile of x */
    /* over the snapshots */
    int64_t escaped;           /* the most soil particles below the terrain's core line at once */
    double ke_max, ke_last, vmax;
    /* the deposit at the end */
    int64_t n1;
    double x01, x99;           /* the 1 % and 99 % quantiles of the soil's x */
    double tmax, tsum;         /* thickness per column: largest, sum over the tn columns */
    int tn;
} landslide;

/* The case and output landslide can judge, the terrain, and the buffer of x: 0, or -1 with r->err. */
static int landslide_setup(const lahar_case *c, const lahar_check_data *d, landslide *ls, lahar_check_result *r)
{
    const lahar_check_particles *p = d->particles;
    const int tb = lahar_case_find_body(c, "terrain");
    if (!p || !p->phase || !p->vx || p->nsnap < 2 || c->dim != 2 || tb < 0 ||
        c->bodies[tb].motion != LAHAR_MOTION_FIXED || c->bodies[tb].shape.nf != 0 || c->bodies[tb].shape.nv < 2) {
        snprintf(r->err, sizeof r->err, "landslide: needs a 2D case with a terrain: section (its body named "
                 "terrain), a soil block, >= 2 snapshots and the particle fields velocity and phase");
        return -1;
    }
    const lahar_shape *ts = &c->bodies[tb].shape;
    for (int i = 1; i < ts->nv; i++)
        if (!(ts->v[i][0] > ts->v[i - 1][0])) {
            snprintf(r->err, sizeof r->err, "landslide: the terrain's x must increase along its points");
            return -1;
        }
    ls->ts = ts;
    ls->dx = c->sph_dx;
    ls->xs = malloc((size_t)(p->nmax > 0 ? p->nmax : 1) * sizeof *ls->xs);
    if (!ls->xs) {
        snprintf(r->err, sizeof r->err, "out of memory");
        return -1;
    }
    return 0;
}

/* The soil at t = 0 (left in the buffers): its count and front. 0, or -1 with r->err. */
static int landslide_initial(lahar_check_particles *p, landslide *ls, lahar_check_result *r)
{
    if (lahar_check_particles_read(p, 0, r->err, sizeof r->err))
        return -1;
    ls->n0 = soil_xs(p, ls->xs);
    if (ls->n0 < 2) {
        snprintf(r->err, sizeof r->err, "landslide: fewer than 2 soil particles at t = 0");
        return -1;
    }
    ls->front0 = quantile(ls->xs, ls->n0, 0.99);
    return 0;
}

/* The deposit panel with the terrain's surface and the initial mass's surface: the highest
 * particle + dx/2 per column of dx (drawn only if its columns fit in memory). */
static void landslide_plot_initial(const lahar_check_particles *p, landslide *ls, lahar_check_result *r)
{
    const lahar_shape *ts = ls->ts;
    const double dx = ls->dx;
    ls->pl = lahar_check_panel(r, "deposit at the end, the initial mass and the terrain", "x (m)", "y (m)");
    lahar_check_curve(r, ls->pl, 0, "terrain (surface)");
    for (int i = 0; i < ts->nv; i++)
        lahar_check_point(r, ts->v[i][0], terrain_surface(ts, ts->v[i][0]));
    const double xa = ls->xs[0], xb = ls->xs[ls->n0 - 1];
    const int nc0 = (int)ceil((xb - xa) / dx) + 1;
    double *top0 = malloc((size_t)nc0 * sizeof *top0);
    if (!top0)
        return;
    for (int k = 0; k < nc0; k++)
        top0[k] = -INFINITY;
    for (int64_t i = 0; i < p->cur_n; i++)
        if (p->phase[i] == 1) {
            int col = (int)floor((p->x[i] - xa) / dx);
            if (col >= 0 && col < nc0)
                top0[col] = fmax(top0[col], p->y[i] + 0.5 * dx);
        }
    lahar_check_curve(r, ls->pl, 0, "initial mass (surface)");
    for (int k = 0; k < nc0; k++)
        if (top0[k] > -INFINITY)
            lahar_check_point(r, xa + (k + 0.5) * dx, top0[k]);
    free(top0);
}

/* Every snapshot in turn: the soil particles through the terrain's core line, the kinetic energy
 * (per unit particle mass: only its ratio is reported) and the largest speed. The last snapshot
 * stays in the buffers. 0, or -1 with r->err. */
static int landslide_snapshots(lahar_check_particles *p, landslide *ls, lahar_check_result *r)
{
    int64_t escaped = 0;
    double ke_max = 0.0, ke_last = 0.0, vmax = 0.0;
    for (int64_t k = 0; k < p->nsnap; k++) {
        if (lahar_check_particles_read(p, k, r->err, sizeof r->err))
            return -1;
        double ke = 0.0;
        int64_t esc = 0;
        for (int64_t i = 0; i < p->cur_n; i++)
            if (p->phase[i] == 1) {
                double v2 = p->vx[i] * p->vx[i] + p->vy[i] * p->vy[i];
                ke += 0.5 * v2;
                vmax = fmax(vmax, sqrt(v2));
                esc += p->y[i] < terrain_y(ls->ts, p->x[i]);
            }
        escaped = esc > escaped ? esc : escaped;
        ke_max = fmax(ke_max, ke);
        ke_last = ke;
    }
    ls->escaped = escaped, ls->ke_max = ke_max, ls->ke_last = ke_last, ls->vmax = vmax;
    return 0;
}

/* The deposit (the last snapshot, in the buffers) between the 1 % and 99 % quantiles of x: its
 * surface per column of dx (the highest particle + dx/2), drawn, and its vertical thickness above
 * the terrain's surface. 0, or -1 with r->err. */
static int landslide_deposit(const lahar_check_particles *p, landslide *ls, lahar_check_result *r)
{
    const double dx = ls->dx;
    ls->n1 = soil_xs(p, ls->xs);
    if (ls->n1 < 2) {
        snprintf(r->err, sizeof r->err, "landslide: fewer than 2 soil particles at the end");
        return -1;
    }
    const double x01 = quantile(ls->xs, ls->n1, 0.01), x99 = quantile(ls->xs, ls->n1, 0.99);
    ls->x01 = x01, ls->x99 = x99;
    const int ncol = (int)ceil((x99 - x01) / dx) + 1;
    double *top = malloc((size_t)ncol * sizeof *top);
    if (!top) {
        snprintf(r->err, sizeof r->err, "out of memory");
        return -1;
    }
    for (int k = 0; k < ncol; k++)
        top[k] = -INFINITY;
    for (int64_t i = 0; i < p->cur_n; i++)
        if (p->phase[i] == 1 && p->x[i] >= x01 && p->x[i] <= x99) {
            int col = (int)floor((p->x[i] - x01) / dx);
            if (col >= 0 && col < ncol)
                top[col] = fmax(top[col], p->y[i] + 0.5 * dx);
        }
    double tmax = 0.0, tsum = 0.0;
    int tn = 0;
    lahar_check_curve(r, ls->pl, 1, "lahar deposit (surface, 1-99 % of the mass)");
    for (int k = 0; k < ncol; k++) {
        if (!(top[k] > -INFINITY))
            continue;
        double xc = x01 + (k + 0.5) * dx, th = fmax(0.0, top[k] - terrain_surface(ls->ts, xc));
        tmax = fmax(tmax, th);
        tsum += th;
        tn++;
        lahar_check_point(r, xc, top[k]);
    }
    free(top);
    ls->tmax = tmax, ls->tsum = tsum, ls->tn = tn;
    return 0;
}

/* The metrics against the field deposit (Trujillo-Vela et al. 2020 section 5.4), the information
 * values (check.json), the note and the convention. */
static void landslide_report(const landslide *ls, lahar_check_result *r)
{
    const double L = ls->x99 - ls->x01, tmax = ls->tmax;
    lahar_check_value(r, "escaped_particles", (double)ls->escaped);
    lahar_check_value(r, "mass_change", fabs((double)(ls->n1 - ls->n0)) / (double)ls->n0);
    lahar_check_value(r, "deposit_length_m", L);
    lahar_check_value(r, "deposit_length_field_m", LANDSLIDE_FIELD_LENGTH);
    lahar_check_value(r, "deposit_length_rel_diff", (L - LANDSLIDE_FIELD_LENGTH) / LANDSLIDE_FIELD_LENGTH);
    lahar_check_value(r, "deposit_length_rel_error", fabs(L - LANDSLIDE_FIELD_LENGTH) / LANDSLIDE_FIELD_LENGTH);
    lahar_check_value(r, "deposit_rear_x_m", ls->x01);
    lahar_check_value(r, "front_x_m", ls->x99);
    lahar_check_value(r, "runout_m", ls->x99 - ls->front0);
    lahar_check_value(r, "deposit_thickness_max_m", tmax);
    const double tmean = ls->tn > 0 ? ls->tsum / ls->tn : 0.0;
    lahar_check_value(r, "deposit_thickness_mean_m", tmean);
    lahar_check_value(r, "deposit_thickness_outside_field_m",
                      fmax(0.0, fmax(LANDSLIDE_FIELD_THICK_LO - tmean, tmax - LANDSLIDE_FIELD_THICK_HI)));
    lahar_check_value(r, "kinetic_energy_rel", ls->ke_max > 0.0 ? ls->ke_last / ls->ke_max : 0.0);
    lahar_check_value(r, "speed_max_m_s", ls->vmax);
    snprintf(r->note, sizeof r->note, "field deposit (Yangbaodi, Trujillo-Vela et al. 2020 section 5.4): about 140 m "
             "long, 1-5 m thick; the paper's SPH overestimates the run-out");
    snprintf(r->convention, sizeof r->convention, "deposit between the 1 %% and 99 %% quantiles of the soil's x at "
             "the end; thickness vertical, column tops (dx wide) above the terrain's surface");
}

/* The steps from the initial mass to the report; xs is the caller's to free. */
static int landslide_measure(lahar_check_particles *p, landslide *ls, lahar_check_result *r)
{
    if (landslide_initial(p, ls, r))
        return -1;
    landslide_plot_initial(p, ls, r);
    if (landslide_snapshots(p, ls, r) || landslide_deposit(p, ls, r))
        return -1;
    landslide_report(ls, r);
    return 0;
}

int lahar_check_landslide(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r)
{
    landslide ls = {0};
    if (landslide_setup(c, d, &ls, r))
        return -1;
    const int rc = landslide_measure(d->particles, &ls, r);
    free(ls.xs);
    return rc;
}
