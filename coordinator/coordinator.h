/* The coordinator: owns time and the step size, starts the nodes a scene needs, drives the
 * lockstep over the link layer and writes OUT/summary.json. Protocol: lcm_types/README.md. */
#ifndef LAHAR_COORDINATOR_H
#define LAHAR_COORDINATOR_H
#include <stdint.h>
#include "scene.h"

typedef struct {
    const char *outdir;
    const char *lcm_url;   /* explicit URL (--lcm-url or $LCM_DEFAULT_URL): no namespace */
    int threads;           /* OpenMP threads per node, 0 = default */
    int in_process;        /* nodes as threads over memq:// */
    int no_spawn;          /* nodes are started by the user */
    int quiet;
    double progress_every_s; /* stderr not a terminal (a log file, a pipe): a progress line every this
                                many seconds of wall time; 0: none (on a terminal one line is rewritten) */
    double join_wait_s;    /* how long to wait for the nodes' hello (default 30 s) */
    const char *auth_key_path; /* authenticated run across machines (common/protocol/auth.h); NULL: $LAHAR_AUTH_KEY */
    int overwrite;         /* 1: remove an earlier run's files in outdir first (else such an outdir is refused) */
    double node_timeout_s; /* a node silent this long is lost, unless it is ours and still computing
                              (default COORD_NODE_SILENCE, 2 s) */
    const char *argv0;     /* for locating lahar-dem / lahar-sph next to lahar */
    int resume;            /* `lahar resume OUT`: continue the run in outdir from its newest checkpoint */
    double resume_t_end;   /* > 0: the resumed run ends at this time instead of the case's time.end */
} lahar_coord_options;

/* Exit statuses of `lahar run`. */
enum {
    LAHAR_EXIT_OK = 0,
    LAHAR_EXIT_RUN_ERROR = 1,   /* a node reported an error (engine instability, output, dt collapse) */
    LAHAR_EXIT_SETUP = 2,       /* bad input, no namespace, nodes never answered */
    LAHAR_EXIT_NODE_LOST = 3,   /* a node went silent for 2 s */
};

/* Time stepping without accumulated sums (lcm_types/README.md "Time and Δt"). */
typedef struct {
    double t_end, out_interval;
    int64_t nout;      /* number of output times after t = 0: T_j = j * out_interval, T_nout = t_end */
    int64_t j;         /* index of the last output time reached */
    double t_base;     /* start of the current segment: T_j or a time at which h changed */
    double h;          /* step inside the segment */
    int64_t i, m;      /* steps taken in the segment, steps the segment needs to reach T_{j+1} */
} lahar_clock;

void lahar_clock_init(lahar_clock *c, double t_end, double out_interval);
double lahar_clock_output_time(const lahar_clock *c, int64_t j);
/* Plan the next step under the limit dt_allowed: fills t_k, t_{k+1} and whether t_{k+1} is an
 * output time. Returns 0, or 1 when the run is already at t_end. */
int lahar_clock_next(lahar_clock *c, double dt_allowed, double *t, double *t_next, int *is_output);
/* Commit the planned step. */
void lahar_clock_advance(lahar_clock *c);

/* `lahar resume OUT`: load the case the run in OUT was started with (OUT/checkpoints/case.yaml,
 * its relative paths resolved against the original case's directory). 0, or 2 with a message
 * on stderr (no checkpoints, unreadable case). */
int lahar_coord_resume_case(const char *outdir, lahar_case *c);

/* For --in-process runs on a busy machine (more threads than free cores) with no OMP_WAIT_POLICY
 * set: run this program again (argv, /proc/self/exe) with OMP_WAIT_POLICY=passive, which libgomp
 * reads before main; results are the same. Returns only when nothing was done or the exec failed.
 * Call before anything is created (files, threads). */
void lahar_coord_in_process_wait_policy(char **argv, const lahar_coord_options *o);

/* Run a loaded case (case.h). Returns a LAHAR_EXIT_* status. Call before creating threads (the
 * private network namespace requires a single-threaded process). */
int lahar_coord_run(const lahar_case *c, const lahar_coord_options *o);

#endif
