/* The coordinator's run, shared by the files of coordinator/run/ (and only by them): the record of
 * a run and of each node, the timing constants, and the steps one file calls in another. The
 * public entry points are in coordinator.h. */
#ifndef LAHAR_COORD_RUN_H
#define LAHAR_COORD_RUN_H
#include <limits.h>
#include <pthread.h>
#include <signal.h>
#include <stdint.h>
#include <sys/types.h>
#include "auth.h"
#include "case.h"
#include "coordinator.h"
#include "instability.h"
#include "lahar_status_t.h"
#include "link.h"
#include "machine_load.h"
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

/* What a set-up step returns when the run goes on; any other value is the exit status to end
 * with. */
#define COORD_GO_ON (-1)

/* The signal that ended the run (SIGINT, SIGTERM, SIGHUP; 0: none); SIGTERM or SIGHUP with
 * checkpoints (a checkpoint, then a clean stop); SIGUSR1 (a checkpoint after the next step). Set by
 * run.c's signal handlers. */
extern volatile sig_atomic_t coord_interrupted;
extern volatile sig_atomic_t coord_term;
extern volatile sig_atomic_t coord_ckpt_request;

/* outdir.c: OUT claimed (created, absolute, locked), prepared (an earlier run refused or removed,
 * or cut back for a resume), summary.json's room reserved */
int coord_claim_outdir(coord *co);
int coord_prepare_outdir(coord *co);
int coord_reserve_summary(coord *co);

/* nodes.c: the nodes started and set up, their STATUS collected, STOP and their exit, the files a
 * dead node left released */
int coord_start_nodes(coord *co);
int coord_set_up_nodes(coord *co);
int coord_collect_status(coord *co, int64_t k);
int coord_stop_nodes(coord *co, int status);
void coord_release_files(coord *co);

/* lockstep.c: the steps to the end time, and the progress line */
int coord_step_to_end(coord *co);
void coord_progress(coord *co, int final);

/* checkpoints.c: a checkpoint after step k, the case kept beside the checkpoints, and `lahar
 * resume`'s start from the newest one */
int coord_checkpoint(coord *co, int64_t k, lahar_clock *clk, double dt_allowed, double dt_first, int is_output);
int coord_save_case(const char *outdir, const lahar_case *c);
int coord_resume_prepare(coord *co, lahar_case *rc, double t_end);
int coord_rm_ckpt_dir(const char *path);

/* summary.c: OUT/summary.json */
void coord_write_summary(coord *co);

#endif
