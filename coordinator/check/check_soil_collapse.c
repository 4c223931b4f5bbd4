/* `lahar check` reference granular_collapse: a dry soil column's run-out and deposit against the
 * published scalings (documented below and in cases/README.md; the shared soil helpers:
 * check_soil.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "check_soil.h"

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
