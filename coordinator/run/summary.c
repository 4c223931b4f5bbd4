/* OUT/summary.json: how the run ended, where its time went, the nodes, the traffic, the work, the
 * machine, an instability and the checkpoints, written into the room reserved at the start. */
#define _GNU_SOURCE
#include <cjson/cJSON.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "coord_run.h"
#include "output.h"

/* summary.json "machine": the cores and the load when the run started, the threads per node, and
 * the nodes' OpenMP wait policy (coord_machine_load). */
static void coord_summary_machine(const coord *co, cJSON *root)
{
    if (!co->load_read)
        return;
    cJSON *m = cJSON_AddObjectToObject(root, "machine");
    cJSON_AddNumberToObject(m, "cores", co->load.cores);
    cJSON_AddNumberToObject(m, "load_average_1min", co->load.load1);
    if (co->load.busy_now >= 0.0)
        cJSON_AddNumberToObject(m, "busy_cores_sampled", co->load.busy_now);
    cJSON_AddNumberToObject(m, "other_lahar_runs", co->load.other_runs);
    cJSON_AddNumberToObject(m, "threads_per_node", lahar_machine_threads(&co->load, co->o->threads));
    cJSON_AddBoolToObject(m, "busy", co->busy);
    if (co->wait_policy)
        cJSON_AddStringToObject(m, "omp_wait_policy", co->wait_policy);
    else
        cJSON_AddNullToObject(m, "omp_wait_policy");
    cJSON_AddBoolToObject(m, "omp_wait_policy_set_by_lahar", co->wait_policy_set);
}

/* summary.json "flow": the open boundaries' counters of the last SPH STATUS (only for a case with
 * inlets, outlets or a domain box; names in common/io/output.h) */
static void coord_summary_flow(const coord *co, cJSON *root)
{
    const lahar_case *c = co->c;
    if (!(c->ninlet > 0 || c->noutlet > 0 || c->has_domain))
        return;
    cJSON *fj = cJSON_AddObjectToObject(root, "flow");
    for (int k = 0; k < LAHAR_FLOW_NVAL; k++)
        cJSON_AddNumberToObject(fj, lahar_flow_names[k] + 5, co->node[LAHAR_ROLE_SPH].work.flow[k]);
}

/* summary.json "work": what the run computed and sent, per kind (coordinator/README.md). Nodes
 * that did not take part count 0. */
static void coord_summary_work(const coord *co, cJSON *root)
{
    const lahar_status_t *sph = &co->node[LAHAR_ROLE_SPH].work, *dem = &co->node[LAHAR_ROLE_DEM].work;
    cJSON *w = cJSON_AddObjectToObject(root, "work");
    cJSON_AddBoolToObject(w, "dem_node", co->node[LAHAR_ROLE_DEM].needed);
    cJSON_AddBoolToObject(w, "sph_node", co->node[LAHAR_ROLE_SPH].needed);
    cJSON_AddNumberToObject(w, "sph_passes", (double)sph->work_passes);
    cJSON_AddNumberToObject(w, "pairs_fluid_fluid", (double)sph->work_pairs_fluid);
    cJSON_AddNumberToObject(w, "pairs_soil_soil", (double)sph->work_pairs_soil);
    cJSON_AddNumberToObject(w, "pairs_fluid_soil", (double)sph->work_pairs_fluid_soil);
    cJSON_AddNumberToObject(w, "particle_body", (double)sph->work_particle_body);
    cJSON_AddNumberToObject(w, "body_body", (double)dem->work_body_body);
    cJSON_AddNumberToObject(w, "dem_substeps", (double)co->node[LAHAR_ROLE_DEM].substeps);
    cJSON_AddNumberToObject(w, "output_derived", (double)(sph->work_output_derived + dem->work_output_derived));
    /* per channel: messages and bytes of the run's first publications (re-sends excluded; they
     * are in "channels") */
    cJSON *ch = cJSON_AddObjectToObject(w, "channels");
    if (co->link) {
        lahar_link_stats st[LAHAR_NMSG];
        lahar_link_get_stats(co->link, st);
        for (int ty = 1; ty < LAHAR_NMSG; ty++) {
            const lahar_link_stats *s = &st[ty];
            cJSON *j = cJSON_AddObjectToObject(ch, lahar_link_channel(ty));
            cJSON_AddNumberToObject(j, "messages", (double)(s->msgs_sent + s->msgs_heard));
            cJSON_AddNumberToObject(j, "bytes", (double)(s->bytes_sent + s->bytes_heard - s->bytes_resent_heard));
        }
    }
}

/* summary.json of a run that did not finish: "instability" (what, where, when, as the node or
 * the coordinator caught it) and "final_snapshot" (the last snapshot of each file: the state to
 * inspect, marked in the HDF5 with an "instability" or "stopped" attribute). */
static void coord_summary_instability(coord *co, cJSON *root)
{
    if (co->has_inst) {
        const lahar_instability *u = &co->inst;
        cJSON *j = cJSON_AddObjectToObject(root, "instability");
        cJSON_AddStringToObject(j, "what", u->what);
        cJSON_AddStringToObject(j, "caught_by", co->inst_node ? co->inst_node : "");
        cJSON *w = cJSON_AddObjectToObject(j, "where");
        cJSON_AddStringToObject(w, "kind", u->kind);
        cJSON_AddNumberToObject(w, "id", (double)u->id);
        cJSON_AddStringToObject(w, "name", u->name);
        if (isfinite(u->x[0]) && isfinite(u->x[1]) && isfinite(u->x[2]))
            cJSON_AddItemToObject(w, "position", cJSON_CreateDoubleArray(u->x, 3));
        else
            cJSON_AddNullToObject(w, "position");
        cJSON *when = cJSON_AddObjectToObject(j, "when");
        cJSON_AddNumberToObject(when, "step", (double)u->step);
        cJSON_AddNumberToObject(when, "time", u->t);
        if (isfinite(u->value))
            cJSON_AddNumberToObject(j, "value", u->value);
        else
            cJSON_AddNullToObject(j, "value");
        if (isfinite(u->limit))
            cJSON_AddNumberToObject(j, "limit", u->limit);
        else
            cJSON_AddNullToObject(j, "limit");
        cJSON_AddStringToObject(j, "message", u->text);
    }
    if (strcmp(co->status, "finished") == 0)
        return;
    cJSON *fs = NULL;
    static const char *const files[] = {"particles.h5", "bodies.h5"};
    for (int i = 0; i < 2; i++) {
        char group[64];
        int64_t step;
        double t;
        if (lahar_output_last_snapshot(co->outdir, files[i], group, sizeof group, &step, &t) != 0)
            continue;
        if (!fs)
            fs = cJSON_AddObjectToObject(root, "final_snapshot");
        cJSON *j = cJSON_AddObjectToObject(fs, files[i]);
        cJSON_AddStringToObject(j, "group", group);
        cJSON_AddNumberToObject(j, "step", (double)step);
        cJSON_AddNumberToObject(j, "time", t);
    }
}

/* summary.json: how the run ended and what it was (case, OUT, transport, run id), and how far it
 * came. */
static void coord_summary_outcome(const coord *co, cJSON *root)
{
    cJSON_AddStringToObject(root, "status", co->status);
    cJSON_AddNumberToObject(root, "exit_status", co->exit_status);
    cJSON_AddStringToObject(root, "message", co->message);
    char case_path[PATH_MAX];
    cJSON_AddStringToObject(root, "case", lahar_case_path_abs(co->c, case_path, sizeof case_path));
    cJSON_AddStringToObject(root, "output_dir", co->outdir);
    cJSON_AddStringToObject(root, "mode", co->mode);
    cJSON_AddStringToObject(root, "lcm_url", co->url ? co->url : "");
    char run[32];
    snprintf(run, sizeof run, "%016llx", (unsigned long long)co->run_id);
    cJSON_AddStringToObject(root, "run_id", run);
    cJSON_AddNumberToObject(root, "steps", (double)co->steps);
    cJSON_AddNumberToObject(root, "sim_time", co->sim_time);
    cJSON_AddNumberToObject(root, "t_end", co->c->t_end);
}

/* summary.json: where the wall time went */
static void coord_summary_times(const coord *co, cJSON *root)
{
    double wall = lahar_now() - co->wall0;
    cJSON_AddNumberToObject(root, "wall_time_s", wall);
    /* a resumed run: steps counts from t = 0, the rate only this invocation's */
    cJSON_AddNumberToObject(root, "steps_per_s", wall > 0 ? (double)(co->steps - co->k0) / wall : 0.0);
    /* the wall time split: start-up (nodes started, scene sent, nodes set up), the steps, the end
     * (STOP, nodes' last output and exit, this summary): the steps' share is what a longer run
     * scales */
    const int stepped = co->lock0 > 0.0 && co->lock1 >= co->lock0;
    cJSON_AddNumberToObject(root, "setup_s", stepped ? co->lock0 - co->wall0 : wall);
    cJSON_AddNumberToObject(root, "stepping_s", stepped ? co->lock1 - co->lock0 : 0.0);
    cJSON_AddNumberToObject(root, "finish_s", stepped ? wall - (co->lock1 - co->wall0) : 0.0);
    cJSON_AddNumberToObject(root, "coordinator_wait_s", co->link ? lahar_link_wait_seconds(co->link) : 0.0);
    /* the coordinator's own scheduling gaps while it waited (not counted as the nodes' silence) */
    double gap_max = 0.0, gap_sum = 0.0;
    if (co->link)
        lahar_link_sched_gaps(co->link, &gap_max, &gap_sum);
    cJSON_AddNumberToObject(root, "coordinator_sched_gap_max_s", gap_max);
    cJSON_AddNumberToObject(root, "coordinator_sched_gap_sum_s", gap_sum);
}

/* summary.json "nodes": per node what it is, where it ran, what it last reported and how it
 * answered (liveness); then "dem_substeps" */
static void coord_summary_nodes(const coord *co, cJSON *root)
{
    cJSON *nodes = cJSON_AddObjectToObject(root, "nodes");
    int64_t dem_substeps = 0;
    for (int r = 1; r < LAHAR_NROLES; r++) {
        const coord_node *n = &co->node[r];
        if (!n->needed)
            continue;
        cJSON *j = cJSON_AddObjectToObject(nodes, r == LAHAR_ROLE_DEM ? "dem" : "sph");
        cJSON_AddStringToObject(j, "engine", n->engine);
        cJSON_AddStringToObject(j, "engine_detail", n->engine_desc);
        cJSON_AddStringToObject(j, "version", n->version);
        cJSON_AddStringToObject(j, "host", n->host);
        cJSON_AddNumberToObject(j, "pid", n->remote_pid);
        cJSON_AddNumberToObject(j, "compute_s", n->compute_s);
        cJSON_AddNumberToObject(j, "wait_s", n->wait_s);
        cJSON_AddNumberToObject(j, "last_step", (double)n->last_step);
        cJSON_AddNumberToObject(j, "dt_stable", n->dt_stable);
        cJSON_AddNumberToObject(j, "kinetic_energy", n->kinetic_energy);
        cJSON_AddNumberToObject(j, "contacts", n->ncontacts);
        if (r == LAHAR_ROLE_DEM) {
            cJSON_AddNumberToObject(j, "substeps", (double)n->substeps);
            dem_substeps = n->substeps;
        }
        cJSON_AddNumberToObject(j, "exit_status", n->exit_status);
        /* liveness: the longest gap between two frames heard from the node, and the silences
         * forgiven because the node was still running (coordinator/README.md) */
        cJSON_AddNumberToObject(j, "max_silence_s", co->link ? lahar_link_max_silence(co->link, r) : 0.0);
        cJSON_AddNumberToObject(j, "starved_silences", n->starved_count);
        cJSON_AddNumberToObject(j, "starved_max_s", n->starved_max_s);
    }
    cJSON_AddNumberToObject(root, "dem_substeps", (double)dem_substeps);
}

/* summary.json "channels" and "resent_frames": traffic as seen by the coordinator, what it sent
 * and every frame of the run it heard (it listens on all channels, so node-to-node traffic is
 * included) */
static void coord_summary_channels(const coord *co, cJSON *root)
{
    cJSON *ch = cJSON_AddObjectToObject(root, "channels");
    uint64_t resent = 0;
    if (co->link) {
        lahar_link_stats st[LAHAR_NMSG];
        lahar_link_get_stats(co->link, st);
        for (int ty = 1; ty < LAHAR_NMSG; ty++) {
            const lahar_link_stats *s = &st[ty];
            cJSON *j = cJSON_AddObjectToObject(ch, lahar_link_channel(ty));
            cJSON_AddNumberToObject(j, "messages", (double)(s->msgs_sent + s->msgs_heard));
            cJSON_AddNumberToObject(j, "bytes", (double)(s->bytes_sent + s->bytes_resent + s->bytes_heard));
            cJSON_AddNumberToObject(j, "frames", (double)(s->frames_sent + s->frames_resent + s->frames_heard));
            cJSON_AddNumberToObject(j, "resent_frames", (double)(s->frames_resent + s->frames_resent_heard));
            /* bytes without the re-sends: what the run itself costs on the wire (the re-sends
             * depend on timing, e.g. a NACK that crossed a late original) */
            cJSON_AddNumberToObject(j, "first_bytes", (double)(s->bytes_sent + s->bytes_heard - s->bytes_resent_heard));
            cJSON_AddNumberToObject(j, "sent_messages", (double)s->msgs_sent);
            cJSON_AddNumberToObject(j, "sent_bytes", (double)(s->bytes_sent + s->bytes_resent));
            cJSON_AddNumberToObject(j, "heard_messages", (double)s->msgs_heard);
            cJSON_AddNumberToObject(j, "heard_bytes", (double)s->bytes_heard);
            cJSON_AddNumberToObject(j, "nacks_sent", (double)s->nacks_sent);
            cJSON_AddNumberToObject(j, "send_failures", (double)s->send_failures);
            resent += s->frames_resent + s->frames_resent_heard;
        }
    }
    cJSON_AddNumberToObject(root, "resent_frames", (double)resent);
}

/* summary.json "auth": what the coordinator dropped plus what each node reported in its last
 * STATUS */
static void coord_summary_auth(const coord *co, cJSON *root)
{
    lahar_link_auth_stats as = {0};
    cJSON *auth = cJSON_AddObjectToObject(root, "auth");
    cJSON_AddBoolToObject(auth, "enabled", co->link && lahar_link_auth(co->link, &as));
    double rejected = (double)as.frames_rejected, replayed = (double)as.frames_replayed;
    cJSON_AddNumberToObject(auth, "coordinator_rejected", rejected);
    cJSON_AddNumberToObject(auth, "coordinator_replayed", replayed);
    for (int r = 1; r < LAHAR_NROLES; r++) {
        rejected += (double)co->node[r].work.auth_rejected;
        replayed += (double)co->node[r].work.auth_replayed;
    }
    cJSON_AddNumberToObject(auth, "frames_rejected", rejected);
    cJSON_AddNumberToObject(auth, "frames_replayed", replayed);
}

/* summary.json "checkpoints" (a run with checkpoints, or resumed) and "resumed_from": where
 * `lahar resume` would continue, and where this invocation continued from */
static void coord_summary_checkpoints(const coord *co, cJSON *root)
{
    if (co->ckpt_on || co->resumed) {
        cJSON *ck = cJSON_AddObjectToObject(root, "checkpoints");
        cJSON_AddNumberToObject(ck, "interval", co->c->checkpoint_interval);
        cJSON_AddNumberToObject(ck, "keep", co->c->checkpoint_keep);
        cJSON_AddNumberToObject(ck, "written", co->ckpt_written);
        cJSON_AddNumberToObject(ck, "last_step", (double)co->ckpt_last_step);
        if (co->ckpt_last_step >= 0)
            cJSON_AddNumberToObject(ck, "last_time", co->ckpt_last_t);
        else
            cJSON_AddNullToObject(ck, "last_time");
    }
    if (co->resumed) {
        cJSON *r = cJSON_AddObjectToObject(root, "resumed_from");
        cJSON_AddStringToObject(r, "checkpoint", co->resume_dir);
        cJSON_AddNumberToObject(r, "step", (double)co->k0);
        cJSON_AddNumberToObject(r, "time", co->resume_t);
        cJSON_AddStringToObject(r, "run_id", co->resume_run_id);
    }
}

/* OUT/summary.json written from root, into the room reserved at the start
 * (coord_reserve_summary): written in place, then cut to its length, which needs no new space on
 * a full disk. Failing that, stderr says why and how the run ended. */
static void coord_summary_save(coord *co, const cJSON *root)
{
    char *text = cJSON_Print(root);
    char path[PATH_MAX + 32];
    snprintf(path, sizeof path, "%s/summary.json", co->outdir);
    int fd = co->summary_fd >= 0 ? co->summary_fd : open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    int ok = 0;
    if (fd >= 0 && text) {
        size_t len = strlen(text);
        text[len] = '\n'; /* cJSON_Print's terminator becomes the final newline */
        ok = pwrite(fd, text, len + 1, 0) == (ssize_t)(len + 1) && ftruncate(fd, (off_t)(len + 1)) == 0;
        text[len] = '\0';
    }
    if (!ok)
        fprintf(stderr, "lahar: cannot write %s: %s (the run ended with status %d: %s)\n", path,
                text ? strerror(errno) : "out of memory", co->exit_status, co->status);
    if (fd >= 0 && close(fd) != 0 && ok)
        fprintf(stderr, "lahar: cannot write %s: %s\n", path, strerror(errno));
    co->summary_fd = -1;
    free(text);
}

/* OUT/summary.json, section by section (their order here is the order of its keys) */
void coord_write_summary(coord *co)
{
    cJSON *root = cJSON_CreateObject();
    coord_summary_outcome(co, root);
    coord_summary_times(co, root);
    coord_summary_nodes(co, root);
    coord_summary_channels(co, root);
    coord_summary_auth(co, root);
    coord_summary_work(co, root);
    coord_summary_flow(co, root);
    coord_summary_machine(co, root);
    coord_summary_instability(co, root);
    coord_summary_checkpoints(co, root);
    coord_summary_save(co, root);
    cJSON_Delete(root);
}
