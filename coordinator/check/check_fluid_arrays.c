/* `lahar check` references of flows through periodic arrays of fixed obstacles: the drag of a
 * square array of discs (cylinder_array, Sangani & Acrivos 1982) and of a simple cubic array of
 * spheres (sphere_array, Zick & Homsy 1982), as permeabilities K against tabulated values.
 * Shared helpers and the conventions (late window, free-surface level): check_fluid.c. */
#include <math.h>
#include <stdio.h>
#include "check_fluid.h"

/* K at solid fraction x, interpolated in ln K between the tabulated (c_i, K_i), x within the table. */
static double table_ln_interp(const double *tc, const double *tK, int n, double x)
{
    int i = 0;
    while (i + 2 < n && x > tc[i + 1])
        i++;
    double s = (x - tc[i]) / (tc[i + 1] - tc[i]);
    return exp((1.0 - s) * log(tK[i]) + s * log(tK[i + 1]));
}

/* The obstacle of an array case: the first body that is one vertex (a disc or a sphere) and not
 * free; -1 if none. */
static int array_obstacle(const lahar_case *c)
{
    for (int j = 0; j < c->nbody; j++)
        if (c->bodies[j].shape.nv == 1 && c->bodies[j].motion != LAHAR_MOTION_FREE)
            return j;
    return -1;
}

/* The sum over the particles of a snapshot of their velocity along eg. */
static double velocity_sum_along(const lahar_check_particles *p, vec3 eg)
{
    double s = 0.0;
    for (int64_t i = 0; i < p->cur_n; i++)
        s += v3_dot(fluid_vel(p, i), eg);
    return s;
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
    return table_ln_interp(sa_c, sa_K, SA_N, c);
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
    const int disc = array_obstacle(c);
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
        const double s = velocity_sum_along(p, eg);
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
    return table_ln_interp(zh_c, zh_K, ZH_N, c);
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
    const int sph = array_obstacle(c);
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
        const double s = velocity_sum_along(p, eg);
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
