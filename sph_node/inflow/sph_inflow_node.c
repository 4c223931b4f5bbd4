/* The SPH node's side of the open boundaries (sph_inflow.h): set-up from the case, checkpoint
 * state, the counters a snapshot and STATUS carry. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "checkpoint.h"
#include "kernel.h"
#include "output.h"
#include "sph_inflow.h"

int sph_inflow_case_wanted(const lahar_case *c) { return c->ninlet > 0 || c->noutlet > 0 || c->has_domain; }

int sph_inflow_setup_case(sph_inflow *fl, const lahar_case *c, const sph_params *prm, char *err, int errlen)
{
    /* the kernel support of the case's kernel and h */
    const kernel_def *kd = kernel_find(prm->opt.kernel);
    const double h_over_dx = prm->opt.h_over_dx;
    const double support = (kd ? kd->kappa : 2.0) * h_over_dx * c->sph_dx;
    return sph_inflow_init(fl, c->dim, c->sph_dx, support, c->gravity, c->ninlet, c->inlets, c->noutlet, c->outlets,
                           c->has_domain, c->domain_lo, c->domain_hi, c->t_end, err, errlen);
}

void sph_inflow_values(const sph_inflow *fl, const sph_particles *p, double *v)
{
    const sph_flow_counts *k = &fl->counts;
    v[0] = (double)k->entered;
    v[1] = k->entered_mass;
    v[2] = (double)k->removed[0];
    v[3] = k->removed_mass[0];
    v[4] = (double)k->removed[1];
    v[5] = k->removed_mass[1];
    v[6] = (double)k->created;
    v[7] = sph_inflow_domain_mass(fl, p);
}

int sph_inflow_state_io(sph_inflow *fl, sph_particles *p, lahar_ckpt_file *f)
{
    /* the particle count is read by the caller (sph_node_state_io) through sph_inflow_take_count */
    lahar_ckpt_i32(f, "inlet", p->inlet, p->n);
    lahar_ckpt_i64(f, "flow_next_id", &fl->next_id, 1);
    int64_t ci[5] = {fl->counts.entered, fl->counts.removed[0], fl->counts.removed[1], fl->counts.created, 0};
    double cm[3] = {fl->counts.entered_mass, fl->counts.removed_mass[0], fl->counts.removed_mass[1]};
    lahar_ckpt_i64(f, "flow_counts", ci, 5);
    lahar_ckpt_f64(f, "flow_masses", cm, 3);
    for (int k = 0; k < fl->ninlet; k++) {
        sph_inlet *in = &fl->in[k];
        char name[48];
        double d[2] = {in->disp, in->u};
        int64_t r[2] = {in->next_row, in->created};
        snprintf(name, sizeof name, "inlet%d_disp_u", k);
        lahar_ckpt_f64(f, name, d, 2);
        snprintf(name, sizeof name, "inlet%d_rows_created", k);
        lahar_ckpt_i64(f, name, r, 2);
        if (!f->writing && !f->failed) {
            in->disp = d[0], in->u = d[1];
            in->next_row = r[0], in->created = r[1];
        }
    }
    if (!f->writing && !f->failed) {
        fl->counts.entered = ci[0], fl->counts.removed[0] = ci[1], fl->counts.removed[1] = ci[2];
        fl->counts.created = ci[3];
        fl->counts.entered_mass = cm[0], fl->counts.removed_mass[0] = cm[1], fl->counts.removed_mass[1] = cm[2];
    }
    return f->failed ? -1 : 0;
}
