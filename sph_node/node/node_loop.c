/* SPH node loop (see sph_node.h; the other steps are in the files beside this one, README.md and the lockstep in lcm_types/README.md). Per step k:
 *
 *   wait STEP(k)
 *   k = 0: evaluate the rates at t_0 (particle-particle sums and the coupling with the bodies at
 *          their initial states, K_n for dt_0): the forces on the bodies at t_0
 *   [DEM node] send LOADS(k): per body near particles the resultant force and torque at t_k
 *          (from the evaluation that ended step k-1, which used BODY_STATE(k-1), the bodies at t_k)
 *          and, for moving bodies and bodies marked record_contacts, the contact points
 *   sph_fluid_step_begin(dt_k): kick, drift, sort, EOS, SPS, particle-particle sums at t_{k+1}
 *          (no body state needed: this overlaps the DEM node's advance and the BODY_STATE latency)
 *   [DEM node, moving bodies] wait BODY_STATE(k): the bodies at t_{k+1}, after the DEM node's
 *          advance with LOADS(k)
 *   sph_fluid_step_end(dt_k, bodies at t_{k+1}): coupling forces at t_{k+1} (sent as LOADS(k+1)),
 *          vmax/amax, kick
 *   snapshot if write_output (or if a particle crossed a body surface), STATUS(k) with the
 *   solver's dt proposal for step k+1.
 *
 * So the forces the DEM node applies over step k are those of the bodies and particles at t_k,
 * and the fluid integrated over step k sees the bodies at t_k and t_{k+1} (KDK, both ends): a
 * staggered explicit coupling. The split step is bitwise the one-call sph_fluid_step
 * (tests/test_sph_split.c), so the overlap changes timing only, never results. */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "case_keys.h"
#include "errmsg.h"
#include "lahar_body_state_t.h"
#include "lahar_loads_t.h"
#include "shape_build.h"
#include "transport.h"
#include "sph_soil_model.h"
#include "vec.h"
#include "sph_node_run.h"

static int sph_node_wait_stop(sph_node *s)
{
    lahar_link_msg msg;
    for (;;) {
        int rc = lahar_link_wait(s->link, LAHAR_ROLE_COORDINATOR, LAHAR_FRAME_T_MSG_STOP, LAHAR_LINK_ANY_STEP, -1, &msg);
        if (rc == LAHAR_LINK_OK || rc == LAHAR_LINK_LOST || rc == LAHAR_LINK_ERROR)
            return rc;
    }
}

static int sph_node_alloc(sph_node *s)
{
    int n = s->nbody > 0 ? s->nbody : 1;
    s->states = calloc((size_t)n, sizeof *s->states);
    s->l_id = calloc((size_t)n, sizeof *s->l_id);
    s->l_np = calloc((size_t)n, sizeof *s->l_np);
    s->l_force = calloc((size_t)n, sizeof *s->l_force);
    s->l_torque = calloc((size_t)n, sizeof *s->l_torque);
    s->l_pforce = calloc((size_t)n, sizeof *s->l_pforce);
    s->l_ptorque = calloc((size_t)n, sizeof *s->l_ptorque);
    s->l_pcap = 1024;
    s->l_px = calloc((size_t)s->l_pcap, sizeof *s->l_px);
    s->l_pf = calloc((size_t)s->l_pcap, sizeof *s->l_pf);
    if (!s->states || !s->l_id || !s->l_np || !s->l_force || !s->l_torque || !s->l_pforce || !s->l_ptorque ||
        !s->l_px || !s->l_pf)
        return -1;
    for (int i = 0; i < n; i++) {
        s->l_pforce[i] = s->l_force[i];
        s->l_ptorque[i] = s->l_torque[i];
    }
    const lahar_case *c = &s->ns.scene;
    for (int b = 0; b < s->nbody; b++) {
        const lahar_body *bd = &c->bodies[b];
        lahar_body_state *st = &s->states[b];
        memcpy(st->x, bd->x, sizeof st->x);
        memcpy(st->q, bd->q, sizeof st->q);
        if (bd->motion != LAHAR_MOTION_FIXED) {
            memcpy(st->v, bd->v, sizeof st->v);
            memcpy(st->w, bd->w, sizeof st->w);
        }
    }
    return 0;
}

static void sph_node_free(sph_node *s)
{
    lahar_particle_output_close(s->out);
    if (s->fluid_ready)
        sph_fluid_free(&s->f);
    lahar_body_state_buf_free(&s->bodies);
    free(s->states);
    free(s->l_id);
    free(s->l_np);
    free(s->l_force);
    free(s->l_torque);
    free(s->l_pforce);
    free(s->l_ptorque);
    free(s->l_px);
    free(s->l_pf);
    free(s->out_pressure);
    lahar_body_output_close(s->bout);
    lahar_contact_output_close(s->cout);
    lahar_gauge_output_close(s->gauges);
    sph_probes_free(&s->probes);
    sph_inflow_free(&s->flow);
    free(s->reports);
    free(s->c_x);
    free(s->c_f);
    lahar_case_free(&s->ns.scene);
}

/* The region where a body can touch a particle at t_{k+1}: the particles' bounding box at t_k
 * grown by the kernel support (the coupling's range) plus how far a particle can move in a step
 * (CFL keeps it below a fraction of h; twice the support covers it with room to spare). The DEM
 * node sends BODY_STATE only for moving bodies whose bounding sphere reaches into it. */
static void sph_node_reach(const sph_node *s, double lo[3], double hi[3])
{
    const sph_particles *p = &s->f.p;
    const double margin = 2.0 * s->f.k.support;
    for (int a = 0; a < 3; a++) {
        lo[a] = INFINITY;
        hi[a] = -INFINITY;
    }
    /* comparisons, not fmin/fmax calls (libm, 2 % of a 2-thread step serially); NaN is skipped
     * either way */
    for (int64_t i = 0; i < p->n; i++) {
        const double x = p->x[i], y = p->y[i], z = p->z[i];
        lo[0] = x < lo[0] ? x : lo[0], hi[0] = x > hi[0] ? x : hi[0];
        lo[1] = y < lo[1] ? y : lo[1], hi[1] = y > hi[1] ? y : hi[1];
        lo[2] = z < lo[2] ? z : lo[2], hi[2] = z > hi[2] ? z : hi[2];
    }
    for (int a = 0; a < 3; a++) {
        if (s->f.prm.opt.periodic[a]) { /* particles wrap: the whole period, and beyond by the margin */
            lo[a] = fmin(lo[a], s->f.prm.opt.lo[a]);
            hi[a] = fmax(hi[a], s->f.prm.opt.hi[a]);
        }
        lo[a] -= margin;
        hi[a] += margin;
    }
}

/* The rows of LOADS from the coupling's last evaluation (the bodies and particles at t_k): every
 * body with at least one particle within reach; contact points for moving bodies and for bodies
 * marked record_contacts (fixed ones: the resultant only otherwise, for forces.h5). Returns the
 * number of bodies listed (rows in s->l_*; *npoints the points in s->l_px/l_pf), or -1 when
 * out of memory. */
int sph_node_build_loads(sph_node *s, int64_t *npoints)
{
    const sph_coupling *cp = &s->f.cpl;
    const lahar_case *c = &s->ns.scene;
    int nb = 0;
    int64_t np = 0;
    for (int b = 0; b < s->nbody; b++) {
        int64_t n = cp->body_start[b + 1] - cp->body_start[b];
        if (n == 0)
            continue;
        const lahar_body *bd = &c->bodies[b];
        int points = bd->motion != LAHAR_MOTION_FIXED || bd->record_contacts;
        s->l_id[nb] = b;
        memcpy(s->l_force[nb], cp->force[b], sizeof s->l_force[nb]);
        memcpy(s->l_torque[nb], cp->torque[b], sizeof s->l_torque[nb]);
        s->l_np[nb] = points ? (int32_t)n : 0;
        if (points) {
            if (np + n > s->l_pcap) {
                int64_t cap = s->l_pcap;
                while (cap < np + n)
                    cap *= 2;
                double **px = realloc(s->l_px, (size_t)cap * sizeof *px);
                if (px)
                    s->l_px = px;
                double **pf = px ? realloc(s->l_pf, (size_t)cap * sizeof *pf) : NULL;
                if (!px || !pf)
                    return -1;
                s->l_pf = pf;
                s->l_pcap = cap;
            }
            for (int64_t i = 0; i < n; i++) {
                sph_contact *ct = &cp->contacts[cp->body_start[b] + i];
                s->l_px[np + i] = ct->xs;
                s->l_pf[np + i] = ct->force;
            }
            np += n;
        }
        nb++;
    }
    if (np > INT32_MAX)
        return -1;
    *npoints = np;
    return nb;
}

/* LOADS(k) for the DEM node (sph_node_build_loads). */
static int sph_node_send_loads(sph_node *s, int64_t k)
{
    int64_t np;
    int nb = sph_node_build_loads(s, &np);
    if (nb < 0)
        return -1;
    lahar_loads_t m = {
        .run_id = lahar_link_run_id(s->link), .step = k, .nbody = nb, .body_id = s->l_id, .force = s->l_pforce,
        .torque = s->l_ptorque, .npoints = s->l_np, .ntotal = (int32_t)np, .point_x = s->l_px, .point_f = s->l_pf,
    };
    sph_node_reach(s, m.reach_lo, m.reach_hi);
    int rc;
    LAHAR_LINK_SEND(rc, s->link, LAHAR_FRAME_T_MSG_LOADS, lahar_loads_t, k, &m);
    return rc;
}

/* Bodies at t_{k+1} from BODY_STATE(k). A moving body the DEM node did not list is out of reach
 * of every particle: it is placed at infinity, where the coupling's distance test skips it (its
 * last known pose may be near the water it has since left). */
static void sph_node_take_states(sph_node *s)
{
    const lahar_case *c = &s->ns.scene;
    for (int b = 0; b < s->nbody; b++)
        if (c->bodies[b].motion != LAHAR_MOTION_FIXED) {
            s->states[b].x[0] = s->states[b].x[1] = s->states[b].x[2] = INFINITY;
        }
    const lahar_body_state_buf *m = &s->bodies;
    for (int i = 0; i < m->n; i++) {
        int b = m->id[i];
        if (b < 0 || b >= s->nbody)
            continue;
        lahar_body_state *st = &s->states[b];
        memcpy(st->x, m->x[i], sizeof st->x);
        memcpy(st->q, m->q[i], sizeof st->q);
        memcpy(st->v, m->v[i], sizeof st->v);
        memcpy(st->w, m->w[i], sizeof st->w);
    }
}

/* Kinetic energy of the fluid (J, J/m in 2D), summed serially: the same bits for any thread count. */
static double sph_node_kinetic_energy(const sph_particles *p)
{
    double e = 0.0;
    for (int64_t i = 0; i < p->n; i++)
        e += 0.5 * p->m[i] * (p->vx[i] * p->vx[i] + p->vy[i] * p->vy[i] + p->vz[i] * p->vz[i]);
    return e;
}

/* The work counters of STATUS (cumulative since set-up; lcm_types/status_t.lcm). Pairs are the
 * solver's neighbour counts halved: every pass visits each pair from both ends (soil-soil: the
 * soil pass; fluid-soil: the soil pass's water neighbours and the seepage pass's soil ones, both
 * only when the soil has k_h > 0, i.e. there is seepage work). */
static void sph_node_work(const sph_node *s, lahar_status_t *st)
{
    st->work_passes = s->f.work_passes;
    st->work_pairs_fluid = s->f.work_neighbours_fluid / 2;
    st->work_pairs_soil = s->f.work_neighbours_soil / 2;
    st->work_pairs_fluid_soil = s->f.work_neighbours_fluid_soil / 2;
    st->work_particle_body = s->work_particle_body;
    st->work_body_body = 0;
    st->work_output_derived = s->work_output_derived;
    if (s->has_flow) /* cumulative, like the work counters; the coordinator's summary.json "flow" */
        sph_inflow_values(&s->flow, &s->f.p, st->flow);
}

/* After every evaluation of the coupling: its contacts join the particle-body work. */
static void sph_node_count_coupling(sph_node *s)
{
    if (s->f.has_bodies)
        s->work_particle_body += s->f.cpl.ncontacts;
}

/* One step of sph_node_loop as its phases see it: what they did, and the first failure. */
typedef struct {
    lahar_status_t st; /* the STATUS sent at the end of the step; st.error: the step failed */
    char err[2048];    /* why, when st.error */
    int begun;         /* sph_fluid_step_begin ran: the particles have drifted */
    int stepped;       /* ... and sph_fluid_step_end: the state is t_{k+1} */
    int unstable;      /* a stability check failed; u says which */
    lahar_instability u;
} sph_step;

/* The first half of step k, which needs no body states: done before waiting for them, so the DEM
 * node's advance and the BODY_STATE latency hide behind it. At k = 0 the rates at t_0 with K_n of
 * the first step (eq. 15 depends on dt); without bodies the rates of the set-up do not depend on
 * dt and stand. Then the loads to the DEM node (or the forces on fixed bodies), the inflow and the
 * drift. */
static void sph_step_first_half(sph_node *s, int64_t k, const lahar_step_t *step, int has_dem, sph_step *w)
{
    if (k == 0 && s->f.has_bodies) {
        int64_t cross = sph_fluid_rates(&s->f, has_dem ? s->states : NULL, step->dt);
        sph_node_count_coupling(s);
        if (cross < 0) {
            w->st.error = 1;
            lahar_errf(w->err, sizeof w->err, "out of memory in the SPH rates");
        } else if (cross > 0) {
            w->st.error = 1;
            sph_node_crossing_message(s, -1, 0.0, w->err, sizeof w->err);
        }
    }
    if (has_dem && sph_node_send_loads(s, k) != 0 && !w->st.error) {
        w->st.error = 1;
        lahar_errf(w->err, sizeof w->err, "cannot send LOADS(%lld) (out of memory)", (long long)k);
    } else if (s->fixed_only && !w->st.error && sph_node_fixed_forces(s, k, step, w->err, sizeof w->err) != 0) {
        w->st.error = 1;
    }
    if (!w->st.error && s->has_flow &&
        sph_inflow_apply(&s->flow, &s->f, step->t, step->dt, w->err, (int)sizeof w->err) == INT64_MIN)
        w->st.error = 1;
    if (w->st.error)
        return;
    if (sph_fluid_step_begin(&s->f, step->dt) != 0) {
        w->st.error = 1;
        lahar_errf(w->err, sizeof w->err, "out of memory in the SPH step");
    } else {
        w->begun = 1;
    }
}

/* The moving bodies at t_{k+1}, after the DEM node's advance with LOADS(k). Returns -1 to go on
 * (w->st.error set if the message was bad), else the node's exit status: 0 when the coordinator
 * stopped the run, 3 when the link was lost. */
static int sph_step_wait_bodies(sph_node *s, int64_t k, const lahar_step_t *step, sph_step *w)
{
    lahar_link_msg msg;
    int rc = lahar_link_wait(s->link, LAHAR_ROLE_DEM, LAHAR_FRAME_T_MSG_BODY_STATE, k, -1, &msg);
    if (rc == LAHAR_LINK_STOP) {
        if (w->begun)
            sph_node_stopped_half_step(s, &msg, k, step);
        return 0;
    }
    if (rc == LAHAR_LINK_LOST) {
        lahar_node_report_lost("lahar-sph", "the DEM node's body states of step", k);
        return 3;
    }
    if (rc != LAHAR_LINK_OK || lahar_body_state_decode(msg.data, msg.size, &s->bodies) != 0) {
        if (!w->st.error)
            snprintf(w->err, sizeof w->err, "undecodable BODY_STATE(%lld)", (long long)k);
        w->st.error = 1;
    } else {
        sph_node_take_states(s);
    }
    return -1;
}

/* The second half: the kick with the body states, then the checks of the new state (a body
 * crossed, the stability checks) and the probes at t_{k+1}. A failed BODY_STATE after step_begin
 * leaves the particles drifted but not kicked: that state is neither t_k nor t_{k+1}, so the step
 * is not taken (stepped stays 0) and no snapshot is written for it (sph_step_output). */
static void sph_step_second_half(sph_node *s, int64_t k, const lahar_step_t *step, int has_dem, sph_step *w)
{
    w->stepped = w->begun && !w->st.error;
    if (!w->stepped)
        return;
    int64_t cross = sph_fluid_step_end(&s->f, step->dt, has_dem ? s->states : NULL);
    sph_node_count_coupling(s);
    if (cross < 0) {
        w->st.error = 1;
        lahar_errf(w->err, sizeof w->err, "out of memory in the SPH step");
    } else if (cross > 0) {
        sph_node_crossing_report(s, k, step->t_next, &w->u);
        w->unstable = 1;
    } else {
        w->unstable = sph_node_check_particles(s, k, step->t_next, &w->u) > 0;
    }
    if (w->unstable) {
        w->st.error = 1;
        lahar_instability_encode(&w->u, w->err, sizeof w->err);
    } else if (!w->st.error && sph_node_probes_sample(s, k, step->t_next) != 0) {
        w->st.error = 1;
        lahar_errf(w->err, sizeof w->err, "cannot write gauges.h5 in %s", s->ns.output_dir);
        lahar_output_explain(w->err, sizeof w->err);
    }
}

/* What the step leaves: the snapshot, the STATUS figures and the checkpoint. On an error the state
 * reached is kept as the last snapshot to look at: after the step, or at t_k when the step was not
 * taken (unless a snapshot of t_k exists). */
static void sph_step_output(sph_node *s, int64_t k, const lahar_step_t *step, sph_step *w)
{
    if (w->stepped && (step->write_output || w->st.error) && sph_node_snapshot(s, k + 1, step->t_next) != 0 &&
        !w->st.error) {
        w->st.error = 1;
        lahar_errf(w->err, sizeof w->err, "cannot write a snapshot in %s", s->ns.output_dir);
        lahar_output_explain(w->err, sizeof w->err);
    } else if (!w->stepped && !w->begun && s->last_snapshot != k) {
        sph_node_snapshot(s, k, step->t);
    }
    if (w->unstable && s->last_snapshot == k + 1)
        sph_node_mark_last(s, "instability", w->u.text);
    w->st.dt_proposed = sph_fluid_dt(&s->f);
    w->st.dt_stable = w->st.dt_proposed;
    w->st.ncontacts = s->f.has_bodies ? (int32_t)s->f.cpl.ncontacts : 0;
    /* the kinetic energy is a summary figure (the coordinator keeps the last one): computed at the
     * output times (the last step is one) and on an error, not every step */
    if (step->write_output || w->st.error)
        s->kinetic_energy = sph_node_kinetic_energy(&s->f.p);
    w->st.kinetic_energy = s->kinetic_energy;
    sph_node_work(s, &w->st);
    if (step->checkpoint && !w->st.error) {
        if (sph_node_checkpoint(s, k + 1, step->t_next, w->err, sizeof w->err) == 0)
            w->st.checkpointed = 1;
        else
            w->st.error = 1;
    }
}

/* The steps from k0 (the state at t0) until the coordinator stops the run: the node's exit status. */
static int sph_node_loop(sph_node *s, int64_t k0, double t0)
{
    const int has_dem = s->ns.has_dem && s->nbody > 0;
    double t_now = t0; /* time of the state: the end of the last step taken */
    for (int64_t k = k0;; k++) {
        double wait0 = lahar_link_wait_seconds(s->link);
        lahar_link_msg msg;
        lahar_step_t step;
        int rc = lahar_node_wait_step(s->link, "lahar-sph", k, &msg, &step);
        if (rc == 0)
            sph_node_final_snapshot(s, &msg, k, t_now);
        if (rc >= 0)
            return rc;
        sph_step w = {.st = {0}};
        double c0 = lahar_now();
        sph_step_first_half(s, k, &step, has_dem, &w);
        double compute = lahar_now() - c0;
        if (has_dem && s->nmoving > 0 && (rc = sph_step_wait_bodies(s, k, &step, &w)) >= 0)
            return rc;
        c0 = lahar_now();
        sph_step_second_half(s, k, &step, has_dem, &w);
        sph_step_output(s, k, &step, &w);
        compute += lahar_now() - c0;
        w.st.compute_s = compute;
        w.st.wait_s = lahar_link_wait_seconds(s->link) - wait0;
        lahar_node_send_status(s->link, ROLE, k, &w.st, w.err);
        if (w.st.error) {
            fprintf(stderr, "lahar-sph: step %lld: %s%s\n", (long long)k, w.unstable ? "unstable: " : "",
                    w.unstable ? w.u.text : w.err);
            sph_node_wait_stop(s);
            return 1;
        }
        lahar_link_set_step(s->link, k);
        t_now = step.t_next;
    }
}

/* Build the solver from the scene: parameters, particles of every block, the bodies. */
static int sph_node_setup(sph_node *s, char *err, size_t errlen)
{
    const lahar_case *c = &s->ns.scene;
    sph_params prm;
    if (!(c->sph_dx > 0.0)) {
        snprintf(err, errlen, "the particle spacing sph.dx must be > 0 (got %g)", c->sph_dx);
        return -1;
    }
    if (lahar_sph_node_params(c, &prm, err, errlen) != 0)
        return -1;
    int64_t total = sph_node_count(c), room = 0;
    if (sph_inflow_case_wanted(c)) {
        s->has_flow = 1;
        if (sph_inflow_setup_case(&s->flow, c, &prm, err, (int)errlen) != 0)
            return -1;
        room = sph_inflow_capacity(&s->flow); /* what the inlets may add */
    }
    if (sph_fluid_init(&s->f, &prm, total + room > 0 ? total + room : 1, err, (int)errlen) != 0)
        return -1;
    s->fluid_ready = 1;
    err[0] = '\0';
    if (total < 0) {
        snprintf(err, errlen, "cannot count the particles (a lattice with too many points, or out of memory)");
        return -1;
    }
    if (sph_node_add_blocks(&s->f.p, c, err, errlen) != 0)
        return -1; /* the message is in err */
    if (s->has_flow && sph_inflow_start(&s->flow, &s->f, 0.0, err, (int)errlen) != 0)
        return -1;
    if (sph_node_alloc(s) != 0) {
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    if (s->nbody > 0 && sph_fluid_attach_bodies(&s->f, s->nbody, c->bodies) != 0) {
        snprintf(err, errlen, "out of memory for the coupling");
        return -1;
    }
    if (sph_cells_sort(&s->f.cells, &s->f.p) != 0) {
        snprintf(err, errlen, "out of memory for the cell lists");
        return -1;
    }
    /* rates at t_0 for the first dt proposal (with K_n of a CFL step; step 0 re-evaluates them
     * with the granted dt) */
    double dt_guess = prm.opt.cfl * s->f.k.h / prm.opt.c0;
    if (sph_fluid_rates(&s->f, s->nbody > 0 ? s->states : NULL, dt_guess) < 0) {
        snprintf(err, errlen, "out of memory in the SPH rates");
        return -1;
    }
    sph_node_count_coupling(s);
    /* the snapshot pressure (sph_node_snapshot) has a buffer only when the case writes it */
    if ((c->output_fields & LAHAR_PFIELD_PRESSURE) && !(s->out_pressure = malloc((size_t)s->f.p.cap * sizeof(double)))) {
        snprintf(err, errlen, "out of memory for %lld particles", (long long)s->f.p.cap);
        return -1;
    }
    return 0;
}

/* Without a DEM node in the run (the coordinator starts none when every body is fixed), this
 * node writes the body files itself; a moving body without a DEM node cannot be integrated. */
static int sph_node_setup_bodies(sph_node *s, char *err, size_t errlen)
{
    const lahar_case *c = &s->ns.scene;
    if (s->ns.has_dem || s->nbody == 0)
        return 0;
    for (int b = 0; b < s->nbody; b++)
        if (c->bodies[b].motion != LAHAR_MOTION_FIXED) {
            snprintf(err, errlen, "body %d '%s' moves, but the run has no DEM node to integrate it", b, c->bodies[b].name);
            return -1;
        }
    s->fixed_only = 1;
    return sph_node_fixed_open(s, err, errlen);
}

int lahar_sph_node_run(const lahar_sph_node_options *o)
{
    char err[2048];
    sph_node s;
    memset(&s, 0, sizeof s);
    unsigned want = LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_HELLO) | LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_SCENE) |
                    LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_STEP) | LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_BODY_STATE) |
                    LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_STOP);
    lahar_transport *t;
    if (lahar_node_connect(o, "lahar-sph", ROLE, want, &t, &s.link) != 0)
        return 2;
    static const char *const caps[] = {"dim2", "dim3", "gravity", "wcsph", "coupling"};
    int status = 0;
    int rc = lahar_node_join(s.link, ROLE, "lahar-sph/wcsph", LAHAR_VERSION, caps, 5,
                             o->join_wait_s > 0 ? o->join_wait_s : 30.0, &s.ns, err, sizeof err);
    if (rc == LAHAR_LINK_STOP)
        goto done;
    if (rc != LAHAR_LINK_OK) {
        fprintf(stderr, "lahar-sph: %s\n", err);
        status = rc == LAHAR_LINK_LOST ? 3 : 2;
        goto done;
    }
    const lahar_case *c = &s.ns.scene;
    s.nbody = c->nbody;
    for (int i = 0; i < c->nbody; i++)
        s.nmoving += c->bodies[i].motion != LAHAR_MOTION_FIXED;
    lahar_status_t st = {0};
    int64_t k0 = 0;
    double t0 = 0.0;
    err[0] = '\0';
    if (sph_node_setup(&s, err, sizeof err) != 0)
        ;
    else if (!(s.out = lahar_particle_output_open(s.ns.output_dir, c, c->output_fields, err, sizeof err)))
        ;
    else if (!c->resume && sph_node_snapshot(&s, 0, 0.0) != 0) {
        snprintf(err, sizeof err, "cannot write the first particle snapshot in %s", s.ns.output_dir);
        lahar_output_explain(err, sizeof err);
    } else if (sph_node_setup_bodies(&s, err, sizeof err) != 0) {
        /* the message is in err */
    } else if (sph_node_probes_open(&s, err, sizeof err) != 0) {
        /* the message is in err */
    } else if (c->resume) {
        /* lahar resume: the state of the checkpoint replaces the initial one set up above */
        char path[1300];
        snprintf(path, sizeof path, "%s/sph.h5", c->resume_dir);
        lahar_ckpt_file f;
        if (lahar_ckpt_open(&f, path, "sph") == 0)
            sph_node_state_io(&s, &f, &k0, &t0);
        if (lahar_ckpt_close(&f) != 0)
            snprintf(err, sizeof err, "%s", f.err);
        else if (k0 != c->resume_step)
            snprintf(err, sizeof err, "%s holds step %lld, the coordinator resumes step %lld", path, (long long)k0,
                     (long long)c->resume_step);
    }
    char desc[256];
    if (s.fluid_ready)
        snprintf(desc, sizeof desc, "WCSPH, %lld particles, kernel %s, h = %g m, c0 = %g m/s, %d bodies coupled%s%s",
                 (long long)s.f.p.n, s.f.prm.opt.kernel, s.f.k.h, s.f.prm.opt.c0, s.nbody,
                 s.f.prm.opt.sps ? ", SPS turbulence" : "", s.f.has_soil ? ", Drucker-Prager soil" : "");
    st.error = err[0] != '\0';
    st.dt_proposed = st.error ? 0.0 : sph_fluid_dt(&s.f);
    st.dt_stable = st.dt_proposed;
    s.kinetic_energy = st.error ? 0.0 : sph_node_kinetic_energy(&s.f.p);
    st.kinetic_energy = s.kinetic_energy;
    if (s.fluid_ready)
        sph_node_work(&s, &st);
    lahar_node_send_status(s.link, ROLE, -1, &st, st.error ? err : desc);
    if (st.error) {
        fprintf(stderr, "lahar-sph: %s\n", err);
        sph_node_wait_stop(&s);
        status = 1;
        goto done;
    }
    status = sph_node_loop(&s, k0, t0);
done:
    lahar_link_heartbeat_stop(s.link);
    sph_node_free(&s);
    lahar_link_destroy(s.link);
    lahar_transport_close(t);
    return status;
}
