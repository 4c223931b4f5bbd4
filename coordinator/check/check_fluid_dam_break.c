/* `lahar check` reference of a collapsing water column (dam_break): mass conservation, no particle
 * escaping the tank or entering a body, a front that only advances, and the front against Martin
 * & Moyce 1952.
 * Shared helpers and the conventions (late window, free-surface level): check_fluid.c. */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include "check_fluid.h"
#include "geometry.h"

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
