/* Open boundaries of the SPH fluid (sph_inflow.h). */
#include "sph_inflow.h"
#include "soa_alloc.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "vec.h"

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

double sph_inflow_area(const sph_inflow *fl, int k, double h)
{
    const sph_inlet *in = &fl->in[k];
    int wet = 0;
    for (int s = 0; s < in->nslot; s++)
        wet += in->slot_s[s] < h;
    return wet * (fl->dim == 3 ? fl->dx * fl->dx : fl->dx);
}

double sph_inflow_velocity(const sph_inflow *fl, int k, double t)
{
    const sph_inlet *in = &fl->in[k];
    const double v = lahar_inlet_hydrograph(in->def, t);
    if (in->def->kind != LAHAR_HYDRO_TABLE_Q)
        return v;
    const double a = in->def->nlevel > 0 ? sph_inflow_area(fl, k, lahar_inlet_level(in->def, t)) : in->area;
    return a > 0.0 ? v / a : 0.0;
}

int sph_inflow_init(sph_inflow *fl, int dim, double dx, double support, const double gravity[3], int ninlet, const lahar_inlet *inlets,
                    int noutlet, const lahar_outlet *outlets, int has_domain, const double lo[3], const double hi[3],
                    double t_end, char *err, int errlen)
{
    memset(fl, 0, sizeof *fl);
    fl->dim = dim;
    fl->dx = dx;
    memcpy(fl->gravity, gravity, sizeof fl->gravity);
    fl->noutlet = noutlet;
    fl->out = outlets;
    fl->has_domain = has_domain;
    if (has_domain)
        for (int a = 0; a < 3; a++)
            fl->lo[a] = lo[a], fl->hi[a] = hi[a];
    if (ninlet == 0)
        return 0;
    const double gmag = sqrt(dot3(gravity, gravity));
    if (!(gmag > 0.0)) {
        snprintf(err, (size_t)errlen, "inlets need gravity (their level is a depth along it); set gravity:");
        return -1;
    }
    if (!(fl->in = calloc((size_t)ninlet, sizeof *fl->in))) {
        snprintf(err, (size_t)errlen, "out of memory for the inlets");
        return -1;
    }
    fl->ninlet = ninlet;
    for (int k = 0; k < ninlet; k++) {
        sph_inlet *in = &fl->in[k];
        const lahar_inlet *d = &inlets[k];
        in->def = d;
        for (int a = 0; a < 3; a++)
            in->up[a] = -gravity[a] / gmag;
        const double l1 = sqrt(dot3(d->e1, d->e1)), l2 = dim == 3 ? sqrt(dot3(d->e2, d->e2)) : 0.0;
        const int n1 = (int)floor(l1 / dx + 1e-9), n2 = dim == 3 ? (int)floor(l2 / dx + 1e-9) : 1;
        if (n1 < 1 || n2 < 1) {
            snprintf(err, (size_t)errlen, "inlets[%d] '%s': the section (%g x %g m) is shorter than one particle "
                     "spacing dx = %g m; make its edges at least dx long", k, d->name, l1, l2, dx);
            return -1;
        }
        for (int a = 0; a < 3; a++) {
            in->t1[a] = d->e1[a] / l1;
            in->t2[a] = dim == 3 ? d->e2[a] / l2 : 0.0;
        }
        /* the lowest corner of the section along up */
        in->s_low = HUGE_VAL;
        for (int c = 0; c < (dim == 3 ? 4 : 2); c++) {
            double q[3];
            for (int a = 0; a < 3; a++)
                q[a] = d->x0[a] + (c & 1 ? d->e1[a] : 0.0) + (c & 2 ? d->e2[a] : 0.0);
            in->s_low = fmin(in->s_low, dot3(q, in->up));
        }
        in->slot_s = malloc((size_t)n1 * (size_t)n2 * sizeof *in->slot_s);
        if (!(in->slot = malloc((size_t)n1 * (size_t)n2 * 3 * sizeof *in->slot)) || !in->slot_s) {
            snprintf(err, (size_t)errlen, "out of memory for the inlets");
            return -1;
        }
        for (int j = 0; j < n2; j++)
            for (int i = 0; i < n1; i++) {
                double q[3];
                for (int a = 0; a < 3; a++)
                    q[a] = d->x0[a] + (i + 0.5) * dx * in->t1[a] + (dim == 3 ? (j + 0.5) * dx * in->t2[a] : 0.0);
                if (dot3(q, in->up) - in->s_low < d->level) {
                    memcpy(&in->slot[3 * in->nslot], q, sizeof q);
                    in->slot_s[in->nslot] = dot3(q, in->up) - in->s_low;
                    in->nslot++;
                }
            }
        if (in->nslot == 0) {
            snprintf(err, (size_t)errlen, "inlets[%d] '%s': level %g m leaves no particle of spacing %g m below it "
                     "on the section; raise inlets[%d].level to at least dx/2", k, d->name, d->level, dx, k);
            return -1;
        }
        in->layers = d->layers > 0 ? d->layers : (int)ceil(support / dx - 1e-9);
        in->area = in->nslot * (dim == 3 ? dx * dx : dx);
        in->h = d->level;
        in->max_particles = d->max_particles;
        if (in->max_particles <= 0) {
            /* the estimate: the rows the hydrograph pushes through the section in the active window
             * (trapezoids of |u| on 4000 intervals), the buffer, 10 % more */
            const double ta = fmax(d->t_start, 0.0), tb = fmin(d->t_end, t_end);
            double disp = 0.0;
            if (tb > ta) {
                const int m = 4000;
                const double h = (tb - ta) / m;
                for (int s = 0; s <= m; s++) {
                    double t = ta + s * h;
                    if (s == m)
                        t = nextafter(tb, ta); /* the window is [start, end) */
                    disp += (s == 0 || s == m ? 0.5 : 1.0) * h * fabs(sph_inflow_velocity(fl, k, t));
                }
            }
            const double rows = ceil(disp / dx) + in->layers + 2;
            in->max_particles = (int64_t)ceil(1.1 * rows * in->nslot) + in->nslot;
        }
    }
    return 0;
}

int64_t sph_inflow_capacity(const sph_inflow *fl)
{
    int64_t total = 0;
    for (int k = 0; k < fl->ninlet; k++)
        total += fl->in[k].max_particles;
    return total;
}

/* the hydrostatic density at x below the inlet's level (p = rho0 |g| (h - s), >= 0) */
static double inlet_density(const sph_inflow *fl, const sph_inlet *in, const sph_params *prm, const double x[3])
{
    const double gmag = sqrt(dot3(fl->gravity, fl->gravity));
    const double depth = in->h - (dot3(x, in->up) - in->s_low);
    return sph_fluid_density_of_pressure(prm, prm->rho0 * gmag * fmax(depth, 0.0));
}

/* Row r of inlet k at normal coordinate c. 0, or -1 with a message (capacity). */
static int inlet_row(sph_inflow *fl, sph_fluid *f, int k, double c, double t, char *err, int errlen)
{
    sph_inlet *in = &fl->in[k];
    sph_particles *p = &f->p;
    const lahar_inlet *d = in->def;
    const double vol = fl->dim == 3 ? fl->dx * fl->dx * fl->dx : fl->dx * fl->dx;
    /* the slots below the level at the time the row will cross the section (c < 0 behind it, at
     * the current velocity): the buffer's transit does not delay a change of level */
    const double hr = d->nlevel > 0 && in->u > 0.0 ? lahar_inlet_level(d, t - c / in->u) : in->h;
    int nrow = 0;
    for (int s = 0; s < in->nslot; s++)
        nrow += in->slot_s[s] < hr;
    if (in->created + nrow > in->max_particles || p->n + nrow > p->cap) {
        snprintf(err, (size_t)errlen, "inlets[%d] '%s' has created %lld particles at t = %g s and needs %d more: "
                 "its limit is inlets[%d].max_particles = %lld (by default the estimate from its hydrograph "
                 "+ 10 %%); raise inlets[%d].max_particles", k, d->name, (long long)in->created, t, nrow, k,
                 (long long)in->max_particles, k);
        return -1;
    }
    const double v[3] = {in->u * d->n[0], in->u * d->n[1], in->u * d->n[2]};
    for (int s = 0; s < in->nslot; s++) {
        if (!(in->slot_s[s] < hr))
            continue;
        double x[3];
        for (int a = 0; a < 3; a++)
            x[a] = in->slot[3 * s + a] + c * d->n[a];
        const double rho = inlet_density(fl, in, &f->prm, x);
        const int64_t i = sph_particles_add(p, x, v, rho * vol, rho, 0);
        p->id[i] = fl->next_id++;
        p->inlet[i] = k;
    }
    in->created += nrow;
    fl->counts.created += nrow;
    return 0;
}

/* rows whose coordinate D - (r + 1/2) dx has reached the back of the buffer, -layers dx */
static int inlet_rows(sph_inflow *fl, sph_fluid *f, int k, double t, char *err, int errlen)
{
    sph_inlet *in = &fl->in[k];
    const double dx = fl->dx, back = -in->layers * dx;
    for (;;) {
        const double c = in->disp - (in->next_row + 0.5) * dx;
        if (c < back)
            return 0;
        if (inlet_row(fl, f, k, c, t, err, errlen) != 0)
            return -1;
        in->next_row++;
    }
}

int sph_inflow_start(sph_inflow *fl, sph_fluid *f, double t, char *err, int errlen)
{
    sph_particles *p = &f->p;
    if (sph_particles_alloc_inlet(p) != 0 || !(fl->drop = lahar_soa_calloc((size_t)p->cap, 1))) {
        snprintf(err, (size_t)errlen, "out of memory for %lld particles", (long long)p->cap);
        return -1;
    }
    int64_t top = -1;
    for (int64_t i = 0; i < p->n; i++)
        top = p->id[i] > top ? p->id[i] : top;
    fl->next_id = top + 1;
    for (int k = 0; k < fl->ninlet; k++) {
        fl->in[k].h = lahar_inlet_level(fl->in[k].def, t);
        fl->in[k].u = sph_inflow_velocity(fl, k, t);
        if (inlet_rows(fl, f, k, t, err, errlen) != 0)
            return -1;
    }
    return 0;
}

/* beyond outlet o: past its section along n (at most depth) and within its edges */
static int beyond_outlet(const lahar_outlet *o, int dim, const double x[3])
{
    const double r[3] = {x[0] - o->x0[0], x[1] - o->x0[1], x[2] - o->x0[2]};
    const double d = dot3(r, o->n);
    if (!(d > 0.0 && d <= o->depth))
        return 0;
    const double a = dot3(r, o->e1) / dot3(o->e1, o->e1);
    if (!(a >= 0.0 && a <= 1.0))
        return 0;
    if (dim == 3) {
        const double b = dot3(r, o->e2) / dot3(o->e2, o->e2);
        if (!(b >= 0.0 && b <= 1.0))
            return 0;
    }
    return 1;
}

int64_t sph_inflow_apply(sph_inflow *fl, sph_fluid *f, double t, double dt, char *err, int errlen)
{
    sph_particles *p = &f->p;
    const int64_t n_before = p->n;
    const int dim = fl->dim;
    /* 1. outflow: domain particles beyond an outlet or outside the domain box */
    if (fl->noutlet > 0 || fl->has_domain) {
        int64_t ndrop = 0;
        for (int64_t i = 0; i < p->n; i++) {
            const double x[3] = {p->x[i], p->y[i], dim == 3 ? p->z[i] : 0.0};
            int out = 0;
            if (p->inlet[i] < 0) {
                if (fl->has_domain)
                    for (int a = 0; a < dim; a++)
                        out |= !(x[a] >= fl->lo[a] && x[a] <= fl->hi[a]);
                for (int o = 0; o < fl->noutlet && !out; o++)
                    out = beyond_outlet(&fl->out[o], dim, x);
            }
            fl->drop[i] = (unsigned char)out;
            if (out) {
                const int ph = p->phase[i] == 1 ? 1 : 0;
                fl->counts.removed[ph]++;
                fl->counts.removed_mass[ph] += p->m[i];
                ndrop++;
            }
        }
        if (ndrop > 0)
            sph_particles_remove(p, fl->drop);
    }
    if (fl->ninlet > 0) {
        /* 2. buffer particles past their section enter the domain as they are */
        for (int64_t i = 0; i < p->n; i++) {
            const int k = p->inlet[i];
            if (k < 0)
                continue;
            const lahar_inlet *d = fl->in[k].def;
            const double r[3] = {p->x[i] - d->x0[0], p->y[i] - d->x0[1], dim == 3 ? p->z[i] - d->x0[2] : 0.0};
            if (dot3(r, d->n) >= 0.0) {
                p->inlet[i] = -1;
                fl->counts.entered++;
                fl->counts.entered_mass += p->m[i];
            }
        }
        /* 3. the hydrograph at t; new rows behind the buffer */
        for (int k = 0; k < fl->ninlet; k++) {
            fl->in[k].h = lahar_inlet_level(fl->in[k].def, t);
            fl->in[k].u = sph_inflow_velocity(fl, k, t);
            if (inlet_rows(fl, f, k, t, err, errlen) != 0)
                return INT64_MIN;
        }
        /* 4. the buffer's prescribed state: velocity u n, hydrostatic density, no rates, so the
         * step's drift moves it by exactly u dt along n */
        for (int64_t i = 0; i < p->n; i++) {
            const int k = p->inlet[i];
            if (k < 0)
                continue;
            const sph_inlet *in = &fl->in[k];
            const double x[3] = {p->x[i], p->y[i], dim == 3 ? p->z[i] : 0.0};
            p->vx[i] = p->vhx[i] = in->u * in->def->n[0];
            p->vy[i] = p->vhy[i] = in->u * in->def->n[1];
            p->vz[i] = p->vhz[i] = dim == 3 ? in->u * in->def->n[2] : 0.0;
            p->rho[i] = p->rhoh[i] = inlet_density(fl, in, &f->prm, x);
            p->ax[i] = p->ay[i] = p->az[i] = p->drho[i] = 0.0;
        }
        for (int k = 0; k < fl->ninlet; k++)
            fl->in[k].disp += fl->in[k].u * dt;
    }
    if (p->n != n_before)
        f->cpl.near_valid = 0;
    return p->n - n_before;
}

double sph_inflow_domain_mass(const sph_inflow *fl, const sph_particles *p)
{
    (void)fl;
    double m = 0.0;
    for (int64_t i = 0; i < p->n; i++)
        if (!p->inlet || p->inlet[i] < 0)
            m += p->m[i];
    return m;
}

void sph_inflow_free(sph_inflow *fl)
{
    for (int k = 0; k < fl->ninlet; k++)
        free(fl->in[k].slot), free(fl->in[k].slot_s);
    free(fl->in);
    lahar_soa_free(fl->drop);
    memset(fl, 0, sizeof *fl);
}
