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
 * create() (lammps_create.c) checks everything LAMMPS could refuse before it sends a single command. */
#include "lammps_internal.h"
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <lammps/library.h>

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

void lmp_cmd(lahar_dem_engine *e, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(e->cmd, sizeof e->cmd, fmt, ap);
    va_end(ap);
    lammps_command(e->lmp, e->cmd);
}

/* Issue a fix command and keep it for lmp_refix (id: the fix's ID). */
void lmp_keep_fix(lahar_dem_engine *e, const char *id, const char *fmt, ...)
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
int lmp_is_sphere(const lahar_shape *s)
{
    return s->nv == 1 && s->ne == 0 && s->nf == 0 && s->radius > 0.0 &&
           fabs(s->v[0][0]) + fabs(s->v[0][1]) + fabs(s->v[0][2]) <= 1e-12 * s->radius;
}

/* pair_style granular coefficients for `law` with effective mass mstar (used by the linear law only). */
int lmp_law_coeffs(const dem_pair_law *law, double mstar, char *out, size_t n, char *err, size_t errlen,
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
void lmp_callback(void *ptr, int64_t step, int nlocal, int *ids, double **x, double **fext)
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

void lmp_refix(lahar_dem_engine *e)
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
