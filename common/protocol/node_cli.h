/* What the node processes (lahar-dem, lahar-sph) share: their command line, and connecting to a
 * run (transport + link). One place, so that every node takes the same options. */
#ifndef LAHAR_NODE_CLI_H
#define LAHAR_NODE_CLI_H
#include <stdint.h>
#include "lahar_step_t.h"
#include "link.h"
#include "transport.h"

typedef struct {
    const char *lcm_url; /* udpm://... or memq:// */
    int64_t run_id;      /* 0: join the first run announced */
    int threads;         /* OpenMP threads of the node's loops; 0 = OpenMP's default */
    double join_wait_s;  /* how long to wait for the coordinator's HELLO (0: 30 s) */
    const char *auth_key_path; /* authenticated run (common/protocol/auth.h): key file, or NULL */
    const char *engine;  /* DEM node only (lahar-dem --engine): engine used instead of the case's
                            dem.engine; NULL: the case's */
} lahar_node_options;

/* Parse a node's command line into o (URL default: $LCM_DEFAULT_URL, else LAHAR_NETNS_URL).
 * `prog` is the program name, `about` a paragraph on what the node does and `exit_codes` the
 * line on its exit statuses, both for --help. Returns -1 to go on, or the exit status to return
 * from main (0 after --help, 2 on a bad option). */
int lahar_node_parse_args(int argc, char **argv, const char *prog, const char *about, const char *exit_codes,
                          lahar_node_options *o);

/* Open the transport of o->lcm_url and a link for `role` that reassembles the message types in
 * `want` (LAHAR_MSG_BIT mask); applies o->threads. Returns 0, or 2 (the setup-error exit status)
 * after printing "prog: reason". */
int lahar_node_connect(const lahar_node_options *o, const char *prog, int role, unsigned want,
                       lahar_transport **t, lahar_link **l);

/* Wait for the coordinator's STEP(k) and decode it into *step. Returns -1 when the step is there,
 * otherwise the node's exit status: 0 the run was stopped, 3 the coordinator went silent
 * (reported as "prog: ..."), 1 a broken message. `msg` is the caller's receive slot. */
int lahar_node_wait_step(lahar_link *l, const char *prog, int64_t k, lahar_link_msg *msg, lahar_step_t *step);

/* Why a wait of the node ended with LAHAR_LINK_LOST, as "prog: ..." on stderr: lahar, which
 * started the node, has ended, or the coordinator went silent. `what` names what the node was
 * waiting for ("step", "the SPH node's loads of step"), k the step. Every wait that can be lost
 * says it, so a node never stops without a reason whichever wait the loss finds it in. */
void lahar_node_report_lost(const char *prog, const char *what, int64_t k);

/* After lahar_node_wait_step returned 0: the reason of the coordinator's STOP in msg (stop_t:
 * 0 finished, 1 error, 2 interrupted, 3 node lost; -1 if undecodable) and its message into
 * text (n bytes, may be NULL). A node writes its final snapshot for inspection when it is not 0. */
int lahar_node_stop_reason(const lahar_link_msg *msg, char *text, size_t n);

#endif
