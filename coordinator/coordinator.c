/* The coordinator (see coordinator.h, protocol in lcm_types/README.md). */
#define _GNU_SOURCE
#include "coordinator.h"
#include "msg_check.h"
#include <cjson/cJSON.h>
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <libgen.h>
#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/file.h>
#include <dirent.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#include "auth.h"
#include "case.h"
#include "checkpoint.h"
#include "dem_node.h"
#include "instability.h"
#include "lahar_hello_t.h"
#include "lahar_status_t.h"
#include "lahar_step_t.h"
#include "lahar_stop_t.h"
#include "link.h"
#include "machine_load.h"
#include "netns.h"
#include "output.h"
#include "scene_msg.h"
#include "sph_node.h"
#include "transport.h"

#define COORD_NODE_SILENCE 2.0   /* s without a frame from a node: node lost */
/* A node the coordinator started itself (process or thread) that is silent but whose CPU time is
 * still advancing is starved by an overloaded machine, not lost: its silence is forgiven, with one
 * warning, for at most this long in all (a node spinning without ever answering still ends). */
#define COORD_NODE_STARVED_MAX 120.0
#define COORD_STARVED_PROBE_MS 500 /* CPU time must advance within this to count as computing */
#define COORD_HELLO_PERIOD_MS 100
#define COORD_STOP_WAIT 3.0      /* s the nodes get to exit after STOP */
#define COORD_SETUP_POLL_MS 100  /* set-up: how often Ctrl-C and the progress line are looked at */
#define COORD_SETUP_SHOW 2.0     /* s of set-up after which a progress line is shown */
enum { COORD_PROGRESS_TERMINAL = 1, /* one line rewritten in place (\r), at most 4 Hz */
       COORD_PROGRESS_LOG = 2 };    /* stderr is a file or a pipe: whole lines, one per --progress-every s */
#define COORD_SETUP_STOP_WAIT 0.3 /* s a node interrupted in set-up gets to exit before it is killed */
#define COORD_STEP_RESEND_MS 250 /* re-publish STEP(k) while STATUS(k) is missing */
#define COORD_DEATH_POLL_MS 50   /* while STATUS(k) is missing, the started nodes are reaped this often */
/* summary.json's room, taken on the disk when the run starts, so that a run that fills the disk
 * can still say how it ended */
#define COORD_SUMMARY_RESERVE (64 * 1024)

typedef struct {
    int role;
    const char *exe_name;        /* lahar-dem, lahar-sph */
    int needed;
    pid_t pid;                   /* spawned process, 0 if none */
    int exited, exit_status;
    pthread_t thread;            /* --in-process */
    int thread_started;
    _Atomic int thread_done;
    int thread_status;
    int joined;
    /* from hello_t and status_t */
    char engine[160], version[64], host[128], engine_desc[512];
    int remote_pid;
    double compute_s, wait_s;
    int64_t substeps, last_step;
    double dt_proposed, dt_stable, kinetic_energy;
    int ncontacts;
    double starved_s;            /* silence forgiven in the current silence (COORD_NODE_STARVED_MAX) */
    double starved_max_s;        /* the longest silence forgiven in the run */
    int starved_count, starved_warned; /* silences forgiven (probes that found it starved); warned once */
    int checkpointed;            /* STATUS(k).checkpointed of the last step */
    lahar_status_t work;         /* the work_* fields of the last STATUS (cumulative) */
} coord_node;

typedef struct {
    const lahar_case *c;
    const lahar_coord_options *o;
    char outdir[PATH_MAX];
    const char *url;
    const char *mode;
    lahar_transport *t;
    lahar_link *link;
    int64_t run_id;
    coord_node node[LAHAR_NROLES];
    int64_t steps;
    double sim_time;
    double wall0;
    double lock0, lock1; /* wall clock at the first STEP and after the last step's STATUS (0: not reached) */
    const char *status;
    char message[1024];
    lahar_instability inst;  /* status "unstable": what, where, when (summary.json "instability") */
    int has_inst;
    const char *inst_node;   /* who caught it: "dem", "sph" or "coordinator" */
    int exit_status;
    int progress;           /* progress on stderr: 0 none, COORD_PROGRESS_TERMINAL, COORD_PROGRESS_LOG */
    double last_progress;
    int setup_shown;        /* a set-up progress line is on the terminal (ended by a newline) */
    double stop_wait;       /* s the nodes get to exit after STOP (0: COORD_STOP_WAIT) */
    int summary_fd;         /* OUT/summary.json, its room reserved at the start (-1: none) */
    char auth_key_path[PATH_MAX]; /* authenticated run: the key file (absolute), passed to the nodes */
    uint8_t auth_key[LAHAR_AUTH_KEYBYTES];
    /* checkpoints (case section checkpoint:; coordinator/README.md "Checkpoints and resume") */
    int ckpt_on;
    int ckpt_written;         /* checkpoints written by this invocation */
    int64_t ckpt_last_step;   /* the newest complete checkpoint (-1: none) */
    double ckpt_last_t;
    int clean_stop;           /* stopped after a checkpoint (SIGTERM): STOP says 0, no final snapshots */
    /* lahar resume: where the lockstep continues */
    int resumed;
    int64_t k0;
    lahar_clock clk0;
    double dt_allowed0, dt_first0;
    char resume_dir[PATH_MAX];
    double resume_t;
    char resume_run_id[32];   /* the run id of the checkpoint's run */
    /* the machine when the run started (summary.json "machine") */
    lahar_machine_load load;
    int load_read;            /* load holds a reading */
    int busy;                 /* lahar_machine_busy */
    const char *wait_policy;  /* OMP_WAIT_POLICY of the nodes: the user's, "passive" (set here), or NULL */
    int wait_policy_set;      /* 1: lahar set it (busy machine, the user set none) */
} coord;

static volatile sig_atomic_t coord_interrupted;
static volatile sig_atomic_t coord_term;          /* SIGTERM: with checkpoints, checkpoint then stop */
static volatile sig_atomic_t coord_ckpt_request;  /* SIGUSR1: a checkpoint after the next step */
static void coord_on_sigterm(int sig)
{
    (void)sig;
    coord_term = 1;
    coord_interrupted = 1;
}
static void coord_on_sigusr1(int sig)
{
    (void)sig;
    coord_ckpt_request = 1;
}

/* Silence after which a node is lost (--node-timeout, else COORD_NODE_SILENCE). */
static double coord_silence(const coord *co)
{
    return co->o->node_timeout_s > 0.0 ? co->o->node_timeout_s : COORD_NODE_SILENCE;
}
static void coord_on_sigint(int sig)
{
    (void)sig;
    coord_interrupted = 1;
}

/* ---- nodes: processes or threads ----------------------------------------------------------- */

/* Before the nodes start: OpenMP threads wait for each other at the end of every parallel loop of
 * a step, and libgomp's waiting thread spins (OMP_WAIT_POLICY unset) for a while before it sleeps.
 * On cores that other work holds, or with more threads than cores, the spinning takes the CPU from
 * the threads it waits for (docs/bench/busy_machine.md). So, when the machine is
 * busy (lahar_machine_busy) and the user set no OMP_WAIT_POLICY, the nodes lahar starts as
 * processes get OMP_WAIT_POLICY=passive, which changes no result; --in-process nodes share this
 * process's OpenMP, configured before main: they only get the note. */
static void coord_machine_load(coord *co)
{
    const lahar_coord_options *o = co->o;
    co->wait_policy = getenv("OMP_WAIT_POLICY");
    co->load_read = lahar_machine_load_read(&co->load) == 0;
    co->busy = co->load_read && lahar_machine_busy(&co->load, o->threads);
    /* the load average lags by a minute: see whether the load is still there (0.2 s, paid only when
     * the average says busy) */
    if (co->busy && lahar_machine_sample(&co->load, 0.2) == 0)
        co->busy = lahar_machine_busy(&co->load, o->threads);
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
            : o->in_process     ? "Set OMP_WAIT_POLICY=passive in the environment (lahar sets it only for nodes it starts "
                                  "as processes). "
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
        /* never outlive the coordinator; Ctrl-C is the coordinator's to handle */
        prctl(PR_SET_PDEATHSIG, SIGKILL);
        if (getppid() != parent)
            _exit(3);
        signal(SIGINT, SIG_IGN);
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

/* ---- messages ------------------------------------------------------------------------------ */

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
 * rows it flushed can be read (nodes on other hosts, --no-spawn, are not ours to judge). */
static void coord_release_files(coord *co)
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
static int coord_collect_status(coord *co, int64_t k)
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

static void coord_progress(coord *co, int final)
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

/* ---- checkpoints --------------------------------------------------------------------------- */

/* The coordinator's part of a checkpoint (common/io/checkpoint.h; one function both ways): the step
 * and time, the clock, the next step's limit and the first step (dt collapse), whether the state
 * is a scheduled snapshot, and the totals summary.json continues. */
static int coord_state_io(coord *co, lahar_ckpt_file *f, int64_t *k, lahar_clock *clk, double *dt_allowed,
                          double *dt_first, int *is_output)
{
    lahar_ckpt_i64(f, "step", k, 1);
    lahar_ckpt_f64(f, "t", &co->sim_time, 1);
    double cd[4] = {clk->t_end, clk->out_interval, clk->t_base, clk->h};
    int64_t ci[4] = {clk->nout, clk->j, clk->i, clk->m};
    lahar_ckpt_f64(f, "clock_t_end_interval_base_h", cd, 4);
    lahar_ckpt_i64(f, "clock_nout_j_i_m", ci, 4);
    double dts[2] = {*dt_allowed, *dt_first};
    lahar_ckpt_f64(f, "dt_allowed_first", dts, 2);
    lahar_ckpt_int(f, "snapshot_at_step", is_output);
    lahar_ckpt_i64(f, "steps", &co->steps, 1);
    int64_t run_id = co->run_id;
    lahar_ckpt_i64(f, "run_id", &run_id, 1);
    for (int r = 1; r < LAHAR_NROLES; r++) {
        coord_node *n = &co->node[r];
        char name[48];
        double nf[5] = {n->compute_s, n->wait_s, n->dt_proposed, n->dt_stable, n->kinetic_energy};
        int64_t ni[4] = {n->substeps, n->last_step, n->ncontacts, n->needed};
        snprintf(name, sizeof name, "node%d_compute_wait_dtp_dts_ke", r);
        lahar_ckpt_f64(f, name, nf, 5);
        snprintf(name, sizeof name, "node%d_substeps_last_contacts_needed", r);
        lahar_ckpt_i64(f, name, ni, 4);
        if (!f->writing && !f->failed) {
            n->compute_s = nf[0], n->wait_s = nf[1], n->dt_proposed = nf[2], n->dt_stable = nf[3];
            n->kinetic_energy = nf[4];
            n->substeps = ni[0], n->last_step = ni[1], n->ncontacts = (int)ni[2];
            if (ni[3] != n->needed) {
                snprintf(f->err, sizeof f->err, "the checkpoint's run %s a %s, this case %s (another case?)",
                         ni[3] ? "had" : "had no", lahar_link_role_name(r), n->needed ? "needs one" : "none");
                f->failed = 1;
            }
        }
    }
    if (!f->writing && !f->failed) {
        clk->t_end = cd[0], clk->out_interval = cd[1], clk->t_base = cd[2], clk->h = cd[3];
        clk->nout = ci[0], clk->j = ci[1], clk->i = ci[2], clk->m = ci[3];
        *dt_allowed = dts[0], *dt_first = dts[1];
        snprintf(co->resume_run_id, sizeof co->resume_run_id, "%016llx", (unsigned long long)run_id);
    }
    return f->failed ? -1 : 0;
}

/* Remove a directory and what it holds (checkpoints/ holds NNNNNN/ directories of files). 0, or -1
 * with errno set when the directory itself could not be removed. */
static int coord_rm_ckpt_dir(const char *path)
{
    DIR *d = opendir(path);
    if (d) {
        struct dirent *e;
        while ((e = readdir(d)) != NULL) {
            if (e->d_name[0] == '.')
                continue;
            char p[4400];
            snprintf(p, sizeof p, "%.4000s/%.255s", path, e->d_name);
            if (unlink(p) != 0)
                coord_rm_ckpt_dir(p);
        }
        closedir(d);
    }
    return rmdir(path);
}

/* The checkpoints in OUT/checkpoints: the step indices of the complete ones (NNNNNN holding
 * coord.h5), newest first, into steps (up to cap); *.tmp ones (an interrupted checkpoint) are
 * removed when remove_tmp. Returns the count. */
static int coord_list_ckpts(const char *outdir, int64_t *steps, int cap, int remove_tmp)
{
    char dir[PATH_MAX + 32];
    snprintf(dir, sizeof dir, "%s/" LAHAR_CKPT_DIR, outdir);
    DIR *d = opendir(dir);
    if (!d)
        return 0;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        char *end;
        if (e->d_name[0] < '0' || e->d_name[0] > '9')
            continue;
        long long st = strtoll(e->d_name, &end, 10);
        char path[PATH_MAX + 320];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        if (strcmp(end, ".tmp") == 0) {
            if (remove_tmp)
                coord_rm_ckpt_dir(path);
            continue;
        }
        char coordf[PATH_MAX + 340];
        snprintf(coordf, sizeof coordf, "%s/coord.h5", path);
        if (*end || access(coordf, R_OK) != 0 || n >= cap)
            continue;
        steps[n++] = st;
    }
    closedir(d);
    for (int i = 0; i < n; i++) /* newest first */
        for (int j = i + 1; j < n; j++)
            if (steps[j] > steps[i]) {
                int64_t t = steps[i];
                steps[i] = steps[j];
                steps[j] = t;
            }
    return n;
}

/* After STATUS(k) of a step that carried the checkpoint flag (state K = k + 1): every node has
 * written and synced NNNNNN.tmp/<role>.h5; write coord.h5 there, sync it and the directory,
 * rename NNNNNN.tmp -> NNNNNN (atomic), sync OUT/checkpoints, and keep the newest
 * checkpoint.keep. A crash at any moment leaves the previous checkpoint or the new one
 * complete. 0, or -1 with co->message. */
static int coord_checkpoint(coord *co, int64_t k, lahar_clock *clk, double dt_allowed, double dt_first, int is_output)
{
    int64_t K = k + 1;
    char tmp[PATH_MAX + 64], fin[PATH_MAX + 64], path[PATH_MAX + 96], dir[PATH_MAX + 32];
    lahar_ckpt_dir(tmp, sizeof tmp, co->outdir, K, 1);
    lahar_ckpt_dir(fin, sizeof fin, co->outdir, K, 0);
    snprintf(dir, sizeof dir, "%s/" LAHAR_CKPT_DIR, co->outdir);
    for (int r = 1; r < LAHAR_NROLES; r++)
        if (co->node[r].needed && !co->node[r].checkpointed) {
            snprintf(co->message, sizeof co->message, "the %s did not write its checkpoint of step %lld",
                     lahar_link_role_name(r), (long long)K);
            return -1;
        }
    if (lahar_mkdir_p(tmp) != 0) {
        snprintf(co->message, sizeof co->message, "cannot create %.900s: %s", tmp, strerror(errno));
        return -1;
    }
    snprintf(path, sizeof path, "%s/coord.h5", tmp);
    lahar_ckpt_file f;
    int64_t kk = K;
    if (lahar_ckpt_create(&f, path, "coordinator") == 0)
        coord_state_io(co, &f, &kk, clk, &dt_allowed, &dt_first, &is_output);
    if (lahar_ckpt_close(&f) != 0) {
        snprintf(co->message, sizeof co->message, "%s", f.err);
        return -1;
    }
    if (access(fin, F_OK) == 0) /* a checkpoint of this step from before a resume: replaced */
        coord_rm_ckpt_dir(fin);
    if (lahar_ckpt_fsync_path(tmp) != 0 || rename(tmp, fin) != 0 || lahar_ckpt_fsync_path(dir) != 0) {
        snprintf(co->message, sizeof co->message, "cannot complete the checkpoint %.900s: %s", fin, strerror(errno));
        return -1;
    }
    co->ckpt_written++;
    co->ckpt_last_step = K;
    co->ckpt_last_t = co->sim_time;
    int64_t steps[1024];
    int n = coord_list_ckpts(co->outdir, steps, 1024, 0);
    int keep = co->c->checkpoint_keep > 0 ? co->c->checkpoint_keep : 2;
    for (int i = keep; i < n; i++) {
        lahar_ckpt_dir(path, sizeof path, co->outdir, steps[i], 0);
        coord_rm_ckpt_dir(path);
    }
    if (n > keep)
        lahar_ckpt_fsync_path(dir);
    return 0;
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
            snprintf(co->message, sizeof co->message, "interrupted at step %lld (t = %.9g s)", (long long)k, co->sim_time);
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
            snprintf(co->message, sizeof co->message, "stopped by SIGTERM after the checkpoint of step %lld (t = %.9g "
                     "s); continue with `lahar resume %.800s`", (long long)(k + 1), co->sim_time, co->outdir);
            return LAHAR_EXIT_RUN_ERROR;
        }
        coord_progress(co, 0);
    }
}

/* ---- summary ------------------------------------------------------------------------------- */

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
    cJSON_AddStringToObject(root, "case", co->c->path);
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
static void coord_write_summary(coord *co)
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

/* ---- entry --------------------------------------------------------------------------------- */

/* OUT/.lahar.lock, held (flock) for the whole run: a second run into the same directory is refused
 * with the holder's pid, host, start time and case (the file's text), instead of two runs writing
 * one set of HDF5 files. The lock goes with the process (also when it is killed); the file stays.
 * Returns the descriptor, or -1 after saying why (and exit status 2 is the caller's). */
static int coord_lock_outdir(const char *outdir, const char *case_path)
{
    char path[PATH_MAX + 16];
    snprintf(path, sizeof path, "%s/.lahar.lock", outdir);
    int fd = open(path, O_RDWR | O_CREAT | O_CLOEXEC, 0666);
    if (fd < 0) {
        fprintf(stderr, "lahar: cannot write in the output directory %s: %s; choose another -o or make it "
                        "writable\n", outdir, strerror(errno));
        return -1;
    }
    if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
        char text[512] = "", holder[768] = "";
        ssize_t n = pread(fd, text, sizeof text - 1, 0);
        text[n > 0 ? n : 0] = '\0';
        size_t h = 0; /* the file's lines joined by ", " */
        for (char *line = strtok(text, "\n"); line && h < sizeof holder; line = strtok(NULL, "\n"))
            h += (size_t)snprintf(holder + h, sizeof holder - h, "%s%s", h ? ", " : "", line);
        fprintf(stderr, "lahar: %s is in use by another lahar run (%s); wait for it to end, stop it, or choose "
                        "another -o\n", outdir, holder[0] ? holder : "no details");
        close(fd);
        return -1;
    }
    char host[256] = "?", when[64] = "?";
    gethostname(host, sizeof host - 1);
    time_t now = time(NULL);
    struct tm tm;
    if (gmtime_r(&now, &tm))
        strftime(when, sizeof when, "%Y-%m-%d %H:%M:%S UTC", &tm);
    char text[PATH_MAX + 640];
    int len = snprintf(text, sizeof text, "pid %ld\nhost %s\nstarted %s\ncase %s\n", (long)getpid(), host, when,
                       case_path);
    if (ftruncate(fd, 0) != 0 || pwrite(fd, text, (size_t)len, 0) != len) {
        fprintf(stderr, "lahar: cannot write in the output directory %s: %s; choose another -o or free space "
                        "there\n", outdir, strerror(errno));
        close(fd);
        return -1;
    }
    return fd;
}

/* OUT holding an earlier run's files (common/io/output.h, lahar_output_run_files) is refused, so
 * that runs never mix (a water run's particles.h5 left beside a later DEM-only run, lahar.xmf
 * pointing at both); with --overwrite those files are removed first. 0 to go on, -1 refused. */
static int coord_clear_outdir(const char *outdir, int overwrite)
{
    char path[PATH_MAX + 32], found[256] = "";
    size_t nf = 0;
    for (int i = 0; lahar_output_run_files[i]; i++) {
        snprintf(path, sizeof path, "%s/%s", outdir, lahar_output_run_files[i]);
        if (access(path, F_OK) != 0)
            continue;
        if (overwrite) {
            if (unlink(path) != 0) {
                fprintf(stderr, "lahar: --overwrite: cannot remove %s: %s\n", path, strerror(errno));
                return -1;
            }
        } else if (nf < sizeof found) {
            nf += (size_t)snprintf(found + nf, sizeof found - nf, "%s%s", nf ? ", " : "", lahar_output_run_files[i]);
        }
    }
    /* the checkpoints of an earlier run (and the copy of its case) */
    snprintf(path, sizeof path, "%s/" LAHAR_CKPT_DIR, outdir);
    DIR *d = opendir(path);
    if (d && overwrite) {
        closedir(d);
        if (coord_rm_ckpt_dir(path) != 0) {
            fprintf(stderr, "lahar: --overwrite: cannot remove %s: %s\n", path, strerror(errno));
            return -1;
        }
    } else if (d) {
        closedir(d);
        if (nf < sizeof found)
            nf += (size_t)snprintf(found + nf, sizeof found - nf, "%s" LAHAR_CKPT_DIR "/", nf ? ", " : "");
    }
    if (!found[0])
        return 0;
    fprintf(stderr, "lahar: %s holds the output of an earlier run (%s); add --overwrite to replace it (those files "
                    "are removed first),%s or choose another -o\n", outdir, found,
            strstr(found, LAHAR_CKPT_DIR) ? " continue it with `lahar resume OUT`," : "");
    return -1;
}

/* Before anything runs: OUT must have room for the first snapshots, the writers' margin and
 * summary.json, whose room is taken now (a placeholder that says the run has not ended, padded
 * to COORD_SUMMARY_RESERVE bytes), so that a run that fills the disk can still write it. A full
 * disk is refused with exit status 2. The descriptor goes to co->summary_fd. */
static int coord_reserve_summary(coord *co)
{
    const lahar_case *c = co->c;
    double particles = 0.0;
    for (int b = 0; b < c->nblock; b++) {
        double cells = 1.0;
        for (int a = 0; a < c->dim; a++)
            cells *= (c->blocks[b].hi[a] - c->blocks[b].lo[a]) / c->sph_dx + 1.0;
        particles += cells;
    }
    /* a particle snapshot (17 values per particle at most), the bodies' files with their
     * geometry, the writers' margin */
    double need = 17.0 * 8.0 * particles + 64.0 * 1024.0 * (c->nbody + 1) + 2.0 * LAHAR_OUTPUT_RESERVE +
                  COORD_SUMMARY_RESERVE;
    double avail = lahar_output_free_bytes(co->outdir);
    char path[PATH_MAX + 32];
    snprintf(path, sizeof path, "%s/summary.json", co->outdir);
    int fd = -1, rc = avail >= 0.0 && avail < need ? ENOSPC : 0;
    if (!rc) {
        fd = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
        static const char head[] = "{\"status\": \"running\", \"message\": \"the run has not ended, or lahar was "
                                   "killed before it could write this summary\"}\n";
        char *buf = fd >= 0 ? malloc(COORD_SUMMARY_RESERVE) : NULL;
        if (buf) {
            memset(buf, ' ', COORD_SUMMARY_RESERVE);
            memcpy(buf, head, sizeof head - 1);
            buf[COORD_SUMMARY_RESERVE - 1] = '\n';
        }
        /* the blocks are allocated now (posix_fallocate), not at some later write-back */
        if (fd < 0 || !buf)
            rc = errno ? errno : ENOMEM;
        else if ((rc = posix_fallocate(fd, 0, COORD_SUMMARY_RESERVE)) == 0 &&
                 pwrite(fd, buf, COORD_SUMMARY_RESERVE, 0) != COORD_SUMMARY_RESERVE)
            rc = errno ? errno : EIO;
        free(buf);
    }
    if (rc) {
        if (fd >= 0) {
            close(fd);
            unlink(path);
        }
        if (rc == ENOSPC)
            fprintf(stderr, "lahar: %s: no space left on device (%.0f bytes free; this run needs at least %.0f for "
                            "its first snapshots and summary.json); free space there or choose another -o\n",
                    co->outdir, avail, need);
        else
            fprintf(stderr, "lahar: cannot write %s: %s; choose another -o\n", path, strerror(rc));
        return -1;
    }
    co->summary_fd = fd;
    return 0;
}

static int64_t coord_random_run_id(void)
{
    uint64_t r = 0;
    if (getrandom(&r, sizeof r, 0) != (ssize_t)sizeof r) {
        struct timespec ts;
        clock_gettime(CLOCK_REALTIME, &ts);
        r = (uint64_t)ts.tv_nsec ^ ((uint64_t)ts.tv_sec << 20) ^ ((uint64_t)getpid() << 40);
    }
    r &= 0x7fffffffffffffffull; /* positive, so that it prints the same everywhere */
    return r ? (int64_t)r : 1;
}

/* The DEM node integrates bodies. With particles in the scene it is needed only when a body
 * moves (free or prescribed): the SPH node knows fixed bodies from the scene, couples with them
 * and writes their files, so a scene of water and fixed walls runs without it (no DEM STEP,
 * STATUS, LOADS or BODY_STATE). Without particles it runs whenever there are bodies. */
static int coord_dem_needed(const lahar_case *c)
{
    if (c->nbody == 0)
        return 0;
    if (c->nblock == 0)
        return 1;
    for (int i = 0; i < c->nbody; i++)
        if (c->bodies[i].motion != LAHAR_MOTION_FIXED)
            return 1;
    return 0;
}

/* A run with checkpoints keeps the case it was started with in OUT/checkpoints: case.yaml (a
 * byte copy) and case_source (the original path and the directory its relative paths start
 * from), so that `lahar resume OUT` needs nothing else. 0 or -1 (message on stderr). */
static int coord_save_case(const char *outdir, const lahar_case *c)
{
    char dir[PATH_MAX + 32], path[PATH_MAX + 64], src_dir[PATH_MAX];
    snprintf(dir, sizeof dir, "%s/" LAHAR_CKPT_DIR, outdir);
    if (lahar_mkdir_p(dir) != 0) {
        fprintf(stderr, "lahar: cannot create %s: %s\n", dir, strerror(errno));
        return -1;
    }
    char tmp[PATH_MAX];
    snprintf(tmp, sizeof tmp, "%s", c->path);
    if (!realpath(dirname(tmp), src_dir))
        snprintf(src_dir, sizeof src_dir, ".");
    FILE *in = fopen(c->path, "rb");
    snprintf(path, sizeof path, "%s/case.yaml", dir);
    FILE *out = in ? fopen(path, "wb") : NULL;
    int rc = in && out ? 0 : -1;
    char buf[65536];
    size_t n;
    while (!rc && (n = fread(buf, 1, sizeof buf, in)) > 0)
        if (fwrite(buf, 1, n, out) != n)
            rc = -1;
    if (in)
        fclose(in);
    if (out && fclose(out) != 0)
        rc = -1;
    snprintf(path, sizeof path, "%s/case_source", dir);
    char abs[PATH_MAX];
    if (!realpath(c->path, abs))
        snprintf(abs, sizeof abs, "%s", c->path);
    out = rc ? NULL : fopen(path, "w");
    if (!out || fprintf(out, "%s\n%s\n", abs, src_dir) < 0)
        rc = -1;
    if (out && fclose(out) != 0)
        rc = -1;
    if (rc)
        fprintf(stderr, "lahar: cannot keep a copy of the case %s in %s: %s\n", c->path, dir, strerror(errno));
    return rc;
}

int lahar_coord_resume_case(const char *outdir, lahar_case *c)
{
    char path[PATH_MAX + 64], src[PATH_MAX + 64], line1[PATH_MAX], line2[PATH_MAX];
    snprintf(src, sizeof src, "%s/" LAHAR_CKPT_DIR "/case_source", outdir);
    FILE *f = fopen(src, "r");
    if (!f) {
        fprintf(stderr, "lahar resume: %s has no checkpoints (no %s: the run's case had no checkpoint: section, "
                        "or this is not a lahar output directory); start it again with `lahar run CASE -o %s "
                        "--overwrite`\n", outdir, src, outdir);
        return LAHAR_EXIT_SETUP;
    }
    int ok = fgets(line1, sizeof line1, f) && fgets(line2, sizeof line2, f);
    fclose(f);
    if (!ok) {
        fprintf(stderr, "lahar resume: %s is incomplete; start the run again with lahar run --overwrite\n", src);
        return LAHAR_EXIT_SETUP;
    }
    line1[strcspn(line1, "\n")] = '\0';
    line2[strcspn(line2, "\n")] = '\0';
    snprintf(path, sizeof path, "%s/" LAHAR_CKPT_DIR "/case.yaml", outdir);
    char err[2048];
    if (lahar_case_load_dir(path, line2, c, err, sizeof err) != 0) {
        fprintf(stderr, "lahar resume: %s (the run's case, kept in %s; its files are read from %s)\n", err, path,
                line2);
        return LAHAR_EXIT_SETUP;
    }
    snprintf(c->path, sizeof c->path, "%.1023s", line1);
    return 0;
}

/* `lahar resume`: the newest complete checkpoint of OUT (stale *.tmp removed), its coordinator
 * state, the output cut back to it; fills the resume fields of rc. 0, or -1 with a message on
 * stderr (status 2). 1: nothing to do (the checkpoint is at the end time). */
static int coord_resume_prepare(coord *co, lahar_case *rc, double t_end)
{
    int64_t steps[1024];
    int n = coord_list_ckpts(co->outdir, steps, 1024, 1);
    if (n == 0) {
        fprintf(stderr, "lahar resume: %s has no complete checkpoint (none was written before the run ended); "
                        "start it again with `lahar run CASE -o %s --overwrite`\n", co->outdir, co->outdir);
        return -1;
    }
    char dir[PATH_MAX + 64], path[PATH_MAX + 96];
    lahar_ckpt_dir(dir, sizeof dir, co->outdir, steps[0], 0);
    snprintf(path, sizeof path, "%s/coord.h5", dir);
    lahar_ckpt_file f;
    int64_t k = -1;
    int is_output = 0;
    if (lahar_ckpt_open(&f, path, "coordinator") == 0)
        coord_state_io(co, &f, &k, &co->clk0, &co->dt_allowed0, &co->dt_first0, &is_output);
    if (lahar_ckpt_close(&f) != 0) {
        fprintf(stderr, "lahar resume: %s\n", f.err);
        return -1;
    }
    if (k != steps[0]) {
        fprintf(stderr, "lahar resume: %s holds step %lld, not %lld\n", path, (long long)k, (long long)steps[0]);
        return -1;
    }
    co->resume_t = co->sim_time;
    if (t_end > 0.0) {
        if (!(t_end > co->resume_t) || t_end < rc->output_interval) {
            fprintf(stderr, "lahar resume: --time-end %g must be later than the checkpoint (t = %.9g s) and at least "
                            "output_interval (%g s)\n", t_end, co->resume_t, rc->output_interval);
            return -1;
        }
        rc->t_end = t_end;
    }
    if (co->resume_t >= rc->t_end * (1.0 - 1e-12)) {
        printf("lahar resume: the run in %s is at its end time already (checkpoint of step %lld, t = %.9g s); "
               "give --time-end T to extend it\n", co->outdir, (long long)k, co->resume_t);
        return 1;
    }
    if (rc->t_end != co->clk0.t_end) {
        /* a later end: the output times after the checkpoint are those of a run to the new end;
         * a segment aimed at the old end is planned again from the checkpoint's time */
        lahar_clock fresh;
        lahar_clock_init(&fresh, rc->t_end, rc->output_interval);
        double old_target = lahar_clock_output_time(&co->clk0, co->clk0.j + 1);
        co->clk0.t_end = fresh.t_end;
        co->clk0.out_interval = fresh.out_interval;
        co->clk0.nout = fresh.nout;
        if (co->clk0.m > 0 && lahar_clock_output_time(&co->clk0, co->clk0.j + 1) != old_target) {
            co->clk0.t_base = co->resume_t;
            co->clk0.i = 0;
            co->clk0.m = 0;
        }
    }
    char err[1024];
    if (lahar_output_resume_trim(co->outdir, k, is_output, err, sizeof err) != 0) {
        fprintf(stderr, "lahar resume: %s\n", err);
        return -1;
    }
    co->resumed = 1;
    co->k0 = k;
    co->steps = k;
    co->ckpt_last_step = k;
    co->ckpt_last_t = co->resume_t;
    size_t dlen = strlen(dir);
    if (dlen >= sizeof rc->resume_dir) {
        fprintf(stderr, "lahar resume: the checkpoint's path %s is longer than %zu characters\n", dir,
                sizeof rc->resume_dir - 1);
        return -1;
    }
    memcpy(co->resume_dir, dir, dlen + 1);
    rc->resume = 1;
    rc->resume_step = k;
    memcpy(rc->resume_dir, dir, dlen + 1);
    return 0;
}

/* ---- a run, step by step (lahar_coord_run) ------------------------------------------------- */

/* What a set-up step returns when the run goes on; any other value is the exit status to end
 * with. */
#define COORD_GO_ON (-1)

/* The run's record before anything is touched; -1 (and the message) when the case has nothing for
 * either node to do, so that OUT is not even created. */
static int coord_init(coord *co, const lahar_case *c, const lahar_coord_options *o)
{
    memset(co, 0, sizeof *co);
    co->c = c;
    co->o = o;
    co->status = "error";
    co->summary_fd = -1;
    co->wall0 = lahar_now();
    co->node[LAHAR_ROLE_DEM] =
        (coord_node){.role = LAHAR_ROLE_DEM, .exe_name = "lahar-dem", .needed = coord_dem_needed(c), .last_step = -1};
    co->node[LAHAR_ROLE_SPH] =
        (coord_node){.role = LAHAR_ROLE_SPH, .exe_name = "lahar-sph", .needed = c->nblock > 0, .last_step = -1};
    if (!co->node[LAHAR_ROLE_DEM].needed && !co->node[LAHAR_ROLE_SPH].needed) {
        fprintf(stderr, "lahar: %s: nothing to simulate (no bodies and no particle blocks)\n", c->path);
        return -1;
    }
    co->ckpt_last_step = -1;
    co->ckpt_on = c->checkpoint_interval > 0.0;
    return 0;
}

/* OUT created, its absolute path (the nodes write there from their own working directories) and
 * its lock; the lock's descriptor, or -1 after saying why. */
static int coord_claim_outdir(coord *co)
{
    if (lahar_mkdir_p(co->o->outdir) != 0 || !realpath(co->o->outdir, co->outdir)) {
        fprintf(stderr, "lahar: cannot create the output directory %s: %s\n", co->o->outdir, strerror(errno));
        return -1;
    }
    return coord_lock_outdir(co->outdir, co->c->path);
}

/* What OUT holds before the nodes start: for `lahar resume` the output cut back to the newest
 * checkpoint and the case it continues (co->c becomes that copy, with the resume fields); for a
 * new run an OUT without an earlier run's files, and the case kept beside the checkpoints.
 * COORD_GO_ON, or the exit status (LAHAR_EXIT_OK: a resume with nothing left to do). */
static int coord_prepare_outdir(coord *co)
{
    static lahar_case resumed_case; /* the case with the resume fields (and a later end) */
    if (co->o->resume) {
        resumed_case = *co->c;
        int rc = coord_resume_prepare(co, &resumed_case, co->o->resume_t_end);
        if (rc != 0)
            return rc > 0 ? LAHAR_EXIT_OK : LAHAR_EXIT_SETUP;
        co->c = &resumed_case;
        return COORD_GO_ON;
    }
    if (coord_clear_outdir(co->outdir, co->o->overwrite) != 0 ||
        (co->ckpt_on && coord_save_case(co->outdir, co->c) != 0))
        return LAHAR_EXIT_SETUP;
    return COORD_GO_ON;
}

/* Where the messages go (co->url, co->mode). Default: a private network namespace of our own, so
 * that nothing leaves the machine and two runs never hear each other. 0, or -1 after saying why. */
static int coord_choose_network(coord *co)
{
    const lahar_coord_options *o = co->o;
    char err[1024];
    const char *env_url = getenv("LCM_DEFAULT_URL");
    if (o->in_process) {
        co->url = "memq://";
        co->mode = "in-process";
    } else if (o->lcm_url || env_url) {
        co->url = o->lcm_url ? o->lcm_url : env_url;
        co->mode = o->no_spawn ? "no-spawn" : "processes";
        if (strncmp(co->url, "udpm://", 7) == 0 && !strstr(co->url, "recv_buf_size"))
            fprintf(stderr, "lahar: warning: %s has no recv_buf_size; large messages may be lost "
                            "(add ?recv_buf_size=8388608)\n", co->url);
    } else if (o->no_spawn) {
        /* nodes started by hand cannot join a namespace made here; the network must be named */
        fprintf(stderr, "lahar: --no-spawn needs --lcm-url URL (or $LCM_DEFAULT_URL), the same URL the nodes you "
                        "start are given, e.g. '%s' inside a network namespace you made\n", LAHAR_NETNS_URL);
        return -1;
    } else {
        if (lahar_netns_enter(err, sizeof err) != 0) {
            fprintf(stderr, "lahar: %s\n", err);
            return -1;
        }
        co->url = LAHAR_NETNS_URL;
        co->mode = "processes";
    }
    return 0;
}

/* An authenticated run (--auth-key or $LAHAR_AUTH_KEY): memq:// inside this process has no one to
 * keep out, every network run takes the key. 0, or -1 after saying why. */
static int coord_load_auth_key(coord *co)
{
    const lahar_coord_options *o = co->o;
    char err[1024];
    const char *key_path = o->auth_key_path ? o->auth_key_path : getenv(LAHAR_AUTH_ENV);
    if (key_path && *key_path && !o->in_process) {
        /* realpath may leave part of a path in its buffer when it fails: say why from errno */
        if (!realpath(key_path, co->auth_key_path)) {
            const int e = errno;
            fprintf(stderr, "lahar: auth key %s: %s (%s)\n", key_path, strerror(e),
                    e == ENOENT ? "make one with `lahar keygen FILE`" : "check the path and its permissions");
            co->auth_key_path[0] = '\0';
            return -1;
        }
        if (lahar_auth_key_load(co->auth_key_path, co->auth_key, err, sizeof err) != 0) {
            fprintf(stderr, "lahar: %s\n", err);
            return -1;
        }
    }
    return 0;
}

/* Progress on stderr: none with --quiet, a line rewritten in place on a terminal, whole lines
 * every --progress-every s into a file or a pipe (a batch job's log). */
static void coord_choose_progress(coord *co)
{
    const lahar_coord_options *o = co->o;
    co->progress = o->quiet ? 0
                   : isatty(STDERR_FILENO) ? COORD_PROGRESS_TERMINAL
                   : o->progress_every_s > 0 ? COORD_PROGRESS_LOG : 0;
    co->last_progress = co->wall0;
}

/* Ctrl-C ends the run (the nodes are stopped, summary.json written); SIGTERM too, or with
 * checkpoints a checkpoint first and a clean, resumable stop; SIGUSR1 asks for a checkpoint. */
static void coord_catch_signals(const coord *co)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = coord_on_sigint;
    sigaction(SIGINT, &sa, NULL);
    if (co->ckpt_on) /* SIGTERM: a checkpoint, then a clean stop (resumable) */
        sa.sa_handler = coord_on_sigterm;
    sigaction(SIGTERM, &sa, NULL);
    sa.sa_handler = coord_on_sigusr1;
    sigaction(SIGUSR1, &sa, NULL);
}

/* The transport and the coordinator's link on it (with the run's key). LAHAR_EXIT_OK, or
 * LAHAR_EXIT_SETUP with co->message saying why. */
static int coord_open_link(coord *co)
{
    char err[1024];
    co->t = lahar_transport_open(co->url, err, sizeof err);
    if (!co->t) {
        snprintf(co->message, sizeof co->message, "%s", err);
        return LAHAR_EXIT_SETUP;
    }
    co->link = lahar_link_create(co->t, LAHAR_ROLE_COORDINATOR, co->run_id,
                                 LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_HELLO) | LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_STATUS), err,
                                 sizeof err);
    if (!co->link) {
        snprintf(co->message, sizeof co->message, "%s", err);
        return LAHAR_EXIT_SETUP;
    }
    if (co->auth_key_path[0])
        lahar_link_set_auth_key(co->link, co->auth_key);
    return LAHAR_EXIT_OK;
}

/* The nodes started (unless the user starts them, --no-spawn), the heartbeat running and every
 * node's HELLO heard. The machine's load is read first: it decides the nodes' OpenMP wait policy
 * (coord_machine_load). LAHAR_EXIT_OK or the exit status, with co->message. */
static int coord_start_nodes(coord *co)
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
static int coord_set_up_nodes(coord *co)
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

/* The lockstep, timed apart from set-up and finish (summary.json setup_s, stepping_s, finish_s). */
static int coord_step_to_end(coord *co)
{
    co->lock0 = lahar_now();
    int status = coord_lockstep(co);
    co->lock1 = lahar_now();
    if (status == LAHAR_EXIT_OK)
        co->status = "finished";
    return status;
}

/* STOP (its reason from how the run ended) and the nodes' exit. A node that fails on its way out
 * (an output error at close, a sanitizer report) fails a run that had finished. The run's exit
 * status. */
static int coord_stop_nodes(coord *co, int status)
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

/* Where the output is and how to look at it (stdout; not with --quiet). */
static void coord_print_hints(const coord *co)
{
    printf("lahar: %s: %lld steps to t = %.6g s in %.2f s wall; output in %s\n", co->status, (long long)co->steps,
           co->sim_time, lahar_now() - co->wall0, co->outdir);
    printf("  look at it: paraview %s/lahar.xmf (bodies and particles over time)\n", co->outdir);
    static const char *const files[] = {"bodies.h5", "forces.h5", "particles.h5", "contacts.h5"};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        char path[PATH_MAX + 32];
        snprintf(path, sizeof path, "%s/%s", co->outdir, files[i]);
        if (access(path, R_OK) == 0)
            printf("              h5dump -H %s\n", path);
    }
    if (co->c->nbody > 0 && co->c->output_forces)
        printf("              python3 %s/plot_forces.py %s   (force history, see tools/README.md)\n",
               LAHAR_TOOLS_DIR, co->outdir);
    printf("              python3 %s/plot_snapshot.py %s   (last snapshot to PNG; --all for frames)\n", LAHAR_TOOLS_DIR,
           co->outdir);
    printf("  run summary: %s/summary.json\n", co->outdir);
}

/* However the run ended once it had a summary.json: the files a dead node left readable, the
 * reason on stderr, summary.json, the combined ParaView file and the closing hints. */
static void coord_report_end(coord *co, int status)
{
    coord_release_files(co);
    co->exit_status = status;
    if (status != LAHAR_EXIT_OK)
        fprintf(stderr, "lahar: %s\n", co->message[0] ? co->message : "run failed");
    if (co->link)
        lahar_link_heartbeat_stop(co->link);
    coord_write_summary(co);
    if (co->node[LAHAR_ROLE_DEM].needed || co->node[LAHAR_ROLE_SPH].needed) {
        char err[1024];
        if (lahar_output_xdmf_combine(co->outdir, err, sizeof err) != 0 && !co->o->quiet)
            fprintf(stderr, "lahar: %s\n", err);
    }
    if (!co->o->quiet)
        coord_print_hints(co);
}

/* Set-up that can still refuse the run (exit 2, or 0 for a resume with nothing to do) without
 * having written anything of it, then the run: nodes, scene, steps, STOP; summary.json is written
 * however it ends. */
int lahar_coord_run(const lahar_case *c, const lahar_coord_options *o)
{
    coord co;
    if (coord_init(&co, c, o) != 0)
        return LAHAR_EXIT_SETUP;
    const int lock_fd = coord_claim_outdir(&co);
    if (lock_fd < 0)
        return LAHAR_EXIT_SETUP;
    int status = coord_prepare_outdir(&co);
    if (status == COORD_GO_ON &&
        (coord_choose_network(&co) != 0 || coord_load_auth_key(&co) != 0 || coord_reserve_summary(&co) != 0))
        status = LAHAR_EXIT_SETUP;
    if (status != COORD_GO_ON) {
        close(lock_fd);
        return status;
    }
    co.run_id = coord_random_run_id();
    coord_choose_progress(&co);
    coord_catch_signals(&co);

    status = coord_open_link(&co);
    if (status == LAHAR_EXIT_OK) { /* a link to send STOP on: from here the nodes are stopped however it ends */
        status = coord_start_nodes(&co);
        if (status == LAHAR_EXIT_OK)
            status = coord_set_up_nodes(&co);
        if (status == LAHAR_EXIT_OK)
            status = coord_step_to_end(&co);
        status = coord_stop_nodes(&co, status);
    }
    coord_report_end(&co, status);
    lahar_link_destroy(co.link);
    lahar_transport_close(co.t);
    close(lock_fd);
    return status;
}
