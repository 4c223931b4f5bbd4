/* `lahar check` references of the DEM alone: a sphere dropped on a floor (restitution) and a
 * sphere or disc on an incline (incline_roll), against the material's restitution and the rolling
 * or sliding theory. The driver, the reading of the output and the helpers every evaluator uses:
 * check.c. */
#include <inttypes.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "check.h"
#include "geometry.h"
#include "vec.h"

#define check_value lahar_check_value

static vec3 check_vec(const lahar_check_data *d, const double *a, int64_t k, int b)
{
    return v3_load(a + ((size_t)k * (size_t)d->nbody + (size_t)b) * 3);
}

static int check_first_free_body(const lahar_case *c)
{
    for (int b = 0; b < c->nbody; b++)
        if (c->bodies[b].motion == LAHAR_MOTION_FREE)
            return b;
    return -1;
}

static double check_material(const lahar_case *c, int body, size_t off)
{
    int m = c->bodies[body].material;
    if (m < 0 || m >= c->nmaterial)
        return NAN;
    double v;
    memcpy(&v, (const char *)&c->materials[m] + off, sizeof v);
    return v;
}

/* Fixed bodies that ever touched something according to the force stream (all fixed bodies
 * when there is no force stream). */
static int check_fixed_touched(const lahar_case *c, const lahar_check_data *d, int j)
{
    if (c->bodies[j].motion != LAHAR_MOTION_FIXED)
        return 0;
    if (d->nrow == 0)
        return 1;
    for (int64_t k = 0; k < d->nrow; k++)
        if (d->ncontacts[k * d->nbody + j] > 0)
            return 1;
    return 0;
}

/* ---------------------------------------------------------------- restitution ----------- */

static double check_gap(const lahar_case *c, int j, vec3 x, double R, vec3 *normal);

/* A sphere dropped on a fixed floor (reference 06 §6.2/6.3/6.7). Between contacts the body is
 * in free flight, so each snapshot fixes a parabola h(t) = h_k + u_k (t - t_k) - g (t - t_k)^2/2
 * along -g. A bounce lies between the last snapshot moving down and the first moving up; e is
 * the speed of the rising parabola over the speed of the falling one, both taken at the touching
 * height (where the overlap is zero: contact start and end) when the nearest fixed body is a
 * horizontal surface, otherwise at the instant where the two parabolas meet (contact time
 * neglected, an error of order g t_c (1 - e) / 2v). Independent of the snapshot interval. */

/* What restitution measures, step by step (the helpers below fill it in order). */
typedef struct {
    const lahar_check_data *d;
    int b;                     /* the free body */
    vec3 gh;                   /* unit vector along gravity */
    double g, e_ref;           /* |gravity|; the least restitution of the body and what it touched */
    /* the bounces found */
    int nb;
    int64_t last_q;            /* the last bounce's first snapshot after it */
    double err_max;
    /* the first bounce */
    double e_first, u_imp_first, u_reb_first, t_first, h_contact, t_sep_first;
    int64_t p_first;
} bounces;

/* One bounce between the free-flight snapshots p (before) and q (after). */
typedef struct {
    double u_imp, u_reb;       /* the speeds of the falling and of the rising parabola */
    double hi, t_touch, t_sep; /* where and when they are taken: contact start and end */
} bounce;

/* Height of the body along -g at snapshot k, and its velocity along -g. */
static double bounce_h(const bounces *bs, int64_t k) { return -v3_dot(check_vec(bs->d, bs->d->x, k, bs->b), bs->gh); }
static double bounce_u(const bounces *bs, int64_t k) { return -v3_dot(check_vec(bs->d, bs->d->v, k, bs->b), bs->gh); }

/* 1 when the body flies freely from snapshot k0 to k1: u_k follows u_{k-1} - g dt (exact for
 * leap-frog under constant gravity). */
static int bounce_free(const bounces *bs, int64_t k0, int64_t k1)
{
    const double g = bs->g, *t = bs->d->t;
    return fabs(bounce_u(bs, k1) - (bounce_u(bs, k0) - g * (t[k1] - t[k0]))) <=
           1e-6 * (fabs(bounce_u(bs, k0)) + g * (t[k1] - t[k0])) + 1e-12;
}

/* The free body, gravity and the reference e: 0, or -1 with r->err. */
static int bounce_setup(const lahar_case *c, const lahar_check_data *d, bounces *bs, lahar_check_result *r)
{
    int b = check_first_free_body(c);
    vec3 gv = v3_load(c->gravity);
    double g = v3_norm(gv);
    if (b < 0 || g <= 0.0 || d->nsnap < 3) {
        snprintf(r->err, sizeof r->err, "restitution: needs a free body, gravity and >= 3 snapshots (have %" PRId64 ")",
                 d->nsnap);
        return -1;
    }
    bs->d = d, bs->b = b, bs->g = g;
    bs->gh = v3_scale(gv, 1.0 / g);
    double e_ref = check_material(c, b, offsetof(lahar_material, restitution));
    for (int j = 0; j < c->nbody; j++)
        if (check_fixed_touched(c, d, j))
            e_ref = fmin(e_ref, check_material(c, j, offsetof(lahar_material, restitution)));
    bs->e_ref = e_ref;
    bs->e_first = NAN;
    return 0;
}

/* The free-flight snapshots around the turn between k (moving down) and k + 1 (moving up): a
 * snapshot taken during the contact is skipped, at most 3 each way. 1 with *p, *q; 0 when the
 * bounce does not resolve that way (a ball settling, jitter at rest) or overlaps the last one. */
static int bounce_flight(bounces *bs, int64_t k, int64_t *p_out, int64_t *q_out)
{
    const int64_t nsnap = bs->d->nsnap;
    int64_t p = k, q = k + 1;
    for (int tries = 0; tries < 3 && p >= 1 && !bounce_free(bs, p - 1, p); tries++)
        p--;
    for (int tries = 0; tries < 3 && q + 1 < nsnap && !bounce_free(bs, q, q + 1) && bounce_u(bs, q + 1) > 0.0; tries++)
        q++;
    if (p < 1 || p < bs->last_q || !bounce_free(bs, p - 1, p) || q + 1 >= nsnap || !bounce_free(bs, q, q + 1))
        return 0;
    bs->last_q = q;
    *p_out = p, *q_out = q;
    return 1;
}

/* The instant where the falling parabola of p meets the rising one of q, and their speeds there
 * (the contact time neglected, an error of order g t_c (1 - e) / 2v). 1, or 0 when they do not
 * meet between the two snapshots. */
static int bounce_meet(const bounces *bs, int64_t p, int64_t q, bounce *bn)
{
    const double g = bs->g;
    double tp = bs->d->t[p], tq = bs->d->t[q], up = bounce_u(bs, p), uq = bounce_u(bs, q), hp = bounce_h(bs, p),
           hq = bounce_h(bs, q);
    double beta = up - uq - g * (tq - tp);
    double alpha = hp - hq - up * tp + uq * tq + 0.5 * g * (tq - tp) * (tp + tq);
    if (beta == 0.0)
        return 0;
    double ti = -alpha / beta;
    if (!(ti >= tp && ti <= tq))
        return 0;
    bn->u_imp = -(up - g * (ti - tp)), bn->u_reb = uq - g * (ti - tq);
    bn->hi = hp + up * (ti - tp) - 0.5 * g * (ti - tp) * (ti - tp), bn->t_touch = ti, bn->t_sep = ti;
    return 1;
}

/* With a flat floor under the ball the contact starts and ends at the touching height h_c (zero
 * overlap), and energy along each parabola gives the speeds there exactly: u^2 = u_k^2 + 2 g (h_k
 * - h_c). This removes the g t_c/2 bias of the meeting point. 1 (bn changed only over a flat
 * floor), or 0 when p or q lies inside the contact (not free flight). */
static int bounce_flat_floor(const lahar_case *c, const bounces *bs, int64_t p, int64_t q, bounce *bn)
{
    const int b = bs->b;
    const double g = bs->g;
    int floor_j = -1;
    double gap_p = INFINITY;
    vec3 xp = check_vec(bs->d, bs->d->x, p, b), nrm;
    for (int j = 0; j < c->nbody; j++) {
        if (c->bodies[j].motion != LAHAR_MOTION_FIXED || c->bodies[j].shape.nv == 0)
            continue;
        double gap = check_gap(c, j, xp, c->bodies[b].shape.radius, NULL);
        if (gap < gap_p)
            gap_p = gap, floor_j = j;
    }
    if (floor_j < 0 || c->bodies[b].shape.nv != 1)
        return 1;
    check_gap(c, floor_j, xp, c->bodies[b].shape.radius, &nrm);
    double tp = bs->d->t[p], tq = bs->d->t[q], up = bounce_u(bs, p), uq = bounce_u(bs, q), hp = bounce_h(bs, p),
           hq = bounce_h(bs, q);
    double hc = hp - gap_p;
    if (!(-v3_dot(nrm, bs->gh) > 0.999))
        return 1;
    if (!(hp > hc && hq > hc))
        return 0; /* a snapshot inside the contact: not free flight */
    bn->u_imp = sqrt(up * up + 2.0 * g * (hp - hc));
    bn->u_reb = sqrt(uq * uq + 2.0 * g * (hq - hc));
    bn->hi = hc;
    bn->t_touch = tp + (up + bn->u_imp) / g; /* u(t) = up - g (t - tp) reaches -u_imp */
    bn->t_sep = tq - (bn->u_reb - uq) / g;   /* and the rising parabola left h_c at +u_reb */
    return 1;
}

/* The turn between snapshots k and k + 1, if it is a bounce that can be measured: its e against
 * e_ref; the first bounce is kept for the report and the plot. */
static void bounce_measure(const lahar_case *c, bounces *bs, int64_t k)
{
    int64_t p, q;
    bounce bn;
    if (!(bounce_u(bs, k) < 0.0 && bounce_u(bs, k + 1) > 0.0) || !bounce_flight(bs, k, &p, &q) ||
        !bounce_meet(bs, p, q, &bn) || !bounce_flat_floor(c, bs, p, q, &bn))
        return;
    if (bn.u_imp <= 0.0 || bn.u_reb <= 0.0)
        return;
    double e = bn.u_reb / bn.u_imp;
    if (bs->nb == 0) {
        bs->e_first = e, bs->u_imp_first = bn.u_imp, bs->u_reb_first = bn.u_reb, bs->t_first = bn.t_touch;
        bs->h_contact = bn.hi, bs->p_first = p, bs->t_sep_first = bn.t_sep;
    }
    /* later bounces count only while the flight after them spans >= 3 snapshots, so that no
     * second bounce hides between two snapshots */
    double dt_out = bs->d->t[q] - bs->d->t[q - 1];
    if (bs->nb == 0 || 2.0 * bn.u_reb / bs->g >= 3.0 * dt_out)
        bs->err_max = fmax(bs->err_max, fabs(e - bs->e_ref) / bs->e_ref);
    bs->nb++;
}

/* The metrics and the information values (check.json), the note, the title and the axes. */
static void bounce_report(const lahar_case *c, const bounces *bs, lahar_check_result *r)
{
    const double e_ref = bs->e_ref;
    const char *name = c->bodies[bs->b].name;
    check_value(r, "restitution_rel_error", fabs(bs->e_first - e_ref) / e_ref);
    check_value(r, "restitution_rel_error_max", bs->err_max);
    check_value(r, "e_measured", bs->e_first);
    check_value(r, "e_reference", e_ref);
    check_value(r, "impact_speed", bs->u_imp_first);
    check_value(r, "rebound_speed", bs->u_reb_first);
    check_value(r, "impact_time", bs->t_first);
    check_value(r, "bounces", bs->nb);
    snprintf(r->note, sizeof r->note, "body %s; e_ref = min restitution of the body and the fixed bodies it touched",
             name);
    snprintf(r->title, sizeof r->title, "restitution: %s, e = %.4f (reference %.4f)", name, bs->e_first, e_ref);
    snprintf(r->xlabel, sizeof r->xlabel, "t [s]");
    snprintf(r->ylabel, sizeof r->ylabel, "height along -g [m]");
}

/* The measured height next to the reference: the measured flight before the first impact, then
 * bounces at the impact height with e_ref. */
static void bounce_plot(const bounces *bs, lahar_check_result *r)
{
    const lahar_check_data *d = bs->d;
    const double g = bs->g, e_ref = bs->e_ref, t_first = bs->t_first, t_sep_first = bs->t_sep_first;
    const double h_contact = bs->h_contact;
    double t0 = t_sep_first, u0 = e_ref * bs->u_imp_first;
    double hp = bounce_h(bs, bs->p_first), up = bounce_u(bs, bs->p_first), tp = d->t[bs->p_first];
    for (int64_t k = 0; k < d->nsnap && r->nseries < LAHAR_CHECK_MAX_SERIES; k++) {
        double t = d->t[k], href;
        if (t <= t_first) {
            href = hp + up * (t - tp) - 0.5 * g * (t - tp) * (t - tp);
        } else if (t <= t_sep_first) {
            href = h_contact; /* in contact (the overlap is not drawn) */
        } else {
            while (u0 > 1e-9 && t > t0 + 2.0 * u0 / g) {
                t0 += 2.0 * u0 / g;
                u0 *= e_ref;
            }
            href = u0 > 1e-9 ? h_contact + u0 * (t - t0) - 0.5 * g * (t - t0) * (t - t0) : h_contact;
        }
        r->series_t[r->nseries] = t;
        r->series_measured[r->nseries] = bounce_h(bs, k);
        r->series_reference[r->nseries] = href;
        r->nseries++;
    }
}

int lahar_check_restitution(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r)
{
    bounces bs = {0};
    if (bounce_setup(c, d, &bs, r))
        return -1;
    for (int64_t k = 0; k + 1 < d->nsnap; k++)
        bounce_measure(c, &bs, k);
    if (bs.nb == 0) {
        snprintf(r->err, sizeof r->err,
                 "restitution: no bounce of body %s found in %" PRId64 " snapshots (does it reach the floor before "
                 "t_end?)",
                 c->bodies[bs.b].name, d->nsnap);
        return -1;
    }
    bounce_report(c, &bs, r);
    bounce_plot(&bs, r);
    return 0;
}

/* ---------------------------------------------------------------- incline roll ---------- */

/* Least-squares s = c0 + c1 tau + c2 tau^2 (normal equations, 3x3, Gaussian elimination). */
static int check_fit_quadratic(const double *tau, const double *s, int n, double c[3])
{
    double A[3][4] = {{0}};
    for (int i = 0; i < n; i++) {
        double p[3] = {1.0, tau[i], tau[i] * tau[i]};
        for (int r = 0; r < 3; r++) {
            for (int k = 0; k < 3; k++)
                A[r][k] += p[r] * p[k];
            A[r][3] += p[r] * s[i];
        }
    }
    for (int col = 0; col < 3; col++) {
        int piv = col;
        for (int r = col + 1; r < 3; r++)
            if (fabs(A[r][col]) > fabs(A[piv][col]))
                piv = r;
        if (A[piv][col] == 0.0)
            return -1;
        for (int k = 0; k < 4; k++) {
            double tmp = A[col][k];
            A[col][k] = A[piv][k];
            A[piv][k] = tmp;
        }
        for (int r = 0; r < 3; r++) {
            if (r == col)
                continue;
            double f = A[r][col] / A[col][col];
            for (int k = col; k < 4; k++)
                A[r][k] -= f * A[col][k];
        }
    }
    for (int r = 0; r < 3; r++)
        c[r] = A[r][3] / A[r][r];
    return 0;
}

/* Gap between the swept surfaces of the free body (a sphere/disc of radius R) at x and fixed
 * body j; *normal is the outward normal of j at the closest point. */
static double check_gap(const lahar_case *c, int j, vec3 x, double R, vec3 *normal)
{
    const lahar_body *f = &c->bodies[j];
    vec3 cp;
    int feature;
    double dist = geom_point_body_core(&f->shape, f->x, f->q, x, &cp, &feature);
    if (normal)
        *normal = v3_normalize(v3_sub(x, cp));
    return dist - f->shape.radius - R;
}

/* What incline_roll measures, step by step (the helpers below fill it in order). */
typedef struct {
    /* the ball and gravity */
    int b;                     /* the ball: the first free body */
    const lahar_body *ball;
    double g, R, m, I;         /* |gravity|; the ball's radius, mass, moment of inertia */
    vec3 gh;                   /* gravity's direction */
    /* the incline and the contact */
    int inc;                   /* the incline: the fixed body closest to the ball at the first snapshot */
    int64_t i0, i1;            /* the longest run of snapshots in contact */
    /* the theory */
    double cos_t, sin_t;       /* the slope's angle theta */
    vec3 down;                 /* down the slope */
    double k_i, mu, a_ref;     /* I/(m R^2), the friction, the reference acceleration */
    int rolling;
    /* the fit */
    int64_t start;             /* the first snapshot fitted */
    int np;                    /* snapshots fitted */
    double *tau, *s;           /* [np] time since start, distance down the slope */
    double cf[3], a;           /* s = cf[0] + cf[1] tau + cf[2] tau^2; the acceleration 2 cf[2] */
} incline;

/* The ball (a sphere or disc) and gravity: 0, or -1 with r->err. */
static int incline_ball(const lahar_case *c, const lahar_check_data *d, incline *in, lahar_check_result *r)
{
    int b = check_first_free_body(c);
    vec3 gv = v3_load(c->gravity);
    double g = v3_norm(gv);
    if (b < 0 || g <= 0.0 || d->nsnap < 5) {
        snprintf(r->err, sizeof r->err,
                 "incline_roll: needs a free body, gravity and >= 5 snapshots (have %" PRId64 ")", d->nsnap);
        return -1;
    }
    const lahar_body *ball = &c->bodies[b];
    double R = ball->shape.radius, m = ball->mass, I = c->dim == 2 ? ball->inertia[2] : ball->inertia[0];
    if (ball->shape.nv != 1 || R <= 0.0 || m <= 0.0) {
        snprintf(r->err, sizeof r->err, "incline_roll: body %s must be a sphere or disc (one vertex, radius > 0)",
                 ball->name);
        return -1;
    }
    in->b = b, in->ball = ball, in->g = g, in->R = R, in->m = m, in->I = I;
    in->gh = v3_scale(gv, 1.0 / g);
    return 0;
}

/* The incline: the fixed body closest to the ball at the first snapshot. 0, or -1 with r->err. */
static int incline_body(const lahar_case *c, const lahar_check_data *d, incline *in, lahar_check_result *r)
{
    int inc = -1;
    double best = INFINITY;
    vec3 x0 = check_vec(d, d->x, 0, in->b);
    for (int j = 0; j < c->nbody; j++) {
        if (c->bodies[j].motion != LAHAR_MOTION_FIXED)
            continue;
        double gap = check_gap(c, j, x0, in->R, NULL);
        if (gap < best)
            best = gap, inc = j;
    }
    if (inc < 0) {
        snprintf(r->err, sizeof r->err, "incline_roll: no fixed body (the incline) in the case");
        return -1;
    }
    in->inc = inc;
    return 0;
}

/* Contact snapshots: the longest run of consecutive snapshots touching the incline (a ball placed
 * above it may bounce first; one rolling off the end leaves it). 0, or -1 with r->err. */
static int incline_contact(const lahar_case *c, const lahar_check_data *d, incline *in, lahar_check_result *r)
{
    double tol = 0.02 * in->R;
    int64_t i0 = -1, i1 = -1, run0 = -1;
    for (int64_t k = 0; k <= d->nsnap; k++) {
        int touching = k < d->nsnap && check_gap(c, in->inc, check_vec(d, d->x, k, in->b), in->R, NULL) <= tol;
        if (touching && run0 < 0)
            run0 = k;
        if (!touching && run0 >= 0) {
            if (k - run0 > i1 - i0 + 1 || i0 < 0)
                i0 = run0, i1 = k - 1;
            run0 = -1;
        }
    }
    if (i0 < 0) {
        snprintf(r->err, sizeof r->err, "incline_roll: body %s never touches %s", in->ball->name,
                 c->bodies[in->inc].name);
        return -1;
    }
    in->i0 = i0, in->i1 = i1;
    return 0;
}

/* theta from the incline's normal at the closest point where the contact starts (geometry.h) and
 * the reference acceleration (reference 06 §6.4): g sin(theta) / (1 + k), k = I/(m R^2), when the
 * ball rolls, i.e. when mu >= k/(1+k) tan(theta); otherwise g (sin(theta) - mu cos(theta)). */
static void incline_theory(const lahar_case *c, const lahar_check_data *d, incline *in)
{
    const double g = in->g, R = in->R;
    const vec3 gh = in->gh;
    vec3 n;
    check_gap(c, in->inc, check_vec(d, d->x, in->i0, in->b), R, &n);
    double cos_t = fmin(1.0, fmax(-1.0, -v3_dot(n, gh))), sin_t = sqrt(fmax(0.0, 1.0 - cos_t * cos_t));
    in->down = v3_normalize(v3_sub(gh, v3_scale(n, v3_dot(gh, n))));
    double k_i = in->I / (in->m * R * R);
    double mu = fmin(check_material(c, in->b, offsetof(lahar_material, friction)),
                     check_material(c, in->inc, offsetof(lahar_material, friction)));
    int rolling = mu * cos_t >= k_i / (1.0 + k_i) * sin_t;
    in->a_ref = rolling ? g * sin_t / (1.0 + k_i) : g * (sin_t - mu * cos_t);
    in->cos_t = cos_t, in->sin_t = sin_t, in->k_i = k_i, in->mu = mu, in->rolling = rolling;
}

/* The distance travelled down the slope while in contact, after the start transient (the first
 * tenth of the contact window, at least one snapshot), and its quadratic fit. 0, or -1 with r->err
 * (tau and s are freed). */
static int incline_fit(const lahar_check_data *d, incline *in, lahar_check_result *r)
{
    const int64_t i0 = in->i0, i1 = in->i1;
    const int64_t start = i0 + ((i1 - i0 + 1) / 10 > 1 ? (i1 - i0 + 1) / 10 : 1);
    const int np = (int)(i1 - start + 1);
    in->start = start, in->np = np;
    if (np < 4) {
        snprintf(r->err, sizeof r->err,
                 "incline_roll: only %d snapshots in contact after the start; lower time.output_interval", np);
        return -1;
    }
    double *tau = malloc((size_t)np * sizeof *tau), *s = malloc((size_t)np * sizeof *s);
    if (!tau || !s) {
        free(tau), free(s);
        snprintf(r->err, sizeof r->err, "out of memory");
        return -1;
    }
    vec3 xs = check_vec(d, d->x, start, in->b);
    for (int i = 0; i < np; i++) {
        tau[i] = d->t[start + i] - d->t[start];
        s[i] = v3_dot(v3_sub(check_vec(d, d->x, start + i, in->b), xs), in->down);
    }
    int fit = check_fit_quadratic(tau, s, np, in->cf);
    if (fit) {
        free(tau), free(s);
        snprintf(r->err, sizeof r->err, "incline_roll: degenerate fit");
        return -1;
    }
    in->tau = tau, in->s = s;
    in->a = 2.0 * in->cf[2];
    return 0;
}

/* The metric and the information values (check.json), the note, the title, and the fitted
 * distance next to the reference parabola through the fit's start. */
static void incline_report(const lahar_case *c, const lahar_check_data *d, const incline *in, lahar_check_result *r)
{
    const double a = in->a, a_ref = in->a_ref;
    const int rolling = in->rolling, np = in->np;
    const lahar_body *ball = in->ball;
    check_value(r, "accel_rel_error", fabs(a - a_ref) / a_ref);
    check_value(r, "accel_measured", a);
    check_value(r, "accel_reference", a_ref);
    check_value(r, "theta_deg", atan2(in->sin_t, in->cos_t) * 180.0 / M_PI);
    check_value(r, "mu", in->mu);
    check_value(r, "inertia_ratio", in->k_i);
    check_value(r, "rolling", rolling);
    check_value(r, "fit_points", np);
    snprintf(r->note, sizeof r->note, "body %s on %s: %s (mu %s k/(1+k) tan(theta))", ball->name,
             c->bodies[in->inc].name, rolling ? "rolling without slip" : "sliding", rolling ? ">=" : "<");
    snprintf(r->title, sizeof r->title, "incline: %s %s, a = %.5g (reference %.5g) m/s^2", ball->name,
             rolling ? "rolling" : "sliding", a, a_ref);
    snprintf(r->xlabel, sizeof r->xlabel, "t [s]");
    snprintf(r->ylabel, sizeof r->ylabel, "distance down the slope [m]");
    const double *tau = in->tau, *cf = in->cf;
    for (int i = 0; i < np && r->nseries < LAHAR_CHECK_MAX_SERIES; i++) {
        r->series_t[r->nseries] = d->t[in->start + i];
        r->series_measured[r->nseries] = in->s[i];
        r->series_reference[r->nseries] = cf[0] + cf[1] * tau[i] + 0.5 * a_ref * tau[i] * tau[i];
        r->nseries++;
    }
}

/* A sphere or disc on a fixed incline (reference 06 §6.4): acceleration along the slope is
 * g sin(theta) / (1 + k), k = I/(m R^2) (sphere 5/7, disc 2/3), when it rolls, i.e. when
 * mu >= k/(1+k) tan(theta); otherwise g (sin(theta) - mu cos(theta)). theta comes from the
 * incline's geometry (normal at the closest point, geometry.h), the measured acceleration from a
 * quadratic fit of the distance travelled along the slope while in contact. */
int lahar_check_incline_roll(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r)
{
    incline in = {0};
    if (incline_ball(c, d, &in, r) || incline_body(c, d, &in, r) || incline_contact(c, d, &in, r))
        return -1;
    incline_theory(c, d, &in);
    if (incline_fit(d, &in, r))
        return -1;
    incline_report(c, d, &in, r);
    free(in.tau), free(in.s);
    return 0;
}
