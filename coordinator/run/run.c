/* A run from start to end (lahar_coord_run): the case's record, where the messages go, the key,
 * the signals, the link; then the nodes, the steps and the report. The steps themselves live in
 * the other files of this folder (README.md). */
#define _GNU_SOURCE
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>
#include <time.h>
#include <unistd.h>
#include "coord_run.h"
#include "netns.h"
#include "output.h"

/* set by the signal handlers below (coord_catch_signals), read by the set-up and the lockstep */
volatile sig_atomic_t coord_interrupted;
volatile sig_atomic_t coord_term;
volatile sig_atomic_t coord_ckpt_request;

static void coord_on_sigterm(int sig)
{
    coord_term = sig;
    coord_interrupted = sig;
}

static void coord_on_sigusr1(int sig)
{
    (void)sig;
    coord_ckpt_request = 1;
}

static void coord_on_sigint(int sig)
{
    coord_interrupted = sig;
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

/* Ctrl-C ends the run (the nodes are stopped, summary.json written); SIGTERM and SIGHUP (the
 * terminal or the ssh session closed; unless started with SIGHUP ignored, as by nohup) too, or
 * with checkpoints a checkpoint first and a clean, resumable stop; SIGUSR1 asks for a checkpoint.
 * A log reader that went away (`| tee` closed with the terminal) must not end a run of hours:
 * SIGPIPE is ignored, writes to it just fail. */
static void coord_catch_signals(const coord *co)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = coord_on_sigint;
    sigaction(SIGINT, &sa, NULL);
    if (co->ckpt_on) /* SIGTERM, SIGHUP: a checkpoint, then a clean stop (resumable) */
        sa.sa_handler = coord_on_sigterm;
    sigaction(SIGTERM, &sa, NULL);
    struct sigaction hup;
    sigaction(SIGHUP, NULL, &hup);
    if (hup.sa_handler != SIG_IGN) /* `nohup lahar run ...`: the user wants the run to outlive the terminal */
        sigaction(SIGHUP, &sa, NULL);
    sa.sa_handler = coord_on_sigusr1;
    sigaction(SIGUSR1, &sa, NULL);
    sa.sa_handler = SIG_IGN;
    sigaction(SIGPIPE, &sa, NULL);
    /* SIGUSR2 means nothing to lahar; sent to the whole process group (by hand, a batch system)
     * it would end the run by its default action (the nodes take it only as lahar's death,
     * lahar_link_watch_parent, and only when their parent is gone) */
    sigaction(SIGUSR2, &sa, NULL);
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
