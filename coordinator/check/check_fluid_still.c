/* `lahar check` references of water at rest and bodies in it: hydrostatic pressure and wall
 * forces in a tank (hydrostatic), a floating box's draft (floating_box, Archimedes) and a disc
 * sinking onto a floor (sinking_disc); each measures a settled state from the free surface, the
 * pressures and the bodies' poses.
 * Shared helpers and the conventions (late window, free-surface level): check_fluid.c. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include "check_fluid.h"
#include "geometry.h"

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
 *  - free_surface_spread_rel: (highest - lowest level gauge) / h, mean over the window;
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
    double tmax;               /* the highest particle at the last snapshot (sizes the rows) */
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
    free(hs->bp), free(hs->by), free(hs->bn);
    hs->bp = hs->by = NULL, hs->bn = NULL;
    fluid_columns_free(&hs->cols);
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
 * whose surface faces up under the lowest particle) and the highest particle, which sizes the
 * rows. 0, or -1 with r->err. */
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
    hs->tmax = -INFINITY;
    for (int64_t i = 0; i < p->cur_n; i++) {
        if (v3_dot(fluid_pos(p, i), up) < v3_dot(fluid_pos(p, ilow), up))
            ilow = i;
        hs->tmax = fmax(hs->tmax, v3_dot(fluid_pos(p, i), up));
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
    if (floor_j < 0) {
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
        if (!fluid_surface(c, p, hs->up, hs->e1, hs->e2, hs->dx, INFINITY, -INFINITY, &hs->cols, &level, &tmin,
                           &tmax))
            continue;
        hs->level_sum += level, hs->spread_sum += tmax - tmin, hs->nwin++;
        hydrostatic_bin_snapshot(p, k, hs);
    }
    if (hs->nwin == 0) {
        snprintf(r->err, sizeof r->err,
                 "hydrostatic: no free surface found: the water must reach a kernel support (%s, h = %g dx) beyond "
                 "its sides, and sph.kernel must be valid",
                 c->sph.kernel, c->sph.h_over_dx);
        return -1;
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
             "floor %s; h from the free-surface level (mean of the level gauges, kernel volume fraction 1/2); "
             "wall force: late-window mean, worst side wall, reference rho g h^2/2 per unit width",
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
 * pressure carries the box, p = rho_f g d. The level gauges' surface (fluid_surface, a kernel
 * support clear of the box and the walls) is reported as draft_level (at dx = 10 mm 0.16 mm above
 * the pressure's zero: draft -0.78 % against -1.09 %).
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
    fluid_columns cols = {0};
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
            fluid_columns_free(&cols);
            return -1;
        }
        double level, tmin, tmax, zero, grad;
        if (!fluid_surface(c, p, up, e1, e2, dx, slo - R - dx, shi + R + dx, &cols, &level, &tmin,
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
    fluid_columns_free(&cols);
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
    lahar_check_value(r, "draft_level", sum_cols / nwin);
    lahar_check_value(r, "draft_level_rel_error", fabs(sum_cols / nwin - d_ref) / d_ref);
    lahar_check_value(r, "pressure_gradient_over_rho_g", sum_grad / nwin);
    lahar_check_value(r, "draft_reference", d_ref);
    lahar_check_value(r, "box_height", hb);
    lahar_check_value(r, "box_density", rho_b);
    lahar_check_value(r, "tilt_deg", tilt);
    snprintf(r->note, sizeof r->note,
             "box %s; draft averaged over the snapshots of the last 10 %% of the run (%d); free surface: where the "
             "pressure of the water 3 dx clear of every body extrapolates to zero (draft_level: from the level gauges "
             "instead)",
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
