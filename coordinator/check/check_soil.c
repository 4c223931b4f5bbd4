/* `lahar check` references of the SPH soil (sph_node/soil/sph_soil.h; cases/README.md).
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
#include "check.h"
#include <hdf5.h>
#include "geometry.h"
#include "output.h"
#include "vec.h"

/* The soil material of the case (the first soil block's), or NULL. */
static const lahar_material *soil_material(const lahar_case *c)
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

/* granular_collapse: a soil column against a fixed wall released to one side onto a fixed floor
 * (Bui et al. 2008 aluminium bars; the published parameters give the material, not the deposit).
 * The wall (x_wall) and the floor (y_floor) are the left and bottom edges of the column's lattice
 * cells at t = 0 (the column stands in the corner). Reported (last
 * snapshot): run-out L_f (the front: the rightmost soil particle + dx/2, from the wall; and where
 * the deposit stops being at least two particles thick, runout_2dx_thick_m), the
 * height at the wall H_f, the surface profile (highest particle + dx/2 per column of dx), and the
 * slope of the deposit's surface fitted over its sloping part (columns from the wall's
 * neighbourhood to the front with height between 10 % and 90 % of H_f). Metrics:
 *   escaped_particles   soil particles below the floor or behind the wall at any snapshot (0)
 *   kinetic_energy_rel  kinetic energy of the soil at the end / its largest value (settled: small)
 *   slope_excess_deg    max(0, fitted deposit slope - friction angle): a dry deposit rests at or
 *                       below its angle of repose
 *   runout_band_excess_rel  the mass run-out against the published 2D scalings (below): 0 inside
 *                       the band they span, else the relative distance to its nearer edge
 * The mass run-out L_99 (runout_mass99_m, from the wall) is where 99 % of the soil particles (equal
 * masses) lie behind: the front particle of an SPH deposit is a spray of single particles whose
 * reach changes with dx (it grew 13 % from dx = 5 to 2.5 mm, a = 1), L_99 converges (3.5 %).
 * Scalings (L_inf - L0)/L0 of quasi-2D column collapses, a = H0/L0, as consolidated by Lagree,
 * Staron & Popinet (2011, J. Fluid Mech. 686:378, eq. 3.1; docs/soil/column_collapse_scalings.md):
 *   Lube et al. (2005, Phys. Rev. E 72:041301):      1.2 a (a < 1.8),  1.9 a^(2/3) (a > 2.8)
 *   Lajeunesse et al. (2005, Phys. Fluids 17:103302): 1.8 a (a < 3),    2.3 a^(2/3) (a > 3)
 * The band is [min, max] of the branches that apply at a (both of Lube's between 1.8 and 2.8): the
 * experiments' own spread between materials and set-ups. */

#define COLLAPSE_NCOL 4096 /* columns of dx from the wall for the deposit's surface */

/* What granular_collapse measures, step by step (the helpers below fill it in order). */
typedef struct {
    const lahar_material *mat; /* the soil's */
    double dx;
    /* the column at t = 0 */
    double x_wall, y_floor;    /* its lattice cells' left and bottom edges: the wall's and floor's surfaces */
    double L0, H0;             /* its width and height */
    /* the snapshots */
    int64_t escaped;
    double ke_max, ke_last;
    /* the deposit (the last snapshot) */
    double *top;               /* [COLLAPSE_NCOL] the highest particle + dx/2 above the floor per column */
    double front, front2;      /* the rightmost particle + dx/2; the end of the part >= 2 dx thick */
    double Lf, Hf;             /* run-out from the wall, height at the wall */
    double L99;                /* the mass run-out */
    /* the published scalings at a = H0/L0 */
    double asp, band_lo, band_hi, r99, excess;
    double slope_deg, phi_deg; /* the fitted deposit slope, the friction angle */
} collapse;

/* The fields and the soil: 0, or -1 with r->err. */
static int collapse_setup(const lahar_case *c, const lahar_check_data *d, collapse *cl, lahar_check_result *r)
{
    const lahar_check_particles *p = d->particles;
    cl->mat = soil_material(c);
    if (!p || !p->phase || !p->vx || !cl->mat || p->nsnap < 2 || c->dim != 2) {
        snprintf(r->err, sizeof r->err, "granular_collapse: needs a 2D case with a soil block, >= 2 snapshots and the "
                 "particle fields velocity and phase");
        return -1;
    }
    cl->dx = c->sph_dx;
    return 0;
}

/* The column at t = 0: the wall and the floor at its lattice cells' edges (the column stands in
 * the corner), its width and height. 0, or -1 with r->err. */
static int collapse_column(lahar_check_particles *p, collapse *cl, lahar_check_result *r)
{
    const double dx = cl->dx;
    if (lahar_check_particles_read(p, 0, r->err, sizeof r->err))
        return -1;
    double xmin = INFINITY, xmax = -INFINITY, ymin = INFINITY, ymax = -INFINITY;
    for (int64_t i = 0; i < p->cur_n; i++)
        if (p->phase[i] == 1) {
            xmin = fmin(xmin, p->x[i]), xmax = fmax(xmax, p->x[i]);
            ymin = fmin(ymin, p->y[i]), ymax = fmax(ymax, p->y[i]);
        }
    if (!(xmax >= xmin)) {
        snprintf(r->err, sizeof r->err, "granular_collapse: no soil particles at t = 0");
        return -1;
    }
    /* the column's lattice cell edges stand for the wall and the floor surfaces */
    cl->x_wall = xmin - 0.5 * dx, cl->y_floor = ymin - 0.5 * dx;
    cl->L0 = xmax + 0.5 * dx - cl->x_wall, cl->H0 = ymax + 0.5 * dx - cl->y_floor;
    return 0;
}

/* Every snapshot: the most soil particles below the floor or behind the wall at once, and the
 * soil's kinetic energy (per unit mass), its largest and its last. The last snapshot stays in the
 * buffers. 0, or -1 with r->err. */
static int collapse_snapshots(lahar_check_particles *p, collapse *cl, lahar_check_result *r)
{
    cl->escaped = 0, cl->ke_max = 0.0, cl->ke_last = 0.0;
    for (int64_t k = 0; k < p->nsnap; k++) {
        if (lahar_check_particles_read(p, k, r->err, sizeof r->err))
            return -1;
        double ke = 0.0;
        int64_t esc = 0;
        for (int64_t i = 0; i < p->cur_n; i++)
            if (p->phase[i] == 1) {
                ke += 0.5 * (p->vx[i] * p->vx[i] + p->vy[i] * p->vy[i]);
                esc += p->y[i] < cl->y_floor || p->x[i] < cl->x_wall;
            }
        cl->escaped = esc > cl->escaped ? esc : cl->escaped;
        cl->ke_max = fmax(cl->ke_max, ke);
        cl->ke_last = ke;
    }
    return 0;
}

/* The deposit at the last snapshot (in the buffers): the surface per column of dx, the front,
 * where it stops being two particles thick, the run-out and the height at the wall. 0, or -1
 * with r->err. */
static int collapse_deposit(const lahar_check_particles *p, collapse *cl, lahar_check_result *r)
{
    const double dx = cl->dx, x_wall = cl->x_wall;
    double *top = cl->top = malloc(COLLAPSE_NCOL * sizeof *top);
    if (!top) {
        snprintf(r->err, sizeof r->err, "out of memory");
        return -1;
    }
    for (int k = 0; k < COLLAPSE_NCOL; k++)
        top[k] = -INFINITY;
    double front = x_wall, front2 = x_wall;
    for (int64_t i = 0; i < p->cur_n; i++)
        if (p->phase[i] == 1) {
            int col = (int)floor((p->x[i] - x_wall) / dx);
            if (col >= 0 && col < COLLAPSE_NCOL)
                top[col] = fmax(top[col], p->y[i] + 0.5 * dx - cl->y_floor);
            front = fmax(front, p->x[i] + 0.5 * dx);
        }
    for (int k = 0; k < COLLAPSE_NCOL && top[k] >= 2.0 * dx; k++) /* the deposit at least two particles thick */
        front2 = x_wall + (k + 1) * dx;
    cl->front = front, cl->front2 = front2;
    cl->Lf = front - x_wall, cl->Hf = top[0] > 0.0 ? top[0] : 0.0;
    return 0;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The mass run-out L_99 from the wall (see above): 99 % of the soil particles (equal masses)
 * of the last snapshot (in the buffers) behind it, by linear interpolation between
 * order statistics (numpy's default quantile). 0, or -1 with r->err. */
static int collapse_mass_runout(const lahar_check_particles *p, collapse *cl, lahar_check_result *r)
{
    cl->L99 = NAN;
    int64_t ns = 0;
    for (int64_t i = 0; i < p->cur_n; i++)
        ns += p->phase[i] == 1;
    double *xs = malloc((size_t)(ns > 0 ? ns : 1) * sizeof *xs);
    if (!xs) {
        snprintf(r->err, sizeof r->err, "out of memory");
        return -1;
    }
    int64_t m = 0;
    for (int64_t i = 0; i < p->cur_n; i++)
        if (p->phase[i] == 1)
            xs[m++] = p->x[i];
    qsort(xs, (size_t)ns, sizeof *xs, cmp_double);
    if (ns > 0) {
        double q = 0.99 * (double)(ns - 1);
        int64_t k0 = (int64_t)floor(q), k1 = k0 + 1 < ns ? k0 + 1 : k0;
        cl->L99 = xs[k0] + (q - (double)k0) * (xs[k1] - xs[k0]) - cl->x_wall;
    }
    free(xs);
    return 0;
}

/* The band the published scalings span at a = H0/L0 (Lube et al. 2005, Lajeunesse et al. 2005,
 * as consolidated by Lagree, Staron & Popinet 2011 eq. 3.1; the branches that apply at a) and the
 * normalised mass run-out's relative distance outside it. */
static void collapse_scaling_band(collapse *cl)
{
    const double asp = cl->H0 / cl->L0, a23 = pow(asp, 2.0 / 3.0);
    double band_lo = INFINITY, band_hi = -INFINITY;
    const double branch[4] = {asp < 2.8 ? 1.2 * asp : NAN, asp > 1.8 ? 1.9 * a23 : NAN, asp <= 3.0 ? 1.8 * asp : NAN,
                              asp >= 3.0 ? 2.3 * a23 : NAN};
    for (int b = 0; b < 4; b++)
        if (branch[b] == branch[b]) {
            band_lo = fmin(band_lo, branch[b]);
            band_hi = fmax(band_hi, branch[b]);
        }
    const double r99 = (cl->L99 - cl->L0) / cl->L0;
    cl->asp = asp, cl->band_lo = band_lo, cl->band_hi = band_hi, cl->r99 = r99;
    cl->excess = r99 < band_lo ? (band_lo - r99) / band_lo : r99 > band_hi ? (r99 - band_hi) / band_hi : 0.0;
}

/* The deposit's surface next to the initial column, and the slope of the surface fitted over its
 * sloping part (the columns between 10 % and 90 % of the height at the wall): a dry deposit rests
 * at or below its angle of repose. */
static void collapse_slope(collapse *cl, lahar_check_result *r)
{
    const double dx = cl->dx, Hf = cl->Hf, *top = cl->top;
    int pl = lahar_check_panel(r, "deposit surface (last snapshot) and the initial column", "x from the wall (m)",
                               "height (m)");
    lahar_check_curve(r, pl, 1, "lahar deposit");
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    int nfit = 0;
    for (int k = 0; k < COLLAPSE_NCOL; k++) {
        if (!(top[k] > -INFINITY))
            continue;
        double xc = (k + 0.5) * dx;
        lahar_check_point(r, xc, top[k]);
        if (top[k] >= 0.1 * Hf && top[k] <= 0.9 * Hf) {
            sx += xc, sy += top[k], sxx += xc * xc, sxy += xc * top[k];
            nfit++;
        }
    }
    lahar_check_curve(r, pl, 0, "initial column");
    lahar_check_point(r, 0.0, cl->H0);
    lahar_check_point(r, cl->L0, cl->H0);
    lahar_check_point(r, cl->L0, 0.0);
    const double slope = nfit >= 2 ? -(nfit * sxy - sx * sy) / (nfit * sxx - sx * sx) : 0.0;
    cl->slope_deg = atan(slope) * 180.0 / acos(-1.0), cl->phi_deg = cl->mat->friction_angle * 180.0 / acos(-1.0);
}

/* The metrics and the information values (check.json), the note and the convention. */
static void collapse_report(const collapse *cl, lahar_check_result *r)
{
    const double L0 = cl->L0, H0 = cl->H0, slope_deg = cl->slope_deg, phi_deg = cl->phi_deg;
    lahar_check_value(r, "escaped_particles", (double)cl->escaped);
    lahar_check_value(r, "kinetic_energy_rel", cl->ke_max > 0.0 ? cl->ke_last / cl->ke_max : 0.0);
    lahar_check_value(r, "slope_excess_deg", slope_deg > phi_deg ? slope_deg - phi_deg : 0.0);
    lahar_check_value(r, "runout_band_excess_rel", cl->excess);
    lahar_check_value(r, "runout_mass99_m", cl->L99);
    lahar_check_value(r, "runout_mass99_normalised", cl->r99);
    lahar_check_value(r, "aspect_ratio", cl->asp);
    lahar_check_value(r, "scaling_band_lo", cl->band_lo);
    lahar_check_value(r, "scaling_band_hi", cl->band_hi);
    lahar_check_value(r, "runout_m", cl->Lf);
    lahar_check_value(r, "runout_normalised", (cl->Lf - L0) / L0);
    lahar_check_value(r, "runout_2dx_thick_m", cl->front2 - cl->x_wall);
    lahar_check_value(r, "height_at_wall_m", cl->Hf);
    lahar_check_value(r, "height_at_wall_normalised", cl->Hf / H0);
    lahar_check_value(r, "deposit_slope_deg", slope_deg);
    lahar_check_value(r, "friction_angle_deg", phi_deg);
    lahar_check_value(r, "L0_m", L0);
    lahar_check_value(r, "H0_m", H0);
    snprintf(r->note, sizeof r->note, "no published run-out for this set-up: run-out and profile reported only");
    snprintf(r->convention, sizeof r->convention, "run-out from the wall to the front (rightmost particle + dx/2); "
             "slope fitted to the column tops between 10 %% and 90 %% of the height at the wall");
}

int lahar_check_granular_collapse(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r)
{
    lahar_check_particles *p = d->particles;
    collapse cl = {0};
    if (collapse_setup(c, d, &cl, r) || collapse_column(p, &cl, r) || collapse_snapshots(p, &cl, r) ||
        collapse_deposit(p, &cl, r))
        return -1;
    if (collapse_mass_runout(p, &cl, r)) {
        free(cl.top);
        return -1;
    }
    collapse_scaling_band(&cl);
    collapse_slope(&cl, r);
    free(cl.top);
    collapse_report(&cl, r);
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

/* granular_impact: a soil mass flowing down a chute onto a fixed wall (Trujillo-Vela et al. 2020 section 5.3,
 * Moriguchi et al. 2009). The chute's bed is normal to the last axis (z in 3D, y in 2D) and
 * gravity is tilted from it; "down the chute" is the unit vector t along gravity's tangential part,
 * and the wall is the fixed body named `wall` across it. The soil block fills the chute's width at
 * t = 0 (its lattice's side faces are the side walls). Measured:
 *   F(t)  the force of the soil on the wall along t, every row of the force stream (forces.h5 needs
 *         time.forces_interval: 0, every step); its peak F_peak after a moving average over
 *         10 ms (a load cell's bandwidth; the raw peak of single steps is in the info) and the time
 *         of first impact (the first row where F exceeds 1 % of M g_t: a stray particle does not
 *         count);
 *   F_mf  the momentum flux of the soil arriving at the wall, rho u^2 A estimated at each snapshot
 *         as sum m u^2 / L over the particles moving towards the wall (u = v.t > 0) in the slab of
 *         length L = max(0.1 m, 3 dx) in front of the wall's face: a jet of density rho, speed u and
 *         section A stopped by a wall pushes it with rho u^2 A (the fluid-mechanics estimate of a
 *         granular impact, dynamic part only);
 *   momentum balance along t: the soil's momentum changes by M g_t T minus the impulse of every
 *         body's force on it (action and reaction of Trujillo-Vela et al. 2020 eq. 15, 20 and 26), so
 *         sum_b J_b(T) = M g_t T - (P(T) - P(0)), with J_b the impulse of the force stream of body b.
 * Metrics:
 *   escaped_particles           soil particles that went through the wall, the bed or a side wall:
 *                               followed by id (output field id) from snapshot to snapshot, a particle
 *                               that crossed the wall's face, or a side face, with both positions more
 *                               than 2 dx below the wall's top, or the bed's plane upstream of the
 *                               wall (0). Particles passing over the wall's top (the experiment's
 *                               overtopping: the run-up reaches ~1.1 m at 45 deg) are counted apart,
 *                               overtopped_particles (info, those beyond the wall at the end)
 *   particle_count_change       |n(end) - n(0)| (0)
 *   momentum_balance_rel_error  |sum_b J_b - (M g_t T - dP)| / (M g_t T) at the last snapshot; needs
 *                               the soil's damping 0 (damping is an external force)
 *   peak_to_load_estimate_log   |ln(F_peak / (max_t F_mf + M g_t))|: the peak against the dynamic
 *                               load of the arriving front plus the whole mass's weight along the
 *                               chute (the static load of the deposit if the bed held none of it);
 *                               a missing or spiky wall force (no coupling, a blow-up) is far off
 *   first_impact_outside_s      how far the first impact lies outside [t_ritter, t_block] (s): the
 *                               frictionless dam-break front on the slope, s = 2 sqrt(g_n H) t + g_t
 *                               t^2/2, arrives first; a rigid block sliding from rest with mu_phi,
 *                               s = (g_t - mu_phi g_n) t^2/2, last (0)
 * Trujillo-Vela et al. 2020, Fig. 14-15 are images without numbers in the text (shared/papers/000): no published
 * peak force is compared; the peak, its time and the first impact are reported. */

/* The particle ids of snapshot k (output field id), read beside the check's buffers. */
static int impact_read_ids(const lahar_check_particles *p, int64_t k, int64_t *ids, char *err, size_t n)
{
    char name[64];
    snprintf(name, sizeof name, "snapshots/%06lld/id", (long long)k);
    hid_t ds = (p->fields & LAHAR_PFIELD_ID) ? H5Dopen2((hid_t)p->file, name, H5P_DEFAULT) : -1;
    int rc = ds < 0 || (p->n[k] > 0 && H5Dread(ds, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, ids) < 0);
    if (ds >= 0)
        H5Dclose(ds);
    if (rc)
        snprintf(err, n, "granular_impact: particles.h5: %s missing (output: fields needs id)", name);
    return rc ? -1 : 0;
}

static int impact_wall_body(const lahar_case *c)
{
    for (int b = 0; b < c->nbody; b++)
        if (strcmp(c->bodies[b].name, "wall") == 0 && c->bodies[b].motion == LAHAR_MOTION_FIXED)
            return b;
    return -1;
}

/* What granular_impact measures, step by step (the helpers below fill it in order). */
typedef struct {
    /* the set-up and the chute's frame */
    const lahar_material *mat; /* the soil's */
    int wall;                  /* the fixed body `wall` */
    int dim, up, nb;           /* up: the bed's normal axis (the last); nb bodies in the force stream */
    double dx, gtm, m;         /* spacing, |gravity along the chute|, soil particle mass */
    vec3 t;                    /* down the chute: the unit vector along gravity's tangential part */
    /* the soil block at t = 0 */
    double lo[3], hi[3];
    vec3 centre;
    int64_t n0;
    double P0, front0;         /* momentum along t, the block's front along t */
    /* the wall and the chute against which the particles are measured */
    double s_wall, bed, L, M, h_top;
    int side;                  /* the axis across the chute (3D), -1 in 2D */
    /* the particles over the snapshots */
    int64_t escaped, nlast, over;
    double Plast, tlast, fmf_max, fmf_t;
    double *fmf, *pt;          /* [nsnap] momentum flux arriving at the wall; momentum along t */
    int64_t nid;               /* ids are below this */
    double *prev;              /* [nid][3] s, up, across of each id at the last snapshot */
    int64_t *ids;              /* [nmax] the ids of the snapshot read */
    unsigned char *seen;       /* [nid] the id was in an earlier snapshot */
    /* the force stream */
    double J, t_first, raw_peak; /* every body's impulse up to the last snapshot; first impact; raw peak */
    double *force, *jcum;      /* [nrow] F along t on the wall; [nrow + 1] its cumulative impulse */
    double peak, t_peak;       /* the 10 ms moving average's */
} impact;

/* The case and output granular_impact can judge, and the chute's frame: 0, or -1 with r->err. */
static int impact_frame(const lahar_case *c, const lahar_check_data *d, impact *im, lahar_check_result *r)
{
    const lahar_check_particles *p = d->particles;
    im->mat = soil_material(c);
    im->wall = impact_wall_body(c);
    if (!p || !p->phase || !p->vx || !im->mat || p->nsnap < 2 || im->wall < 0 || d->nrow < 2 ||
        d->nbody != c->nbody) {
        snprintf(r->err, sizeof r->err, "granular_impact: needs a soil block, a fixed body named `wall`, the force "
                 "stream (forces.h5), >= 2 snapshots and the particle fields velocity and phase");
        return -1;
    }
    /* the impulses need every step's force, and damping would be an external force in the balance */
    if (c->forces_interval != 0.0 || im->mat->damping != 0.0) {
        snprintf(r->err, sizeof r->err, "granular_impact: needs time.forces_interval: 0 (the impulse of every step) "
                 "and the soil's damping 0 (got %g s, %g 1/s)", c->forces_interval, im->mat->damping);
        return -1;
    }
    im->dim = c->dim, im->up = im->dim - 1, im->nb = d->nbody;
    vec3 gt = v3(c->gravity[0], c->gravity[1], c->gravity[2]);
    if (im->up == 1)
        gt.y = 0.0;
    else
        gt.z = 0.0;
    im->gtm = v3_norm(gt), im->dx = c->sph_dx;
    if (!(im->gtm > 0.0) || !(c->gravity[im->up] < 0.0)) {
        snprintf(r->err, sizeof r->err, "granular_impact: gravity must point into the bed (-%c) with a component "
                 "down the chute", "xyz"[im->up]);
        return -1;
    }
    im->t = v3_scale(gt, 1.0 / im->gtm);
    im->m = im->mat->density * pow(im->dx, im->dim); /* soil particle mass (sph_node: rho dx^D) */
    return 0;
}

/* The initial block (snapshot 0): bed, chute width, centroid, momentum, its front along t.
 * 0, or -1 with r->err. */
static int impact_initial_block(lahar_check_particles *p, impact *im, lahar_check_result *r)
{
    if (lahar_check_particles_read(p, 0, r->err, sizeof r->err))
        return -1;
    const vec3 t = im->t;
    for (int a = 0; a < 3; a++)
        im->lo[a] = INFINITY, im->hi[a] = -INFINITY;
    vec3 centre = v3(0, 0, 0);
    int64_t n0 = 0;
    double P0 = 0.0, front0 = -INFINITY;
    for (int64_t i = 0; i < p->cur_n; i++)
        if (p->phase[i] == 1) {
            const double xx[3] = {p->x[i], p->y[i], p->z[i]};
            for (int a = 0; a < 3; a++)
                im->lo[a] = fmin(im->lo[a], xx[a]), im->hi[a] = fmax(im->hi[a], xx[a]);
            centre = v3_add(centre, v3_load(xx));
            P0 += im->m * (p->vx[i] * t.x + p->vy[i] * t.y + p->vz[i] * t.z);
            front0 = fmax(front0, v3_dot(v3_load(xx), t) + 0.5 * im->dx);
            n0++;
        }
    if (n0 == 0) {
        snprintf(r->err, sizeof r->err, "granular_impact: no soil particles at t = 0");
        return -1;
    }
    im->centre = v3_scale(centre, 1.0 / (double)n0);
    im->n0 = n0, im->P0 = P0, im->front0 = front0;
    return 0;
}

/* The wall's face along t (the body's distance from the block's centroid), the bed, the slab in
 * front of the face, the soil's mass, the wall's top. */
static void impact_wall_geometry(const lahar_case *c, impact *im)
{
    const lahar_body *wb = &c->bodies[im->wall];
    const double dx = im->dx;
    vec3 cp;
    int feature;
    const double wall_gap =
        geom_point_body_core(&wb->shape, wb->x, wb->q, im->centre, &cp, &feature) - wb->shape.radius;
    im->s_wall = v3_dot(im->centre, im->t) + wall_gap; /* the wall's face along t */
    im->bed = im->lo[im->up] - 0.5 * dx;
    im->side = im->up == 2 ? 1 : -1; /* the axis across the chute (3D) */
    im->L = fmax(0.1, 3.0 * dx), im->M = im->m * (double)im->n0;
    /* the top of the wall along the up axis (its highest core vertex + its sweep radius): a particle
     * above it passes over the wall and the side walls (the experiment's overtopping), not through */
    double h_top = -INFINITY;
    for (int v = 0; v < wb->shape.nv; v++) {
        const vec3 xv = v3_add(v3_load(wb->x), q_rotate(q_load(wb->q), v3_load(wb->shape.v[v])));
        h_top = fmax(h_top, (im->up == 2 ? xv.z : xv.y) + wb->shape.radius);
    }
    im->h_top = h_top;
}

/* The escape trackers (by particle id from snapshot to snapshot): needed only while the snapshots
 * are read. */
static void impact_free_tracking(impact *im)
{
    free(im->prev), free(im->ids), free(im->seen);
    im->prev = NULL, im->ids = NULL, im->seen = NULL;
}

static void impact_free(impact *im)
{
    free(im->fmf), free(im->pt), free(im->force), free(im->jcum);
    im->fmf = im->pt = im->force = im->jcum = NULL;
    impact_free_tracking(im);
}

/* Every buffer of the evaluation at once, before any snapshot is read: 0, or -1 ("out of memory"). */
static int impact_alloc(const lahar_check_particles *p, const lahar_check_data *d, impact *im,
                        lahar_check_result *r)
{
    im->nid = 4 * p->nmax + 1; /* ids are below this (particles are never created later) */
    im->fmf = malloc((size_t)p->nsnap * sizeof *im->fmf), im->pt = malloc((size_t)p->nsnap * sizeof *im->pt);
    im->force = malloc((size_t)d->nrow * sizeof *im->force);
    im->jcum = malloc(((size_t)d->nrow + 1) * sizeof *im->jcum);
    im->prev = malloc((size_t)im->nid * 3 * sizeof *im->prev);
    im->ids = malloc((size_t)(p->nmax ? p->nmax : 1) * sizeof *im->ids);
    im->seen = calloc((size_t)im->nid, 1);
    if (!im->fmf || !im->pt || !im->force || !im->jcum || !im->prev || !im->ids || !im->seen) {
        impact_free(im);
        snprintf(r->err, sizeof r->err, "out of memory");
        return -1;
    }
    return 0;
}

/* Did particle `id`, now at s (along t), hgt (up) and acr (across), cross a boundary since the
 * last snapshot, more than 2 dx below the walls' top (a particle arcing over the rounded top edge
 * between two snapshots is not through it)? */
static int impact_crossed(const impact *im, int64_t id, double s, double hgt, double acr)
{
    const double dx = im->dx, s_wall = im->s_wall, bed = im->bed;
    const int side = im->side;
    const double s0 = im->prev[id * 3], h0 = im->prev[id * 3 + 1], a0 = im->prev[id * 3 + 2];
    const int low = h0 < im->h_top - 2.0 * dx && hgt < im->h_top - 2.0 * dx, upstream = s0 <= s_wall && s <= s_wall;
    const double alo = im->lo[side > 0 ? side : 0] - 0.5 * dx, ahi = im->hi[side > 0 ? side : 0] + 0.5 * dx;
    return (s0 <= s_wall && s > s_wall && low) ||                /* through the wall */
           (upstream && h0 >= bed && hgt < bed) ||                /* through the bed */
           (side > 0 && upstream && low &&
            ((a0 >= alo && acr < alo) || (a0 <= ahi && acr > ahi))); /* through a side wall */
}

/* Snapshot k (read): the soil particles' escapes since the last snapshot, those over the wall,
 * their momentum along t and the momentum flux arriving at the wall. */
static void impact_snapshot(const lahar_check_particles *p, int64_t k, impact *im)
{
    const vec3 t = im->t;
    const int up = im->up, side = im->side;
    const double m = im->m, s_wall = im->s_wall, L = im->L;
    double *prev = im->prev;
    unsigned char *seen = im->seen;
    int64_t n = 0, escaped = im->escaped, over = 0;
    double P = 0.0, flux = 0.0;
    for (int64_t i = 0; i < p->cur_n; i++) {
        if (p->phase[i] != 1)
            continue;
        const vec3 x = v3(p->x[i], p->y[i], p->z[i]);
        const double u = p->vx[i] * t.x + p->vy[i] * t.y + p->vz[i] * t.z, s = v3_dot(x, t);
        const double xs[3] = {x.x, x.y, x.z}, hgt = xs[up], acr = side > 0 ? xs[side] : 0.0;
        const int64_t id = im->ids[i];
        if (id < 0 || id >= im->nid || !isfinite(s) || !isfinite(hgt)) {
            escaped++;
            continue;
        }
        if (seen[id])
            escaped += impact_crossed(im, id, s, hgt, acr);
        seen[id] = 1;
        prev[id * 3] = s, prev[id * 3 + 1] = hgt, prev[id * 3 + 2] = acr;
        over += s > s_wall;
        P += m * u;
        if (s > s_wall - L && s <= s_wall && u > 0.0)
            flux += m * u * u / L;
        n++;
    }
    im->escaped = escaped, im->over = over;
    im->fmf[k] = flux, im->pt[k] = P;
    if (flux > im->fmf_max)
        im->fmf_max = flux, im->fmf_t = p->t[k];
    im->nlast = n, im->Plast = P, im->tlast = p->t[k];
}

/* Every snapshot in turn (escapes by id between consecutive snapshots, momentum, momentum flux at
 * the wall); the escape trackers are freed after. 0, or -1 with r->err (the caller frees the buffers). */
static int impact_particles(lahar_check_particles *p, impact *im, lahar_check_result *r)
{
    im->escaped = 0, im->nlast = im->n0, im->over = 0;
    im->Plast = im->P0, im->tlast = p->t[0], im->fmf_max = 0.0, im->fmf_t = 0.0;
    for (int64_t k = 0; k < p->nsnap; k++) {
        if (lahar_check_particles_read(p, k, r->err, sizeof r->err) ||
            impact_read_ids(p, k, im->ids, r->err, sizeof r->err))
            return -1;
        impact_snapshot(p, k, im);
    }
    impact_free_tracking(im);
    return 0;
}

/* The force stream: F(t) on the wall along t and its cumulative impulse, every body's impulse up
 * to the last snapshot, the first impact (F over 1 % of M g_t: a stray particle does not count) and
 * the raw peak. */
static void impact_force_stream(const lahar_check_data *d, impact *im)
{
    const vec3 t = im->t;
    const int wall = im->wall, nb = im->nb;
    double J = 0.0, tprev = 0.0, t_first = NAN, raw_peak = 0.0;
    im->jcum[0] = 0.0;
    for (int64_t k = 0; k < d->nrow; k++) {
        const double *f = d->force + (size_t)k * (size_t)nb * 3;
        im->force[k] = f[wall * 3] * t.x + f[wall * 3 + 1] * t.y + f[wall * 3 + 2] * t.z;
        const double dt = d->ft[k] - tprev;
        im->jcum[k + 1] = im->jcum[k] + im->force[k] * dt;
        if (d->ft[k] <= im->tlast * (1.0 + 1e-12))
            for (int b = 0; b < nb; b++)
                J += (f[b * 3] * t.x + f[b * 3 + 1] * t.y + f[b * 3 + 2] * t.z) * dt;
        if (isnan(t_first) && im->force[k] > 0.01 * im->M * im->gtm)
            t_first = d->ft[k];
        raw_peak = fmax(raw_peak, im->force[k]);
        tprev = d->ft[k];
    }
    im->J = J, im->t_first = t_first, im->raw_peak = raw_peak;
}

/* Every how many rows of the force stream a curve takes a point (about 2000 points at most). */
static int64_t impact_plot_stride(const lahar_check_data *d)
{
    return d->nrow / 2000 + 1;
}

/* Panel 1: the wall force's 10 ms moving average (a load cell's bandwidth: the impulse over
 * [t - w/2, t + w/2] / w, from the cumulative impulse) and its peak, the momentum flux arriving at
 * each snapshot, and the load estimate. */
static void impact_plot_force(const lahar_check_particles *p, const lahar_check_data *d, impact *im,
                              lahar_check_result *r)
{
    const double w = 0.01;
    double peak = 0.0, t_peak = 0.0;
    int64_t lo_k = 0, hi_k = 0;
    const int64_t stride = impact_plot_stride(d);
    int pf = lahar_check_panel(r, "impact force on the wall (along the chute)", "t (s)", "F (N)");
    lahar_check_curve(r, pf, 1, "lahar, 10 ms moving average");
    for (int64_t k = 0; k < d->nrow; k++) {
        const double tc = d->ft[k];
        if (tc - 0.5 * w < 0.0 || tc + 0.5 * w > d->ft[d->nrow - 1])
            continue;
        while (lo_k < d->nrow && d->ft[lo_k] < tc - 0.5 * w)
            lo_k++;
        while (hi_k < d->nrow && d->ft[hi_k] <= tc + 0.5 * w)
            hi_k++;
        const double ta = lo_k > 0 ? d->ft[lo_k - 1] : 0.0, tb = d->ft[hi_k - 1];
        const double fs = tb > ta ? (im->jcum[hi_k] - im->jcum[lo_k]) / (tb - ta) : im->force[k];
        if (fs > peak)
            peak = fs, t_peak = tc;
        if (k % stride == 0)
            lahar_check_point(r, tc, fs);
    }
    im->peak = peak, im->t_peak = t_peak;
    lahar_check_curve(r, pf, 0, "momentum flux rho u^2 A arriving (snapshots)");
    for (int64_t k = 0; k < p->nsnap; k++)
        lahar_check_point(r, p->t[k], im->fmf[k]);
    lahar_check_curve(r, pf, 0, "estimate max rho u^2 A + M g sin(theta)");
    lahar_check_point(r, 0.0, im->fmf_max + im->M * im->gtm);
    lahar_check_point(r, d->ft[d->nrow - 1], im->fmf_max + im->M * im->gtm);
}

/* Panel 2: the momentum balance over time, the particles' side against the bodies' impulses. */
static void impact_plot_momentum(const lahar_check_particles *p, const lahar_check_data *d, const impact *im,
                                 lahar_check_result *r)
{
    const vec3 t = im->t;
    const int nb = im->nb;
    const int64_t stride = impact_plot_stride(d);
    int pm = lahar_check_panel(r, "momentum balance along the chute", "t (s)", "impulse (N s)");
    lahar_check_curve(r, pm, 1, "M g_t t - (P(t) - P(0)) (particles)");
    for (int64_t k = 0; k < p->nsnap; k++)
        lahar_check_point(r, p->t[k], im->M * im->gtm * p->t[k] - (im->pt[k] - im->P0));
    lahar_check_curve(r, pm, 0, "impulse of every body's force (force stream)");
    double jall = 0.0, tprev = 0.0;
    for (int64_t k = 0; k < d->nrow; k++) {
        const double *f = d->force + (size_t)k * (size_t)nb * 3;
        for (int b = 0; b < nb; b++)
            jall += (f[b * 3] * t.x + f[b * 3 + 1] * t.y + f[b * 3 + 2] * t.z) * (d->ft[k] - tprev);
        tprev = d->ft[k];
        if (k % stride == 0)
            lahar_check_point(r, d->ft[k], jall);
    }
    lahar_check_curve(r, pm, 0, "impulse of the wall alone");
    for (int64_t k = 0; k < d->nrow; k += stride)
        lahar_check_point(r, d->ft[k], im->jcum[k + 1]);
}

/* The metrics and the information values (check.json), the note and the convention. */
static void impact_report(const lahar_case *c, const lahar_check_particles *p, const impact *im,
                          lahar_check_result *r)
{
    const int up = im->up;
    const double M = im->M, gtm = im->gtm, dx = im->dx, peak = im->peak, t_first = im->t_first;
    const double grav_impulse = M * gtm * (im->tlast - p->t[0]);
    const double balance = fabs(im->J - (grav_impulse - (im->Plast - im->P0))) / grav_impulse;
    const double theta = atan2(gtm, -c->gravity[up]) * 180.0 / acos(-1.0);
    const double a_block = gtm - im->mat->friction * (-c->gravity[up]);
    const double travel = im->s_wall - im->front0;
    lahar_check_value(r, "escaped_particles", (double)im->escaped);
    lahar_check_value(r, "particle_count_change", fabs((double)(im->nlast - im->n0)));
    lahar_check_value(r, "momentum_balance_rel_error", balance);
    const double load_est = im->fmf_max + M * gtm;
    lahar_check_value(r, "peak_to_load_estimate_log", peak > 0.0 ? fabs(log(peak / load_est)) : INFINITY);
    lahar_check_value(r, "overtopped_particles", (double)im->over);
    lahar_check_value(r, "peak_force_N", peak);
    lahar_check_value(r, "peak_time_s", im->t_peak);
    lahar_check_value(r, "peak_force_raw_N", im->raw_peak);
    lahar_check_value(r, "first_impact_s", t_first);
    lahar_check_value(r, "momentum_flux_max_N", im->fmf_max);
    lahar_check_value(r, "momentum_flux_max_time_s", im->fmf_t);
    lahar_check_value(r, "load_estimate_N", load_est);
    lahar_check_value(r, "weight_along_chute_N", M * gtm);
    lahar_check_value(r, "soil_mass_kg", M);
    lahar_check_value(r, "slope_deg", theta);
    lahar_check_value(r, "travel_m", travel);
    lahar_check_value(r, "dx_m", dx);
    lahar_check_value(r, "wall_face_m", im->s_wall);
    lahar_check_value(r, "wall_top_m", im->h_top);
    /* bounds on the arrival of the front: no later than a rigid block sliding from rest with mu_phi
     * (t_block; the flowing front runs ahead of the block it was), no earlier than the frictionless
     * dam-break front on a slope, s = 2 sqrt(g_n H) t + g_t t^2 / 2 (Ritter's front speed 2 sqrt(g H)
     * of a column of height H plus the free acceleration along the chute; the fastest a mass without
     * any friction spreads) */
    const double t_block = a_block > 0.0 ? sqrt(2.0 * travel / a_block) : INFINITY;
    const double c_front = 2.0 * sqrt(-c->gravity[up] * (im->hi[up] + 0.5 * dx - im->bed));
    const double t_ritter = (-c_front + sqrt(c_front * c_front + 2.0 * gtm * travel)) / gtm;
    lahar_check_value(r, "first_impact_outside_s",
                      isnan(t_first) ? INFINITY : fmax(0.0, fmax(t_ritter - t_first, t_first - t_block)));
    lahar_check_value(r, "sliding_block_arrival_s", t_block);
    lahar_check_value(r, "frictionless_front_arrival_s", t_ritter);
    snprintf(r->note, sizeof r->note, "slope %.1f deg, travel %.3g m from the block's front to the wall; Trujillo-Vela et al. 2020 "
             "Fig. 14-15 give no numbers in the text: no published peak compared", theta, travel);
    snprintf(r->convention, sizeof r->convention, "F = force of the soil on the body `wall` along the chute, "
             "10 ms moving average; F_mf = sum m u^2 / L over particles moving to the wall within L = %.3g m", im->L);
}

int lahar_check_granular_impact(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r)
{
    lahar_check_particles *p = d->particles;
    impact im = {0};
    if (impact_frame(c, d, &im, r) != 0 || impact_initial_block(p, &im, r) != 0)
        return -1;
    impact_wall_geometry(c, &im);
    if (impact_alloc(p, d, &im, r) != 0)
        return -1;
    if (impact_particles(p, &im, r) != 0) {
        impact_free(&im);
        return -1;
    }
    impact_force_stream(d, &im);
    impact_plot_force(p, d, &im, r);
    impact_plot_momentum(p, d, &im, r);
    impact_free(&im);
    impact_report(c, p, &im, r);
    return 0;
}
