/* The LAMMPS DEM engine: lahar_dem_engine_ops on top of the LAMMPS C library (library.h of
 * Debian's liblammps-dev, LAMMPS 29Sep2021). Conventions and limits: README.md in this folder.
 *
 * One LAMMPS instance per engine, serial (lammps_open_no_mpi). Free bodies are atoms of
 * atom_style sphere (tag = 1 + index among the free bodies); fixed planes (3D) and segments (2D)
 * are `fix wall/gran/region` on a `region plane`. The contact law of every pair of materials is
 * the one of dem_node/contact/dem_contact.c (dem_pair_law_make: E*, kn, e -> calibrated damping, mu,
 * kt_ratio), written as `pair_style granular` coefficients per pair of atom types:
 *   linear: hooke kn c_n, c_n = 2 zeta sqrt(kn m*), tangential linear_history kt_ratio kn,
 *           sqrt(kt_ratio) c_n, mu, damping velocity   -> F = kn d + c_n d'
 *   Hertz:  hertz 4/3 E*, tangential mindlin kt_ratio 4/3 E*, damping tsuji (c = alpha sqrt(m* k_H)
 *           d^(1/4), Canelas et al. 2015 eq. 14-15 with the exponent 3/2) with the restitution
 *           handed to LAMMPS chosen so that its polynomial gives lahar's calibrated alpha.
 * Both with limit_damping (the normal force is clipped at 0, as dem_contact.c does). Since c_n of
 * the linear law depends on m*, free bodies of a linear material get one atom type per
 * (material, mass); Hertz needs one type per material (LAMMPS computes m* and R* itself).
 *
 * LAMMPS of Debian is built without C++ exceptions: an error inside LAMMPS ends the process. So
 * create() checks everything LAMMPS could refuse before it sends a single command. */
#include "lammps_engine.h"
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <lammps/library.h>
#include "dem_contact.h"
#include "vec.h"

#define LMP_MAX_TYPES 256 /* atom types (contact classes); pair coefficients grow with the square */
/* a coupling step within LMP_CLOCK_EPS x t_next of n x the current substep is the same step: twice
 * the round-off 2 eps t_next of dt = t_next - t (lmp_advance) */
#define LMP_CLOCK_EPS (4.0 * DBL_EPSILON)

typedef struct {
    int body;        /* index in the scene */
    double p[3], n[3]; /* the contact surface: a point (the face moved out by the sweep radius) and the normal */
    double radius;   /* sweep radius of the wall */
    double c[3];     /* the body's reference point (torques of its report are about it) */
    int material;
} lmp_wall;

struct lahar_dem_engine {
    void *lmp;
    int dim, nbody, nfree, nwall, ntype;
    int *free_of_body;  /* body -> index among the free bodies (tag - 1), -1 for walls */
    int *body_of_free;  /* tag - 1 -> body */
    int *type_of_free;  /* atom type (1-based) */
    double *mass, *radius, *inertia; /* per free body (I = 2/5 m r^2 sphere, 1/2 m r^2 disc) */
    lmp_wall *walls;
    lahar_body_state *st;            /* every body, refreshed after each advance */
    double (*load_f)[3], (*load_t)[3]; /* per free body, constant over the coupling step */
    double (*acc_f)[3], (*acc_t)[3];   /* contact + external, summed over the substeps */
    double (*rep_f)[3], (*rep_t)[3];   /* the report of the last step (time average) */
    double (*last_f)[3], (*last_t)[3]; /* contact force and torque of the last substep */
    /* walls (per body, 0 for free bodies): the contact force the free bodies exert on them, summed
     * over the substeps, the SPH load of the step and the report (time average + load), as
     * spheropoly reports its fixed bodies */
    double (*wacc_f)[3], (*wacc_t)[3], (*wload_f)[3], (*wload_t)[3], (*wrep_f)[3], (*wrep_t)[3];
    int nwfix;            /* wall fixes (one per wall and atom type), made with `contacts` */
    char (*wfix_id)[32];  /* their IDs, for lammps_extract_fix */
    int *wfix_wall;       /* their wall */
    int have_last;
    /* fixes made again before every init after the first (see lmp_advance): the Hertz walls
     * and, after them, the stateless fixes that must follow the walls in post_force order */
    int nrefix, caprefix;
    char (*refix_id)[32];
    char (*refix_cmd)[1024];
    int *ncontact_body, ncontacts;
    double dt_stable, h_last, max_overlap;
    double t_req, lag; /* time the engine was asked to reach; that minus LAMMPS' time (see lmp_advance) */
    int64_t step_start;
    long substep;
    int initialized;
    long long contacts_evaluated;
    int has_fault;
    lahar_dem_fault fault;
    char cmd[1024];
};

/* ---- LAMMPS' Tsuji damping, inverted --------------------------------------------------------- */

double lahar_lammps_tsuji_alpha(double e)
{
    /* the fit pair_style granular uses for `damping tsuji` (LAMMPS documentation, pair_granular) */
    return 1.2728 - 4.2783 * e + 11.087 * e * e - 22.348 * pow(e, 3) + 27.467 * pow(e, 4) - 18.022 * pow(e, 5) +
           4.8218 * pow(e, 6);
}

/* The restitution to give LAMMPS so that its fit returns alpha. The fit decreases on (-inf, 1]
 * (test_dem_lammps checks it on a grid) from +inf to 3e-4; lahar's alpha for e < ~0.27 is above
 * the fit's value at 0 (1.2728), reached with a negative argument, which LAMMPS accepts: it is
 * only the parameter of the polynomial. */
static int tsuji_cor_for_alpha(double alpha, double *cor)
{
    double lo = -1.0, hi = 1.0;
    if (alpha <= lahar_lammps_tsuji_alpha(1.0)) { /* e > ~0.9998: the fit's floor 3e-4, negligible */
        *cor = 1.0;
        return 0;
    }
    while (lahar_lammps_tsuji_alpha(lo) < alpha && lo > -1e3) lo *= 2.0;
    for (int i = 0; i < 200 && hi - lo > 1e-15; i++) {
        double mid = 0.5 * (lo + hi);
        if (lahar_lammps_tsuji_alpha(mid) > alpha) lo = mid;
        else hi = mid;
    }
    *cor = 0.5 * (lo + hi);
    return fabs(lahar_lammps_tsuji_alpha(*cor) - alpha) <= 1e-9 * fmax(alpha, 1e-3) ? 0 : -1;
}

/* ---- small helpers ------------------------------------------------------------------------------ */

static void lmp_cmd(lahar_dem_engine *e, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(e->cmd, sizeof e->cmd, fmt, ap);
    va_end(ap);
    lammps_command(e->lmp, e->cmd);
}

/* Issue a fix command and keep it for lmp_refix (id: the fix's ID). */
static void lmp_keep_fix(lahar_dem_engine *e, const char *id, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(e->cmd, sizeof e->cmd, fmt, ap);
    va_end(ap);
    if (e->nrefix < e->caprefix) {
        snprintf(e->refix_id[e->nrefix], sizeof e->refix_id[0], "%s", id);
        snprintf(e->refix_cmd[e->nrefix], sizeof e->refix_cmd[0], "%s", e->cmd);
        e->nrefix++;
    }
    lammps_command(e->lmp, e->cmd);
}

/* Make the kept fixes again, in their order, and hand fix external its callback again. The only
 * state lost: the tangential springs of the Hertz wall contacts (README.md "Step"). */
static void lmp_refix(lahar_dem_engine *e);

static int is_sphere(const lahar_shape *s)
{
    return s->nv == 1 && s->ne == 0 && s->nf == 0 && s->radius > 0.0 &&
           fabs(s->v[0][0]) + fabs(s->v[0][1]) + fabs(s->v[0][2]) <= 1e-12 * s->radius;
}

/* pair_style granular coefficients for `law` with effective mass mstar (used by the linear law only). */
static int law_coeffs(const dem_pair_law *law, double mstar, char *out, size_t n, char *err, size_t errlen,
                      const char *what)
{
    double sk = sqrt(law->kt_ratio);
    if (law->model == LAHAR_CONTACT_HERTZ) {
        /* F = k_H d^(3/2), k_H = 4/3 E* sqrt(R*): LAMMPS' `hertz k` is k a d with a = sqrt(R* d) */
        double k = 4.0 / 3.0 * law->estar, cor;
        if (tsuji_cor_for_alpha(law->damp, &cor) != 0) {
            snprintf(err, errlen,
                     "%s: restitution %g needs the Hertz damping alpha = %.4g, which LAMMPS' Tsuji damping cannot "
                     "express; use the linear law or dem.engine: spheropoly",
                     what, law->e, law->damp);
            return -1;
        }
        snprintf(out, n, "hertz %.17g %.17g tangential mindlin %.17g %.17g %.17g damping tsuji limit_damping", k, cor,
                 law->kt_ratio * k, sk, law->mu);
    } else {
        double cn = 2.0 * law->damp * sqrt(law->kn * mstar); /* reference 06 sec. 6.2, dem_contact.c */
        snprintf(out, n, "hooke %.17g %.17g tangential linear_history %.17g %.17g %.17g damping velocity limit_damping",
                 law->kn, cn, law->kt_ratio * law->kn, sk, law->mu);
    }
    return 0;
}

/* ---- the step ----------------------------------------------------------------------------------- */

static void accumulate_wall_forces(lahar_dem_engine *e, int nlocal);

/* fix external's callback, at post_force of every substep (and once in the setup of a `run pre yes`):
 * contact forces (pairs and walls) are complete in f and torque, gravity not yet added. */
static void lmp_callback(void *ptr, int64_t step, int nlocal, int *ids, double **x, double **fext)
{
    (void)x;
    lahar_dem_engine *e = ptr;
    double **f = lammps_extract_atom(e->lmp, "f");
    double **tq = lammps_extract_atom(e->lmp, "torque");
    double **om = lammps_extract_atom(e->lmp, "omega");
    const int setup = step == e->step_start;
    const double h = e->h_last;
    if (!setup) accumulate_wall_forces(e, nlocal);
    for (int i = 0; i < nlocal; i++) {
        int k = ids[i] - 1;
        if (setup && e->have_last) {
            /* the setup of `run pre yes` evaluated the contacts again with the full-step velocity;
             * the step goes on with the forces of the last substep (half-step velocity in the
             * dashpots), as velocity Verlet does and spheropoly does */
            for (int a = 0; a < 3; a++) {
                f[i][a] = e->last_f[k][a];
                tq[i][a] = e->last_t[k][a];
            }
        }
        if (!setup)
            for (int a = 0; a < 3; a++) {
                e->last_f[k][a] = f[i][a];
                e->last_t[k][a] = tq[i][a];
            }
        for (int a = 0; a < 3; a++) {
            fext[i][a] = e->load_f[k][a];
            tq[i][a] += e->load_t[k][a];
        }
        if (setup) continue;
        for (int a = 0; a < 3; a++) {
            e->acc_f[k][a] += f[i][a] + fext[i][a];
            e->acc_t[k][a] += tq[i][a];
        }
        /* orientation, not tracked by LAMMPS for spheres: at post_force omega is the half-step
         * value, the exact rotation of the step exp(h omega) (as spheropoly does for spheres) */
        e->have_last = 1;
        lahar_body_state *s = &e->st[e->body_of_free[k]];
        vec3 w = v3(om[i][0], om[i][1], om[i][2]);
        double wn = v3_norm(w);
        if (wn > 0.0) {
            quat r = q_axis_angle(v3_scale(w, 1.0 / wn), wn * h);
            q_store(q_normalize(q_mul(r, q_load(s->q))), s->q);
        }
    }
}

/* The force each wall receives at this substep: minus the force of its fix on every atom in
 * contact (the per-atom array of `contacts`: flag, force on the atom, contact point, radius), with
 * the torque about the wall body's reference point. Called from the callback (the wall fixes have
 * run: they come before fix external). */
static void accumulate_wall_forces(lahar_dem_engine *e, int nlocal)
{
    for (int q = 0; q < e->nwfix; q++) {
        double **arr = lammps_extract_fix(e->lmp, e->wfix_id[q], LMP_STYLE_ATOM, LMP_TYPE_ARRAY, 0, 0);
        if (!arr) continue;
        const lmp_wall *wl = &e->walls[e->wfix_wall[q]];
        double *af = e->wacc_f[wl->body], *at = e->wacc_t[wl->body];
        for (int i = 0; i < nlocal; i++) {
            if (arr[i][0] == 0.0) continue;
            vec3 f = v3(-arr[i][1], -arr[i][2], -arr[i][3]);
            vec3 r = v3(arr[i][4] - wl->c[0], arr[i][5] - wl->c[1], arr[i][6] - wl->c[2]);
            vec3 t = v3_cross(r, f);
            af[0] += f.x, af[1] += f.y, af[2] += f.z;
            at[0] += t.x, at[1] += t.y, at[2] += t.z;
        }
    }
}

static void refresh_state(lahar_dem_engine *e)
{
    int nlocal = lammps_extract_setting(e->lmp, "nlocal");
    int *id = lammps_extract_atom(e->lmp, "id");
    double **x = lammps_extract_atom(e->lmp, "x");
    double **v = lammps_extract_atom(e->lmp, "v");
    double **om = lammps_extract_atom(e->lmp, "omega");
    for (int i = 0; i < nlocal; i++) {
        lahar_body_state *s = &e->st[e->body_of_free[id[i] - 1]];
        for (int a = 0; a < 3; a++) {
            s->x[a] = x[i][a];
            s->v[a] = v[i][a];
            s->w[a] = om[i][a];
        }
    }
}

static void set_fault(lahar_dem_engine *e, const char *what, int body, int other, const double *x, double value,
                      double limit)
{
    e->has_fault = 1;
    snprintf(e->fault.what, sizeof e->fault.what, "%s", what);
    e->fault.body = body;
    e->fault.other = other;
    for (int a = 0; a < 3; a++) e->fault.x[a] = x ? x[a] : NAN;
    e->fault.value = value;
    e->fault.limit = limit;
    e->fault.substep = e->substep;
}

/* Contacts at the end of the step (pairs from LAMMPS' neighbour list, walls by distance), and the
 * checks of the state: finite, no runaway, overlaps below stability.max_overlap. */
static int count_and_check(lahar_dem_engine *e, char *err, size_t errlen)
{
    const lahar_body_state *st = e->st;
    memset(e->ncontact_body, 0, sizeof(int) * (size_t)e->nbody);
    e->ncontacts = 0;
    for (int k = 0; k < e->nfree; k++) {
        int b = e->body_of_free[k];
        const lahar_body_state *s = &st[b];
        int finite = 1;
        for (int a = 0; a < 3; a++) finite = finite && isfinite(s->x[a]) && isfinite(s->v[a]) && isfinite(s->w[a]);
        if (!finite) {
            set_fault(e, "non-finite state", b, -1, NULL, NAN, NAN);
            snprintf(err, errlen, "lammps engine: body %d has a non-finite state after substep %ld", b, e->substep);
            return -1;
        }
        double r = v3_norm(v3_load(s->x));
        if (r > 1e12) {
            set_fault(e, "runaway", b, -1, s->x, r, 1e12);
            snprintf(err, errlen, "lammps engine: body %d ran away (|x| = %g m) by substep %ld", b, r, e->substep);
            return -1;
        }
        for (int w = 0; w < e->nwall; w++) {
            const lmp_wall *wl = &e->walls[w];
            double d = v3_dot(v3_sub(v3_load(s->x), v3_load(wl->p)), v3_load(wl->n));
            double ov = e->radius[k] - d;
            if (ov > 0.0) {
                e->ncontact_body[b]++;
                e->ncontact_body[wl->body]++;
                e->ncontacts++;
                double lim = e->max_overlap * fmin(e->radius[k], wl->radius);
                if (ov > lim) {
                    double cp[3]; /* the middle of the overlap */
                    for (int a = 0; a < 3; a++) cp[a] = s->x[a] - wl->n[a] * (e->radius[k] - 0.5 * ov);
                    set_fault(e, "overlap", b, wl->body, cp, ov, lim);
                    snprintf(err, errlen, "lammps engine: overlap %g m of body %d with wall %d exceeds %g m by substep %ld",
                             ov, b, wl->body, lim, e->substep);
                    return -1;
                }
            }
        }
    }
    int idx = lammps_find_pair_neighlist(e->lmp, "granular", 1, 0, 0);
    if (idx < 0) return 0;
    int *id = lammps_extract_atom(e->lmp, "id");
    double **x = lammps_extract_atom(e->lmp, "x");
    int nel = lammps_neighlist_num_elements(e->lmp, idx);
    for (int el = 0; el < nel; el++) {
        int i, nn, *nb;
        lammps_neighlist_element_neighbors(e->lmp, idx, el, &i, &nn, &nb);
        int ki = id[i] - 1;
        for (int jj = 0; jj < nn; jj++) {
            int j = nb[jj] & 0x1FFFFFFF; /* LAMMPS' NEIGHMASK: the top bits flag special bonds */
            int kj = id[j] - 1;
            double d = v3_norm(v3_sub(v3(x[i][0], x[i][1], x[i][2]), v3(x[j][0], x[j][1], x[j][2])));
            double ov = e->radius[ki] + e->radius[kj] - d;
            if (!(ov > 0.0)) continue;
            int bi = e->body_of_free[ki], bj = e->body_of_free[kj];
            e->ncontact_body[bi]++;
            e->ncontact_body[bj]++;
            e->ncontacts++;
            double lim = e->max_overlap * fmin(e->radius[ki], e->radius[kj]);
            if (ov > lim) {
                int a = bi < bj ? bi : bj, b = bi < bj ? bj : bi;
                double cp[3], u = (e->radius[ki] - 0.5 * ov) / d; /* the middle of the overlap */
                for (int c = 0; c < 3; c++) cp[c] = x[i][c] + (x[j][c] - x[i][c]) * u;
                set_fault(e, "overlap", a, b, cp, ov, lim);
                snprintf(err, errlen, "lammps engine: overlap %g m of bodies %d and %d exceeds %g m by substep %ld", ov,
                         a, b, lim, e->substep);
                return -1;
            }
        }
    }
    return 0;
}

static void lmp_refix(lahar_dem_engine *e)
{
    for (int i = 0; i < e->nrefix; i++) lmp_cmd(e, "unfix %s", e->refix_id[i]);
    for (int i = 0; i < e->nrefix; i++) lammps_command(e->lmp, e->refix_cmd[i]);
    lammps_set_fix_external_callback(e->lmp, "lahar_ext", lmp_callback, e);
}

static int lmp_advance(lahar_dem_engine *e, double dt, const lahar_body_load *loads, char *err, size_t errlen)
{
    e->has_fault = 0;
    if (!(dt > 0.0) || !isfinite(dt)) {
        snprintf(err, errlen, "lammps engine: bad step dt = %g", dt);
        return -1;
    }
    long n = dem_substeps(dt, e->dt_stable);
    if (n > 100000000L) {
        snprintf(err, errlen, "lammps engine: step %g s needs %ld substeps of %g s", dt, n, e->dt_stable);
        return -1;
    }
    double h = dt / (double)n;
    /* The coupling step dt = t_next - t comes from the coordinator's clock and carries its
     * round-off: |dt - D| <= ulp(t) + ulp(t_next) <= 2 eps t_next for a nominal step D. Steps that
     * differ by that much are the same step: LAMMPS keeps its substep h_last, and the engine keeps
     * the difference between the time it was asked to advance and the time LAMMPS advanced (lag,
     * the sum of dt - n h_last, exact to eps dt per step). Only when |lag| would exceed twice the
     * clock's round-off (LMP_CLOCK_EPS x t_next) does the substep change. Without this, a step
     * that differs from the last by one ulp re-initialised LAMMPS (below) and restarted the
     * tangential springs of the Hertz walls at every coupling step. */
    double t_next = e->t_req + dt;
    double lag = e->lag + (dt - (double)n * e->h_last);
    int same = e->initialized && fabs(lag) <= LMP_CLOCK_EPS * fabs(t_next);
    if (same) h = e->h_last;
    e->lag = e->initialized && h == e->h_last ? lag : dt - (double)n * h; /* a new substep: its own residual */
    e->t_req = t_next;
    /* A new substep length needs LAMMPS' init (`run pre yes`): in this version the `timestep`
     * command between runs does not reach the fixes and the pair style, which keep dt from their
     * init. The setup of such a run evaluates the forces again with the full-step velocity; the
     * callback puts back those of the last substep (velocity Verlet goes on unchanged). And an
     * init applies the restitution -> coefficient polynomial of `damping tsuji` again to the
     * coefficient of a fix wall/gran(/region) (FixWallGran::init overwrites it in place): the
     * Hertz wall fixes are made anew before every init after the first. */
    int pre = !e->initialized || h != e->h_last;
    if (pre && e->initialized && e->nrefix > 0) lmp_refix(e);
    /* `run pre no` skips the setup: the first half kick uses the forces left by the last substep
     * of the previous run, with the previous load in them; they get the new load instead (with
     * `pre yes` the setup's force evaluation calls the callback, which applies it) */
    int nlocal = lammps_extract_setting(e->lmp, "nlocal");
    int *id = lammps_extract_atom(e->lmp, "id");
    double **f = lammps_extract_atom(e->lmp, "f"), **tq = lammps_extract_atom(e->lmp, "torque");
    for (int i = 0; i < nlocal; i++) {
        int k = id[i] - 1;
        const lahar_body_load *l = loads ? &loads[e->body_of_free[k]] : NULL;
        for (int a = 0; a < 3; a++) {
            double lf = l ? l->force[a] : 0.0, lt = l ? l->torque[a] : 0.0;
            if (e->dim == 2 && a == 2) lf = 0.0;
            if (e->dim == 2 && a < 2) lt = 0.0;
            if (!pre) {
                f[i][a] += lf - e->load_f[k][a];
                tq[i][a] += lt - e->load_t[k][a];
            }
            e->load_f[k][a] = lf;
            e->load_t[k][a] = lt;
            e->acc_f[k][a] = e->acc_t[k][a] = 0.0;
        }
    }
    for (int w = 0; w < e->nwall; w++) {
        int b = e->walls[w].body;
        for (int a = 0; a < 3; a++) {
            e->wload_f[b][a] = loads ? loads[b].force[a] : 0.0;
            e->wload_t[b][a] = loads ? loads[b].torque[a] : 0.0;
            e->wacc_f[b][a] = e->wacc_t[b][a] = 0.0;
        }
    }
    if (h != e->h_last) lmp_cmd(e, "timestep %.17g", h);
    e->h_last = h;
    e->step_start = *(int64_t *)lammps_extract_global(e->lmp, "ntimestep");
    lmp_cmd(e, "run %ld pre %s post no", n, pre ? "yes" : "no");
    e->initialized = 1;
    e->substep += n;
    for (int k = 0; k < e->nfree; k++)
        for (int a = 0; a < 3; a++) {
            e->rep_f[k][a] = e->acc_f[k][a] / (double)n;
            e->rep_t[k][a] = e->acc_t[k][a] / (double)n;
        }
    for (int w = 0; w < e->nwall; w++) {
        int b = e->walls[w].body;
        for (int a = 0; a < 3; a++) {
            e->wrep_f[b][a] = e->wacc_f[b][a] / (double)n + e->wload_f[b][a];
            e->wrep_t[b][a] = e->wacc_t[b][a] / (double)n + e->wload_t[b][a];
        }
    }
    refresh_state(e);
    if (count_and_check(e, err, errlen) != 0) return -1;
    e->contacts_evaluated += (long long)e->ncontacts * n; /* approximate: the end-of-step count per substep */
    return (int)n;
}

/* ---- setup -------------------------------------------------------------------------------------- */

/* Largest stable substep: the rule every engine uses (dem_stable_dt, dem_contact.h), on the
 * scene's bodies (walls with their sweep radius, as spheropoly), so that both engines take the
 * same substeps. */
static double stable_dt_of(const lahar_case *c, const dem_pair_law *laws, char *err, size_t errlen)
{
    double safety = c->dem_dt_safety > 0.0 ? c->dem_dt_safety : 0.02;
    vec3 lo = v3(DBL_MAX, DBL_MAX, DBL_MAX), hi = v3(-DBL_MAX, -DBL_MAX, -DBL_MAX);
    double vmax = 0.0;
    dem_step_body *sb = malloc((size_t)(c->nbody > 0 ? c->nbody : 1) * sizeof *sb);
    if (!sb) {
        snprintf(err, errlen, "lammps engine: out of memory");
        return 0.0;
    }
    for (int i = 0; i < c->nbody; i++) {
        const lahar_body *b = &c->bodies[i];
        for (int k = 0; k < b->shape.nv; k++) {
            vec3 w = v3_add(v3_load(b->x), q_rotate(q_load(b->q), v3_load(b->shape.v[k])));
            lo = v3(fmin(lo.x, w.x), fmin(lo.y, w.y), fmin(lo.z, w.z));
            hi = v3(fmax(hi.x, w.x), fmax(hi.y, w.y), fmax(hi.z, w.z));
        }
        /* a sphere's bounding radius about its centre is its radius */
        double v = v3_norm(v3_load(b->v)) + v3_norm(v3_load(b->w)) * b->shape.radius;
        if (v > vmax) vmax = v;
        sb[i] = (dem_step_body){.material = b->material, .free = b->motion == LAHAR_MOTION_FREE,
                                .radius = b->shape.radius, .mass = b->mass};
    }
    double extent = c->nbody > 0 ? v3_norm(v3_sub(hi, lo)) : 0.0;
    double dt = dem_stable_dt(sb, c->nbody, laws, c->nmaterial, dem_impact_speed(vmax, v3_norm(v3_load(c->gravity)), extent),
                              safety, c->dt_max);
    free(sb);
    return dt;
}

static void lmp_destroy(lahar_dem_engine *e)
{
    if (!e) return;
    if (e->lmp) lammps_close(e->lmp);
    free(e->free_of_body);
    free(e->body_of_free);
    free(e->type_of_free);
    free(e->mass);
    free(e->radius);
    free(e->inertia);
    free(e->walls);
    free(e->st);
    free(e->load_f);
    free(e->load_t);
    free(e->acc_f);
    free(e->acc_t);
    free(e->rep_f);
    free(e->rep_t);
    free(e->last_f);
    free(e->last_t);
    free(e->wacc_f);
    free(e->wacc_t);
    free(e->wload_f);
    free(e->wload_t);
    free(e->wrep_f);
    free(e->wrep_t);
    free(e->wfix_id);
    free(e->wfix_wall);
    free(e->refix_id);
    free(e->refix_cmd);
    free(e->ncontact_body);
    free(e);
}

/* A fixed body LAMMPS can hold: a plane (3D, one flat face) or a segment (2D, one edge), as the
 * infinite plane through it on the side of the free bodies. */
static int make_wall(const lahar_case *c, int i, lmp_wall *w, char *err, size_t errlen)
{
    const lahar_body *b = &c->bodies[i];
    const lahar_shape *s = &b->shape;
    vec3 p0, n;
    if (c->dim == 3 && s->nf == 1 && s->nv >= 3) {
        int f0 = s->face_start[0];
        vec3 a = v3_load(s->v[s->face_v[f0]]), bb = v3_load(s->v[s->face_v[f0 + 1]]);
        vec3 cc = v3_load(s->v[s->face_v[f0 + 2]]);
        n = v3_cross(v3_sub(bb, a), v3_sub(cc, a));
        p0 = a;
        for (int k = 0; k < s->nv; k++)
            if (fabs(v3_dot(v3_sub(v3_load(s->v[k]), a), v3_normalize(n))) > 1e-9 * (1.0 + v3_norm(v3_load(s->v[k])))) {
                n = v3(0, 0, 0);
                break;
            }
    } else if (c->dim == 2 && s->nv == 2 && s->ne == 1 && s->nf == 0) {
        vec3 a = v3_load(s->v[0]), d = v3_sub(v3_load(s->v[1]), a);
        n = v3(-d.y, d.x, 0.0);
        p0 = a;
    } else {
        n = v3(0, 0, 0);
        p0 = v3(0, 0, 0);
    }
    if (!(v3_norm(n) > 0.0)) {
        snprintf(err, errlen,
                 "%s: body '%s': the lammps engine holds only fixed planes (3D, shape: plane) and segments (2D, shape: "
                 "segment) as walls, not this %d-vertex %d-face shape; use dem.engine: spheropoly",
                 c->path, b->name, s->nv, s->nf);
        return -1;
    }
    n = v3_normalize(n);
    /* the side of the free bodies */
    int pos = 0, neg = 0;
    for (int j = 0; j < c->nbody; j++) {
        if (c->bodies[j].motion != LAHAR_MOTION_FREE) continue;
        double d = v3_dot(v3_sub(v3_load(c->bodies[j].x), p0), n);
        if (d > 0.0) pos++;
        else if (d < 0.0) neg++;
    }
    if (pos && neg) {
        snprintf(err, errlen,
                 "%s: body '%s': free bodies lie on both sides of this wall; the lammps engine makes a wall an infinite "
                 "one-sided plane: split the scene or use dem.engine: spheropoly",
                 c->path, b->name);
        return -1;
    }
    if (neg) n = v3_neg(n);
    w->body = i;
    w->material = b->material;
    w->radius = s->radius;
    for (int a = 0; a < 3; a++) w->c[a] = b->x[a];
    v3_store(v3_axpy(s->radius, n, p0), w->p);
    v3_store(n, w->n);
    return 0;
}

/* ---- create: the refusals, before LAMMPS ------------------------------------------------------- */

/* What create works with and the engine does not keep: the contact law of every pair of materials
 * and the classes behind the atom types. Freed on every way out of lmp_build. */
typedef struct {
    dem_pair_law *laws; /* [a * nmaterial + b] */
    int *tmat;          /* per atom type (0-based): its material */
    double *tmass;      /* per atom type: the mass of its bodies (linear law; c_n needs it), 0 (Hertz) */
} lmp_setup;

static void setup_free(lmp_setup *su)
{
    free(su->laws);
    free(su->tmat);
    free(su->tmass);
}

static int lmp_oom(char *err, size_t errlen)
{
    snprintf(err, errlen, "lammps engine: out of memory");
    return -1;
}

static const dem_pair_law *type_law(const lahar_case *c, const lmp_setup *su, int t, int u)
{
    return &su->laws[su->tmat[t] * c->nmaterial + su->tmat[u]];
}

static const dem_pair_law *wall_law(const lahar_case *c, const lmp_setup *su, int t, const lmp_wall *wl)
{
    return &su->laws[su->tmat[t] * c->nmaterial + wl->material];
}

/* m* of two atom types for the linear law's c_n (Hertz types carry mass 0: LAMMPS computes m*) */
static double type_mstar(const lmp_setup *su, int t, int u)
{
    const double *tmass = su->tmass;
    return tmass[t] > 0.0 && tmass[u] > 0.0 ? tmass[t] * tmass[u] / (tmass[t] + tmass[u]) : 0.0;
}

/* What the engine cannot run whatever the bodies are. */
static int check_case_sections(const lahar_case *c, char *err, size_t errlen)
{
    if (c->checkpoint_interval > 0.0 || c->resume) {
        snprintf(err, errlen,
                 "%s: checkpoint: the lammps engine has no bitwise checkpoint/restart (lahar resume could not "
                 "continue the run bit for bit): remove the checkpoint: section or use dem.engine: spheropoly",
                 c->path);
        return -1;
    }
    if (c->dim != 2 && c->dim != 3) {
        snprintf(err, errlen, "%s: dimensions %d", c->path, c->dim);
        return -1;
    }
    return 0;
}

/* The per-body arrays are sized for every body: how many are free and how many are walls is known
 * only once take_body has seen them all. */
static int alloc_engine(lahar_dem_engine *e, const lahar_case *c, lmp_setup *su, char *err, size_t errlen)
{
    e->dim = c->dim;
    e->nbody = c->nbody;
    e->max_overlap = c->stability.max_overlap > 0.0 ? c->stability.max_overlap : 0.5;
    size_t nb = (size_t)(c->nbody > 0 ? c->nbody : 1);
    e->free_of_body = malloc(nb * sizeof(int));
    e->body_of_free = malloc(nb * sizeof(int));
    e->type_of_free = malloc(nb * sizeof(int));
    e->mass = malloc(nb * sizeof(double));
    e->radius = malloc(nb * sizeof(double));
    e->inertia = malloc(nb * sizeof(double));
    e->walls = calloc(nb, sizeof(lmp_wall));
    e->st = calloc(nb, sizeof(lahar_body_state));
    e->load_f = calloc(nb, sizeof *e->load_f);
    e->load_t = calloc(nb, sizeof *e->load_t);
    e->acc_f = calloc(nb, sizeof *e->acc_f);
    e->acc_t = calloc(nb, sizeof *e->acc_t);
    e->rep_f = calloc(nb, sizeof *e->rep_f);
    e->rep_t = calloc(nb, sizeof *e->rep_t);
    e->last_f = calloc(nb, sizeof *e->last_f);
    e->wacc_f = calloc(nb, sizeof *e->wacc_f);
    e->wacc_t = calloc(nb, sizeof *e->wacc_t);
    e->wload_f = calloc(nb, sizeof *e->wload_f);
    e->wload_t = calloc(nb, sizeof *e->wload_t);
    e->wrep_f = calloc(nb, sizeof *e->wrep_f);
    e->wrep_t = calloc(nb, sizeof *e->wrep_t);
    e->last_t = calloc(nb, sizeof *e->last_t);
    e->ncontact_body = calloc(nb, sizeof(int));
    int nm = c->nmaterial > 0 ? c->nmaterial : 1;
    su->laws = calloc((size_t)nm * (size_t)nm, sizeof *su->laws);
    if (!e->free_of_body || !e->body_of_free || !e->type_of_free || !e->mass || !e->radius || !e->inertia ||
        !e->walls || !e->st || !e->load_f || !e->load_t || !e->acc_f || !e->acc_t || !e->rep_f || !e->rep_t || !e->last_f || !e->last_t ||
        !e->wacc_f || !e->wacc_t || !e->wload_f || !e->wload_t || !e->wrep_f || !e->wrep_t ||
        !e->ncontact_body || !su->laws)
        return lmp_oom(err, errlen);
    return 0;
}

/* The laws of dem_contact.c, combined as spheropoly combines them, so both engines agree. */
static int make_pair_laws(const lahar_case *c, dem_pair_law *laws, char *err, size_t errlen)
{
    for (int a = 0; a < c->nmaterial; a++)
        for (int b = 0; b < c->nmaterial; b++)
            if (dem_pair_law_make(&c->materials[a], &c->materials[b], &laws[a * c->nmaterial + b], err, errlen) != 0)
                return -1;
    return 0;
}

/* Body i becomes a wall (fixed) or a free sphere/disc; anything else is refused by its name, since
 * LAMMPS itself would end the process instead of answering. */
static int take_body(lahar_dem_engine *e, const lahar_case *c, int i, char *err, size_t errlen)
{
    const lahar_body *b = &c->bodies[i];
    e->free_of_body[i] = -1;
    for (int a = 0; a < 3; a++) {
        e->st[i].x[a] = b->x[a];
        e->st[i].v[a] = b->v[a];
        e->st[i].w[a] = b->w[a];
    }
    for (int a = 0; a < 4; a++) e->st[i].q[a] = b->q[a];
    if (b->material < 0 || b->material >= c->nmaterial || c->materials[b->material].model == LAHAR_CONTACT_SOIL) {
        snprintf(err, errlen, "%s: body '%s': needs a DEM material (linear or hertz)", c->path, b->name);
        return -1;
    }
    if (b->motion == LAHAR_MOTION_PRESCRIBED) {
        snprintf(err, errlen,
                 "%s: body '%s': the lammps engine has no prescribed motion; make it fixed or use dem.engine: "
                 "spheropoly",
                 c->path, b->name);
        return -1;
    }
    if (b->motion == LAHAR_MOTION_FIXED) {
        if (make_wall(c, i, &e->walls[e->nwall], err, errlen) != 0) return -1;
        e->nwall++;
        return 0;
    }
    if (!is_sphere(&b->shape)) {
        snprintf(err, errlen,
                 "%s: body '%s': the lammps engine moves only spheres (3D) and discs (2D); this free body is a "
                 "sphero-polyhedron (%d vertices): use dem.engine: spheropoly",
                 c->path, b->name, b->shape.nv);
        return -1;
    }
    /* LAMMPS derives the moment of inertia from mass and radius: a body whose case gives another
     * would silently turn differently */
    double r = b->shape.radius, m = b->mass;
    double iref = (c->dim == 3 ? 0.4 : 0.5) * m * r * r, imom = c->dim == 3 ? b->inertia[0] : b->inertia[2];
    if (!(m > 0.0) || fabs(imom - iref) > 1e-9 * iref) {
        snprintf(err, errlen,
                 "%s: body '%s': mass %g kg and moment of inertia %g are not those of a solid %s (LAMMPS uses "
                 "%g); use dem.engine: spheropoly",
                 c->path, b->name, m, imom, c->dim == 3 ? "sphere" : "disc", iref);
        return -1;
    }
    int k = e->nfree++;
    e->free_of_body[i] = k;
    e->body_of_free[k] = i;
    e->mass[k] = m;
    e->radius[k] = r;
    e->inertia[k] = iref;
    return 0;
}

/* One atom type per material (Hertz) or per (material, mass) (linear: c_n depends on m*). */
static int define_atom_types(lahar_dem_engine *e, const lahar_case *c, lmp_setup *su, char *err, size_t errlen)
{
    int *tmat = su->tmat = malloc((size_t)LMP_MAX_TYPES * sizeof(int));
    double *tmass = su->tmass = malloc((size_t)LMP_MAX_TYPES * sizeof(double));
    if (!tmat || !tmass) return lmp_oom(err, errlen);
    for (int k = 0; k < e->nfree; k++) {
        int mat = c->bodies[e->body_of_free[k]].material;
        double key = c->materials[mat].model == LAHAR_CONTACT_HERTZ ? 0.0 : e->mass[k];
        int t = 0;
        while (t < e->ntype && !(tmat[t] == mat && tmass[t] == key)) t++;
        if (t == e->ntype) {
            if (e->ntype == LMP_MAX_TYPES) {
                snprintf(err, errlen,
                         "%s: more than %d distinct (material, mass) classes of free bodies with the linear law; the "
                         "lammps engine writes one LAMMPS atom type per class: use hertz materials, fewer sizes, or "
                         "dem.engine: spheropoly",
                         c->path, LMP_MAX_TYPES);
                return -1;
            }
            tmat[t] = mat;
            tmass[t] = key;
            e->ntype++;
        }
        e->type_of_free[k] = t + 1;
    }
    return 0;
}

/* Every coefficient start_lammps will write, made once here with the names of the materials and
 * walls for the message: an argument LAMMPS refuses (a Tsuji restitution it cannot express) would
 * end the process. */
static int check_coefficients(const lahar_dem_engine *e, const lahar_case *c, const lmp_setup *su, char *err,
                              size_t errlen)
{
    char coeff[512];
    for (int t = 0; t < e->ntype; t++) {
        for (int u = t; u < e->ntype; u++) {
            char what[1400];
            snprintf(what, sizeof what, "%s: materials '%s'/'%s'", c->path, c->materials[su->tmat[t]].name,
                     c->materials[su->tmat[u]].name);
            if (law_coeffs(type_law(c, su, t, u), type_mstar(su, t, u), coeff, sizeof coeff, err, errlen, what) != 0)
                return -1;
        }
        for (int w = 0; w < e->nwall; w++) {
            char what[1400];
            snprintf(what, sizeof what, "%s: body '%s'", c->path, c->bodies[e->walls[w].body].name);
            if (law_coeffs(wall_law(c, su, t, &e->walls[w]), su->tmass[t], coeff, sizeof coeff, err, errlen, what) != 0)
                return -1;
        }
    }
    return 0;
}

/* The wall fixes (one per wall and atom type) and the fixes made again before an init: every
 * wall x type (the Hertz ones are kept) and four more (external, gravity, integrator, enforce2d). */
static int alloc_fix_tables(lahar_dem_engine *e, char *err, size_t errlen)
{
    e->caprefix = e->nwall * e->ntype + 4;
    e->refix_id = calloc((size_t)e->caprefix, sizeof *e->refix_id);
    e->wfix_id = calloc((size_t)(e->nwall * e->ntype + 1), sizeof *e->wfix_id);
    e->wfix_wall = calloc((size_t)(e->nwall * e->ntype + 1), sizeof *e->wfix_wall);
    e->refix_cmd = calloc((size_t)e->caprefix, sizeof *e->refix_cmd);
    if (!e->refix_id || !e->refix_cmd || !e->wfix_id || !e->wfix_wall) return lmp_oom(err, errlen);
    return 0;
}

/* ---- create: LAMMPS ---------------------------------------------------------------------------- */

/* One serial instance that writes nothing of its own (no log, screen or citation file): the node's
 * output is lahar's. The boundaries shrink-wrap, so that no atom can be lost (README.md "Limits of
 * the build"); in 2D z is periodic. */
static int open_lammps(lahar_dem_engine *e, const lahar_case *c, char *err, size_t errlen)
{
    const char *args[] = {"lahar-dem", "-log", "none", "-screen", "none", "-nocite"};
    e->lmp = lammps_open_no_mpi((int)(sizeof args / sizeof args[0]), (char **)args, NULL);
    if (!e->lmp) {
        snprintf(err, errlen, "lammps engine: lammps_open_no_mpi failed");
        return -1;
    }
    lmp_cmd(e, "units si");
    lmp_cmd(e, "dimension %d", c->dim);
    lmp_cmd(e, "atom_style sphere");
    lmp_cmd(e, "atom_modify map array sort 0 0.0");
    lmp_cmd(e, c->dim == 3 ? "boundary m m m" : "boundary m m p");
    lmp_cmd(e, "comm_modify vel yes");
    lmp_cmd(e, "newton off");
    return 0;
}

/* The box only has to hold the free bodies at the start (it shrink-wraps from there), with one
 * largest radius to spare. Returns the smallest radius, which sets the neighbour skin. */
static double create_box(lahar_dem_engine *e, const lahar_case *c)
{
    double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX}, rmin = DBL_MAX, rmax = 0.0;
    for (int k = 0; k < e->nfree; k++) {
        const double *x = c->bodies[e->body_of_free[k]].x;
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], x[a] - e->radius[k]);
            hi[a] = fmax(hi[a], x[a] + e->radius[k]);
        }
        rmin = fmin(rmin, e->radius[k]);
        rmax = fmax(rmax, e->radius[k]);
    }
    if (e->nfree == 0) {
        for (int a = 0; a < 3; a++) lo[a] = -1.0, hi[a] = 1.0;
        rmin = rmax = 1.0;
    }
    /* 2D: z is periodic; its period (> 4 rmax) keeps the periodic images out of contact */
    if (c->dim == 2) lo[2] = -2.0 * rmax - 0.5, hi[2] = 2.0 * rmax + 0.5;
    for (int a = 0; a < c->dim; a++) lo[a] -= rmax, hi[a] += rmax;
    lmp_cmd(e, "region lahar_box block %.17g %.17g %.17g %.17g %.17g %.17g", lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]);
    lmp_cmd(e, "create_box %d lahar_box", e->ntype > 0 ? e->ntype : 1);
    return rmin;
}

/* The free bodies as atoms, tag = 1 + index among the free bodies; radius, mass and spin are set
 * in LAMMPS' arrays afterwards (lammps_create_atoms takes positions and velocities only). */
static int create_atoms(lahar_dem_engine *e, const lahar_case *c, char *err, size_t errlen)
{
    int *ids = malloc((size_t)e->nfree * sizeof(int));
    double *xs = malloc((size_t)e->nfree * 3 * sizeof(double)), *vs = malloc((size_t)e->nfree * 3 * sizeof(double));
    if (!ids || !xs || !vs) {
        free(ids);
        free(xs);
        free(vs);
        return lmp_oom(err, errlen);
    }
    for (int k = 0; k < e->nfree; k++) {
        const lahar_body *b = &c->bodies[e->body_of_free[k]];
        ids[k] = k + 1;
        for (int a = 0; a < 3; a++) xs[3 * k + a] = b->x[a], vs[3 * k + a] = b->v[a];
        if (c->dim == 2) xs[3 * k + 2] = vs[3 * k + 2] = 0.0;
    }
    lammps_create_atoms(e->lmp, e->nfree, ids, e->type_of_free, xs, vs, NULL, 0);
    free(ids);
    free(xs);
    free(vs);
    int nlocal = lammps_extract_setting(e->lmp, "nlocal");
    int *id = lammps_extract_atom(e->lmp, "id");
    double *rad = lammps_extract_atom(e->lmp, "radius"), *rm = lammps_extract_atom(e->lmp, "rmass");
    double **om = lammps_extract_atom(e->lmp, "omega");
    if (nlocal != e->nfree) {
        snprintf(err, errlen, "lammps engine: LAMMPS created %d of %d spheres", nlocal, e->nfree);
        return -1;
    }
    for (int i = 0; i < nlocal; i++) {
        int k = id[i] - 1;
        const lahar_body *b = &c->bodies[e->body_of_free[k]];
        rad[i] = e->radius[k];
        rm[i] = e->mass[k];
        for (int a = 0; a < 3; a++) om[i][a] = c->dim == 2 && a < 2 ? 0.0 : b->w[a];
    }
    return 0;
}

/* Neighbour lists checked at every substep, and the contact law of every pair of atom types
 * (without free bodies the box still has one type, and LAMMPS' init refuses a type without
 * coefficients). law_coeffs cannot fail here: check_coefficients made the same calls. */
static void write_pair_coeffs(lahar_dem_engine *e, const lahar_case *c, const lmp_setup *su, double rmin, char *err,
                              size_t errlen)
{
    char coeff[512];
    lmp_cmd(e, "neighbor %.17g bin", 0.25 * rmin);
    lmp_cmd(e, "neigh_modify delay 0 every 1 check yes");
    lmp_cmd(e, "pair_style granular");
    if (e->ntype == 0) lmp_cmd(e, "pair_coeff * * hooke 1 0 tangential linear_nohistory 0 0");
    for (int t = 0; t < e->ntype; t++)
        for (int u = t; u < e->ntype; u++) {
            law_coeffs(type_law(c, su, t, u), type_mstar(su, t, u), coeff, sizeof coeff, err, errlen, "");
            lmp_cmd(e, "pair_coeff %d %d %s", t + 1, u + 1, coeff);
        }
}

/* One fix wall/gran/region per wall and atom type (a wall's law depends on the free body's type),
 * each with `contacts` so that accumulate_wall_forces can report the wall's force. The linear
 * fixes come first; the Hertz ones follow and are kept, since lmp_refix must make them anew (and
 * everything after them) before every init but the first (README.md "Step"). */
static void create_walls(lahar_dem_engine *e, const lahar_case *c, const lmp_setup *su, char *err, size_t errlen)
{
    char coeff[512];
    for (int t = 0; t < e->ntype; t++) lmp_cmd(e, "group lahar_t%d type %d", t + 1, t + 1);
    for (int w = 0; w < e->nwall; w++) {
        const lmp_wall *wl = &e->walls[w];
        lmp_cmd(e, "region lahar_w%d plane %.17g %.17g %.17g %.17g %.17g %.17g side in", w, wl->p[0], wl->p[1], wl->p[2],
                wl->n[0], wl->n[1], wl->n[2]);
        for (int t = 0; t < e->ntype; t++) {
            const dem_pair_law *law = wall_law(c, su, t, wl);
            law_coeffs(law, su->tmass[t], coeff, sizeof coeff, err, errlen, "");
            if (law->model == LAHAR_CONTACT_HERTZ) continue; /* after the linear ones, below */
            snprintf(e->wfix_id[e->nwfix], sizeof e->wfix_id[0], "lahar_w%d_%d", w, t + 1);
            e->wfix_wall[e->nwfix++] = w;
            lmp_cmd(e, "fix lahar_w%d_%d lahar_t%d wall/gran/region granular %s region lahar_w%d contacts", w, t + 1,
                    t + 1, coeff, w);
        }
    }
    for (int w = 0; w < e->nwall; w++) {
        const lmp_wall *wl = &e->walls[w];
        for (int t = 0; t < e->ntype; t++) {
            const dem_pair_law *law = wall_law(c, su, t, wl);
            if (law->model != LAHAR_CONTACT_HERTZ) continue;
            law_coeffs(law, su->tmass[t], coeff, sizeof coeff, err, errlen, "");
            char id[32];
            snprintf(id, sizeof id, "lahar_w%d_%d", w, t + 1);
            snprintf(e->wfix_id[e->nwfix], sizeof e->wfix_id[0], "%s", id);
            e->wfix_wall[e->nwfix++] = w;
            lmp_keep_fix(e, id, "fix %s lahar_t%d wall/gran/region granular %s region lahar_w%d contacts", id, t + 1,
                         coeff, w);
        }
    }
}

/* The fixes of the step, after the walls (post_force runs in this order: the callback must see
 * the walls' forces and none of gravity) and kept for lmp_refix: the SPH loads and the report
 * (fix external, lmp_callback), gravity, the integrator, and in 2D enforce2d. */
static void add_step_fixes(lahar_dem_engine *e, const lahar_case *c)
{
    lmp_keep_fix(e, "lahar_ext", "fix lahar_ext all external pf/callback 1 1");
    lammps_set_fix_external_callback(e->lmp, "lahar_ext", lmp_callback, e);
    vec3 gv = v3(c->gravity[0], c->gravity[1], c->dim == 3 ? c->gravity[2] : 0.0);
    double g = v3_norm(gv);
    if (g > 0.0)
        lmp_keep_fix(e, "lahar_g", "fix lahar_g all gravity %.17g vector %.17g %.17g %.17g", g, gv.x / g, gv.y / g,
                     gv.z / g);
    lmp_keep_fix(e, "lahar_nve", c->dim == 3 ? "fix lahar_nve all nve/sphere" : "fix lahar_nve all nve/sphere disc");
    if (c->dim == 2) lmp_keep_fix(e, "lahar_2d", "fix lahar_2d all enforce2d");
}

/* LAMMPS from the checked engine: every command below has been made acceptable beforehand. */
static int start_lammps(lahar_dem_engine *e, const lahar_case *c, const lmp_setup *su, char *err, size_t errlen)
{
    if (open_lammps(e, c, err, errlen) != 0) return -1;
    double rmin = create_box(e, c);
    if (e->nfree > 0 && create_atoms(e, c, err, errlen) != 0) return -1;
    write_pair_coeffs(e, c, su, rmin, err, errlen);
    create_walls(e, c, su, err, errlen);
    add_step_fixes(e, c);
    lmp_cmd(e, "thermo_style custom step");
    lmp_cmd(e, "thermo 0");
    return 0;
}

/* Everything up to LAMMPS itself; with start = 0 the engine is returned before LAMMPS is opened,
 * so that check_case can run every refusal without starting it. */
static lahar_dem_engine *lmp_build(const lahar_case *c, int start, char *err, size_t errlen)
{
    /* everything LAMMPS could refuse is checked before LAMMPS starts (no exceptions in this build) */
    if (check_case_sections(c, err, errlen) != 0) return NULL;
    lahar_dem_engine *e = calloc(1, sizeof *e);
    if (!e) {
        lmp_oom(err, errlen);
        return NULL;
    }
    lmp_setup su = {0};
    if (alloc_engine(e, c, &su, err, errlen) != 0 || make_pair_laws(c, su.laws, err, errlen) != 0) goto fail;
    for (int i = 0; i < c->nbody; i++)
        if (take_body(e, c, i, err, errlen) != 0) goto fail;
    if (define_atom_types(e, c, &su, err, errlen) != 0 || check_coefficients(e, c, &su, err, errlen) != 0 ||
        alloc_fix_tables(e, err, errlen) != 0)
        goto fail;
    e->dt_stable = stable_dt_of(c, su.laws, err, errlen);
    if (!(e->dt_stable > 0.0)) goto fail;
    if (start && start_lammps(e, c, &su, err, errlen) != 0) goto fail;
    setup_free(&su);
    return e;
fail:
    setup_free(&su);
    lmp_destroy(e);
    return NULL;
}

static lahar_dem_engine *lmp_create(const lahar_case *c, char *err, size_t errlen) { return lmp_build(c, 1, err, errlen); }

/* The case's bodies, walls, materials and sections this engine can run (lahar validate, lahar run
 * before any node starts): the refusals of create, without LAMMPS. */
static int lmp_check_case(const lahar_case *c, char *err, size_t errlen)
{
    lahar_dem_engine *e = lmp_build(c, 0, err, errlen);
    if (!e) return -1;
    lmp_destroy(e);
    return 0;
}

/* ---- queries ------------------------------------------------------------------------------------ */

static double lmp_stable_dt(const lahar_dem_engine *e) { return e->dt_stable; }
static int lmp_nbody(const lahar_dem_engine *e) { return e->nbody; }
static int lmp_ncontacts(const lahar_dem_engine *e) { return e->ncontacts; }
static long long lmp_contacts_evaluated(const lahar_dem_engine *e) { return e->contacts_evaluated; }
static void lmp_get_state(const lahar_dem_engine *e, int i, lahar_body_state *out) { *out = e->st[i]; }

static void lmp_get_report(const lahar_dem_engine *e, int i, lahar_body_report *out)
{
    int k = e->free_of_body[i];
    for (int a = 0; a < 3; a++) {
        out->force[a] = k >= 0 ? e->rep_f[k][a] : e->wrep_f[i][a];
        out->torque[a] = k >= 0 ? e->rep_t[k][a] : e->wrep_t[i][a];
    }
    out->ncontacts = e->ncontact_body[i];
}

static double lmp_kinetic_energy(const lahar_dem_engine *e)
{
    double k = 0.0;
    for (int j = 0; j < e->nfree; j++) {
        const lahar_body_state *s = &e->st[e->body_of_free[j]];
        k += 0.5 * e->mass[j] * v3_norm2(v3_load(s->v)) + 0.5 * e->inertia[j] * v3_norm2(v3_load(s->w));
    }
    return k;
}

static int lmp_write_restart(const lahar_dem_engine *e, FILE *f)
{
    (void)e;
    (void)f;
    return -1; /* refused at create (checkpoint:), see README.md */
}

static int lmp_read_restart(lahar_dem_engine *e, FILE *f)
{
    (void)e;
    (void)f;
    return -1;
}

static int lmp_fault(const lahar_dem_engine *e, lahar_dem_fault *out)
{
    if (!e->has_fault) return 0;
    *out = e->fault;
    return 1;
}

const lahar_dem_engine_ops lahar_dem_lammps_ops = {
    .name = "lammps",
    .version = "LAMMPS 29Sep2021 (liblammps)",
    .create = lmp_create,
    .check_case = lmp_check_case,
    .stable_dt = lmp_stable_dt,
    .advance = lmp_advance,
    .nbody = lmp_nbody,
    .get_state = lmp_get_state,
    .get_report = lmp_get_report,
    .ncontacts = lmp_ncontacts,
    .kinetic_energy = lmp_kinetic_energy,
    .contacts_evaluated = lmp_contacts_evaluated,
    .write_restart = lmp_write_restart,
    .read_restart = lmp_read_restart,
    .destroy = lmp_destroy,
    .fault = lmp_fault,
};
