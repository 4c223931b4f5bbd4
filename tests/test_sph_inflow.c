/* Open boundaries (sph_node/inflow/sph_inflow.h) on a 2D channel: a floor (fixed wall) from behind the
 * inlet to x = L, the inlet a vertical line at x = 0 with inward normal +x, water level h.
 *
 *  A. Gumbel hydrograph (Trujillo-Vela et al. 2020, eq. 36, scaled: a_G = 0.2 m, beta_G = 0.1 s,
 *     mu_G = 0.3 s, active on [0, 0.8) s): the volume that crossed the section by t against the
 *     analytic integral A a_G [G(t) - G(0)], G(t) = exp(-exp(-(t - mu_G)/beta_G)) (the Gumbel
 *     CDF), A = h per unit width. Bound: half a row (A dx / 2, the rows are discrete) + 1 % of the
 *     total (the left Riemann sum of u dt), at every 0.05 s.
 *  B. CSV hydrograph t,Q (a trapezoid 0 -> 0.06 m^2/s -> 0): the same against the trapezoid's
 *     integral, same bound; a malformed CSV gives a message with file:line.
 *  C. Constant inflow, outlet line at x = L + 0.05 (outward +x): mass balance every step,
 *     M_domain(t) - M_domain(0) = entered - removed to 1e-12 relative; the outlet removes exactly
 *     the domain particles that vanish (ids tracked); ids unique and below next_id; the
 *     capacity error names inlets[0].max_particles.
 *  D. Supercritical open channel (Froude 2: u = 2 sqrt(g h)) on a frictionless floor with a
 *     free overfall at x = L, removal by the domain box: steady state with the inflow discharge
 *     leaving the domain (last 0.3 s: outflow within 5 % of inflow) and the depth at mid-channel
 *     within 12 % of the prescribed h (shallow water: a supercritical stream on a horizontal
 *     frictionless bed keeps its depth; the bound covers the dx/2 lattice quantisation of the
 *     free surface, dx = h/5). Just past the section (x <= 4 dx) the time-averaged pressure of
 *     each row of dx differs from the hydrostatic rho0 g (h - y) by less than rho0 g h: the
 *     buffer adds no pressure jump beyond the hydrostatic one.
 *  F. A level table h(t) (CSV t,h: 0.03 m rising to 0.07 m in 0.4 s), constant 0.5 m/s: the volume
 *     in against u int h dt, within half a row at the top level + the staircase of the slots
 *     (|A(h) - h| <= dx/2: u dx/2 t) + 1 %, and within half a row + 1 % (the rows take the level
 *     of the time they cross the section, so the buffer's transit does not delay it); the newest
 *     buffer row holds the slots below h(t).
 *  E. 3D: a rectangular inlet (0.1 m wide, level 0.06 m: 5 x 3 slots of dx = 0.02 m) on a
 *     floor, constant 0.5 m/s: 15 slots, area 0.1 x 0.06 m^2, the volume in against A u t within
 *     half a row + 1 %. (No side walls: the water spreads and speeds up past the section, so the
 *     velocity there is not the inlet's.
 *  G. Soil and water leaving (no inlet): a saturated block (a soil lattice and a water lattice on
 *     the same points, as cases/debris_flow_2d.yaml) moving at 1 m/s towards an outlet that covers
 *     the lower half of its height, the upper half leaving through the domain box 0.03 m further.
 *     First one pass with particles already out (soil stress marked by id): exactly those
 *     removed, counted per phase with their masses (summed in particle order: exact), the others
 *     kept in order with their own stress. Then the block runs out: before every pass the
 *     particles out (by the outlet's and the box's geometry) are predicted per phase; the
 *     counters must grow by exactly those counts and masses, the soil's and the water's mass
 *     balance hold (domain + removed = initial, 1e-12), and at the end every particle of both
 *     phases is counted: removed = the block's count, removed mass = the block's mass per phase. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "shape_build.h"
#include "sph_inflow.h"

#include "test_bodies.h"
#include "test_util.h"

static const double G = 9.81;

/* The water of every test here: 2D, Wendland C2 with h = 1.41 dx, rho0 = 1000, mu = 1e-3,
 * Monaghan alpha 0.02, delta-SPH 0.1. */
static void water_params(sph_params *prm, double dx, double c0)
{
    sph_params_default(prm);
    prm->dim = 2;
    prm->dx = dx;
    snprintf(prm->opt.kernel, sizeof prm->opt.kernel, "%s", "wendland2");
    prm->opt.h_over_dx = 1.41;
    prm->rho0 = 1000.0;
    prm->opt.c0 = c0;
    prm->opt.mu = 1e-3;
    prm->opt.alpha = 0.02;
    prm->opt.delta = 0.1;
}

typedef struct {
    sph_fluid f;
    sph_inflow fl;
    lahar_body floor;
    double dx, h;
} channel;

static int channel_open(channel *ch, double dx, double h, double L, double c0, lahar_inlet *in, int noutlet,
                        const lahar_outlet *out, int has_domain, const double lo[3], const double hi[3],
                        double t_end, int64_t extra_cap, char *err, int errlen)
{
    memset(ch, 0, sizeof *ch);
    ch->dx = dx, ch->h = h;
    sph_params prm;
    water_params(&prm, dx, c0);
    prm.body_force[1] = -G;
    const double g[3] = {0.0, -G, 0.0};
    in->x0[0] = 0.0, in->x0[1] = 0.0, in->x0[2] = 0.0;
    in->e1[0] = 0.0, in->e1[1] = 2.0 * h, in->e1[2] = 0.0;
    in->n[0] = 1.0, in->n[1] = 0.0, in->n[2] = 0.0;
    in->level = h;
    in->layers = 3;
    if (sph_inflow_init(&ch->fl, 2, dx, 2.0 * 1.41 * dx, g, 1, in, noutlet, out, has_domain, lo, hi, t_end, err, errlen) != 0)
        return -1;
    const int64_t cap = sph_inflow_capacity(&ch->fl) + extra_cap;
    if (sph_fluid_init(&ch->f, &prm, cap, err, errlen) != 0)
        return -1;
    const double wlo[3] = {-0.2, -0.05, 0.0}, whi[3] = {L, 0.0, 0.0};
    test_fixed_box_lohi(&ch->floor, 2, wlo, whi, 0.002);
    if (sph_fluid_attach_bodies(&ch->f, 1, &ch->floor) != 0 || sph_inflow_start(&ch->fl, &ch->f, 0.0, err, errlen) != 0 ||
        sph_cells_sort(&ch->f.cells, &ch->f.p) != 0 || sph_fluid_rates(&ch->f, NULL, 0.25 * ch->f.k.h / c0) < 0)
        return -1;
    return 0;
}

static void channel_close(channel *ch)
{
    sph_fluid_free(&ch->f);
    sph_inflow_free(&ch->fl);
    lahar_shape_free(&ch->floor.shape);
}

/* one step: open boundaries, then the solver's step; returns the dt taken or -1 */
static double channel_step(channel *ch, double dt_max, char *err, int errlen)
{
    double dt = fmin(sph_fluid_dt(&ch->f), dt_max);
    if (sph_inflow_apply(&ch->fl, &ch->f, ch->f.t, dt, err, errlen) == INT64_MIN)
        return -1.0;
    int64_t c = sph_fluid_step(&ch->f, dt, NULL);
    if (c != 0) {
        snprintf(err, (size_t)errlen, "step at t = %g: %lld crossings", ch->f.t, (long long)c);
        return -1.0;
    }
    return dt;
}

/* volume that entered: particles x dx^2 (each stands for its lattice cell) */
static double entered_volume(const channel *ch) { return (double)ch->fl.counts.entered * ch->dx * ch->dx; }

static void test_hydrograph(const char *name, lahar_inlet *in, double t_stop, double (*exact)(double t, const lahar_inlet *in))
{
    channel ch;
    char err[512];
    const double dx = 0.01, h = 0.05;
    if (channel_open(&ch, dx, h, 1.0, 20.0, in, 0, NULL, 0, NULL, NULL, t_stop, 0, err, sizeof err) != 0) {
        CHECK(0, "%s: set-up: %s", name, err);
        channel_close(&ch);
        return;
    }
    const double A = ch.fl.in[0].area;
    CHECK(fabs(A - h) < 1e-12, "%s: wetted area %g, expected h = %g (level a multiple of dx)", name, A, h);
    const double total = exact(t_stop, in);
    double worst = 0.0, t_next = 0.05;
    while (ch.f.t < t_stop - 1e-12) {
        if (channel_step(&ch, t_next - ch.f.t, err, sizeof err) < 0) {
            CHECK(0, "%s: %s", name, err);
            break;
        }
        if (ch.f.t >= t_next - 1e-12) {
            /* what crossed the section up to the apply at the start of the next step */
            const double ref = exact(ch.f.t, in), got = entered_volume(&ch);
            const double e = fabs(got - ref);
            worst = fmax(worst, e);
            CHECK(e <= 0.5 * A * dx + 0.01 * total + 1e-12, "%s: t = %.3f s: volume in %.6g m^2, hydrograph %.6g m^2 "
                  "(bound %.3g)", name, ch.f.t, got, ref, 0.5 * A * dx + 0.01 * total);
            t_next += 0.05;
        }
    }
    printf("%s: %lld steps to t = %.3g s, volume in %.6g m^2 against %.6g m^2 of the hydrograph; worst |error| "
           "%.3g m^2 (half a row: %.3g m^2); %lld particles created, %lld entered\n",
           name, (long long)ch.f.step, ch.f.t, entered_volume(&ch), total, worst, 0.5 * A * dx,
           (long long)ch.fl.counts.created, (long long)ch.fl.counts.entered);
    CHECK(ch.fl.counts.entered > 10 * ch.fl.in[0].nslot, "%s: the inflow moved (%lld entered)", name,
          (long long)ch.fl.counts.entered);
    channel_close(&ch);
}

/* Gumbel volume: A a_G [G(t) - G(t_start)] */
static double gumbel_volume(double t, const lahar_inlet *in)
{
    const double a = in->gumbel[0], b = in->gumbel[1], mu = in->gumbel[2];
    const double te = fmin(t, in->t_end);
    return in->level * a * (exp(-exp(-(te - mu) / b)) - exp(-exp(-(in->t_start - mu) / b)));
}

/* trapezoid table of Q: exact integral of the piecewise linear Q */
static double table_volume(double t, const lahar_inlet *in)
{
    double v = 0.0;
    for (int r = 0; r + 1 < in->ntable; r++) {
        const double ta = in->table_t[r], tb = in->table_t[r + 1];
        if (t <= ta)
            break;
        const double te = fmin(t, tb);
        const double qa = in->table_v[r], qe = qa + (in->table_v[r + 1] - qa) * (te - ta) / (tb - ta);
        v += 0.5 * (qa + qe) * (te - ta);
    }
    return v;
}

static void test_csv(void)
{
    const char *path = "test_sph_inflow_q.csv";
    FILE *f = fopen(path, "w");
    if (!f) {
        CHECK(0, "cannot write %s", path);
        return;
    }
    fprintf(f, "# a trapezoid hydrograph\nt,Q\n0, 0\n0.15, 0.06\n0.45, 0.06\n0.6, 0\n");
    fclose(f);
    lahar_inlet in;
    memset(&in, 0, sizeof in);
    snprintf(in.name, sizeof in.name, "csv");
    char err[512];
    in.ntable = lahar_hydrograph_read_csv(path, &in.kind, &in.table_t, &in.table_v, err, sizeof err);
    CHECK(in.ntable == 4 && in.kind == LAHAR_HYDRO_TABLE_Q, "csv: %d rows, kind %d (%s)", in.ntable, in.kind,
          in.ntable < 0 ? err : "");
    in.t_start = 0.0, in.t_end = 1e9;
    if (in.ntable == 4)
        test_hydrograph("csv t,Q", &in, 0.7, table_volume);
    free(in.table_t), free(in.table_v);
    /* a malformed row names the file and line */
    f = fopen(path, "w");
    if (f) {
        fprintf(f, "t,u\n0, 1\n0.5; 2\n");
        fclose(f);
    }
    double *tt, *vv;
    int kind;
    int n = lahar_hydrograph_read_csv(path, &kind, &tt, &vv, err, sizeof err);
    CHECK(n < 0 && strstr(err, "test_sph_inflow_q.csv:3:") != NULL, "csv error names file:line: '%s'", err);
    remove(path);
}

/* C: mass balance, outflow counts, ids */
static int cmp_i64(const void *a, const void *b)
{
    const int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

static void test_balance(void)
{
    const double dx = 0.01, h = 0.05, L = 0.4;
    lahar_inlet in;
    memset(&in, 0, sizeof in);
    snprintf(in.name, sizeof in.name, "const");
    in.kind = LAHAR_HYDRO_CONSTANT;
    in.velocity = 1.0;
    in.t_start = 0.0, in.t_end = 1e9;
    lahar_outlet out;
    memset(&out, 0, sizeof out);
    snprintf(out.name, sizeof out.name, "end");
    out.x0[0] = L + 0.05, out.x0[1] = -1.0;
    out.e1[1] = 2.0;
    out.n[0] = 1.0;
    out.depth = 1.0;
    channel ch;
    char err[512];
    const double t_stop = 0.8;
    if (channel_open(&ch, dx, h, L, 20.0, &in, 1, &out, 0, NULL, NULL, t_stop, 0, err, sizeof err) != 0) {
        CHECK(0, "balance: set-up: %s", err);
        channel_close(&ch);
        return;
    }
    sph_particles *p = &ch.f.p;
    int64_t *ids = malloc((size_t)p->cap * sizeof *ids), *ids2 = malloc((size_t)p->cap * sizeof *ids2);
    const double m0 = sph_inflow_domain_mass(&ch.fl, p);
    double worst = 0.0;
    int64_t removed_seen = 0;
    while (ch.f.t < t_stop && ids && ids2) {
        /* the domain particles before the open boundaries act */
        int64_t nd = 0;
        for (int64_t i = 0; i < p->n; i++)
            if (p->inlet[i] < 0)
                ids[nd++] = p->id[i];
        const int64_t removed0 = ch.fl.counts.removed[0];
        const double dt = fmin(sph_fluid_dt(&ch.f), 1e-3);
        if (sph_inflow_apply(&ch.fl, &ch.f, ch.f.t, dt, err, sizeof err) == INT64_MIN) {
            CHECK(0, "balance: %s", err);
            break;
        }
        /* which of them are gone */
        int64_t nk = 0;
        for (int64_t i = 0; i < p->n; i++)
            ids2[nk++] = p->id[i];
        qsort(ids2, (size_t)nk, sizeof *ids2, cmp_i64);
        int64_t gone = 0;
        for (int64_t i = 0; i < nd; i++)
            gone += bsearch(&ids[i], ids2, (size_t)nk, sizeof *ids2, cmp_i64) == NULL;
        CHECK(gone == ch.fl.counts.removed[0] - removed0, "balance: t = %g: %lld particles vanished, %lld counted", ch.f.t,
              (long long)gone, (long long)(ch.fl.counts.removed[0] - removed0));
        removed_seen += gone;
        for (int64_t i = 1; i < nk; i++)
            if (ids2[i] == ids2[i - 1]) {
                CHECK(0, "balance: id %lld twice", (long long)ids2[i]);
                break;
            }
        CHECK(nk == 0 || ids2[nk - 1] < ch.fl.next_id, "balance: id %lld >= next_id %lld", (long long)ids2[nk - 1],
              (long long)ch.fl.next_id);
        const double md = sph_inflow_domain_mass(&ch.fl, p);
        const double bal = (md - m0) - (ch.fl.counts.entered_mass - ch.fl.counts.removed_mass[0]);
        worst = fmax(worst, fabs(bal) / fmax(md, 1e-30));
        if (sph_fluid_step(&ch.f, dt, NULL) != 0) {
            CHECK(0, "balance: step failed at t = %g", ch.f.t);
            break;
        }
    }
    printf("balance: t = %.3g s, %lld entered (%.6g kg/m), %lld removed by the outlet (%.6g kg/m), domain %.6g kg/m, "
           "worst |mass balance| / mass %.3g\n",
           ch.f.t, (long long)ch.fl.counts.entered, ch.fl.counts.entered_mass, (long long)ch.fl.counts.removed[0],
           ch.fl.counts.removed_mass[0], sph_inflow_domain_mass(&ch.fl, p), worst);
    CHECK(worst < 1e-12, "balance: mass balance off by %.3g of the domain's mass", worst);
    CHECK(ch.fl.counts.removed[0] > 100 && removed_seen == ch.fl.counts.removed[0],
          "balance: the outlet removed %lld particles (seen vanish: %lld)", (long long)ch.fl.counts.removed[0],
          (long long)removed_seen);
    free(ids), free(ids2);
    channel_close(&ch);

    /* capacity: a limit of 40 particles is exhausted at the 9th row of 5 slots */
    in.max_particles = 40;
    if (channel_open(&ch, dx, h, L, 20.0, &in, 0, NULL, 0, NULL, NULL, t_stop, 0, err, sizeof err) != 0) {
        CHECK(0, "capacity: set-up: %s", err);
    } else {
        int failed = 0;
        while (ch.f.t < 0.2 && !failed)
            failed = channel_step(&ch, 1e-3, err, sizeof err) < 0;
        CHECK(failed && strstr(err, "inlets[0].max_particles") != NULL, "capacity: error names the key: '%s'",
              failed ? err : "(no error)");
    }
    channel_close(&ch);
}

/* D: supercritical channel reaches a steady depth h and inflow = outflow */
static void test_steady(void)
{
    const double dx = 0.01, h = 0.05, L = 0.6;
    const double u = 2.0 * sqrt(G * h);
    lahar_inlet in;
    memset(&in, 0, sizeof in);
    snprintf(in.name, sizeof in.name, "steady");
    in.kind = LAHAR_HYDRO_CONSTANT;
    in.velocity = u;
    in.t_start = 0.0, in.t_end = 1e9;
    const double lo[3] = {-1.0, -0.3, 0.0}, hi[3] = {L + 0.02, 1.0, 0.0};
    channel ch;
    char err[512];
    const double t_stop = 1.2, t_avg = 0.9;
    if (channel_open(&ch, dx, h, L, 10.0 * u, &in, 0, NULL, 1, lo, hi, t_stop, 0, err, sizeof err) != 0) {
        CHECK(0, "steady: set-up: %s", err);
        channel_close(&ch);
        return;
    }
    double min_in = 0.0, mout_out = 0.0;
    double depth_sum = 0.0;
    int depth_n = 0;
    /* pressure just inside the section (domain particles, x in (0, 4 dx]), time-averaged per row of
     * dx, against the hydrostatic rho0 g (h - y) of the prescribed level */
    enum { NROW = 8 };
    double prow[NROW] = {0}, hrow[NROW] = {0};
    int nrow[NROW] = {0};
    while (ch.f.t < t_stop) {
        if (ch.f.t >= t_avg && min_in == 0.0)
            min_in = ch.fl.counts.entered_mass, mout_out = ch.fl.counts.removed_mass[0];
        if (channel_step(&ch, 1e-3, err, sizeof err) < 0) {
            CHECK(0, "steady: %s", err);
            break;
        }
        if (ch.f.t >= t_avg && ch.f.step % 20 == 0) {
            /* depth at x = L/2: the highest particle centre of the column + dx/2 */
            const sph_particles *p = &ch.f.p;
            double top = -1.0;
            for (int64_t i = 0; i < p->n; i++)
                if (fabs(p->x[i] - 0.5 * L) < dx && p->y[i] > top)
                    top = p->y[i];
            depth_sum += top + 0.5 * dx;
            depth_n++;
            for (int64_t i = 0; i < p->n; i++) {
                const int row = (int)floor(p->y[i] / dx);
                if (p->inlet[i] < 0 && p->x[i] > 0.0 && p->x[i] <= 4.0 * dx && row >= 0 && row < NROW) {
                    prow[row] += p->p[i];
                    hrow[row] += 1000.0 * G * (h - p->y[i]);
                    nrow[row]++;
                }
            }
        }
    }
    /* "nothing inside the domain is disturbed by the buffer": the mean pressure of each row just
     * past the section differs from the hydrostatic one by less than rho0 g h (the hydrostatic
     * pressure at the floor) */
    double worst = 0.0;
    int rows = 0;
    for (int j = 0; j < NROW; j++)
        if (nrow[j] >= 10) {
            worst = fmax(worst, fabs(prow[j] - hrow[j]) / nrow[j]);
            rows++;
        }
    printf("steady: rows just past the inlet (x <= 4 dx): largest |mean p - rho0 g (h - y)| %.1f Pa over %d rows "
           "(rho0 g h = %.1f Pa)\n", worst, rows, 1000.0 * G * h);
    CHECK(rows >= 4, "steady: only %d rows sampled past the inlet", rows);
    CHECK(worst < 1000.0 * G * h, "steady: pressure past the inlet off hydrostatic by %.1f Pa >= rho0 g h = %.1f Pa",
          worst, 1000.0 * G * h);
    const double in_rate = (ch.fl.counts.entered_mass - min_in) / (ch.f.t - t_avg);
    const double out_rate = (ch.fl.counts.removed_mass[0] - mout_out) / (ch.f.t - t_avg);
    const double depth = depth_n ? depth_sum / depth_n : 0.0;
    printf("steady: u = %.3f m/s (Froude 2), h = %.3f m: over t in [%.2f, %.2f] s inflow %.4g kg/(m s), outflow "
           "%.4g kg/(m s) (rho0 u h = %.4g); mean depth at x = %.2f m: %.4f m (%+.1f %%)\n",
           u, h, t_avg, ch.f.t, in_rate, out_rate, 1000.0 * u * h, 0.5 * L, depth, 100.0 * (depth / h - 1.0));
    CHECK(fabs(out_rate / in_rate - 1.0) < 0.05, "steady: outflow %.4g vs inflow %.4g kg/(m s)", out_rate, in_rate);
    CHECK(fabs(depth / h - 1.0) < 0.12, "steady: depth %.4f m vs prescribed level %.4f m", depth, h);
    channel_close(&ch);
}

/* F: level table */
static void test_level(void)
{
    const char *path = "test_sph_inflow_h.csv";
    FILE *fc = fopen(path, "w");
    if (!fc) {
        CHECK(0, "cannot write %s", path);
        return;
    }
    fprintf(fc, "t,h\n0, 0.03\n0.4, 0.07\n1.0, 0.07\n");
    fclose(fc);
    lahar_inlet in;
    memset(&in, 0, sizeof in);
    snprintf(in.name, sizeof in.name, "level");
    char err[512];
    int kind = -1;
    in.nlevel = lahar_hydrograph_read_csv(path, &kind, &in.level_t, &in.level_h, err, sizeof err);
    remove(path);
    CHECK(in.nlevel == 3 && kind == LAHAR_HYDRO_TABLE_H, "level csv: %d rows, kind %d", in.nlevel, kind);
    if (in.nlevel != 3) {
        free(in.level_t), free(in.level_h);
        return;
    }
    in.kind = LAHAR_HYDRO_CONSTANT;
    in.velocity = 0.5;
    in.t_start = 0.0, in.t_end = 1e9;
    channel ch;
    const double dx = 0.01, t_stop = 0.5;
    /* channel_open sets level = h; the table's largest value sets the slots */
    if (channel_open(&ch, dx, 0.07, 1.0, 20.0, &in, 0, NULL, 0, NULL, NULL, t_stop, 0, err, sizeof err) != 0) {
        CHECK(0, "level: set-up: %s", err);
    } else {
        int ok = 1;
        while (ch.f.t < t_stop - 1e-12 && ok)
            ok = channel_step(&ch, 1e-3, err, sizeof err) > 0.0;
        CHECK(ok, "level: %s", err);
        /* u int h dt: h = 0.03 + 0.1 t up to 0.4 s, then 0.07 */
        const double t = ch.f.t, ih = t <= 0.4 ? 0.03 * t + 0.05 * t * t : 0.03 * 0.4 + 0.05 * 0.16 + 0.07 * (t - 0.4);
        const double ref = 0.5 * ih, got = entered_volume(&ch);
        const double bound = 0.5 * 0.07 * dx + 0.5 * 0.5 * dx * t + 0.01 * ref;
        int newest = 0; /* buffer particles of the newest row: those furthest behind the section */
        double back = 0.0;
        for (int64_t i = 0; i < ch.f.p.n; i++)
            if (ch.f.p.inlet[i] == 0)
                back = fmin(back, ch.f.p.x[i]);
        for (int64_t i = 0; i < ch.f.p.n; i++)
            newest += ch.f.p.inlet[i] == 0 && ch.f.p.x[i] < back + 0.5 * dx;
        printf("level: t = %.3g s, volume in %.6g m^2 against u int h dt = %.6g m^2 (bound %.3g); newest buffer row "
               "%d particles (level %.4g m: %d slots below it)\n",
               t, got, ref, bound, newest, ch.fl.in[0].h, (int)floor(ch.fl.in[0].h / dx + 0.5));
        CHECK(fabs(got - ref) <= bound, "level: volume in %.6g vs %.6g", got, ref);
        CHECK(newest == (int)floor(ch.fl.in[0].h / dx + 0.5), "level: newest row %d particles", newest);
        CHECK(fabs(got - ref) <= 0.5 * 0.07 * dx + 0.01 * ref, "level: the volume lags the level by more than half a "
              "row: %.6g vs %.6g", got, ref);
    }
    channel_close(&ch);
    free(in.level_t), free(in.level_h);
}

/* E: 3D rectangle inlet */
static void test_3d(void)
{
    const double dx = 0.02, h = 0.06, u = 0.5;
    lahar_inlet in;
    memset(&in, 0, sizeof in);
    snprintf(in.name, sizeof in.name, "rect");
    in.kind = LAHAR_HYDRO_CONSTANT;
    in.velocity = u;
    in.t_start = 0.0, in.t_end = 1e9;
    in.x0[0] = 0.0, in.x0[1] = 0.0, in.x0[2] = 0.0;
    in.e1[1] = 0.1;            /* across the channel */
    in.e2[2] = 0.12;           /* up */
    in.n[0] = 1.0;
    in.level = h;
    in.layers = 3;
    sph_params prm;
    sph_params_default(&prm);
    prm.dim = 3;
    prm.dx = dx;
    snprintf(prm.opt.kernel, sizeof prm.opt.kernel, "%s", "wendland2");
    prm.opt.h_over_dx = 1.41;
    prm.rho0 = 1000.0;
    prm.opt.c0 = 10.0;
    prm.opt.mu = 1e-3;
    prm.opt.alpha = 0.02;
    prm.opt.delta = 0.1;
    prm.body_force[2] = -G;
    const double g[3] = {0.0, 0.0, -G};
    sph_inflow fl;
    sph_fluid f;
    memset(&f, 0, sizeof f);
    char err[512];
    const double t_stop = 0.3;
    lahar_body floor;
    memset(&floor, 0, sizeof floor);
    if (sph_inflow_init(&fl, 3, dx, 2.0 * 1.41 * dx, g, 1, &in, 0, NULL, 0, NULL, NULL, t_stop, err, sizeof err) != 0 ||
        sph_fluid_init(&f, &prm, sph_inflow_capacity(&fl), err, sizeof err) != 0) {
        CHECK(0, "3d: set-up: %s", err);
        sph_inflow_free(&fl);
        return;
    }
    CHECK(fl.in[0].nslot == 15 && fabs(fl.in[0].area - 0.1 * h) < 1e-12, "3d: %d slots, area %g", fl.in[0].nslot,
          fl.in[0].area);
    const double half[3] = {0.3 - 0.002, 0.1 - 0.002, 0.02 - 0.002}, t[3] = {0.1, 0.05, -0.02};
    if (lahar_shape_make_box(&floor.shape, half, 0.002) != 0)
        abort();
    lahar_shape_transform(&floor.shape, NULL, t, 1.0);
    floor.motion = LAHAR_MOTION_FIXED;
    floor.convex = 1;
    floor.q[0] = 1.0;
    if (sph_fluid_attach_bodies(&f, 1, &floor) != 0 || sph_inflow_start(&fl, &f, 0.0, err, sizeof err) != 0 ||
        sph_cells_sort(&f.cells, &f.p) != 0 || sph_fluid_rates(&f, NULL, 0.25 * f.k.h / prm.opt.c0) < 0) {
        CHECK(0, "3d: start: %s", err);
    } else {
        int ok = 1;
        while (f.t < t_stop && ok) {
            const double dt = fmin(sph_fluid_dt(&f), 1e-3);
            ok = sph_inflow_apply(&fl, &f, f.t, dt, err, sizeof err) != INT64_MIN && sph_fluid_step(&f, dt, NULL) == 0;
        }
        CHECK(ok, "3d: step failed at t = %g: %s", f.t, err);
        const double A = 0.1 * h, vol = (double)fl.counts.entered * dx * dx * dx, ref = A * u * f.t;
        printf("3d: t = %.3g s, %lld entered: volume %.5g m^3 against A u t = %.5g m^3 (half a row %.3g)\n", f.t,
               (long long)fl.counts.entered, vol, ref, 0.5 * A * dx);
        CHECK(fabs(vol - ref) <= 0.5 * A * dx + 0.01 * ref, "3d: volume in %.5g, A u t %.5g", vol, ref);
    }
    sph_fluid_free(&f);
    sph_inflow_free(&fl);
    lahar_shape_free(&floor.shape);
}

/* G: soil and water through an outlet and the domain box */
static int soil_out_geom(const lahar_outlet *o, const double lo[3], const double hi[3], double x, double y)
{
    if (!(x >= lo[0] && x <= hi[0] && y >= lo[1] && y <= hi[1]))
        return 1;
    const double d = (x - o->x0[0]) * o->n[0] + (y - o->x0[1]) * o->n[1];
    const double a = ((x - o->x0[0]) * o->e1[0] + (y - o->x0[1]) * o->e1[1]) / (o->e1[0] * o->e1[0] + o->e1[1] * o->e1[1]);
    return d > 0.0 && d <= o->depth && a >= 0.0 && a <= 1.0;
}

static void test_soil_outflow(void)
{
    const double dx = 0.01, H = 0.1, W = 0.1, L = 0.15, u = 1.0, rho_s = 2000.0, rho_w = 1000.0;
    const int ni = (int)(W / dx + 0.5), nj = (int)(H / dx + 0.5);
    sph_params prm;
    water_params(&prm, dx, 10.0); /* rho0 = rho_w */
    prm.soil = 1;
    prm.soil_mat = (sph_soil_material){.density = rho_s, .young = 1e6, .poisson = 0.3, .phi = 30.0 * 3.14159265358979323846 / 180.0,
                                       .cohesion = 0.0, .psi = 0.0, .mu_phi = 0.5, .av_alpha = 0.1, .g_ref = G,
                                       .rho_water = rho_w};
    lahar_outlet out;
    memset(&out, 0, sizeof out);
    snprintf(out.name, sizeof out.name, "lower");
    out.x0[0] = L, out.x0[1] = 0.0;
    out.e1[1] = 0.5 * H; /* the lower half of the block's height */
    out.n[0] = 1.0;
    out.depth = 1.0;
    const double lo[3] = {-1.0, -1.0, 0.0}, hi[3] = {L + 0.03, 1.0, 0.0};
    const double g[3] = {0.0, -G, 0.0};
    sph_inflow fl;
    sph_fluid f;
    memset(&f, 0, sizeof f);
    char err[512];
    const int64_t n0 = 2 * (int64_t)ni * nj + 8;
    if (sph_inflow_init(&fl, 2, dx, 2.0 * 1.41 * dx, g, 0, NULL, 1, &out, 1, lo, hi, 1.0, err, sizeof err) != 0 ||
        sph_fluid_init(&f, &prm, n0 + sph_inflow_capacity(&fl), err, sizeof err) != 0) {
        CHECK(0, "soil outflow: set-up: %s", err);
        sph_inflow_free(&fl);
        sph_fluid_free(&f);
        return;
    }
    sph_particles *p = &f.p;
    CHECK(p->sig[0] != NULL, "soil outflow: the fluid has soil stress arrays");
    /* 1. one pass with 8 particles already out: water and soil beyond the outlet, water and soil
     *    beyond the box's x and y bounds; the block's own particles (in the domain) kept */
    const double outside[8][3] = {{L + 0.005, 0.01, 0}, {L + 0.005, 0.02, 1}, {L + 0.5, 0.03, 0}, {L + 0.5, 0.04, 1},
                                  {L + 0.1, 0.09, 0},   {L + 0.1, 0.08, 1},   {0.05, -1.5, 0},    {0.05, 1.5, 1}};
    double m_out[2] = {0.0, 0.0}, m_all[2] = {0.0, 0.0};
    int64_t c_out[2] = {0, 0}, c_all[2] = {0, 0};
    for (int ph = 0; ph < 2; ph++)
        for (int i = 0; i < ni; i++)
            for (int j = 0; j < nj; j++) {
                const double x[3] = {(i + 0.5) * dx, (j + 0.5) * dx, 0.0}, v[3] = {u, 0.0, 0.0};
                const double rho = ph ? rho_s : rho_w;
                /* masses differ slightly from particle to particle: a mix-up of phases or
                 * particles in the counters shows */
                const double m = rho * dx * dx * (1.0 + 1e-3 * (i + ni * j) / (ni * nj));
                sph_particles_add(p, x, v, m, rho, ph ? SPH_SOIL_PHASE : 0);
                if (ph == 0 && i == 0 && j == 0)
                    for (int k = 0; k < 8; k++) {
                        const double xo[3] = {outside[k][0], outside[k][1], 0.0};
                        const int pk = (int)outside[k][2];
                        const double mo = (pk ? rho_s : rho_w) * dx * dx * (1.0 + 0.01 * k);
                        sph_particles_add(p, xo, v, mo, pk ? rho_s : rho_w, pk ? SPH_SOIL_PHASE : 0);
                    }
            }
    for (int64_t i = 0; i < p->n; i++) {
        const int ph = p->phase[i] == SPH_SOIL_PHASE;
        const int o = soil_out_geom(&out, lo, hi, p->x[i], p->y[i]);
        c_all[ph] += !o, m_all[ph] += o ? 0.0 : p->m[i];
        if (o)
            c_out[ph]++, m_out[ph] += p->m[i];
        if (ph)
            p->sig[0][i] = -1.0 - (double)p->id[i]; /* a mark that must travel with the particle */
    }
    CHECK(c_out[0] == 4 && c_out[1] == 4, "soil outflow: 4 water and 4 soil particles placed out (%lld, %lld)",
          (long long)c_out[0], (long long)c_out[1]);
    const int64_t nstart = p->n;
    int64_t *ids = malloc((size_t)nstart * sizeof *ids);
    int64_t nk = 0;
    for (int64_t i = 0; i < p->n && ids; i++)
        if (!soil_out_geom(&out, lo, hi, p->x[i], p->y[i]))
            ids[nk++] = p->id[i];
    if (sph_inflow_start(&fl, &f, 0.0, err, sizeof err) != 0 || !ids) {
        CHECK(0, "soil outflow: start: %s", err);
        free(ids);
        sph_inflow_free(&fl);
        sph_fluid_free(&f);
        return;
    }
    const int64_t dn = sph_inflow_apply(&fl, &f, 0.0, 1e-4, err, sizeof err);
    CHECK(dn == -8 && p->n == nstart - 8, "soil outflow: the first pass removed %lld particles (expected 8)", (long long)-dn);
    for (int ph = 0; ph < 2; ph++)
        CHECK(fl.counts.removed[ph] == c_out[ph] && fl.counts.removed_mass[ph] == m_out[ph],
              "soil outflow: phase %d: removed %lld (%.17g kg/m), expected %lld (%.17g kg/m)", ph,
              (long long)fl.counts.removed[ph], fl.counts.removed_mass[ph], (long long)c_out[ph], m_out[ph]);
    int order = p->n == nk, marks = 1;
    for (int64_t i = 0; i < p->n && order; i++) {
        order = p->id[i] == ids[i];
        if (p->phase[i] == SPH_SOIL_PHASE)
            marks &= p->sig[0][i] == -1.0 - (double)p->id[i];
    }
    CHECK(order && marks, "soil outflow: kept particles in order (%d) with their own soil stress (%d)", order, marks);
    free(ids);
    for (int64_t i = 0; i < p->n; i++)
        if (p->phase[i] == SPH_SOIL_PHASE)
            p->sig[0][i] = 0.0;
    /* 2. the block runs out through the outlet (lower half) and the box (upper half) */
    if (sph_cells_sort(&f.cells, p) != 0 || sph_fluid_rates(&f, NULL, 1e-5) < 0) {
        CHECK(0, "soil outflow: rates failed");
        sph_inflow_free(&fl);
        sph_fluid_free(&f);
        return;
    }
    double worst = 0.0;
    int64_t bad = 0, steps = 0, by_outlet = 0, by_box = 0;
    while (p->n > 0 && f.t < 0.5) {
        int64_t pc[2] = {0, 0};
        double pm[2] = {0.0, 0.0};
        for (int64_t i = 0; i < p->n; i++)
            if (soil_out_geom(&out, lo, hi, p->x[i], p->y[i])) {
                const int ph = p->phase[i] == SPH_SOIL_PHASE;
                pc[ph]++, pm[ph] += p->m[i];
                if (p->x[i] <= hi[0] && p->y[i] >= lo[1] && p->y[i] <= hi[1])
                    by_outlet++;
                else
                    by_box++;
            }
        const int64_t r0[2] = {fl.counts.removed[0], fl.counts.removed[1]};
        const double rm0[2] = {fl.counts.removed_mass[0], fl.counts.removed_mass[1]};
        const double dt = fmin(sph_fluid_dt(&f), 1e-3);
        if (sph_inflow_apply(&fl, &f, f.t, dt, err, sizeof err) == INT64_MIN) {
            CHECK(0, "soil outflow: %s", err);
            break;
        }
        double md[2] = {0.0, 0.0};
        for (int64_t i = 0; i < p->n; i++)
            md[p->phase[i] == SPH_SOIL_PHASE] += p->m[i];
        for (int ph = 0; ph < 2; ph++) {
            bad += fl.counts.removed[ph] - r0[ph] != pc[ph];
            bad += fabs(fl.counts.removed_mass[ph] - rm0[ph] - pm[ph]) > 1e-12 * m_all[ph];
            worst = fmax(worst, fabs(md[ph] + fl.counts.removed_mass[ph] - m_out[ph] - m_all[ph]) / m_all[ph]);
        }
        if (p->n > 0 && sph_fluid_step(&f, dt, NULL) != 0) {
            CHECK(0, "soil outflow: step failed at t = %g", f.t);
            break;
        }
        steps++;
    }
    const double rs = fl.counts.removed_mass[1] - m_out[1], rw = fl.counts.removed_mass[0] - m_out[0];
    printf("soil outflow: %lld steps to t = %.3g s: removed %lld water (%.6g kg/m) and %lld soil (%.6g kg/m) of the "
           "block's %lld + %lld (%.6g + %.6g kg/m), %lld by the outlet, %lld by the box; worst per-phase mass balance %.3g\n",
           (long long)steps, f.t, (long long)(fl.counts.removed[0] - c_out[0]), rw,
           (long long)(fl.counts.removed[1] - c_out[1]), rs, (long long)c_all[0], (long long)c_all[1], m_all[0],
           m_all[1], (long long)by_outlet, (long long)by_box, worst);
    CHECK(p->n == 0, "soil outflow: %lld particles still in the domain at t = %g s", (long long)p->n, f.t);
    CHECK(bad == 0, "soil outflow: %lld passes where the counters did not grow by the particles out", (long long)bad);
    CHECK(by_outlet > 0 && by_box > 0, "soil outflow: %lld particles left through the outlet, %lld through the box "
          "(both must act)", (long long)by_outlet, (long long)by_box);
    CHECK(worst < 1e-12, "soil outflow: per-phase mass balance off by %.3g", worst);
    CHECK(fl.counts.removed[0] - c_out[0] == c_all[0] && fl.counts.removed[1] - c_out[1] == c_all[1],
          "soil outflow: removed %lld water, %lld soil of %lld, %lld", (long long)(fl.counts.removed[0] - c_out[0]),
          (long long)(fl.counts.removed[1] - c_out[1]), (long long)c_all[0], (long long)c_all[1]);
    CHECK(fabs(rs - m_all[1]) <= 1e-12 * m_all[1] && fabs(rw - m_all[0]) <= 1e-12 * m_all[0],
          "soil outflow: removed mass soil %.17g of %.17g, water %.17g of %.17g", rs, m_all[1], rw, m_all[0]);
    sph_fluid_free(&f);
    sph_inflow_free(&fl);
}

int main(void)
{
    lahar_inlet in;
    memset(&in, 0, sizeof in);
    snprintf(in.name, sizeof in.name, "gumbel");
    in.kind = LAHAR_HYDRO_GUMBEL;
    in.gumbel[0] = 0.2, in.gumbel[1] = 0.1, in.gumbel[2] = 0.3;
    in.t_start = 0.0, in.t_end = 0.8;
    /* eq. 36 at its peak: a_G / (beta_G e) */
    const double upk = lahar_inlet_hydrograph(&in, 0.3);
    CHECK(fabs(upk - 0.2 / (0.1 * exp(1.0))) < 1e-15, "gumbel peak %.17g", upk);
    CHECK(lahar_inlet_hydrograph(&in, 0.8) == 0.0, "gumbel off at the end of its window");
    test_hydrograph("gumbel", &in, 0.9, gumbel_volume);
    test_csv();
    test_balance();
    test_steady();
    test_3d();
    test_level();
    test_soil_outflow();
    return failures ? 1 : 0;
}
