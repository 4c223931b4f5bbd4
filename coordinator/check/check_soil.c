/* `lahar check` references of the SPH soil (sph_node/soil/sph_soil.h; cases/README.md): here
 * soil_geostatic, soil_slide and darcy, and what the soil evaluators share (check_soil.h);
 * granular_collapse in check_soil_collapse.c, granular_impact in check_soil_impact.c.
 *
 * soil_geostatic: a soil layer at rest under gravity, laterally confined (periodic sides or
 * frictionless walls), loaded by its own weight from a stress-free start. One-dimensional
 * (confined) elastic compression gives, at depth z below the surface (tension positive stress,
 * gravity along the last axis):
 *   sigma_v = -rho g z,  sigma_h = K0 sigma_v,  K0 = nu / (1 - nu)
 * (plane strain and 3D alike: the lateral strains vanish). Measured: the soil particles binned in
 * rows of dx by depth below the current surface (the highest particle + dx/2), each row's mean
 * stress averaged over the snapshots of the last quarter of the run (the start-up oscillation
 * averages out). Metrics over pairs of rows (bins of 2 dx) deeper than H/4 (relative errors near
 * the free surface divide by ~0), without the row resting on the floor (its kernel is cut by the
 * wall):
 *   sigma_v_rel_error  max |mean sigma_v - (-rho g z)| / (rho g z)
 *   K0_rel_error       max |sigma_h / sigma_v - K0| / K0
 * Pairs of rows, because the symmetric SPH divergence sum_j m_j (sigma_i/rho_i^2 + sigma_j/rho_j^2)
 * . grad W cannot see a stress alternating row by row (sigma_k + sigma_(k+-d) cancels in the
 * difference of the two sides of particle k): the start-up leaves such a mode of a few per cent
 * in the layer, and its row-by-row size is reported as sigma_v_row_max_rel_error (info).
 *   sigma_v_floor_rel_error  |mean sigma_v - (-rho g z)| / (rho g z) of the deepest row alone (the
 *                      one resting on the floor): ~0.2 with the penalty wall, whose one-sided kernel
 *                      makes the stress divergence carry the weight with too large a stress; a few
 *                      per cent with the soil's ghost layers (sph.soil_wall_stress: ghost)
 *   creep_rel          |mean height at t_end - mean height at the start of the last quarter|
 *                      / (rho g H^2 / (3 M)), the elastic settlement of the column's mean height
 *                      (M = E (1 - nu) / ((1 + nu)(1 - 2 nu)) the constrained modulus): ~0 when the
 *                      column has stopped settling.
 * Info: the mean settlement against rho g H^2 / (3 M). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "check_soil.h"

/* The soil material of the case (the first soil block's), or NULL. */
const lahar_material *soil_material(const lahar_case *c)
{
    for (int b = 0; b < c->nblock; b++)
        if (c->blocks[b].phase == 1 && c->blocks[b].material >= 0 && c->blocks[b].material < c->nmaterial)
            return &c->materials[c->blocks[b].material];
    return NULL;
}

static double soil_up(const lahar_check_particles *p, int dim, int64_t i)
{
    return dim == 3 ? p->z[i] : p->y[i];
}

/* Height of the surface (highest soil particle + dx/2), bottom (lowest - dx/2) and mean height of
 * the soil particles of the snapshot in p's buffers. Returns the number of soil particles. */
static int64_t soil_extent(const lahar_check_particles *p, int dim, double dx, double *top, double *bottom,
                           double *mean)
{
    int64_t n = 0;
    double hi = -INFINITY, lo = INFINITY, sum = 0.0;
    for (int64_t i = 0; i < p->cur_n; i++) {
        if (p->phase[i] != 1)
            continue;
        double u = soil_up(p, dim, i);
        hi = u > hi ? u : hi;
        lo = u < lo ? u : lo;
        sum += u;
        n++;
    }
    *top = hi + 0.5 * dx;
    *bottom = lo - 0.5 * dx;
    *mean = n ? sum / (double)n : 0.0;
    return n;
}

/* Start of the soil references' window, the last quarter of the run: long enough for the
 * start-up oscillation to average out. */
static double soil_late_from(const lahar_check_particles *p) { return lahar_check_late_from(p->t, p->nsnap, 0.25); }

/* What soil_geostatic measures, step by step (the helpers below fill it in order). */
typedef struct {
    const lahar_material *mat; /* the soil's */
    int dim, up;               /* up: the last axis (gravity along -up) */
    double g, dx, rho, nu;
    double k0, M;              /* nu / (1 - nu); the constrained modulus E (1 - nu) / ((1 + nu)(1 - 2 nu)) */
    double mean0, H;           /* the soil's mean height and thickness at t = 0 */
    /* the rows of dx below the surface, summed over the window */
    int nrow;
    double *sv, *sh;           /* [nrow] sums of sigma_v, sigma_h */
    int64_t *cnt;              /* [nrow] samples */
    int64_t kfirst;            /* the window's first snapshot */
    double mean_first, mean_last; /* the mean height at the window's first and last snapshot */
    /* the errors */
    double ev, ek, erow, efloor;
    int nused;                 /* the 2-row bins in ev, ek */
} geostatic;

static void geostatic_free(geostatic *gs)
{
    free(gs->sv), free(gs->sh), free(gs->cnt);
    gs->sv = gs->sh = NULL, gs->cnt = NULL;
}

/* The fields, the soil and gravity along the last axis: 0, or -1 with r->err. */
static int geostatic_setup(const lahar_case *c, const lahar_check_data *d, geostatic *gs, lahar_check_result *r)
{
    const lahar_check_particles *p = d->particles;
    gs->mat = soil_material(c);
    if (!p || !p->phase || !p->stress || !gs->mat) {
        snprintf(r->err, sizeof r->err, "soil_geostatic: needs a soil block and the particle fields phase and stress "
                 "(output: fields)");
        return -1;
    }
    gs->dim = c->dim, gs->up = gs->dim - 1; /* gravity along the last axis */
    double g = -c->gravity[gs->up];
    gs->dx = c->sph_dx, gs->rho = gs->mat->density, gs->nu = gs->mat->poisson;
    for (int a = 0; a < gs->dim; a++)
        if (a != gs->up && c->gravity[a] != 0.0)
            g = NAN;
    gs->g = g;
    if (!(g > 0.0) || !(gs->dx > 0.0) || p->nsnap < 2) {
        snprintf(r->err, sizeof r->err, "soil_geostatic: needs gravity along -%c only, sph.dx > 0 and >= 2 snapshots",
                 "xyz"[gs->up]);
        return -1;
    }
    const double nu = gs->nu;
    gs->k0 = nu / (1.0 - nu);
    gs->M = gs->mat->young * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
    return 0;
}

/* The layer at t = 0 (its thickness H and mean height) and the rows' buffers, H / dx + 2 rows:
 * the surface may rise by a row. 0, or -1 with r->err. */
static int geostatic_layer(lahar_check_particles *p, geostatic *gs, lahar_check_result *r)
{
    double top0, bot0;
    if (lahar_check_particles_read(p, 0, r->err, sizeof r->err) ||
        soil_extent(p, gs->dim, gs->dx, &top0, &bot0, &gs->mean0) == 0) {
        if (!r->err[0])
            snprintf(r->err, sizeof r->err, "soil_geostatic: no soil particles at t = 0");
        return -1;
    }
    gs->H = top0 - bot0;
    gs->nrow = (int)ceil(gs->H / gs->dx) + 2;
    gs->sv = calloc((size_t)gs->nrow, sizeof *gs->sv), gs->sh = calloc((size_t)gs->nrow, sizeof *gs->sh);
    gs->cnt = calloc((size_t)gs->nrow, sizeof *gs->cnt);
    if (!gs->sv || !gs->sh || !gs->cnt) {
        snprintf(r->err, sizeof r->err, "out of memory");
        return -1;
    }
    return 0;
}

/* The snapshots of the last quarter of the run (latest first): each soil particle's vertical and
 * horizontal stress into its row by depth below the current surface, so that the start-up
 * oscillation averages out; the mean height at both ends of the window (the creep). 0, or -1 with
 * r->err. */
static int geostatic_window(lahar_check_particles *p, geostatic *gs, lahar_check_result *r)
{
    const int dim = gs->dim;
    const int64_t kl = p->nsnap - 1;
    const double t_from = soil_late_from(p), dx = gs->dx;
    /* the stress of component a along axis e: xx, yy or zz */
    const int comp_v = gs->up == 1 ? 3 : 5, comp_h = 0;
    gs->kfirst = kl, gs->mean_first = 0.0, gs->mean_last = 0.0;
    for (int64_t k = kl; k >= 0 && (k == kl || p->t[k] >= t_from); k--) {
        double top, bot, mean;
        if (lahar_check_particles_read(p, k, r->err, sizeof r->err))
            return -1;
        soil_extent(p, dim, dx, &top, &bot, &mean);
        if (k == kl)
            gs->mean_last = mean;
        gs->kfirst = k;
        gs->mean_first = mean;
        for (int64_t i = 0; i < p->cur_n; i++) {
            if (p->phase[i] != 1)
                continue;
            int row = (int)floor((top - soil_up(p, dim, i)) / dx);
            if (row < 0 || row >= gs->nrow)
                continue;
            gs->sv[row] += p->stress[i * 6 + comp_v];
            gs->sh[row] += p->stress[i * 6 + comp_h];
            gs->cnt[row]++;
        }
    }
    return 0;
}

/* The rows' mean stresses against rho g z and K0 rho g z (kPa, compression positive). */
static void geostatic_plot(const geostatic *gs, lahar_check_result *r)
{
    const double dx = gs->dx, H = gs->H, rho = gs->rho, g = gs->g;
    int pv = lahar_check_panel(r, "soil column at rest: stress vs depth (late-window mean per row)", "depth z (m)",
                               "stress (kPa, compression positive)");
    lahar_check_curve(r, pv, 1, "sigma_v (lahar)");
    for (int row = 0; row < gs->nrow; row++)
        if (gs->cnt[row] > 0)
            lahar_check_point(r, (row + 0.5) * dx, -1e-3 * gs->sv[row] / (double)gs->cnt[row]);
    lahar_check_curve(r, pv, 1, "sigma_h (lahar)");
    for (int row = 0; row < gs->nrow; row++)
        if (gs->cnt[row] > 0)
            lahar_check_point(r, (row + 0.5) * dx, -1e-3 * gs->sh[row] / (double)gs->cnt[row]);
    lahar_check_curve(r, pv, 0, "rho g z");
    lahar_check_point(r, 0.0, 0.0);
    lahar_check_point(r, H, 1e-3 * rho * g * H);
    lahar_check_curve(r, pv, 0, "K0 rho g z");
    lahar_check_point(r, 0.0, 0.0);
    lahar_check_point(r, H, 1e-3 * gs->k0 * rho * g * H);
}

/* The errors against sigma_v = -rho g z, sigma_h = K0 sigma_v (see the top of the file): the
 * deepest row's alone (on the floor), every row's deeper than H/4, and those of the bins of two
 * rows that enter the metrics. */
static void geostatic_errors(geostatic *gs)
{
    const double dx = gs->dx, H = gs->H, rho = gs->rho, g = gs->g, k0 = gs->k0;
    const double *sv = gs->sv, *sh = gs->sh;
    const int64_t *cnt = gs->cnt;
    double ev = 0.0, ek = 0.0, erow = 0.0, efloor = NAN;
    int nused = 0;
    for (int row = gs->nrow - 1; row >= 0; row--)
        if (cnt[row] > 0) { /* the deepest row: the one on the floor */
            double z = (row + 0.5) * dx;
            efloor = fabs(sv[row] / (double)cnt[row] + rho * g * z) / (rho * g * z);
            break;
        }
    for (int row = 0; row < gs->nrow; row++) {
        double z = (row + 0.5) * dx;
        if (cnt[row] > 0 && z >= 0.25 * H && z <= H) /* every row, the one on the floor too */
            erow = fmax(erow, fabs(sv[row] / (double)cnt[row] + rho * g * z) / (rho * g * z));
    }
    for (int row = 0; row + 1 < gs->nrow; row += 2) { /* bins of two rows, centred at depth (row + 1) dx */
        double z = (row + 1) * dx;
        int64_t nb = cnt[row] + cnt[row + 1];
        if (cnt[row] == 0 || cnt[row + 1] == 0 || z < 0.25 * H || z + dx > H - dx * (1.0 - 1e-6))
            continue; /* (the row on the floor lacks half its neighbours: left out, its error is in the info) */
        double v = (sv[row] + sv[row + 1]) / (double)nb, h = (sh[row] + sh[row + 1]) / (double)nb;
        double ref = -rho * g * z;
        ev = fmax(ev, fabs(v - ref) / fabs(ref));
        ek = fmax(ek, fabs(h / v - k0) / k0);
        nused++;
    }
    gs->ev = ev, gs->ek = ek, gs->erow = erow, gs->efloor = efloor, gs->nused = nused;
}

/* The metrics and the information values (check.json), the convention and the note. */
static void geostatic_report(const lahar_check_particles *p, const geostatic *gs, lahar_check_result *r)
{
    const double H = gs->H, settle_ref = gs->rho * gs->g * H * H / (3.0 * gs->M);
    lahar_check_value(r, "sigma_v_rel_error", gs->ev);
    lahar_check_value(r, "K0_rel_error", gs->ek);
    lahar_check_value(r, "creep_rel", fabs(gs->mean_last - gs->mean_first) / settle_ref);
    lahar_check_value(r, "sigma_v_row_max_rel_error", gs->erow);
    lahar_check_value(r, "sigma_v_floor_rel_error", gs->efloor);
    lahar_check_value(r, "K0_reference", gs->k0);
    lahar_check_value(r, "settlement_m", gs->mean0 - gs->mean_last);
    lahar_check_value(r, "settlement_elastic_m", settle_ref);
    lahar_check_value(r, "height_m", H);
    lahar_check_value(r, "window_start_s", p->t[gs->kfirst]);
    snprintf(r->convention, sizeof r->convention,
             "stress tension positive; rows of dx by depth below the surface, mean over t >= %.3g s; bins of "
             "two rows deeper than H/4 enter the metrics", p->t[gs->kfirst]);
    snprintf(r->note, sizeof r->note, "K0 = nu/(1-nu) = %.4f, H = %.4g m, 2-row bins used %d", gs->k0, H, gs->nused);
}

int lahar_check_soil_geostatic(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r)
{
    lahar_check_particles *p = d->particles;
    geostatic gs = {0};
    if (geostatic_setup(c, d, &gs, r) || geostatic_layer(p, &gs, r) || geostatic_window(p, &gs, r)) {
        geostatic_free(&gs);
        return -1;
    }
    geostatic_plot(&gs, r);
    geostatic_errors(&gs);
    geostatic_free(&gs);
    if (gs.nused == 0) {
        snprintf(r->err, sizeof r->err, "soil_geostatic: no soil rows below H/4 (H = %g m, dx = %g m)", gs.H, gs.dx);
        return -1;
    }
    geostatic_report(p, &gs, r);
    return 0;
}

/* soil_slide: a soil block resting on a fixed floor whose normal is +y (2D) / +z (3D), gravity
 * tilted by theta from the normal (the same as a block on a plane inclined by theta). With the
 * soil-DEM friction mu_phi (Trujillo-Vela et al. 2020 eq. 22-25) the block slides when tan(theta) > mu_phi with
 *   a = g (sin theta - mu_phi cos theta)
 * and stays put otherwise (a = 0). Measured: the mean velocity of the soil particles along the
 * tangential part of gravity, fitted by a straight line over the snapshots after the first
 * quarter of the run (the block first settles onto the floor). Metric:
 *   accel_rel_error = |a - a_ref| / a_ref when it slides, |a| / (g sin theta) when it should stick. */
int lahar_check_soil_slide(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r)
{
    lahar_check_particles *p = d->particles;
    const lahar_material *mat = soil_material(c);
    if (!p || !p->phase || !p->vx || !mat || p->nsnap < 4) {
        snprintf(r->err, sizeof r->err, "soil_slide: needs a soil block, >= 4 snapshots and the particle fields "
                 "velocity and phase");
        return -1;
    }
    const int dim = c->dim, up = dim - 1;
    double gt[3] = {c->gravity[0], c->gravity[1], c->gravity[2]};
    const double gn = -gt[up];
    gt[up] = 0.0;
    const double gtm = sqrt(gt[0] * gt[0] + gt[1] * gt[1] + gt[2] * gt[2]);
    if (!(gn > 0.0) || !(gtm > 0.0)) {
        snprintf(r->err, sizeof r->err, "soil_slide: gravity must point into the floor (-%c) with a tangential part",
                 "xyz"[up]);
        return -1;
    }
    const double mu = mat->friction, theta = atan2(gtm, gn), g = hypot(gtm, gn);
    const double a_ref = gtm - mu * gn > 0.0 ? gtm - mu * gn : 0.0;
    const int64_t kl = p->nsnap - 1;
    const double t_from = p->t[0] + 0.25 * (p->t[kl] - p->t[0]);
    double st = 0, sv = 0, stt = 0, stv = 0, x0 = 0, x1 = 0;
    int nfit = 0;
    for (int64_t k = 0; k <= kl; k++) {
        if (lahar_check_particles_read(p, k, r->err, sizeof r->err))
            return -1;
        double v = 0.0, x = 0.0;
        int64_t n = 0;
        for (int64_t i = 0; i < p->cur_n; i++)
            if (p->phase[i] == 1) {
                const double vv[3] = {p->vx[i], p->vy[i], p->vz[i]}, xx[3] = {p->x[i], p->y[i], p->z[i]};
                for (int a = 0; a < 3; a++)
                    v += vv[a] * gt[a] / gtm, x += xx[a] * gt[a] / gtm;
                n++;
            }
        if (n == 0)
            continue;
        v /= (double)n, x /= (double)n;
        if (k == 0)
            x0 = x;
        x1 = x;
        if (r->nseries < LAHAR_CHECK_MAX_SERIES) {
            r->series_t[r->nseries] = p->t[k];
            r->series_measured[r->nseries] = v;
            r->series_reference[r->nseries] = 0.0; /* set after the fit */
            r->nseries++;
        }
        if (p->t[k] >= t_from) {
            st += p->t[k], sv += v, stt += p->t[k] * p->t[k], stv += p->t[k] * v;
            nfit++;
        }
    }
    if (nfit < 3) {
        snprintf(r->err, sizeof r->err, "soil_slide: fewer than 3 snapshots after t = %g s", t_from);
        return -1;
    }
    const double a = (nfit * stv - st * sv) / (nfit * stt - st * st), v0 = (sv - a * st) / nfit;
    for (int k = 0; k < r->nseries; k++) /* the reference slope through the fitted velocity at t_from */
        r->series_reference[k] = v0 + a * t_from + a_ref * (r->series_t[k] - t_from);
    lahar_check_value(r, "accel_rel_error", a_ref > 0.0 ? fabs(a - a_ref) / a_ref : fabs(a) / gtm);
    lahar_check_value(r, "accel_measured", a);
    lahar_check_value(r, "accel_reference", a_ref);
    lahar_check_value(r, "theta_deg", theta * 180.0 / acos(-1.0));
    lahar_check_value(r, "mu_phi", mu);
    lahar_check_value(r, "g_sin_theta", g * sin(theta));
    lahar_check_value(r, "displacement_m", x1 - x0);
    snprintf(r->title, sizeof r->title, "soil block on a %.1f deg slope, mu_phi = %.3g: %s", theta * 180.0 / acos(-1.0),
             mu, a_ref > 0.0 ? "slides" : "sticks");
    snprintf(r->xlabel, sizeof r->xlabel, "t (s)");
    snprintf(r->ylabel, sizeof r->ylabel, "mean soil velocity down the slope (m/s)");
    snprintf(r->convention, sizeof r->convention,
             "a fitted to the mean velocity along the slope for t >= %.3g s; reference g (sin theta - mu_phi cos theta)",
             t_from);
    return 0;
}

/* darcy: water driven through a soil by sph.body_force b (fluid only; hydraulic gradient
 * i = |b| / g with g = |gravity|, 9.81 m/s^2 without gravity, the g of k = k_h mu / (rho_w g)).
 * Darcy's law gives the seepage (superficial) velocity u = k_h i along b relative to the soil
 * (Trujillo-Vela et al. 2020 eq. 10). Measured: mean water velocity minus mean soil velocity along b, averaged
 * over the snapshots of the last quarter of the run. Metric:
 *   darcy_velocity_rel_error = |u - k_h i| / (k_h i). */
int lahar_check_darcy(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r)
{
    lahar_check_particles *p = d->particles;
    const lahar_material *mat = soil_material(c);
    const double *b = c->sph.body_force;
    const double bm = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
    const double gg = sqrt(c->gravity[0] * c->gravity[0] + c->gravity[1] * c->gravity[1] + c->gravity[2] * c->gravity[2]);
    if (!p || !p->phase || !p->vx || !mat || !(mat->permeability > 0.0) || !(bm > 0.0) || p->nsnap < 2) {
        snprintf(r->err, sizeof r->err, "darcy: needs a soil with permeability > 0, water, sph.body_force != 0, >= 2 "
                 "snapshots and the particle fields velocity and phase");
        return -1;
    }
    const double g = gg > 0.0 ? gg : 9.81, i_h = bm / g, u_ref = mat->permeability * i_h;
    const int64_t kl = p->nsnap - 1;
    const double t_from = soil_late_from(p);
    double usum = 0.0;
    int nwin = 0;
    for (int64_t k = 0; k <= kl; k++) {
        if (lahar_check_particles_read(p, k, r->err, sizeof r->err))
            return -1;
        double uw = 0.0, us = 0.0;
        int64_t nw = 0, ns = 0;
        for (int64_t i = 0; i < p->cur_n; i++) {
            double u = (p->vx[i] * b[0] + p->vy[i] * b[1] + p->vz[i] * b[2]) / bm;
            if (p->phase[i] == 1)
                us += u, ns++;
            else
                uw += u, nw++;
        }
        if (nw == 0 || ns == 0) {
            snprintf(r->err, sizeof r->err, "darcy: snapshot %lld lacks water or soil particles", (long long)k);
            return -1;
        }
        double u = uw / (double)nw - us / (double)ns;
        if (r->nseries < LAHAR_CHECK_MAX_SERIES) {
            r->series_t[r->nseries] = p->t[k];
            r->series_measured[r->nseries] = u;
            r->series_reference[r->nseries] = u_ref;
            r->nseries++;
        }
        if (p->t[k] >= t_from)
            usum += u, nwin++;
    }
    const double u = usum / nwin;
    lahar_check_value(r, "darcy_velocity_rel_error", fabs(u - u_ref) / u_ref);
    lahar_check_value(r, "darcy_velocity", u);
    lahar_check_value(r, "darcy_velocity_reference", u_ref);
    lahar_check_value(r, "hydraulic_gradient", i_h);
    lahar_check_value(r, "k_h", mat->permeability);
    snprintf(r->title, sizeof r->title, "Darcy flow through a soil: k_h = %g m/s, i = %.3g", mat->permeability, i_h);
    snprintf(r->xlabel, sizeof r->xlabel, "t (s)");
    snprintf(r->ylabel, sizeof r->ylabel, "mean water - mean soil velocity along b (m/s)");
    snprintf(r->convention, sizeof r->convention, "i = |sph.body_force| / g; velocities averaged over t >= %.3g s",
             t_from);
    return 0;
}
