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
 *     (the highest domain particle within dx of the vertical line there, + dx/2, above the inlet
 *     section's lowest point) against the inlet's level. */
#include <hdf5.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
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

int lahar_check_inflow(const lahar_case *c, const lahar_check_data *d, lahar_check_result *r)
{
    lahar_check_particles *p = d->particles;
    if (!p || p->nsnap < 2) {
        snprintf(r->err, sizeof r->err, "inflow: needs at least two particle snapshots (OUT/particles.h5)");
        return -1;
    }
    if (c->ninlet == 0) {
        snprintf(r->err, sizeof r->err, "inflow: the case has no inlets: section");
        return -1;
    }
    const int dim = c->dim;
    const double gmag = sqrt(dot3(c->gravity, c->gravity)), dx = c->sph_dx;
    const double up[3] = {-c->gravity[0] / gmag, -c->gravity[1] / gmag, -c->gravity[2] / gmag};
    double *area = calloc((size_t)c->ninlet, sizeof *area);
    double(*fv)[LAHAR_FLOW_NVAL] = calloc((size_t)p->nsnap, sizeof *fv);
    if (!area || !fv) {
        free(area), free(fv);
        snprintf(r->err, sizeof r->err, "inflow: out of memory");
        return -1;
    }
    for (int k = 0; k < c->ninlet; k++)
        area[k] = inlet_area(&c->inlets[k], dim, up, c->inlets[k].level, 1);
    for (int64_t k = 0; k < p->nsnap; k++)
        if (flow_attrs(p, k, fv[k]) != 0) {
            snprintf(r->err, sizeof r->err, "inflow: snapshot %lld of particles.h5 has no flow_* attributes (written "
                     "by a run with open boundaries)", (long long)k);
            free(area), free(fv);
            return -1;
        }
    const double cell = dim == 3 ? dx * dx * dx : dx * dx;
    double vref_end = 0.0;
    for (int k = 0; k < c->ninlet; k++)
        vref_end += inlet_volume(&c->inlets[k], dim, up, area[k], p->t[p->nsnap - 1]);
    double dis = 0.0, bal = 0.0;
    for (int64_t k = 0; k < p->nsnap; k++) {
        double vref = 0.0;
        for (int i = 0; i < c->ninlet; i++)
            vref += inlet_volume(&c->inlets[i], dim, up, area[i], p->t[k]);
        const double vin = fv[k][0] * cell;
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
    lahar_check_value(r, "discharge_rel_error", vref_end > 0.0 ? dis / vref_end : dis);
    lahar_check_value(r, "mass_balance_rel_error", bal);
    lahar_check_value(r, "volume_in_m", fv[p->nsnap - 1][0] * cell);
    lahar_check_value(r, "volume_hydrograph_m", vref_end);
    const int64_t k0 = p->nsnap - 1 - (p->nsnap - 1) / 3, k1 = p->nsnap - 1;
    const double min_ = fv[k1][1] - fv[k0][1], mout = fv[k1][3] + fv[k1][5] - fv[k0][3] - fv[k0][5];
    lahar_check_value(r, "outflow_rel_error", min_ > 0.0 ? fabs(mout / min_ - 1.0) : 1.0);
    lahar_check_value(r, "mass_in_late", min_);
    lahar_check_value(r, "mass_out_late", mout);
    if (c->ninlet == 1 && c->noutlet >= 1) {
        const lahar_inlet *in = &c->inlets[0];
        const lahar_outlet *o = &c->outlets[0];
        double st[3], low = HUGE_VAL;
        for (int a = 0; a < 3; a++)
            st[a] = 0.5 * ((in->x0[a] + 0.5 * in->e1[a] + 0.5 * in->e2[a]) + (o->x0[a] + 0.5 * o->e1[a] + 0.5 * o->e2[a]));
        for (int cc = 0; cc < (dim == 3 ? 4 : 2); cc++) {
            double q[3];
            for (int a = 0; a < 3; a++)
                q[a] = in->x0[a] + (cc & 1 ? in->e1[a] : 0.0) + (cc & 2 ? in->e2[a] : 0.0);
            low = fmin(low, dot3(q, up));
        }
        double sum = 0.0;
        int cnt = 0;
        for (int64_t k = k0; k <= k1; k++) {
            if (lahar_check_particles_read(p, k, r->err, sizeof r->err) != 0) {
                free(area), free(fv);
                return -1;
            }
            double top = -HUGE_VAL;
            for (int64_t i = 0; i < p->cur_n; i++) {
                const double x[3] = {p->x[i], p->y[i], dim == 3 ? p->z[i] : 0.0};
                const double rr[3] = {x[0] - st[0], x[1] - st[1], x[2] - st[2]};
                const double s = dot3(rr, up);
                const double hz2 = dot3(rr, rr) - s * s; /* squared horizontal distance */
                if (hz2 < dx * dx)
                    top = fmax(top, dot3(x, up));
            }
            if (top > -HUGE_VAL) {
                sum += top + 0.5 * dx - low;
                cnt++;
            }
        }
        const double depth = cnt ? sum / cnt : 0.0;
        /* against the level over the same window (a level table: its mean there) */
        double hl = 0.0;
        for (int64_t k = k0; k <= k1; k++)
            hl += lahar_inlet_level(in, p->t[k]);
        hl /= (double)(k1 - k0 + 1);
        lahar_check_value(r, "depth_rel_error", fabs(depth / hl - 1.0));
        lahar_check_value(r, "depth_m", depth);
    }
    snprintf(r->title, sizeof r->title, "inflow: volume through %d inlet(s) against the hydrograph", c->ninlet);
    snprintf(r->xlabel, sizeof r->xlabel, "t (s)");
    snprintf(r->ylabel, sizeof r->ylabel, dim == 3 ? "volume in (m^3)" : "volume in (m^2)");
    snprintf(r->convention, sizeof r->convention, "volume = particles entered x dx^%d; hydrograph: wetted area x "
             "integral of u, or integral of Q", dim);
    free(area), free(fv);
    return 0;
}
