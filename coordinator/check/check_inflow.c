/* `lahar check` reference `inflow` (cases/README.md): open boundaries of the SPH fluid
 * (common/scene/inflow.h, sph_node/inflow/sph_inflow.h), from the counters every particle snapshot carries
 * (attributes flow_*, common/io/output.h) and the particles.
 *
 *   discharge_rel_error: the volume that entered through the inlets by each snapshot (particles
 *     entered x dx^D, each particle standing for its lattice cell) against the hydrographs'
 *     integral: sum over inlets of A * int u dt (A the wetted area of the section below the level,
 *     sampled on 4000 points along the line / 400 x 400 on the rectangle) or int Q dt for t,Q
 *     tables (trapezoids on 20000 intervals; with a level table int A(h(t)) u dt on 2000); the
 *     largest difference over the snapshots divided by the reference volume at the end.
 *   mass_balance_rel_error: the largest |M(t) - M(0) - (entered - removed)| / M(t) over the
 *     snapshots, M the domain's mass (buffers excluded).
 *   outflow_rel_error: over the last third of the snapshots, |mass removed / mass entered - 1|
 *     (a steady state passes its inflow on).
 *   depth_rel_error (one inlet and at least one outlet): over the last third of the snapshots, the
 *     mean depth at the station halfway between the inlet's centre and the first outlet's centre
 *     (a level gauge there: where the domain particles' kernel-summed volume fraction falls to
 *     1/2, common/kernels/kernel.h, above the inlet section's lowest point) against the inlet's
 *     level. */
#include <hdf5.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "kernel.h"
#include "output.h"

static int flow_attrs(const lahar_check_particles *p, int64_t k, double v[LAHAR_FLOW_NVAL])
{
    char name[48];
    snprintf(name, sizeof name, "snapshots/%06lld", (long long)k);
    for (int a = 0; a < LAHAR_FLOW_NVAL; a++) {
        hid_t at = H5Aopen_by_name((hid_t)p->file, name, lahar_flow_names[a], H5P_DEFAULT, H5P_DEFAULT);
        if (at < 0)
            return -1;
        herr_t rc = H5Aread(at, H5T_NATIVE_DOUBLE, &v[a]);
        H5Aclose(at);
        if (rc < 0)
            return -1;
    }
    return 0;
}

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* wetted area of the inlet's section below its level (per unit thickness in 2D) */
static double inlet_area(const lahar_inlet *in, int dim, const double up[3], double level, int fine)
{
    const int n1 = dim == 3 ? (fine ? 400 : 100) : (fine ? 4000 : 1000), n2 = dim == 3 ? (fine ? 400 : 100) : 1;
    double low = HUGE_VAL;
    for (int c = 0; c < (dim == 3 ? 4 : 2); c++) {
        double q[3];
        for (int a = 0; a < 3; a++)
            q[a] = in->x0[a] + (c & 1 ? in->e1[a] : 0.0) + (c & 2 ? in->e2[a] : 0.0);
        low = fmin(low, dot3(q, up));
    }
    int64_t wet = 0;
    for (int j = 0; j < n2; j++)
        for (int i = 0; i < n1; i++) {
            double q[3];
            for (int a = 0; a < 3; a++)
                q[a] = in->x0[a] + (i + 0.5) / n1 * in->e1[a] + (dim == 3 ? (j + 0.5) / n2 * in->e2[a] : 0.0);
            wet += dot3(q, up) - low < level;
        }
    const double l1 = sqrt(dot3(in->e1, in->e1)), l2 = dim == 3 ? sqrt(dot3(in->e2, in->e2)) : 1.0;
    return l1 * l2 * (double)wet / ((double)n1 * n2);
}

/* the volume the inlet delivers by t: A int u dt, or int Q dt; with a level table int A(h(t)) u dt
 * (coarser: 2000 intervals, the area on 1000 / 100 x 100 points) */
static double inlet_volume(const lahar_inlet *in, int dim, const double up[3], double area, double t)
{
    const double ta = fmax(in->t_start, 0.0), tb = fmin(in->t_end, t);
    if (!(tb > ta))
        return 0.0;
    const int m = in->nlevel > 0 && in->kind != LAHAR_HYDRO_TABLE_Q ? 2000 : 20000;
    const double h = (tb - ta) / m;
    double s = 0.0;
    for (int k = 0; k <= m; k++) {
        double tt = ta + k * h;
        if (k == m && tb == in->t_end)
            tt = nextafter(tb, ta); /* the window is [start, end) */
        const double a = in->kind == LAHAR_HYDRO_TABLE_Q ? 1.0
                         : in->nlevel > 0 ? inlet_area(in, dim, up, lahar_inlet_level(in, tt), 0)
                                          : area;
        s += (k == 0 || k == m ? 0.5 : 1.0) * h * a * lahar_inlet_hydrograph(in, tt);
    }
    return s;
}

/* What inflow measures, step by step (the helpers below fill it in order). */
typedef struct {
    /* the set-up */
    int dim;
    double dx, cell;               /* spacing; a particle's lattice cell dx^D */
    double up[3];                  /* against gravity */
    double *area;                  /* [ninlet] wetted area of each inlet's section below its level */
    double (*fv)[LAHAR_FLOW_NVAL]; /* [nsnap] the flow_* counters of each snapshot */
    /* the discharge and the mass balance over the snapshots */
    double vref_end;               /* the hydrographs' volume by the last snapshot */
    double dis, bal;               /* the largest volume difference, the largest relative mass imbalance */
    /* the late window: the last third of the snapshots */
    int64_t k0, k1;
} inflow;

/* The case and output inflow can judge, the vertical, and the buffers: 0, or -1 with r->err. */
static int inflow_setup(const lahar_case *c, const lahar_check_data *d, inflow *fl, lahar_check_result *r)
{
    const lahar_check_particles *p = d->particles;
    if (!p || p->nsnap < 2) {
        snprintf(r->err, sizeof r->err, "inflow: needs at least two particle snapshots (OUT/particles.h5)");
        return -1;
    }
    if (c->ninlet == 0) {
        snprintf(r->err, sizeof r->err, "inflow: the case has no inlets: section");
        return -1;
    }
    fl->dim = c->dim;
    const double gmag = sqrt(dot3(c->gravity, c->gravity));
    fl->dx = c->sph_dx;
    for (int a = 0; a < 3; a++)
        fl->up[a] = -c->gravity[a] / gmag;
    fl->area = calloc((size_t)c->ninlet, sizeof *fl->area);
    fl->fv = calloc((size_t)p->nsnap, sizeof *fl->fv);
    if (!fl->area || !fl->fv) {
        free(fl->area), free(fl->fv);
        fl->area = NULL, fl->fv = NULL;
        snprintf(r->err, sizeof r->err, "inflow: out of memory");
        return -1;
    }
    return 0;
}

/* Each inlet's wetted area at its level (fine sampling) and every snapshot's flow_* counters.
 * 0, or -1 with r->err. */
static int inflow_counters(const lahar_case *c, const lahar_check_particles *p, inflow *fl, lahar_check_result *r)
{
    for (int k = 0; k < c->ninlet; k++)
        fl->area[k] = inlet_area(&c->inlets[k], fl->dim, fl->up, c->inlets[k].level, 1);
    for (int64_t k = 0; k < p->nsnap; k++)
        if (flow_attrs(p, k, fl->fv[k]) != 0) {
            snprintf(r->err, sizeof r->err, "inflow: snapshot %lld of particles.h5 has no flow_* attributes (written "
                     "by a run with open boundaries)", (long long)k);
            return -1;
        }
    return 0;
}

/* Per snapshot the volume entered (particles x dx^D) against the hydrographs' (the plotted
 * series) and the domain's mass against M(0) + entered - removed. */
static void inflow_discharge(const lahar_case *c, const lahar_check_particles *p, inflow *fl,
                             lahar_check_result *r)
{
    const int dim = fl->dim;
    const double dx = fl->dx;
    double(*fv)[LAHAR_FLOW_NVAL] = fl->fv;
    fl->cell = dim == 3 ? dx * dx * dx : dx * dx;
    double vref_end = 0.0;
    for (int k = 0; k < c->ninlet; k++)
        vref_end += inlet_volume(&c->inlets[k], dim, fl->up, fl->area[k], p->t[p->nsnap - 1]);
    double dis = 0.0, bal = 0.0;
    for (int64_t k = 0; k < p->nsnap; k++) {
        double vref = 0.0;
        for (int i = 0; i < c->ninlet; i++)
            vref += inlet_volume(&c->inlets[i], dim, fl->up, fl->area[i], p->t[k]);
        const double vin = fv[k][0] * fl->cell;
        dis = fmax(dis, fabs(vin - vref));
        const double m = fv[k][7];
        const double b = m - fv[0][7] - (fv[k][1] - fv[k][3] - fv[k][5]);
        bal = fmax(bal, fabs(b) / fmax(m, 1e-300));
        if (r->nseries < LAHAR_CHECK_MAX_SERIES) {
            r->series_t[r->nseries] = p->t[k];
            r->series_measured[r->nseries] = vin;
            r->series_reference[r->nseries] = vref;
            r->nseries++;
        }
    }
    fl->vref_end = vref_end, fl->dis = dis, fl->bal = bal;
}

/* The discharge and mass-balance values, and over the last third of the snapshots the mass
 * removed against the mass entered (a steady state passes its inflow on). */
static void inflow_report_flow(const lahar_check_particles *p, inflow *fl, lahar_check_result *r)
{
    double(*fv)[LAHAR_FLOW_NVAL] = fl->fv;
    lahar_check_value(r, "discharge_rel_error", fl->vref_end > 0.0 ? fl->dis / fl->vref_end : fl->dis);
    lahar_check_value(r, "mass_balance_rel_error", fl->bal);
    lahar_check_value(r, "volume_in_m", fv[p->nsnap - 1][0] * fl->cell);
    lahar_check_value(r, "volume_hydrograph_m", fl->vref_end);
    const int64_t k0 = p->nsnap - 1 - (p->nsnap - 1) / 3, k1 = p->nsnap - 1;
    const double min_ = fv[k1][1] - fv[k0][1], mout = fv[k1][3] + fv[k1][5] - fv[k0][3] - fv[k0][5];
    lahar_check_value(r, "outflow_rel_error", min_ > 0.0 ? fabs(mout / min_ - 1.0) : 1.0);
    lahar_check_value(r, "mass_in_late", min_);
    lahar_check_value(r, "mass_out_late", mout);
    fl->k0 = k0, fl->k1 = k1;
}

/* The depth station halfway between the inlet's centre and the outlet's centre, and the inlet
 * section's lowest point (*low, along up) the depth is measured from. */
static void inflow_station(const lahar_inlet *in, const lahar_outlet *o, const inflow *fl, double st[3],
                           double *low)
{
    for (int a = 0; a < 3; a++)
        st[a] = 0.5 * ((in->x0[a] + 0.5 * in->e1[a] + 0.5 * in->e2[a]) + (o->x0[a] + 0.5 * o->e1[a] + 0.5 * o->e2[a]));
    *low = HUGE_VAL;
    for (int cc = 0; cc < (fl->dim == 3 ? 4 : 2); cc++) {
        double q[3];
        for (int a = 0; a < 3; a++)
            q[a] = in->x0[a] + (cc & 1 ? in->e1[a] : 0.0) + (cc & 2 ? in->e2[a] : 0.0);
        *low = fmin(*low, dot3(q, fl->up));
    }
}

/* Particle i of the snapshot in p's buffers relative to the point st: its squared distance across
 * up (horizontal) and its height along up. */
static double inflow_across2(const lahar_check_particles *p, int dim, int64_t i, const double st[3],
                             const double up[3], double *height)
{
    const double x[3] = {p->x[i], p->y[i], dim == 3 ? p->z[i] : 0.0};
    const double rr[3] = {x[0] - st[0], x[1] - st[1], x[2] - st[2]};
    const double s = dot3(rr, up);
    *height = dot3(x, up);
    return dot3(rr, rr) - s * s;
}

/* The level gauge on the vertical line through st for the snapshot in p's buffers, from `low` to
 * a kernel support above the highest particle within a support of the line: the depth above low
 * where the particles' dx^D W sum falls to 1/2 coming down. NAN when no water stands there,
 * -INFINITY out of memory (*phi, *cap: the line's buffer, grown here). */
static double inflow_gauge(const lahar_check_particles *p, const kernel *k, int dim, double dx, const double st[3],
                           const double up[3], double low, double **phi, size_t *cap)
{
    const double S = k->support, vol = pow(dx, dim), step = 0.1 * dx;
    double top = -HUGE_VAL, hgt;
    for (int64_t i = 0; i < p->cur_n; i++)
        if (inflow_across2(p, dim, i, st, up, &hgt) < S * S)
            top = fmax(top, hgt);
    if (!(top > low))
        return NAN;
    const int npt = lahar_check_gauge_line(phi, cap, low, top, S, step);
    if (npt < 0)
        return -INFINITY;
    for (int64_t i = 0; i < p->cur_n; i++) {
        const double d2 = inflow_across2(p, dim, i, st, up, &hgt);
        kernel_line_add(k, d2, hgt, vol, low, step, npt, *phi);
    }
    return kernel_line_crossing(*phi, npt, step, KERNEL_SURFACE_FRACTION, 1);
}

/* One inlet and an outlet: the mean depth at the station over the late window (inflow_gauge, the
 * rule of the level gauges, above the inlet section's lowest point) against the inlet's level over
 * the same window (a level table: its mean there). 0, or -1 with r->err. */
static int inflow_depth(const lahar_case *c, lahar_check_particles *p, const inflow *fl, lahar_check_result *r)
{
    const lahar_inlet *in = &c->inlets[0];
    kernel k;
    if (kernel_init(&k, c->sph.kernel, fl->dim, c->sph.h_over_dx * fl->dx)) {
        snprintf(r->err, sizeof r->err, "inflow: sph.kernel '%s' with h = %g dx is no kernel", c->sph.kernel,
                 c->sph.h_over_dx);
        return -1;
    }
    double st[3], low;
    inflow_station(in, &c->outlets[0], fl, st, &low);
    double sum = 0.0, *phi = NULL;
    size_t cap = 0;
    int cnt = 0, rc = 0;
    for (int64_t kk = fl->k0; kk <= fl->k1 && !rc; kk++) {
        if (lahar_check_particles_read(p, kk, r->err, sizeof r->err) != 0) {
            rc = -1;
            break;
        }
        const double z = inflow_gauge(p, &k, fl->dim, fl->dx, st, fl->up, low, &phi, &cap);
        if (z == -INFINITY) {
            snprintf(r->err, sizeof r->err, "inflow: out of memory for the depth gauge");
            rc = -1;
        } else if (!isnan(z)) {
            sum += z, cnt++;
        }
    }
    free(phi);
    if (rc)
        return -1;
    const double depth = cnt ? sum / cnt : 0.0;
    double hl = 0.0;
    for (int64_t kk = fl->k0; kk <= fl->k1; kk++)
        hl += lahar_inlet_level(in, p->t[kk]);
    hl /= (double)(fl->k1 - fl->k0 + 1);
    lahar_check_value(r, "depth_rel_error", fabs(depth / hl - 1.0));
    lahar_check_value(r, "depth_m", depth);
    return 0;
}

/* The plot's title and labels and the convention (check.json). */
static void inflow_labels(const lahar_case *c, const inflow *fl, lahar_check_result *r)
{
    snprintf(r->title, sizeof r->title, "inflow: volume through %d inlet(s) against the hydrograph", c->ninlet);
    snprintf(r->xlabel, sizeof r->xlabel, "t (s)");
    snprintf(r->ylabel, sizeof r->ylabel, fl->dim == 3 ? "volume in (m^3)" : "volume in (m^2)");
    snprintf(r->convention, sizeof r->convention, "volume = particles entered x dx^%d; hydrograph: wetted area x "
             "integral of u, or integral of Q", fl->dim);
}

/* The steps from the counters to the labels; the buffers are the caller's to free. */
static int inflow_measure(const lahar_case *c, lahar_check_particles *p, inflow *fl, lahar_check_result *r)
{
    if (inflow_counters(c, p, fl, r))
        return -1;
    inflow_discharge(c, p, fl, r);
    inflow_report_flow(p, fl, r);
    if (c->ninlet == 1 && c->noutlet >= 1 && inflow_depth(c, p, fl, r))
        return -1;
    inflow_labels(c, fl, r);
    return 0;
}

int lahar_check_inflow(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r)
{
    inflow fl = {0};
    if (inflow_setup(c, d, &fl, r))
        return -1;
    const int rc = inflow_measure(c, d->particles, &fl, r);
    free(fl.area), free(fl.fv);
    return rc;
}
