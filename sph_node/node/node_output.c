/* What the node writes besides the force streams: particle snapshots (only the fields the case
 * asks for), the final snapshot of a run that was stopped, marked with the reason, and the probes'
 * samples (gauges.h5). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "sph_node_run.h"

/* A particle snapshot of the fields the case writes (output.fields), nothing else: unselected
 * fields are neither gathered nor computed. The pressure written is the EOS of the density
 * written (Trujillo-Vela et al. 2020, eq. 3 / Canelas et al. 2015, eq. 19), computed here only when the case writes pressure: the
 * solver's own pressure array belongs to its last evaluation (the predicted density at the end
 * of the step, before the second kick and any Shepard filter), so a snapshot's density and
 * pressure agree exactly, whatever the solver stores. */
int sph_node_snapshot(sph_node *s, int64_t step, double t)
{
    const sph_particles *p = &s->f.p;
    const unsigned fields = s->ns.scene.output_fields;
    const int vel = (fields & LAHAR_PFIELD_VELOCITY) != 0;
    lahar_particles_view v = {
        .n = p->n, .x = p->x, .y = p->y, .z = p->z,
        .vx = vel ? p->vx : NULL, .vy = vel ? p->vy : NULL, .vz = vel ? p->vz : NULL,
        .density = fields & LAHAR_PFIELD_DENSITY ? p->rho : NULL,
        .pressure = NULL,
        .phase = fields & LAHAR_PFIELD_PHASE ? p->phase : NULL,
        .id = fields & LAHAR_PFIELD_ID ? p->id : NULL,
        .stress = {NULL, NULL, NULL, NULL, NULL, NULL}, /* soil only, below */
    };
    double flow[LAHAR_FLOW_NVAL];
    if (s->has_flow) {
        sph_inflow_values(&s->flow, p, flow);
        v.inlet = p->inlet;
        v.flow = flow;
    }
    if ((fields & LAHAR_PFIELD_PRESSURE) && s->out_pressure) {
        const sph_params *prm = &s->f.prm;
        for (int64_t i = 0; i < p->n; i++) /* soil (sph_soil.h): the mean stress -tr(sigma)/3 */
            s->out_pressure[i] = p->sig[0] && p->phase[i] == SPH_SOIL_PHASE
                                     ? -(p->sig[0][i] + p->sig[3][i] + p->sig[5][i]) / 3.0
                                     : sph_fluid_pressure(prm, p->rho[i]);
        s->work_output_derived += p->n;
        v.pressure = s->out_pressure;
    }
    if ((fields & LAHAR_PFIELD_STRESS) && p->sig[0])
        for (int a = 0; a < SPH_NSTRESS; a++)
            v.stress[a] = p->sig[a];
    s->last_snapshot = step;
    int rc = lahar_particle_output_snapshot(s->out, step, t, &v);
    /* fixed bodies only: the body snapshot of the same step, as the DEM node would write it */
    if (s->fixed_only && sph_node_fixed_snapshot(s, step, t) != 0)
        rc = -1;
    return rc;
}

/* Mark the last snapshot of the files this node writes (common/io/output.h). */
void sph_node_mark_last(const sph_node *s, const char *name, const char *text)
{
    lahar_output_mark_last_snapshot(s->ns.output_dir, "particles.h5", name, text);
    if (s->fixed_only)
        lahar_output_mark_last_snapshot(s->ns.output_dir, "bodies.h5", name, text);
}

/* The coordinator stopped the run before step k (the particles are at the end of step k - 1,
 * time t): on a stop for an error (another node's instability, a time step collapse) the state
 * reached is written as the final snapshot, marked with the coordinator's reason, unless a
 * snapshot of it exists. */
void sph_node_final_snapshot(sph_node *s, const lahar_link_msg *stop, int64_t k, double t)
{
    char why[512];
    int reason = lahar_node_stop_reason(stop, why, sizeof why);
    if (reason <= 0 || s->f.begun)
        return;
    if (s->last_snapshot != k && sph_node_snapshot(s, k, t) != 0)
        return;
    sph_node_mark_last(s, "stopped", why);
}

/* STOP came while the node waited for BODY_STATE(k) after sph_fluid_step_begin (typically: the
 * DEM node died): the particles are drifted but not kicked, a state of no time. On a stop for an
 * error the step is finished with the moving bodies where the last BODY_STATE put them (t_k) and
 * that state is written as the final snapshot of t_{k+1}, marked `stopped` with the coordinator's
 * reason and that caveat, so the run's particle file ends where the run ended (lcm_types/README.md). */
void sph_node_stopped_half_step(sph_node *s, const lahar_link_msg *stop, int64_t k, const lahar_step_t *step)
{
    char why[512], mark[768];
    if (lahar_node_stop_reason(stop, why, sizeof why) <= 0)
        return;
    if (sph_fluid_step_end(&s->f, step->dt, s->states) < 0 || sph_node_snapshot(s, k + 1, step->t_next) != 0)
        return;
    snprintf(mark, sizeof mark, "%s (step %lld finished with the moving bodies at their state of t = %.9g s: no "
             "BODY_STATE came for it)", why, (long long)k, step->t);
    sph_node_mark_last(s, "stopped", mark);
}

/* Pressure probes (sph_probes.h): set up, and the sample of t = 0. Nothing without probes. */
int sph_node_probes_open(sph_node *s, char *err, size_t errlen)
{
    const lahar_case *c = &s->ns.scene;
    if (c->nprobe <= 0)
        return 0;
    if (sph_probes_init(&s->probes, c) != 0) {
        snprintf(err, errlen, "out of memory for the probes");
        return -1;
    }
    if (!(s->gauges = lahar_gauge_output_open(s->ns.output_dir, c, err, errlen)))
        return -1;
    if (c->resume) /* the sample of t = 0 is on disk */
        return 0;
    sph_probes_sample(&s->probes, &s->f, c, s->nbody > 0 ? s->states : NULL, 0.0);
    if (lahar_gauge_output_write(s->gauges, 0, 0.0, s->probes.value, s->probes.due) != 0) {
        snprintf(err, errlen, "cannot write gauges.h5 in %s", s->ns.output_dir);
        lahar_output_explain(err, errlen);
        return -1;
    }
    return 0;
}

/* The probes due at the state of step k + 1 (time t). 0 or -1 (gauges.h5 not written). */
int sph_node_probes_sample(sph_node *s, int64_t k, double t)
{
    if (!s->gauges)
        return 0;
    if (sph_probes_sample(&s->probes, &s->f, &s->ns.scene, s->nbody > 0 ? s->states : NULL, t) == 0)
        return 0;
    return lahar_gauge_output_write(s->gauges, k + 1, t, s->probes.value, s->probes.due);
}
