/* `lahar check` references of internal flows, with no free surface: plane Poiseuille flow between
 * two plates (poiseuille), the lid-driven cavity against Ghia et al. (lid_driven_cavity) and the
 * decaying Taylor-Green vortex (taylor_green); analytic or tabulated velocity fields.
 * Shared helpers and the conventions (late window, free-surface level): check_fluid.c. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "check_fluid.h"

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

/* ---------------------------------------------------------------- taylor-green ---------- */

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
