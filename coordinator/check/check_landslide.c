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

int lahar_check_landslide(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r)
{
    lahar_check_particles *p = d->particles;
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
    const double dx = c->sph_dx;
    double *xs = malloc((size_t)(p->nmax > 0 ? p->nmax : 1) * sizeof *xs);
    if (!xs) {
        snprintf(r->err, sizeof r->err, "out of memory");
        return -1;
    }
    int rc = -1;
    if (lahar_check_particles_read(p, 0, r->err, sizeof r->err))
        goto done;
    const int64_t n0 = soil_xs(p, xs);
    if (n0 < 2) {
        snprintf(r->err, sizeof r->err, "landslide: fewer than 2 soil particles at t = 0");
        goto done;
    }
    const double front0 = quantile(xs, n0, 0.99);
    int pl = lahar_check_panel(r, "deposit at the end, the initial mass and the terrain", "x (m)", "y (m)");
    lahar_check_curve(r, pl, 0, "terrain (surface)");
    for (int i = 0; i < ts->nv; i++)
        lahar_check_point(r, ts->v[i][0], terrain_surface(ts, ts->v[i][0]));
    {   /* the initial mass's surface: the highest particle + dx/2 per column of dx */
        const double xa = xs[0], xb = xs[n0 - 1];
        const int nc0 = (int)ceil((xb - xa) / dx) + 1;
        double *top0 = malloc((size_t)nc0 * sizeof *top0);
        if (top0) {
            for (int k = 0; k < nc0; k++)
                top0[k] = -INFINITY;
            for (int64_t i = 0; i < p->cur_n; i++)
                if (p->phase[i] == 1) {
                    int col = (int)floor((p->x[i] - xa) / dx);
                    if (col >= 0 && col < nc0)
                        top0[col] = fmax(top0[col], p->y[i] + 0.5 * dx);
                }
            lahar_check_curve(r, pl, 0, "initial mass (surface)");
            for (int k = 0; k < nc0; k++)
                if (top0[k] > -INFINITY)
                    lahar_check_point(r, xa + (k + 0.5) * dx, top0[k]);
            free(top0);
        }
    }
    int64_t escaped = 0;
    double ke_max = 0.0, ke_last = 0.0, vmax = 0.0;
    for (int64_t k = 0; k < p->nsnap; k++) {
        if (lahar_check_particles_read(p, k, r->err, sizeof r->err))
            goto done;
        double ke = 0.0;
        int64_t esc = 0;
        for (int64_t i = 0; i < p->cur_n; i++)
            if (p->phase[i] == 1) {
                double v2 = p->vx[i] * p->vx[i] + p->vy[i] * p->vy[i];
                ke += 0.5 * v2;
                vmax = fmax(vmax, sqrt(v2));
                esc += p->y[i] < terrain_y(ts, p->x[i]);
            }
        escaped = esc > escaped ? esc : escaped;
        ke_max = fmax(ke_max, ke);
        ke_last = ke;
    }
    /* the deposit: the last snapshot is in the buffers */
    const int64_t n1 = soil_xs(p, xs);
    if (n1 < 2) {
        snprintf(r->err, sizeof r->err, "landslide: fewer than 2 soil particles at the end");
        goto done;
    }
    const double x01 = quantile(xs, n1, 0.01), x99 = quantile(xs, n1, 0.99);
    const int ncol = (int)ceil((x99 - x01) / dx) + 1;
    double *top = malloc((size_t)ncol * sizeof *top);
    if (!top) {
        snprintf(r->err, sizeof r->err, "out of memory");
        goto done;
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
    lahar_check_curve(r, pl, 1, "lahar deposit (surface, 1-99 % of the mass)");
    for (int k = 0; k < ncol; k++) {
        if (!(top[k] > -INFINITY))
            continue;
        double xc = x01 + (k + 0.5) * dx, th = fmax(0.0, top[k] - terrain_surface(ts, xc));
        tmax = fmax(tmax, th);
        tsum += th;
        tn++;
        lahar_check_point(r, xc, top[k]);
    }
    free(top);
    const double L = x99 - x01;
    lahar_check_value(r, "escaped_particles", (double)escaped);
    lahar_check_value(r, "mass_change", fabs((double)(n1 - n0)) / (double)n0);
    lahar_check_value(r, "deposit_length_m", L);
    lahar_check_value(r, "deposit_length_field_m", LANDSLIDE_FIELD_LENGTH);
    lahar_check_value(r, "deposit_length_rel_diff", (L - LANDSLIDE_FIELD_LENGTH) / LANDSLIDE_FIELD_LENGTH);
    lahar_check_value(r, "deposit_length_rel_error", fabs(L - LANDSLIDE_FIELD_LENGTH) / LANDSLIDE_FIELD_LENGTH);
    lahar_check_value(r, "deposit_rear_x_m", x01);
    lahar_check_value(r, "front_x_m", x99);
    lahar_check_value(r, "runout_m", x99 - front0);
    lahar_check_value(r, "deposit_thickness_max_m", tmax);
    const double tmean = tn > 0 ? tsum / tn : 0.0;
    lahar_check_value(r, "deposit_thickness_mean_m", tmean);
    lahar_check_value(r, "deposit_thickness_outside_field_m",
                      fmax(0.0, fmax(LANDSLIDE_FIELD_THICK_LO - tmean, tmax - LANDSLIDE_FIELD_THICK_HI)));
    lahar_check_value(r, "kinetic_energy_rel", ke_max > 0.0 ? ke_last / ke_max : 0.0);
    lahar_check_value(r, "speed_max_m_s", vmax);
    snprintf(r->note, sizeof r->note, "field deposit (Yangbaodi, Trujillo-Vela et al. 2020 section 5.4): about 140 m "
             "long, 1-5 m thick; the paper's SPH overestimates the run-out");
    snprintf(r->convention, sizeof r->convention, "deposit between the 1 %% and 99 %% quantiles of the soil's x at "
             "the end; thickness vertical, column tops (dx wide) above the terrain's surface");
    rc = 0;
done:
    free(xs);
    return rc;
}
