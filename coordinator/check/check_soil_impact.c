/* `lahar check` reference granular_impact: a soil mass down a chute onto a fixed wall (documented
 * below and in cases/README.md; the shared soil helpers: check_soil.h). */
#include <hdf5.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "check_soil.h"
#include "geometry.h"
#include "output.h"
#include "vec.h"

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
