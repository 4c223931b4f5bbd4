/* The lahar link layer: typed messages over a transport (common/protocol/transport.h), in frames of at
 * most LAHAR_FRAME_PAYLOAD bytes (one UDP datagram each), with reassembly, duplicate removal and
 * receiver-driven repair: whoever waits for a message NACKs its sender (10 ms, doubling to
 * 200 ms) and the sender re-publishes from the copies it keeps of its last few messages per
 * channel. Frames of other runs are ignored. The protocol itself is in lcm_types/README.md.
 *
 * Threading: one thread uses a link (send/wait/poll); the heartbeat thread started by
 * lahar_link_heartbeat_start only publishes, under the link's lock. */
#ifndef LAHAR_LINK_H
#define LAHAR_LINK_H
#include <stdint.h>
#include <stddef.h>
#include "transport.h"
#include "lahar_frame_t.h"

#define LAHAR_FRAME_PAYLOAD 60000
#define LAHAR_NROLES 3
#define LAHAR_NMSG 10               /* message types are 1 .. LAHAR_NMSG-1 (frame_t MSG_*) */
#define LAHAR_LINK_ANY_STEP INT64_MIN
#define LAHAR_ROLE_COORDINATOR LAHAR_FRAME_T_ROLE_COORDINATOR
#define LAHAR_ROLE_DEM LAHAR_FRAME_T_ROLE_DEM
#define LAHAR_ROLE_SPH LAHAR_FRAME_T_ROLE_SPH
#define LAHAR_MSG_BIT(type) (1u << (type))

enum { LAHAR_LINK_OK = 0, LAHAR_LINK_TIMEOUT = 1, LAHAR_LINK_STOP = 2, LAHAR_LINK_LOST = 3, LAHAR_LINK_ERROR = -1 };

typedef struct lahar_link lahar_link;

/* A complete message handed to the application; data is the LCM encoding of the typed message
 * (decode with lahar_<type>_decode). Valid until the next wait/poll on the link. */
typedef struct {
    int sender;
    int type;
    int64_t step;
    int64_t seq;
    const void *data;
    int size;
} lahar_link_msg;

/* Traffic a link saw, per message type (channel). */
typedef struct {
    uint64_t msgs_sent, frames_sent, bytes_sent;         /* first publications by this process */
    uint64_t frames_resent, bytes_resent;                /* re-publications on NACK by this process */
    uint64_t msgs_heard, frames_heard, bytes_heard;      /* frames of this run from other processes */
    uint64_t frames_resent_heard, bytes_resent_heard;    /* ... of which were re-sends */
    uint64_t nacks_sent;                                 /* NACKs this process sent for this channel */
    uint64_t send_failures;                              /* frames the transport refused (repaired by NACK) */
} lahar_link_stats;

const char *lahar_link_channel(int type);      /* "LAHAR_STEP", ... */
const char *lahar_link_role_name(int role);    /* "coordinator", "DEM node", "SPH node" */

/* run_id 0: adopt the run id of the first coordinator HELLO heard (a node started by hand).
 * want: LAHAR_MSG_BIT mask of the types this process reassembles (heartbeats and NACKs are
 * always handled internally). */
lahar_link *lahar_link_create(lahar_transport *t, int role, int64_t run_id, unsigned want,
                              char *err, size_t errlen);
void lahar_link_destroy(lahar_link *l);
int64_t lahar_link_run_id(const lahar_link *l);

/* A buffer of at least `size` bytes to encode an outgoing message into (reused; grows rarely). */
void *lahar_link_buffer(lahar_link *l, int size);
/* Publish an encoded message of `type` for step `step`, keeping a copy for re-sends. */
int lahar_link_send(lahar_link *l, int type, int64_t step, const void *data, int size);
/* Re-publish the kept copy of the last message of `type` at `step` (e.g. the coordinator's
 * HELLO to nodes that do not know the run yet). Returns 0, or -1 if no copy is kept. */
int lahar_link_republish(lahar_link *l, int type, int64_t step);

/* Encode a typed message (T = generated type name, e.g. lahar_step_t) and send it; rc gets 0/-1. */
#define LAHAR_LINK_SEND(rc, l, msgtype, T, step, msgp)                                        \
    do {                                                                                    \
        int n_ = T##_encoded_size(msgp);                                                    \
        void *b_ = lahar_link_buffer((l), n_);                                              \
        (rc) = (b_ && T##_encode(b_, 0, n_, (msgp)) == n_) ? lahar_link_send((l), (msgtype), (step), b_, n_) : -1; \
    } while (0)

/* Peers whose silence ends every wait with LAHAR_LINK_LOST (silence measured from the last frame
 * heard, heartbeats included; the clock starts at the call; time this process itself was not
 * running while it waited does not count, and what arrived meanwhile is read first). */
void lahar_link_watch(lahar_link *l, int role, double silence_s);
void lahar_link_unwatch(lahar_link *l, int role);
/* Restart the silence clock of a watched peer that the caller knows by other means to be alive
 * (the coordinator: a node it started whose CPU time is advancing). */
void lahar_link_heard_now(lahar_link *l, int role);
int lahar_link_lost_role(const lahar_link *l);
/* A node process lahar started gets SIGUSR2 when lahar dies (PR_SET_PDEATHSIG), if it called
 * this first: from then on every wait of its links finds the coordinator lost at once, so the
 * node closes its files (forces.h5 and gauges.h5 then read without h5clear) and exits; SIGALRM
 * ends it LAHAR_LINK_PARENT_GRACE_S later if it does not get there (a long step). */
#define LAHAR_LINK_PARENT_GRACE_S 10
void lahar_link_watch_parent(void);
/* 1 once that signal came. */
int lahar_link_parent_gone(void);
/* When the last frame of a peer was heard (lahar_now() clock; 0 never). */
double lahar_link_last_heard(const lahar_link *l, int role);
/* Longest time between two frames heard from a peer so far (heartbeats included), in s. */
double lahar_link_max_silence(const lahar_link *l, int role);
/* This process's own scheduling gaps seen while it waited (a wait that returned over 50 ms
 * late): the longest and their sum, in s. That time is not counted as a watched peer's silence. */
void lahar_link_sched_gaps(const lahar_link *l, double *max_s, double *sum_s);
/* Last step a peer reported done in its heartbeats (-1 if none). */
int64_t lahar_link_peer_step(const lahar_link *l, int role);

/* Wait for the message of `type` from `sender` at `step` (LAHAR_LINK_ANY_STEP: the oldest of
 * any step). timeout_ms < 0: no limit. While waiting, serves NACKs, tracks heartbeats and NACKs
 * the sender with back-off. Non-coordinators return LAHAR_LINK_STOP (out = the stop_t) as soon as
 * the coordinator's STOP arrives. */
int lahar_link_wait(lahar_link *l, int sender, int type, int64_t step, int timeout_ms, lahar_link_msg *out);
/* Non-blocking: take a complete message if one is there (1), else 0. */
int lahar_link_take(lahar_link *l, int sender, int type, int64_t step, lahar_link_msg *out);
/* Process incoming traffic for up to timeout_ms (serves NACKs, records heartbeats). */
void lahar_link_poll(lahar_link *l, int timeout_ms);
/* Seconds spent inside wait/poll since creation (the "wait time" of a node). */
double lahar_link_wait_seconds(const lahar_link *l);

/* Authenticated runs (common/protocol/auth.h): from this call on, every frame sent carries a MAC under
 * key, and frames heard without a valid one are dropped. Call before the link sends or hears. */
typedef struct {
    uint64_t frames_rejected; /* no MAC or a wrong one: forged, altered, or another key */
    uint64_t frames_replayed; /* valid MAC but a copy of what was taken already (not a re-send) */
} lahar_link_auth_stats;
void lahar_link_set_auth_key(lahar_link *l, const uint8_t key[32]);
/* 1 when the link authenticates; *out (may be NULL) gets what it dropped so far. */
int lahar_link_auth(const lahar_link *l, lahar_link_auth_stats *out);

/* Heartbeat thread: publishes heartbeat_t with the last completed step every period_s. */
int lahar_link_heartbeat_start(lahar_link *l, double period_s);
void lahar_link_heartbeat_stop(lahar_link *l);
void lahar_link_set_step(lahar_link *l, int64_t completed_step);

void lahar_link_get_stats(const lahar_link *l, lahar_link_stats out[LAHAR_NMSG]);

double lahar_now(void); /* monotonic seconds */

#endif
