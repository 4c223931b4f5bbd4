/* The nodes of a run: started as processes or threads, their OpenMP wait policy, watched
 * (reaped, starved or lost), HELLO, the scene, STATUS collected step by step, STOP and their exit. */
#define _GNU_SOURCE
#include <dirent.h>
#include <errno.h>
#include <libgen.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#include "coord_run.h"
#include "dem_node.h"
#include "lahar_hello_t.h"
#include "lahar_stop_t.h"
#include "msg_check.h"
#include "output.h"
#include "scene_msg.h"
#include "sph_node.h"

/* Silence after which a node is lost (--node-timeout, else COORD_NODE_SILENCE). */
static double coord_silence(const coord *co)
{
    return co->o->node_timeout_s > 0.0 ? co->o->node_timeout_s : COORD_NODE_SILENCE;
}

/* Before the nodes start: OpenMP threads wait for each other at the end of every parallel loop of
 * a step, and libgomp's waiting thread spins (OMP_WAIT_POLICY unset) for a while before it sleeps.
 * On cores that other work holds, or with more threads than cores, the spinning takes the CPU from
 * the threads it waits for (docs/bench/busy_machine.md). So, when the machine is
 * busy (lahar_machine_busy) and the user set no OMP_WAIT_POLICY, the nodes lahar starts as
 * processes get OMP_WAIT_POLICY=passive, which changes no result. --in-process nodes share this
 * process's OpenMP, which libgomp configures before main: lahar_coord_in_process_wait_policy runs
 * lahar again with the policy set, marked by LAHAR_WAIT_POLICY_SET_ENV. */
#define LAHAR_WAIT_POLICY_SET_ENV "LAHAR_OMP_WAIT_POLICY_SET_BY_LAHAR"

/* Busy for `threads` threads per node (`load` read): the load average says so, and still does over
 * 0.2 s (the average lags by a minute; the sample is paid only when it says busy). */
static int machine_busy_now(lahar_machine_load *load, int threads)
{
    if (!lahar_machine_busy(load, threads))
        return 0;
    return lahar_machine_sample(load, 0.2) == 0 ? lahar_machine_busy(load, threads) : 1;
}

void lahar_coord_in_process_wait_policy(char **argv, const lahar_coord_options *o)
{
    lahar_machine_load load;
    if (!o->in_process || getenv("OMP_WAIT_POLICY") || lahar_machine_load_read(&load) != 0 ||
        !machine_busy_now(&load, o->threads))
        return;
    if (setenv("OMP_WAIT_POLICY", "passive", 1) == 0 && setenv(LAHAR_WAIT_POLICY_SET_ENV, "1", 1) == 0)
        execv("/proc/self/exe", argv);
    /* not run again: on with the spinning policy; coord_machine_load's note says what to set */
    unsetenv("OMP_WAIT_POLICY");
    unsetenv(LAHAR_WAIT_POLICY_SET_ENV);
}

static void coord_machine_load(coord *co)
{
    const lahar_coord_options *o = co->o;
    co->wait_policy = getenv("OMP_WAIT_POLICY");
    const char *set_here = getenv(LAHAR_WAIT_POLICY_SET_ENV);
    co->wait_policy_set = o->in_process && set_here && co->wait_policy && strcmp(co->wait_policy, "passive") == 0;
    co->load_read = lahar_machine_load_read(&co->load) == 0;
    co->busy = co->load_read && machine_busy_now(&co->load, o->threads);
    if (!co->busy || o->no_spawn)
        return;
    if (!co->wait_policy && !o->in_process && setenv("OMP_WAIT_POLICY", "passive", 1) == 0) {
        co->wait_policy = "passive";
        co->wait_policy_set = 1;
    }
    if (o->quiet)
        return;
    const int t = lahar_machine_threads(&co->load, o->threads);
    if (t > co->load.cores)
        fprintf(stderr, "lahar: note: %d OpenMP threads per node on %d cores", t, co->load.cores);
    else if (co->load.other_runs > 0)
        fprintf(stderr, "lahar: note: %d other lahar run%s on this machine's %d cores, and each node runs %d OpenMP "
                        "threads",
                co->load.other_runs, co->load.other_runs > 1 ? "s" : "", co->load.cores, t);
    else if (co->load.busy_now >= 0.0)
        fprintf(stderr, "lahar: note: this machine is busy (other work holds %.1f of its %d cores) and each node runs "
                        "%d OpenMP threads",
                co->load.busy_now, co->load.cores, t);
    else
        fprintf(stderr, "lahar: note: this machine is busy (load average %.1f over the last minute on %d cores) and "
                        "each node runs %d OpenMP threads",
                co->load.load1, co->load.cores, t);
    fprintf(stderr, ": threads that share a core wait for each other at every step, which can make the run several "
                    "times slower. %s%s\n",
            co->wait_policy_set ? "The nodes run with OMP_WAIT_POLICY=passive (set by lahar; results are the same). "
            : o->in_process && !co->wait_policy ? "Set OMP_WAIT_POLICY=passive in the environment (lahar could not "
                                                  "run itself again with it). "
                                                : "",
            o->threads == 1 ? "" : "--threads 1 may be faster still.");
}

typedef struct {
    coord_node *n;
    const char *url;
    int64_t run_id;
    int threads;
} coord_thread_arg;
static coord_thread_arg coord_thread_args[LAHAR_NROLES];

static void *coord_node_thread(void *arg)
{
    coord_thread_arg *a = arg;
    if (a->n->role == LAHAR_ROLE_DEM) {
        lahar_dem_node_options o = {.lcm_url = a->url, .run_id = a->run_id, .threads = a->threads};
        a->n->thread_status = lahar_dem_node_run(&o);
    } else {
        lahar_sph_node_options o = {.lcm_url = a->url, .run_id = a->run_id, .threads = a->threads};
        a->n->thread_status = lahar_sph_node_run(&o);
    }
    atomic_store(&a->n->thread_done, 1);
    return NULL;
}

static int coord_exe_dir(char *dir, size_t n)
{
    char self[PATH_MAX];
    ssize_t len = readlink("/proc/self/exe", self, sizeof self - 1);
    if (len <= 0)
        return -1;
    self[len] = '\0';
    snprintf(dir, n, "%s", dirname(self));
    return 0;
}

static int coord_start_node(coord *co, coord_node *n)
{
    if (co->o->in_process) {
        coord_thread_arg *a = &coord_thread_args[n->role];
        a->n = n;
        a->url = co->url;
        a->run_id = co->run_id;
        a->threads = co->o->threads;
        if (pthread_create(&n->thread, NULL, coord_node_thread, a) != 0) {
            fprintf(stderr, "lahar: cannot start the %s thread\n", lahar_link_role_name(n->role));
            return -1;
        }
        n->thread_started = 1;
        return 0;
    }
    char dir[PATH_MAX], exe[PATH_MAX + 32], run[32], threads[16];
    if (coord_exe_dir(dir, sizeof dir) != 0) {
        fprintf(stderr, "lahar: cannot find my own executable (/proc/self/exe)\n");
        return -1;
    }
    snprintf(exe, sizeof exe, "%s/%s", dir, n->exe_name);
    if (access(exe, X_OK) != 0) {
        fprintf(stderr, "lahar: %s not found next to lahar (%s); build it or use --in-process\n", n->exe_name, exe);
        return -1;
    }
    snprintf(run, sizeof run, "%lld", (long long)co->run_id);
    snprintf(threads, sizeof threads, "%d", co->o->threads);
    char *argv[] = {exe, "--lcm-url", (char *)co->url, "--run-id", run, "--threads", threads,
                    co->auth_key_path[0] ? "--auth-key" : NULL, co->auth_key_path, NULL};
    pid_t parent = getpid();
    fflush(NULL);
    pid_t pid = fork();
    if (pid < 0) {
        fprintf(stderr, "lahar: fork: %s\n", strerror(errno));
        return -1;
    }
    if (pid == 0) {
        /* never outlive the coordinator: when it dies the node gets SIGUSR2, closes its files
         * (the SWMR streams stay readable) and exits (lahar_link_watch_parent). Ctrl-C, SIGTERM
         * and SIGHUP are the coordinator's to handle (a checkpoint, then STOP): a terminal, a
         * batch system (Slurm signals every process of the job) or `kill -- -PGID` sends them
         * to the nodes too, which would otherwise die at once and turn the clean stop into a
         * lost node */
        prctl(PR_SET_PDEATHSIG, SIGUSR2);
        if (getppid() != parent)
            _exit(3);
        signal(SIGINT, SIG_IGN);
        signal(SIGTERM, SIG_IGN);
        signal(SIGHUP, SIG_IGN);
        signal(SIGUSR1, SIG_IGN); /* lahar's checkpoint request; a node's default would be to die */
        execv(exe, argv);
        fprintf(stderr, "lahar: exec %s: %s\n", exe, strerror(errno));
        _exit(127);
    }
    n->pid = pid;
    return 0;
}

/* Reap a node that has ended; 1 if it has (exit status recorded). */
static int coord_node_ended(coord_node *n)
{
    if (n->exited)
        return 1;
    if (n->pid > 0) {
        int st;
        if (waitpid(n->pid, &st, WNOHANG) == n->pid) {
            n->exited = 1;
            n->exit_status = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
        }
    } else if (n->thread_started && atomic_load(&n->thread_done)) {
        pthread_join(n->thread, NULL);
        n->joined = 1;
        n->exited = 1;
        n->exit_status = n->thread_status;
    } else if (!n->thread_started) {
        n->exited = 1;
    }
    return n->exited;
}

/* How much a node this coordinator started has run or wanted to run so far, in s: for a process
 * the sum over its threads of the time on a CPU and the time runnable but waiting for one
 * (/proc/PID/task/TID/schedstat, fields 1 and 2, ns); for an --in-process thread its CPU clock.
 * A node that is only starved by an overloaded machine advances this (its threads are runnable),
 * a stopped (SIGSTOP) or dead-locked one does not (no thread runs or waits for a CPU). -1 when it
 * cannot be read (a node started by hand, or a kernel without schedstat: then the process's
 * utime + stime from /proc/PID/stat, in clock ticks). */
static double coord_node_activity(const coord_node *n)
{
    if (n->pid > 0) {
        char path[64], buf[1024];
        snprintf(path, sizeof path, "/proc/%d/task", (int)n->pid);
        DIR *d = opendir(path);
        if (d) {
            unsigned long long sum = 0;
            int seen = 0;
            for (struct dirent *e; (e = readdir(d));) {
                if (e->d_name[0] < '0' || e->d_name[0] > '9')
                    continue;
                char p2[96];
                snprintf(p2, sizeof p2, "/proc/%d/task/%.16s/schedstat", (int)n->pid, e->d_name);
                FILE *fp = fopen(p2, "r");
                unsigned long long run = 0, wait = 0;
                if (fp && fscanf(fp, "%llu %llu", &run, &wait) == 2) {
                    sum += run + wait;
                    seen = 1;
                }
                if (fp)
                    fclose(fp);
            }
            closedir(d);
            if (seen)
                return 1e-9 * (double)sum;
        }
        snprintf(path, sizeof path, "/proc/%d/stat", (int)n->pid);
        FILE *fp = fopen(path, "r");
        if (!fp)
            return -1.0;
        size_t len = fread(buf, 1, sizeof buf - 1, fp);
        fclose(fp);
        buf[len] = '\0';
        /* fields after the command name "(...)": state is field 3, utime 14, stime 15 */
        const char *q = strrchr(buf, ')');
        unsigned long long ut = 0, st = 0;
        if (!q || sscanf(q + 1, " %*c %*d %*d %*d %*d %*d %*u %*u %*u %*u %*u %llu %llu", &ut, &st) != 2)
            return -1.0;
        return (double)(ut + st) / (double)sysconf(_SC_CLK_TCK);
    }
    if (n->thread_started && !atomic_load(&n->thread_done)) {
        clockid_t cid;
        struct timespec ts;
        if (pthread_getcpuclockid(n->thread, &cid) != 0 || clock_gettime(cid, &ts) != 0)
            return -1.0;
        return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
    }
    return -1.0;
}

/* A watched node went silent: 1 if it is one of ours, still running and running or runnable over
 * a short probe (starved by the machine, not dead or hung), so that its silence is forgiven. The
 * link is pumped during the probe, so nothing that arrives meanwhile is missed. One silence is
 * forgiven for at most COORD_NODE_STARVED_MAX s (the count starts again with the node's next
 * STATUS). */
static int coord_node_starved(coord *co, coord_node *n)
{
    if (n->starved_s >= COORD_NODE_STARVED_MAX || coord_node_ended(n))
        return 0;
    double before = coord_node_activity(n);
    if (before < 0.0)
        return 0;
    lahar_link_poll(co->link, COORD_STARVED_PROBE_MS);
    double after = coord_node_activity(n);
    if (coord_node_ended(n) || !(after > before))
        return 0;
    if (!n->starved_warned)
        fprintf(stderr, "\nlahar: warning: the %s has been silent for %.1f s but is still running (the machine "
                        "is overloaded?); waiting up to %.0f s more\n",
                lahar_link_role_name(n->role), coord_silence(co), COORD_NODE_STARVED_MAX);
    n->starved_warned = 1;
    n->starved_count++;
    n->starved_s += coord_silence(co) + 1e-3 * COORD_STARVED_PROBE_MS;
    if (n->starved_s > n->starved_max_s)
        n->starved_max_s = n->starved_s;
    return 1;
}

static void coord_send_stop(coord *co, int reason, const char *message)
{
    lahar_stop_t s = {.run_id = co->run_id, .step = co->steps - 1, .reason = reason, .message = (char *)message};
    int rc;
    LAHAR_LINK_SEND(rc, co->link, LAHAR_FRAME_T_MSG_STOP, lahar_stop_t, s.step, &s);
    (void)rc;
}

/* After STOP: give the nodes time to exit (re-sending STOP in case it was lost), then end them. */
static void coord_finish_nodes(coord *co)
{
    double until = lahar_now() + (co->stop_wait > 0 ? co->stop_wait : COORD_STOP_WAIT), resend = lahar_now() + 0.1;
    for (;;) {
        int all = 1;
        for (int r = 1; r < LAHAR_NROLES; r++)
            all &= coord_node_ended(&co->node[r]);
        if (all || lahar_now() > until)
            break;
        /* short polls: a node's exit is seen within 5 ms (a run's wall time ends with it) */
        lahar_link_poll(co->link, 5);
        if (lahar_now() > resend) {
            lahar_link_republish(co->link, LAHAR_FRAME_T_MSG_STOP, co->steps - 1);
            resend = lahar_now() + 0.1;
        }
    }
    for (int r = 1; r < LAHAR_NROLES; r++) {
        coord_node *n = &co->node[r];
        if (n->pid > 0 && !n->exited) {
            kill(n->pid, SIGKILL);
            int st;
            waitpid(n->pid, &st, 0);
            n->exited = 1;
            n->exit_status = 128 + SIGKILL;
        }
        if (n->thread_started && !n->joined) {
            /* a node thread that ignores STOP cannot be killed; the process exit ends it */
            pthread_detach(n->thread);
            n->joined = 1;
        }
    }
}

/* A node process that died (killed, crashed) leaves the SWMR force stream flagged as open for
 * writing, and h5dump / h5py refuse it: once every node process is gone, clear the flags so the
 * rows it flushed can be read, and remove the twins of its snapshot files (nodes on other hosts,
 * --no-spawn, are not ours to judge). */
void coord_release_files(coord *co)
{
    int died = 0;
    for (int r = 1; r < LAHAR_NROLES; r++) {
        const coord_node *n = &co->node[r];
        if (n->pid > 0 && !n->exited)
            return; /* still running: the file is its */
        died |= n->pid > 0 && n->exited && n->exit_status != 0;
    }
    if (!died)
        return;
    lahar_output_remove_twins(co->outdir);
    for (int i = 0; lahar_output_run_files[i]; i++) { /* every HDF5 file (forces.h5 and gauges.h5 are SWMR) */
        const char *name = lahar_output_run_files[i];
        size_t len = strlen(name);
        if (len < 3 || strcmp(name + len - 3, ".h5") != 0)
            continue;
        char path[PATH_MAX + 32];
        snprintf(path, sizeof path, "%s/%s", co->outdir, name);
        int rc = lahar_output_release_swmr(path);
        if (rc == 1 && !co->o->quiet)
            fprintf(stderr, "lahar: %s: cleared the open-for-writing flags the dead node left; the rows it wrote "
                            "are readable\n", path);
        else if (rc < 0)
            fprintf(stderr, "lahar: %s cannot be opened (its writer died while writing)\n", path);
    }
}

static void coord_read_hello(coord_node *n, const lahar_link_msg *m)
{
    lahar_hello_t h;
    if (LAHAR_MSG_DECODE(lahar_hello_t, m->data, m->size, &h) < 0)
        return;
    snprintf(n->engine, sizeof n->engine, "%s", h.engine ? h.engine : "");
    snprintf(n->version, sizeof n->version, "%s", h.version ? h.version : "");
    snprintf(n->host, sizeof n->host, "%s", h.host ? h.host : "");
    n->remote_pid = h.pid;
    lahar_hello_t_decode_cleanup(&h);
}

static int coord_hello(coord *co)
{
    char host[256] = "";
    gethostname(host, sizeof host - 1);
    lahar_hello_t h = {
        .run_id = co->run_id, .step = -1, .role = LAHAR_ROLE_COORDINATOR, .engine = "lahar-coordinator",
        .version = LAHAR_VERSION, .protocol_version = 1, .ncapabilities = 0, .capabilities = NULL, .host = host,
        .pid = (int32_t)getpid(),
    };
    int rc;
    LAHAR_LINK_SEND(rc, co->link, LAHAR_FRAME_T_MSG_HELLO, lahar_hello_t, -1, &h);
    if (rc != 0) {
        snprintf(co->message, sizeof co->message, "cannot publish on %s", co->url);
        return LAHAR_EXIT_SETUP;
    }
    double wait_s = co->o->join_wait_s > 0 ? co->o->join_wait_s : 30.0;
    for (int r = 1; r < LAHAR_NROLES; r++) {
        coord_node *n = &co->node[r];
        if (!n->needed)
            continue;
        double until = lahar_now() + wait_s;
        lahar_link_msg m;
        for (;;) {
            rc = lahar_link_wait(co->link, r, LAHAR_FRAME_T_MSG_HELLO, -1, COORD_HELLO_PERIOD_MS, &m);
            if (rc == LAHAR_LINK_OK)
                break;
            if (coord_interrupted) {
                snprintf(co->message, sizeof co->message, "interrupted while waiting for the %s", lahar_link_role_name(r));
                return LAHAR_EXIT_SETUP;
            }
            if ((n->pid > 0 || n->thread_started) && coord_node_ended(n)) {
                snprintf(co->message, sizeof co->message, "the %s (%s) ended with status %d before joining the run",
                         lahar_link_role_name(r), n->exe_name, n->exit_status);
                return LAHAR_EXIT_SETUP;
            }
            if (lahar_now() > until) {
                snprintf(co->message, sizeof co->message,
                         "the %s did not answer within %.0f s on %s%s", lahar_link_role_name(r), wait_s, co->url,
                         co->o->no_spawn ? " (with --no-spawn, start it yourself: see lahar run --help)" : "");
                return LAHAR_EXIT_SETUP;
            }
            /* nodes started by hand learn the run id from this announcement */
            lahar_link_republish(co->link, LAHAR_FRAME_T_MSG_HELLO, -1);
        }
        coord_read_hello(n, &m);
        lahar_link_watch(co->link, r, coord_silence(co));
    }
    return LAHAR_EXIT_OK;
}

/* The work counters of a STATUS: cumulative, so the last STATUS holds the run's totals. */
static void coord_take_work(coord_node *n, const lahar_status_t *s)
{
    n->work.work_passes = s->work_passes;
    n->work.work_pairs_fluid = s->work_pairs_fluid;
    n->work.work_pairs_soil = s->work_pairs_soil;
    n->work.work_pairs_fluid_soil = s->work_pairs_fluid_soil;
    n->work.work_particle_body = s->work_particle_body;
    n->work.work_body_body = s->work_body_body;
    n->work.work_output_derived = s->work_output_derived;
    n->work.auth_rejected = s->auth_rejected;
    n->work.auth_replayed = s->auth_replayed;
    memcpy(n->work.flow, s->flow, sizeof n->work.flow);
}

/* While the nodes set up (STATUS(-1) not yet in): a progress line on a terminal once set-up has
 * taken COORD_SETUP_SHOW s, and Ctrl-C / SIGTERM honoured at once (the nodes are stopped by
 * the caller; one busy filling particles is killed after COORD_SETUP_STOP_WAIT). 1 when
 * interrupted. */
static int coord_setup_wait(coord *co, const coord_node *n)
{
    if (coord_interrupted) {
        co->status = "interrupted";
        co->stop_wait = COORD_SETUP_STOP_WAIT;
        snprintf(co->message, sizeof co->message, "interrupted during set-up (waiting for the %s)",
                 lahar_link_role_name(n->role));
        return 1;
    }
    double waited = lahar_now() - co->wall0;
    if (co->progress == COORD_PROGRESS_TERMINAL && waited > COORD_SETUP_SHOW && lahar_now() - co->last_progress >= 1.0) {
        co->last_progress = lahar_now();
        fprintf(stderr, "\r  setting up: waiting for the %s (filling particles, first rates) %.0f s   ",
                lahar_link_role_name(n->role), waited);
        fflush(stderr);
        co->setup_shown = 1;
    } else if (co->progress == COORD_PROGRESS_LOG && lahar_now() - co->last_progress >= co->o->progress_every_s) {
        co->last_progress = lahar_now();
        fprintf(stderr, "lahar: setting up: waiting for the %s (filling particles, first rates) %.0f s\n",
                lahar_link_role_name(n->role), waited);
        fflush(stderr);
    }
    return 0;
}

/* Wait for STATUS(k) from node r. Requests are idempotent: besides the NACKs of both sides,
 * STEP(k) goes out again every 250 ms until STATUS(k) is in (a node that has it already drops the
 * duplicate, and its kept STATUS(k) answers the coordinator's NACK). Every COORD_DEATH_POLL_MS
 * without it, the nodes this coordinator started are reaped: a node that died is lost at once, not
 * after its silence (*lost: its role). Returns the link's code (LAHAR_LINK_*), or
 * COORD_WAIT_INTERRUPTED when Ctrl-C came while a node set up. */
enum { COORD_WAIT_INTERRUPTED = 100 };
static int coord_wait_status(coord *co, int r, int64_t k, lahar_link_msg *m, int *lost)
{
    *lost = -1;
    double resend = lahar_now() + 1e-3 * COORD_STEP_RESEND_MS;
    for (;;) {
        int rc = lahar_link_wait(co->link, r, LAHAR_FRAME_T_MSG_STATUS, k,
                                 k < 0 ? COORD_SETUP_POLL_MS : COORD_DEATH_POLL_MS, m);
        if (rc == LAHAR_LINK_TIMEOUT) {
            for (int d = 1; d < LAHAR_NROLES && k >= 0; d++)
                if (co->node[d].needed && co->node[d].pid > 0 && coord_node_ended(&co->node[d]))
                    *lost = d;
            if (*lost >= 0)
                return LAHAR_LINK_LOST;
            if (k >= 0 && lahar_now() >= resend) {
                lahar_link_republish(co->link, LAHAR_FRAME_T_MSG_STEP, k);
                resend = lahar_now() + 1e-3 * COORD_STEP_RESEND_MS;
            }
            if (k < 0 && coord_setup_wait(co, &co->node[r])) /* Ctrl-C while a node sets up: stop now */
                return COORD_WAIT_INTERRUPTED;
        } else if (rc == LAHAR_LINK_LOST && coord_node_starved(co, &co->node[lahar_link_lost_role(co->link)])) {
            lahar_link_heard_now(co->link, lahar_link_lost_role(co->link));
        } else {
            return rc;
        }
    }
}

/* The message for a lost node: who, how long silent, why if known (ended, hung, starved), and
 * the last step it completed. */
static void coord_report_lost(coord *co, int lost)
{
    coord_node *ln = &co->node[lost];
    int64_t last = ln->last_step > lahar_link_peer_step(co->link, lost) ? ln->last_step
                                                                         : lahar_link_peer_step(co->link, lost);
    char how[96] = "died or hangs";
    double silent = coord_silence(co) + ln->starved_s;
    if (ln->pid > 0 && coord_node_ended(ln))
        silent = lahar_now() - lahar_link_last_heard(co->link, lost);
    if (ln->pid > 0 && !coord_node_ended(ln))
        snprintf(how, sizeof how, ln->starved_s >= COORD_NODE_STARVED_MAX
                                      ? "still running, but it has not answered for %.0f s"
                                      : "hangs: no thread of it ran or waited for a CPU in %.0f ms",
                 ln->starved_s >= COORD_NODE_STARVED_MAX ? COORD_NODE_STARVED_MAX : (double)COORD_STARVED_PROBE_MS);
    if (ln->pid > 0 && coord_node_ended(ln))
        snprintf(how, sizeof how, "%s %d", ln->exit_status > 128 ? "killed by signal" : "exited with status",
                 ln->exit_status > 128 ? ln->exit_status - 128 : ln->exit_status);
    snprintf(co->message, sizeof co->message,
             "lost the %s (%s, pid %d on %s): silent for %.1f s (%s); last completed step %lld "
             "(t = %.9g s); stopping the run",
             lahar_link_role_name(lost), ln->exe_name, ln->remote_pid, ln->host, silent, how, (long long)last,
             co->sim_time);
    co->status = "node lost";
}

/* Node r's STATUS(k): its figures into the node's record, and its error (an instability decoded)
 * into the run's message. Returns LAHAR_EXIT_OK or LAHAR_EXIT_RUN_ERROR. */
static int coord_take_status(coord *co, int r, int64_t k, const lahar_link_msg *m)
{
    coord_node *n = &co->node[r];
    lahar_status_t s;
    if (LAHAR_MSG_DECODE(lahar_status_t, m->data, m->size, &s) < 0) {
        snprintf(co->message, sizeof co->message, "undecodable STATUS(%lld) from the %s", (long long)k,
                 lahar_link_role_name(r));
        return LAHAR_EXIT_RUN_ERROR;
    }
    int err = s.error;
    s.message[sizeof s.message - 1] = 0;
    const char *text = (const char *)s.message;
    if (err && lahar_instability_decode(text, &co->inst)) {
        co->has_inst = 1;
        co->inst_node = r == LAHAR_ROLE_DEM ? "dem" : "sph";
        text = co->inst.text;
    }
    if (err)
        snprintf(co->message, sizeof co->message, "the %s reports at step %lld: %s", lahar_link_role_name(r),
                 (long long)k, text[0] ? text : "(no message)");
    else if (k < 0)
        snprintf(n->engine_desc, sizeof n->engine_desc, "%s", text);
    n->compute_s += s.compute_s;
    n->wait_s += s.wait_s;
    n->substeps += s.nsubsteps;
    n->dt_proposed = s.dt_proposed;
    n->dt_stable = s.dt_stable;
    n->kinetic_energy = s.kinetic_energy;
    n->ncontacts = s.ncontacts;
    n->checkpointed = s.checkpointed;
    coord_take_work(n, &s);
    if (!err)
        n->last_step = k;
    n->starved_s = 0.0; /* an answer ends a silence */
    lahar_status_t_decode_cleanup(&s);
    if (err) {
        co->status = co->has_inst ? "unstable" : "error";
        return LAHAR_EXIT_RUN_ERROR;
    }
    return LAHAR_EXIT_OK;
}

/* STATUS(k) of every node the run needs, in role order. */
int coord_collect_status(coord *co, int64_t k)
{
    for (int r = 1; r < LAHAR_NROLES; r++) {
        if (!co->node[r].needed)
            continue;
        lahar_link_msg m;
        int lost;
        int rc = coord_wait_status(co, r, k, &m, &lost);
        if (rc == COORD_WAIT_INTERRUPTED)
            return LAHAR_EXIT_RUN_ERROR;
        if (rc == LAHAR_LINK_LOST) {
            coord_report_lost(co, lost >= 0 ? lost : lahar_link_lost_role(co->link));
            return LAHAR_EXIT_NODE_LOST;
        }
        if (rc != LAHAR_LINK_OK) {
            snprintf(co->message, sizeof co->message, "link error waiting for the %s", lahar_link_role_name(r));
            return LAHAR_EXIT_RUN_ERROR;
        }
        if (coord_take_status(co, r, k, &m) != LAHAR_EXIT_OK)
            return LAHAR_EXIT_RUN_ERROR;
    }
    return LAHAR_EXIT_OK;
}

/* The nodes started (unless the user starts them, --no-spawn), the heartbeat running and every
 * node's HELLO heard. The machine's load is read first: it decides the nodes' OpenMP wait policy
 * (coord_machine_load). LAHAR_EXIT_OK or the exit status, with co->message. */
int coord_start_nodes(coord *co)
{
    const lahar_coord_options *o = co->o;
    coord_machine_load(co);
    if (!o->no_spawn)
        for (int r = 1; r < LAHAR_NROLES; r++)
            if (co->node[r].needed && coord_start_node(co, &co->node[r]) != 0) {
                snprintf(co->message, sizeof co->message, "cannot start the %s", lahar_link_role_name(r));
                return LAHAR_EXIT_SETUP;
            }
    if (o->no_spawn && !o->quiet)
        fprintf(stderr, "lahar: run %lld on %s: waiting for%s%s (start them with --lcm-url '%s')\n",
                (long long)co->run_id, co->url, co->node[LAHAR_ROLE_DEM].needed ? " lahar-dem" : "",
                co->node[LAHAR_ROLE_SPH].needed ? " lahar-sph" : "", co->url);
    lahar_link_set_step(co->link, -1);
    if (lahar_link_heartbeat_start(co->link, LAHAR_HEARTBEAT_PERIOD) != 0) {
        snprintf(co->message, sizeof co->message, "cannot start the heartbeat thread");
        return LAHAR_EXIT_SETUP;
    }
    return coord_hello(co);
}

/* The scene (the case as the nodes need it) published, then STATUS(-1) of every node awaited: the
 * nodes' set-up (particles filled, first rates). LAHAR_EXIT_OK or the exit status. */
int coord_set_up_nodes(coord *co)
{
    lahar_scene_t sm;
    if (lahar_scene_msg_from_case(co->c, co->outdir, co->node[LAHAR_ROLE_DEM].needed,
                                  co->node[LAHAR_ROLE_SPH].needed, co->run_id, &sm) != 0) {
        snprintf(co->message, sizeof co->message, "out of memory");
        return LAHAR_EXIT_SETUP;
    }
    int rc;
    LAHAR_LINK_SEND(rc, co->link, LAHAR_FRAME_T_MSG_SCENE, lahar_scene_t, -1, &sm);
    lahar_scene_msg_release(&sm);
    if (rc != 0) {
        snprintf(co->message, sizeof co->message, "cannot publish the scene");
        return LAHAR_EXIT_SETUP;
    }
    int status = coord_collect_status(co, -1);
    if (co->setup_shown) { /* end the set-up line on the terminal */
        fprintf(stderr, "\n");
        co->setup_shown = 0;
    }
    return status;
}

/* STOP (its reason from how the run ended) and the nodes' exit. A node that fails on its way out
 * (an output error at close, a sanitizer report) fails a run that had finished. The run's exit
 * status. */
int coord_stop_nodes(coord *co, int status)
{
    coord_progress(co, 1);
    /* STOP's reason (stop_t.lcm): 0 finished, 1 error, 2 interrupted, 3 node lost */
    const int stop_code = status == LAHAR_EXIT_OK || co->clean_stop ? 0
                          : status == LAHAR_EXIT_NODE_LOST            ? 3
                          : coord_interrupted                         ? 2
                                                                      : 1;
    coord_send_stop(co, stop_code, co->message);
    coord_finish_nodes(co);
    for (int r = 1; r < LAHAR_NROLES && status == LAHAR_EXIT_OK; r++)
        if (co->node[r].needed && co->node[r].exited && co->node[r].exit_status != 0) {
            snprintf(co->message, sizeof co->message, "the %s exited with status %d after the run",
                     lahar_link_role_name(r), co->node[r].exit_status);
            co->status = "error";
            status = LAHAR_EXIT_RUN_ERROR;
        }
    return status;
}
