/* DEM node loop (see dem_node.h). Per step k:
 *   wait STEP(k) -> [SPH node present: wait LOADS(k)] -> engine advance(dt_k, loads)
 *   -> [SPH node present and moving bodies: publish BODY_STATE(k), the moving bodies within reach
 *   of the particles at t_{k+1}] -> output -> STATUS(k).
 * The loads of step k were computed by the SPH node from the body states at t_k (BODY_STATE(k-1)
 * or the scene for k = 0) and are held constant over the engine's substeps; the engine adds them
 * to the forces it reports (forces.h5), fixed bodies included (the fluid's force on a wall).
 * Bodies marked record_contacts get their contact points written to contacts.h5 at the output
 * times (the LOADS of the step that starts at an output time). */
#include "dem_node.h"
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "case.h"
#include "checkpoint.h"
#include "dem_engine.h"
#include "energy.h"
#include "instability.h"
#include "node_cli.h"
#include "lahar_body_state_t.h"
#include "lahar_loads_t.h"
#include "lahar_step_t.h"
#include "lahar_stop_t.h"
#include "link.h"
#include "output.h"
#include "scene_msg.h"
#include "transport.h"

#define ROLE LAHAR_ROLE_DEM

typedef struct {
    lahar_link *link;
    lahar_node_scene ns;
    const lahar_dem_engine_ops *ops;
    lahar_dem_engine *engine;
    lahar_body_output *out;
    lahar_contact_output *contacts; /* NULL unless a body is marked record_contacts */
    double *reach_radius;       /* per body: bounding sphere radius about the centre of mass */
    lahar_body_state *states;
    lahar_body_report *reports;
    lahar_body_load *loads;
    lahar_loads_buf loads_msg; /* LOADS decoded in place, kept between steps */
    /* BODY_STATE of the moving bodies: LCM row pointers into preallocated rows */
    int nmoving;
    int32_t *moving_id;
    double (*bx)[3], (*bq)[4], (*bv)[3], (*bw)[3];
    double **px, **pq, **pv, **pw;
    long long work_body_body0; /* body-body contacts evaluated before a resume (the engine counts from its create) */
} dem_node;

static void dem_node_free(dem_node *d)
{
    lahar_body_output_close(d->out);
    lahar_contact_output_close(d->contacts);
    free(d->reach_radius);
    if (d->engine)
        d->ops->destroy(d->engine);
    free(d->states);
    free(d->reports);
    free(d->loads);
    lahar_loads_buf_free(&d->loads_msg);
    free(d->moving_id);
    free(d->bx);
    free(d->bq);
    free(d->bv);
    free(d->bw);
    free(d->px);
    free(d->pq);
    free(d->pv);
    free(d->pw);
    lahar_case_free(&d->ns.scene);
}

static int dem_node_alloc(dem_node *d)
{
    int n = d->ns.scene.nbody > 0 ? d->ns.scene.nbody : 1;
    d->states = calloc((size_t)n, sizeof *d->states);
    d->reports = calloc((size_t)n, sizeof *d->reports);
    d->loads = calloc((size_t)n, sizeof *d->loads);
    d->moving_id = calloc((size_t)n, sizeof *d->moving_id);
    d->bx = calloc((size_t)n, sizeof *d->bx);
    d->bq = calloc((size_t)n, sizeof *d->bq);
    d->bv = calloc((size_t)n, sizeof *d->bv);
    d->bw = calloc((size_t)n, sizeof *d->bw);
    d->px = calloc((size_t)n, sizeof *d->px);
    d->pq = calloc((size_t)n, sizeof *d->pq);
    d->pv = calloc((size_t)n, sizeof *d->pv);
    d->pw = calloc((size_t)n, sizeof *d->pw);
    d->reach_radius = calloc((size_t)n, sizeof *d->reach_radius);
    if (!d->reach_radius || !d->states || !d->reports || !d->loads || !d->moving_id || !d->bx || !d->bq || !d->bv || !d->bw ||
        !d->px || !d->pq || !d->pv || !d->pw)
        return -1;
    d->nmoving = 0;
    for (int i = 0; i < d->ns.scene.nbody; i++) {
        const lahar_shape *sh = &d->ns.scene.bodies[i].shape;
        double r2 = 0.0;
        for (int v = 0; v < sh->nv; v++)
            r2 = fmax(r2, sh->v[v][0] * sh->v[v][0] + sh->v[v][1] * sh->v[v][1] + sh->v[v][2] * sh->v[v][2]);
        d->reach_radius[i] = sqrt(r2) + sh->radius;
    }
    return 0;
}

static void dem_node_get_states(dem_node *d)
{
    for (int i = 0; i < d->ns.scene.nbody; i++)
        d->ops->get_state(d->engine, i, &d->states[i]);
}

/* BODY_STATE(k): the moving bodies at t_{k+1} whose bounding sphere reaches into the region
 * where particles can touch them (LOADS(k).reach_lo/hi); the others are far from every particle
 * and cost nothing on the wire. */
static int dem_node_send_body_state(dem_node *d, int64_t k, double t)
{
    const lahar_loads_buf *lm = &d->loads_msg;
    d->nmoving = 0;
    for (int i = 0; i < d->ns.scene.nbody; i++) {
        if (d->ns.scene.bodies[i].motion == LAHAR_MOTION_FIXED)
            continue;
        const lahar_body_state *s = &d->states[i];
        double r = d->reach_radius[i], gap2 = 0.0;
        for (int a = 0; a < 3; a++) {
            double g = fmax(lm->reach_lo[a] - s->x[a], s->x[a] - lm->reach_hi[a]);
            if (g > 0.0)
                gap2 += g * g;
        }
        if (!(gap2 <= r * r)) /* NaN states are never sent (the engine stops on them anyway) */
            continue;
        int m = d->nmoving++;
        d->moving_id[m] = i;
        memcpy(d->bx[m], s->x, sizeof d->bx[m]);
        memcpy(d->bq[m], s->q, sizeof d->bq[m]);
        memcpy(d->bv[m], s->v, sizeof d->bv[m]);
        memcpy(d->bw[m], s->w, sizeof d->bw[m]);
        d->px[m] = d->bx[m];
        d->pq[m] = d->bq[m];
        d->pv[m] = d->bv[m];
        d->pw[m] = d->bw[m];
    }
    lahar_body_state_t bs = {
        .run_id = lahar_link_run_id(d->link), .step = k, .t = t, .n = d->nmoving, .id = d->moving_id,
        .x = d->px, .q = d->pq, .v = d->pv, .w = d->pw,
    };
    int rc;
    LAHAR_LINK_SEND(rc, d->link, LAHAR_FRAME_T_MSG_BODY_STATE, lahar_body_state_t, k, &bs);
    return rc;
}

/* Loads of step k from the SPH node, one entry per body (zero for bodies not listed). */
static int dem_node_read_loads(dem_node *d, const lahar_link_msg *msg, char *err, size_t errlen)
{
    lahar_loads_buf *lm = &d->loads_msg;
    if (lahar_loads_decode(msg->data, msg->size, lm) != 0) {
        snprintf(err, errlen, "undecodable LOADS(%lld)", (long long)msg->step);
        return -1;
    }
    memset(d->loads, 0, (size_t)d->ns.scene.nbody * sizeof *d->loads);
    for (int i = 0; i < lm->nbody; i++) {
        int b = lm->body_id[i];
        if (b < 0 || b >= d->ns.scene.nbody) {
            snprintf(err, errlen, "LOADS(%lld) names body %d, the scene has %d", (long long)msg->step, b,
                     d->ns.scene.nbody);
            return -1;
        }
        memcpy(d->loads[b].force, lm->force[i], sizeof d->loads[b].force);
        memcpy(d->loads[b].torque, lm->torque[i], sizeof d->loads[b].torque);
    }
    return 0;
}

/* Wait for the coordinator to end the run after an error (the STATUS carried the message). */
static int dem_node_wait_stop(dem_node *d)
{
    lahar_link_msg msg;
    for (;;) {
        int rc = lahar_link_wait(d->link, LAHAR_ROLE_COORDINATOR, LAHAR_FRAME_T_MSG_STOP, LAHAR_LINK_ANY_STEP, -1, &msg);
        if (rc == LAHAR_LINK_OK || rc == LAHAR_LINK_LOST || rc == LAHAR_LINK_ERROR)
            return rc;
    }
}

/* After advance() failed in step k (ending at time t): when the engine reports an instability of
 * the bodies (ops->fault), the report of common/protocol/instability.h with the body's name, the place
 * (its centre or the contact point) and the step, else 0 (the engine's message stays). */
static int dem_node_fault_report(const dem_node *d, int64_t k, double t, lahar_instability *u)
{
    lahar_dem_fault f;
    if (!d->ops->fault || !d->ops->fault(d->engine, &f))
        return 0;
    const lahar_case *c = &d->ns.scene;
    const char *name = f.body >= 0 && f.body < c->nbody ? c->bodies[f.body].name : "?";
    memset(u, 0, sizeof *u);
    snprintf(u->what, sizeof u->what, "%s", f.what);
    snprintf(u->kind, sizeof u->kind, "body");
    u->id = f.body;
    snprintf(u->name, sizeof u->name, "%s", name);
    memcpy(u->x, f.x, sizeof u->x);
    u->step = k;
    u->t = t;
    u->value = f.value;
    u->limit = f.limit;
    if (strcmp(f.what, "overlap") == 0)
        snprintf(u->text, sizeof u->text,
                 "body %d '%s' overlaps body %d '%s' by %.3g m at (%.4g, %.4g, %.4g) m, more than "
                 "stability.max_overlap allows (%.3g m), in step %lld (t = %.9g s, substep %ld)",
                 f.body, name, f.other, f.other >= 0 && f.other < c->nbody ? c->bodies[f.other].name : "?", f.value,
                 f.x[0], f.x[1], f.x[2], f.limit, (long long)k, t, f.substep);
    else
        snprintf(u->text, sizeof u->text, "body %d '%s' has a %s state at (%.4g, %.4g, %.4g) m in step %lld "
                 "(t = %.9g s, substep %ld)", f.body, name, f.what, f.x[0], f.x[1], f.x[2], (long long)k, t, f.substep);
    return 1;
}

/* The coordinator stopped the run before step k (the bodies are at the end of step k - 1, time
 * t): on a stop for an error (an instability in the SPH node, a time step collapse) the state
 * reached is written as the final snapshot, marked with the coordinator's reason, unless a
 * snapshot of it exists. */
static void dem_node_final_snapshot(dem_node *d, const lahar_link_msg *stop, int64_t k, double t, int64_t last)
{
    char why[512];
    if (lahar_node_stop_reason(stop, why, sizeof why) <= 0)
        return;
    if (last != k) {
        dem_node_get_states(d);
        if (lahar_body_output_snapshot(d->out, k, t, d->states) != 0)
            return;
    }
    lahar_output_mark_last_snapshot(d->ns.output_dir, "bodies.h5", "stopped", why);
}

/* The node's whole state for a checkpoint (common/io/checkpoint.h; one function both ways): the
 * engine's restart blob (bodies and contact history, dem_engine.h) and the loop's own state.
 * Returns 0, or -1 with the message in f->err. */
static int dem_node_state_io(dem_node *d, lahar_ckpt_file *f, int64_t *k, double *t_now, int *at_output_time,
                             int64_t *last_snapshot)
{
    lahar_ckpt_i64(f, "step", k, 1);
    lahar_ckpt_f64(f, "t", t_now, 1);
    lahar_ckpt_int(f, "at_output_time", at_output_time);
    lahar_ckpt_i64(f, "last_snapshot", last_snapshot, 1);
    /* the work counter of summary.json continues across a resume */
    const long long now = d->ops->contacts_evaluated ? d->ops->contacts_evaluated(d->engine) : 0;
    int64_t work = now + d->work_body_body0;
    lahar_ckpt_i64(f, "work_body_body", &work, 1);
    if (!f->writing && !f->failed)
        d->work_body_body0 = work - now;
    void *blob = NULL;
    size_t len = 0;
    if (f->writing) {
        FILE *m = open_memstream((char **)&blob, &len);
        int rc = m ? d->ops->write_restart(d->engine, m) : -1;
        if (m && fclose(m) != 0)
            rc = -1;
        if (rc != 0) {
            free(blob);
            snprintf(f->err, sizeof f->err, "the DEM engine %s cannot write its restart data", d->ops->name);
            f->failed = 1;
            return -1;
        }
        lahar_ckpt_blob(f, "engine_restart", &blob, &len);
    } else {
        lahar_ckpt_blob(f, "engine_restart", &blob, &len);
        FILE *m = !f->failed ? fmemopen(blob, len, "rb") : NULL;
        if (!f->failed && (!m || d->ops->read_restart(d->engine, m) != 0)) {
            snprintf(f->err, sizeof f->err, "the DEM engine %s cannot read the checkpoint's restart data (another "
                     "engine, case or build?)", d->ops->name);
            f->failed = 1;
        }
        if (m)
            fclose(m);
    }
    free(blob);
    return f->failed ? -1 : 0;
}

/* Step k done (the state of step index k + 1 at t_next): flush the force stream and write
 * OUT/checkpoints/NNNNNN.tmp/dem.h5, synced. 0, or -1 with a message in err. */
static int dem_node_checkpoint(dem_node *d, int64_t state_step, double t, int at_output_time, int64_t last_snapshot,
                               char *err, size_t errlen)
{
    char dir[1200], path[1300];
    lahar_ckpt_dir(dir, sizeof dir, d->ns.output_dir, state_step, 1);
    snprintf(path, sizeof path, "%s/dem.h5", dir);
    if (lahar_body_output_sync(d->out) != 0 || lahar_mkdir_p(dir) != 0) {
        snprintf(err, errlen, "cannot write the checkpoint in %s", dir);
        return -1;
    }
    lahar_ckpt_file f;
    int64_t k = state_step;
    double tt = t;
    int ao = at_output_time;
    int64_t ls = last_snapshot;
    if (lahar_ckpt_create(&f, path, "dem") == 0)
        dem_node_state_io(d, &f, &k, &tt, &ao, &ls);
    if (lahar_ckpt_close(&f) != 0) {
        snprintf(err, errlen, "%s", f.err);
        return -1;
    }
    return 0;
}

static int dem_node_loop(dem_node *d, int64_t k0, double t0, int at_output0, int64_t last_snapshot0)
{
    char err[2048];
    lahar_link_msg msg;
    const int has_sph = d->ns.has_sph;
    int moving = 0;
    for (int i = 0; i < d->ns.scene.nbody; i++)
        moving += d->ns.scene.bodies[i].motion != LAHAR_MOTION_FIXED;
    int at_output_time = at_output0; /* t_0: 1 */
    int64_t last_snapshot = last_snapshot0;
    double t_now = t0; /* time of the state: the end of the last step taken */
    for (int64_t k = k0;; k++) {
        double wait0 = lahar_link_wait_seconds(d->link);
        lahar_step_t step;
        int rc = lahar_node_wait_step(d->link, "lahar-dem", k, &msg, &step);
        if (rc == 0)
            dem_node_final_snapshot(d, &msg, k, t_now, last_snapshot);
        if (rc >= 0)
            return rc;
        lahar_status_t st = {0};
        err[0] = '\0';
        if (has_sph) {
            rc = lahar_link_wait(d->link, LAHAR_ROLE_SPH, LAHAR_FRAME_T_MSG_LOADS, k, -1, &msg);
            if (rc == LAHAR_LINK_STOP) {
                dem_node_final_snapshot(d, &msg, k, t_now, last_snapshot);
                return 0;
            }
            if (rc == LAHAR_LINK_LOST) {
                lahar_node_report_lost("lahar-dem", "the SPH node's loads of step", k);
                return 3;
            }
            if (rc != LAHAR_LINK_OK || dem_node_read_loads(d, &msg, err, sizeof err) != 0)
                st.error = 1;
            const lahar_loads_buf *lm = &d->loads_msg;
            if (!st.error && at_output_time &&
                lahar_contact_output_write(d->contacts, k, step.t, lm->nbody, lm->body_id, lm->npoints,
                                           (const double(*)[3])lm->point_x, (const double(*)[3])lm->point_f,
                                           (const double(*)[3])lm->force, (const double(*)[3])lm->torque) != 0) {
                st.error = 1;
                snprintf(err, sizeof err, "cannot write to contacts.h5 in %s", d->ns.output_dir);
                lahar_output_explain(err, sizeof err);
            }
        }
        at_output_time = step.write_output;
        double c0 = lahar_now();
        int nsub = st.error ? -1 : d->ops->advance(d->engine, step.dt, has_sph ? d->loads : NULL, err, sizeof err);
        double compute = lahar_now() - c0;
        lahar_instability u;
        int unstable = 0;
        if (nsub < 0 && !st.error && dem_node_fault_report(d, k, step.t_next, &u)) {
            unstable = 1;
            lahar_instability_encode(&u, err, sizeof err);
        }
        if (nsub < 0)
            st.error = 1;
        dem_node_get_states(d);
        if (has_sph && moving > 0 && !st.error)
            dem_node_send_body_state(d, k, step.t_next);
        for (int i = 0; i < d->ns.scene.nbody; i++) {
            d->ops->get_report(d->engine, i, &d->reports[i]);
            lahar_body_energy(&d->ns.scene.bodies[i], &d->states[i], d->ns.scene.gravity, d->reports[i].energy);
        }
        if (lahar_body_output_forces(d->out, k + 1, step.t_next, d->reports) != 0 && !st.error) {
            st.error = 1;
            snprintf(err, sizeof err, "cannot append to forces.h5 in %s", d->ns.output_dir);
            lahar_output_explain(err, sizeof err);
        }
        /* On an engine error the last state is kept as a snapshot to look at. */
        if (step.write_output || st.error) {
            if (lahar_body_output_snapshot(d->out, k + 1, step.t_next, d->states) == 0) {
                last_snapshot = k + 1;
                if (unstable)
                    lahar_output_mark_last_snapshot(d->ns.output_dir, "bodies.h5", "instability", u.text);
            } else if (!st.error) {
                st.error = 1;
                snprintf(err, sizeof err, "cannot write a snapshot to bodies.h5 in %s", d->ns.output_dir);
                lahar_output_explain(err, sizeof err);
            }
        }
        st.dt_proposed = 0.0; /* the engine subcycles: no limit on the coordinator step */
        st.dt_stable = d->ops->stable_dt(d->engine);
        st.compute_s = compute;
        st.wait_s = lahar_link_wait_seconds(d->link) - wait0;
        st.ncontacts = d->ops->ncontacts(d->engine);
        st.nsubsteps = nsub > 0 ? nsub : 0;
        st.kinetic_energy = d->ops->kinetic_energy(d->engine);
        st.work_body_body = (d->ops->contacts_evaluated ? d->ops->contacts_evaluated(d->engine) : 0) + d->work_body_body0;
        if (step.checkpoint && !st.error) {
            if (dem_node_checkpoint(d, k + 1, step.t_next, at_output_time, last_snapshot, err, sizeof err) == 0)
                st.checkpointed = 1;
            else
                st.error = 1;
        }
        lahar_node_send_status(d->link, ROLE, k, &st, err);
        if (st.error) {
            fprintf(stderr, "lahar-dem: step %lld: %s%s\n", (long long)k, unstable ? "unstable: " : "",
                    unstable ? u.text : err);
            dem_node_wait_stop(d);
            return 1;
        }
        lahar_link_set_step(d->link, k);
        t_now = step.t_next;
    }
}

int lahar_dem_node_run(const lahar_dem_node_options *o)
{
    char err[2048];
    dem_node d;
    memset(&d, 0, sizeof d);
    unsigned want = LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_HELLO) | LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_SCENE) |
                    LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_STEP) | LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_LOADS) |
                    LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_STOP);
    lahar_transport *t;
    if (lahar_node_connect(o, "lahar-dem", ROLE, want, &t, &d.link) != 0)
        return 2;
    static const char *const caps[] = {"dim2", "dim3", "hertz", "linear", "subcycle", "restart"};
    int status = 0;
    int rc = lahar_node_join(d.link, ROLE, lahar_dem_engine_names(), LAHAR_VERSION, caps, 6,
                             o->join_wait_s > 0 ? o->join_wait_s : 30.0, &d.ns, err, sizeof err);
    if (rc == LAHAR_LINK_STOP)
        goto done;
    if (rc != LAHAR_LINK_OK) {
        fprintf(stderr, "lahar-dem: %s\n", err);
        status = rc == LAHAR_LINK_LOST ? 3 : 2;
        goto done;
    }
    /* A run whose bodies are all fixed has no DEM node (the SPH node writes the body files): a
     * node started by hand for it has nothing to do. */
    if (!d.ns.has_dem) {
        fprintf(stderr, "lahar-dem: this run has no DEM node (its bodies are all fixed); exiting\n");
        goto done;
    }
    /* Ready = STATUS(-1); an error here (unknown engine, unwritable output) stops the run. */
    lahar_status_t st = {0};
    int64_t k0 = 0, last_snapshot0 = 0;
    double t0 = 0.0;
    int at_output0 = 1;
    err[0] = '\0';
    const char *engine_name = o->engine ? o->engine : d.ns.scene.dem_engine; /* lahar-dem --engine wins */
    d.ops = lahar_dem_engine_find(engine_name);
    if (!d.ops)
        snprintf(err, sizeof err, "unknown DEM engine '%s' (known: %s)", engine_name, lahar_dem_engine_names());
    else if (dem_node_alloc(&d) != 0)
        snprintf(err, sizeof err, "out of memory");
    else if (!(d.engine = d.ops->create(&d.ns.scene, err, sizeof err)))
        ;
    else if (!(d.out = lahar_body_output_open(d.ns.output_dir, &d.ns.scene, err, sizeof err)))
        ;
    else if (d.ns.has_sph && !(d.contacts = lahar_contact_output_open(d.ns.output_dir, &d.ns.scene, err, sizeof err)) &&
             err[0])
        ;
    else if (d.ns.scene.resume) {
        /* lahar resume: the state of the checkpoint instead of the initial one */
        char path[1300];
        snprintf(path, sizeof path, "%s/dem.h5", d.ns.scene.resume_dir);
        lahar_ckpt_file f;
        if (lahar_ckpt_open(&f, path, "dem") == 0)
            dem_node_state_io(&d, &f, &k0, &t0, &at_output0, &last_snapshot0);
        if (lahar_ckpt_close(&f) != 0)
            snprintf(err, sizeof err, "%s", f.err);
        else if (k0 != d.ns.scene.resume_step)
            snprintf(err, sizeof err, "%s holds step %lld, the coordinator resumes step %lld", path, (long long)k0,
                     (long long)d.ns.scene.resume_step);
    } else {
        dem_node_get_states(&d);
        if (lahar_body_output_snapshot(d.out, 0, 0.0, d.states) != 0) {
            snprintf(err, sizeof err, "cannot write the first snapshot in %s", d.ns.output_dir);
            lahar_output_explain(err, sizeof err);
        }
    }
    char engine_desc[128];
    if (d.ops)
        snprintf(engine_desc, sizeof engine_desc, "%s %s", d.ops->name, d.ops->version);
    st.error = err[0] != '\0';
    st.dt_stable = d.engine ? d.ops->stable_dt(d.engine) : 0.0;
    st.kinetic_energy = d.engine ? d.ops->kinetic_energy(d.engine) : 0.0;
    lahar_node_send_status(d.link, ROLE, -1, &st, st.error ? err : (d.ops ? engine_desc : ""));
    if (st.error) {
        fprintf(stderr, "lahar-dem: %s\n", err);
        dem_node_wait_stop(&d);
        status = 1;
        goto done;
    }
    status = dem_node_loop(&d, k0, t0, at_output0, last_snapshot0);
done:
    lahar_link_heartbeat_stop(d.link);
    dem_node_free(&d);
    lahar_link_destroy(d.link);
    lahar_transport_close(t);
    return status;
}
