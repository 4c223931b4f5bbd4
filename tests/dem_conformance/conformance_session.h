/* One run of a DEM engine under the conformance harness (tests/dem_conformance/README.md): the
 * harness plays the coordinator (role 0) and the SPH node (role 2) of the lahar protocol
 * (lcm_types/README.md) over two links of its own, against the engine executable it starts. */
#ifndef LAHAR_CONFORMANCE_SESSION_H
#define LAHAR_CONFORMANCE_SESSION_H
#include <stdint.h>
#include <sys/types.h>
#include "link.h"
#include "scene.h"
#include "transport.h"

/* A transport that loses frames: every `every`-th datagram published and every `every`-th heard
 * (counting from `phase`) is discarded, deterministically; every = 0 passes everything. */
typedef struct {
    lahar_transport outer;      /* what the link uses */
    lahar_transport *inner;     /* the real LCM transport */
    int every, phase;
    uint64_t published, heard, dropped_out, dropped_in;
    lahar_transport_recv_fn fn;
    void *user;
} conf_lossy;

typedef struct {
    /* set by the caller before conf_session_start */
    const char *const *cmd;    /* engine command line, NULL-terminated */
    const char *engine;        /* scene's dem_engine */
    const char *url;           /* LCM URL inside the private namespace (the engine gets it as
                                  LCM_DEFAULT_URL, which the caller sets before any thread exists) */
    int drop_every;            /* message loss: 0 none */
    /* the run */
    lahar_case c;
    char case_path[1024];
    char out[1024];
    pid_t pid;
    int exited, exit_status;   /* exit_status: WEXITSTATUS, or 128 + signal */
    double exit_time;          /* lahar_now() when the exit was seen */
    conf_lossy lc, ls;
    lahar_link *co, *sph;
    int64_t run_id;
    /* what the engine said */
    char hello_engine[256], hello_version[64], hello_host[256];
    int hello_role, hello_protocol, hello_pid, hello_ncaps;
    int64_t hello_run_id;
    char ready_message[512];
    double dt_stable;
    /* the moving bodies (scene order) and the recorded trajectory, one row per completed step */
    int nmoving;
    int *moving;
    int64_t cap, nsteps;
    double *t;                           /* [cap] BODY_STATE(k).t */
    double (*x)[3], (*v)[3], (*w)[3], (*q)[4]; /* [cap * nmoving] */
    int *nsub;                           /* [cap] STATUS(k).nsubsteps */
    double *status_dt_stable;            /* [cap] */
    char fail[1024];                     /* first protocol violation seen, "" none */
} conf_session;

/* Load the case, open the links, start the engine, HELLO, SCENE, STATUS(-1). 0 or -1 (s->fail). */
int conf_session_start(conf_session *s, const char *case_path, const char *out_dir, int64_t max_steps);
/* STEP(k) (t, t_next, dt = t_next - t) and LOADS(k) (loads: one per body, or NULL for none);
 * STATUS(k) and BODY_STATE(k) are checked and recorded. 0 or -1 (s->fail). */
int conf_session_step(conf_session *s, int64_t k, double t, double t_next, const lahar_body_load *loads);
/* Poll both links for ms (heartbeats, NACKs). */
void conf_session_idle(conf_session *s, int ms);
/* STOP (reason 0) re-sent every 100 ms until the engine exits or timeout_s passes. 0 if it exited. */
int conf_session_stop(conf_session *s, double timeout_s);
/* Wait up to timeout_s for the engine to exit without sending anything. 0 if it exited. */
int conf_session_wait_exit(conf_session *s, double timeout_s);
/* Kill the engine if still running, close everything. */
void conf_session_free(conf_session *s);

#endif
