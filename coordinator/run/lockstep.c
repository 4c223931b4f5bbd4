/* The lockstep: STEP(k) to every node, STATUS(k) back, the next step's size, output and checkpoint
 * times from the clock (clock.c); a collapsing step stops the run; the progress line. */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include "coord_run.h"
#include "lahar_step_t.h"

/* The signal a run stopped on, for its message (coord_interrupted, coord_term). */
static const char *coord_signal_name(int sig)
{
    return sig == SIGHUP ? "SIGHUP" : sig == SIGTERM ? "SIGTERM" : "SIGINT";
}

/* A duration for a person: seconds up to 2 min, minutes up to 2 h, then hours. */
static const char *coord_duration(double s, char *buf, size_t n)
{
    if (s < 120.0)
        snprintf(buf, n, "%.0f s", s);
    else if (s < 7200.0)
        snprintf(buf, n, "%.1f min", s / 60.0);
    else
        snprintf(buf, n, "%.1f h", s / 3600.0);
    return buf;
}

void coord_progress(coord *co, int final)
{
    if (!co->progress || (final && co->progress == COORD_PROGRESS_LOG)) /* a log ends with "finished" */
        return;
    double now = lahar_now();
    const double every = co->progress == COORD_PROGRESS_LOG ? co->o->progress_every_s : 0.25;
    if (!final && now - co->last_progress < every)
        return;
    co->last_progress = now;
    double wall = now - co->wall0;
    double rate = wall > 0 ? (double)(co->steps - co->k0) / wall : 0.0;
    double t0 = co->resumed ? co->resume_t : 0.0; /* this invocation's share of the run */
    double frac = co->c->t_end > t0 ? (co->sim_time - t0) / (co->c->t_end - t0) : 1.0;
    double eta = frac > 0 ? wall * (1.0 - frac) / frac : 0.0;
    char eta_s[32], wall_s[32];
    coord_duration(eta, eta_s, sizeof eta_s);
    if (co->progress == COORD_PROGRESS_LOG) {
        fprintf(stderr, "lahar: t = %.4g / %.4g s (%.0f %%)   step %lld   %.0f steps/s   %s elapsed   ETA %s\n",
                co->sim_time, co->c->t_end, 100.0 * frac, (long long)co->steps, rate,
                coord_duration(wall, wall_s, sizeof wall_s), eta_s);
    } else {
        fprintf(stderr, "\r  t = %.4g / %.4g s   step %lld   %.0f steps/s   ETA %s   ", co->sim_time, co->c->t_end,
                (long long)co->steps, rate, eta_s);
        if (final)
            fputc('\n', stderr);
    }
    fflush(stderr);
}

/* Time step collapse before step k (the nodes at t = co->sim_time): the step the nodes allow is
 * below time.dt_min, or below stability.dt_collapse x the first step (the state has gone
 * unstable: a blow-up drives the CFL and force limits of the SPH step down by orders of
 * magnitude first). Names the node whose proposal sets the step. 1 when the run must stop. */
static int coord_dt_collapse(coord *co, int64_t k, double dt_allowed, double dt_first)
{
    const lahar_case *c = co->c;
    const double rel = c->stability.dt_collapse * dt_first;
    if (!(dt_allowed < c->dt_min || dt_allowed < rel))
        return 0;
    int by = 0;
    for (int r = 1; r < LAHAR_NROLES; r++)
        if (co->node[r].needed && co->node[r].dt_proposed > 0 && co->node[r].dt_proposed <= dt_allowed)
            by = r;
    lahar_instability *u = &co->inst;
    memset(u, 0, sizeof *u);
    snprintf(u->what, sizeof u->what, "dt collapse");
    snprintf(u->name, sizeof u->name, "%s", by ? lahar_link_role_name(by) : "");
    u->id = -1;
    u->x[0] = u->x[1] = u->x[2] = NAN;
    u->step = k;
    u->t = co->sim_time;
    u->value = dt_allowed;
    const int absolute = dt_allowed < c->dt_min;
    u->limit = absolute ? c->dt_min : rel;
    if (absolute)
        snprintf(u->text, sizeof u->text,
                 "time step collapse before step %lld (t = %.9g s): the %s allows %.3g s < time.dt_min = %.3g s",
                 (long long)k, co->sim_time, by ? lahar_link_role_name(by) : "nodes", dt_allowed, c->dt_min);
    else
        snprintf(u->text, sizeof u->text,
                 "time step collapse before step %lld (t = %.9g s): the %s allows %.3g s < stability.dt_collapse "
                 "%g x the first step %.3g s",
                 (long long)k, co->sim_time, by ? lahar_link_role_name(by) : "nodes", dt_allowed,
                 c->stability.dt_collapse, dt_first);
    co->has_inst = 1;
    co->inst_node = "coordinator";
    co->status = "unstable";
    snprintf(co->message, sizeof co->message, "%s", u->text);
    return 1;
}

static int coord_lockstep(coord *co)
{
    const lahar_case *c = co->c;
    lahar_clock clk;
    lahar_clock_init(&clk, c->t_end, c->output_interval);
    double dt_allowed = c->dt_max, dt_first = c->dt_max;
    for (int r = 1; r < LAHAR_NROLES; r++)
        if (co->node[r].needed && co->node[r].dt_proposed > 0 && co->node[r].dt_proposed < dt_allowed)
            dt_allowed = co->node[r].dt_proposed;
    int64_t k0 = 0;
    if (co->resumed) { /* lahar resume: the clock and limits of the checkpoint */
        clk = co->clk0;
        dt_allowed = co->dt_allowed0;
        dt_first = co->dt_first0;
        k0 = co->k0;
    }
    int stop_after = 0;
    for (int64_t k = k0;; k++) {
        if (coord_interrupted && !(coord_term && co->ckpt_on)) {
            co->status = "interrupted";
            snprintf(co->message, sizeof co->message, "interrupted by %s at step %lld (t = %.9g s)",
                     coord_signal_name(coord_interrupted), (long long)k, co->sim_time);
            return LAHAR_EXIT_RUN_ERROR;
        }
        if (k == 0)
            dt_first = dt_allowed;
        if (coord_dt_collapse(co, k, dt_allowed, dt_first))
            return LAHAR_EXIT_RUN_ERROR;
        double t, t_next;
        int is_output;
        if (lahar_clock_next(&clk, dt_allowed, &t, &t_next, &is_output))
            return LAHAR_EXIT_OK;
        int write_forces = 1;
        if (c->forces_interval > 0)
            write_forces = k == 0 || floor(t_next / c->forces_interval + 1e-9) > floor(t / c->forces_interval + 1e-9);
        /* a checkpoint after the first step ending at or after each multiple of the interval
         * (integers, as write_forces), after the last step, on SIGUSR1, and on SIGTERM (then
         * the run stops, resumable) */
        int ckpt = 0;
        if (co->ckpt_on) {
            const double ci = c->checkpoint_interval;
            ckpt = floor(t_next / ci + 1e-9) > floor(t / ci + 1e-9) || (is_output && clk.j + 1 >= clk.nout);
            if (coord_ckpt_request || coord_term)
                ckpt = 1;
            if (coord_term)
                stop_after = 1;
            coord_ckpt_request = 0;
        } else if (coord_ckpt_request) {
            coord_ckpt_request = 0;
            fprintf(stderr, "\nlahar: SIGUSR1: this case has no checkpoint: section, so no checkpoint is written\n");
        }
        for (int r = 1; r < LAHAR_NROLES; r++)
            co->node[r].checkpointed = 0;
        lahar_step_t s = {
            .run_id = co->run_id, .step = k, .t = t, .dt = t_next - t, .t_next = t_next,
            .write_output = (int8_t)is_output, .write_forces = (int8_t)write_forces, .checkpoint = (int8_t)ckpt,
        };
        int rc;
        LAHAR_LINK_SEND(rc, co->link, LAHAR_FRAME_T_MSG_STEP, lahar_step_t, k, &s);
        if (rc != 0) {
            co->status = "error";
            snprintf(co->message, sizeof co->message, "cannot publish STEP(%lld)", (long long)k);
            return LAHAR_EXIT_RUN_ERROR;
        }
        rc = coord_collect_status(co, k);
        if (rc != LAHAR_EXIT_OK)
            return rc;
        lahar_clock_advance(&clk);
        lahar_link_set_step(co->link, k);
        co->steps = k + 1;
        co->sim_time = t_next;
        dt_allowed = c->dt_max;
        for (int r = 1; r < LAHAR_NROLES; r++)
            if (co->node[r].needed && co->node[r].dt_proposed > 0 && co->node[r].dt_proposed < dt_allowed)
                dt_allowed = co->node[r].dt_proposed;
        if (ckpt && coord_checkpoint(co, k, &clk, dt_allowed, dt_first, is_output) != 0) {
            co->status = "error";
            return LAHAR_EXIT_RUN_ERROR;
        }
        if (stop_after && clk.j < clk.nout) { /* (at the end time the run simply finishes) */
            co->status = "stopped";
            co->clean_stop = 1;
            snprintf(co->message, sizeof co->message, "stopped by %s after the checkpoint of step %lld (t = %.9g "
                     "s); continue with `lahar resume %.800s`", coord_signal_name(coord_term), (long long)(k + 1),
                     co->sim_time, co->outdir);
            return LAHAR_EXIT_RUN_ERROR;
        }
        coord_progress(co, 0);
    }
}

/* The lockstep, timed apart from set-up and finish (summary.json setup_s, stepping_s, finish_s). */
int coord_step_to_end(coord *co)
{
    co->lock0 = lahar_now();
    int status = coord_lockstep(co);
    co->lock1 = lahar_now();
    if (status == LAHAR_EXIT_OK)
        co->status = "finished";
    return status;
}
