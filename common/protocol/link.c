/* Framing, reassembly and NACK-driven repair of lahar messages; see link.h and
 * lcm_types/README.md for the rules. All buffers are allocated at creation and grow by doubling
 * only when a larger message than ever before shows up. */
#include "link.h"
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include "auth.h"
#include "msg_check.h"
#include "lahar_heartbeat_t.h"
#include "lahar_nack_t.h"

#define LINK_CACHE_DEPTH 4   /* kept copies per channel: the last few steps */
#define LINK_SLOTS 32        /* messages being reassembled or waiting to be taken */
#define LINK_WINDOW 64       /* duplicate detection window in msg_seq per (sender, channel) */
#define LINK_NACK_FIRST 0.010
#define LINK_NACK_MAX 0.200
#define LINK_MAX_MISSING 256
#define LINK_FRAME_BUF (LAHAR_FRAME_PAYLOAD + 256 + LAHAR_AUTH_MACBYTES)
#define LINK_MAX_MESSAGE (1 << 28) /* as LCM_MAX_MESSAGE_SIZE: a larger claim is a corrupt frame */
/* A wait that returns this much later than asked means this process was not running (an
 * overloaded machine): that time is not counted as the peers' silence (link_pump_timed). */
#define LINK_LATE_SLACK 0.05
/* Before a watched peer is called lost, this long is spent reading what has arrived: LCM's
 * receive thread may not have run yet to move queued datagrams from the socket. */
#define LINK_LOST_GRACE_MS 50

static const char *const link_channels[LAHAR_NMSG] = {
    "LAHAR_UNKNOWN", "LAHAR_HELLO", "LAHAR_SCENE", "LAHAR_STEP", "LAHAR_STATUS",
    "LAHAR_BODY_STATE", "LAHAR_LOADS", "LAHAR_STOP", "LAHAR_HEARTBEAT", "LAHAR_NACK",
};

const char *lahar_link_channel(int type)
{
    return (type > 0 && type < LAHAR_NMSG) ? link_channels[type] : link_channels[0];
}

const char *lahar_link_role_name(int role)
{
    switch (role) {
    case LAHAR_ROLE_COORDINATOR: return "coordinator";
    case LAHAR_ROLE_DEM: return "DEM node";
    case LAHAR_ROLE_SPH: return "SPH node";
    default: return "unknown role";
    }
}

double lahar_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct {
    uint8_t *data;
    int cap;
} link_buf;

static int link_buf_reserve(link_buf *b, int size)
{
    if (size <= b->cap)
        return 0;
    int cap = b->cap > 0 ? b->cap : 1024;
    while (cap < size)
        cap *= 2;
    uint8_t *p = realloc(b->data, (size_t)cap);
    if (!p)
        return -1;
    b->data = p;
    b->cap = cap;
    return 0;
}

typedef struct {
    int used;
    int64_t step, seq;
    int size;
    double t_pub; /* last (re)publication */
    link_buf buf;
} link_cached;

typedef struct {
    int used, complete;
    int sender, type;
    int64_t seq, step;
    int nframes, nrecv, total;
    double t_first;
    link_buf buf;
    link_buf got; /* one byte per frame: received */
} link_slot;

typedef struct {
    int64_t max_seq;  /* highest msg_seq taken */
    uint64_t mask;    /* bit i: max_seq - i taken */
} link_window;

struct lahar_link {
    lahar_transport *t;
    int role;
    _Atomic int64_t run_id;
    unsigned want;

    pthread_mutex_t send_lock;  /* seq counters, cache, frame buffer: shared with heartbeat thread */
    int64_t next_seq[LAHAR_NMSG];
    link_cached cache[LAHAR_NMSG][LINK_CACHE_DEPTH];
    int cache_next[LAHAR_NMSG];
    uint8_t frame_buf[LINK_FRAME_BUF];
    link_buf encode;            /* lahar_link_buffer() */
    link_buf nack_buf;

    link_slot slots[LINK_SLOTS];
    int taken;                  /* slot handed out by the last wait/take, freed on the next call */
    link_window window[LAHAR_NROLES][LAHAR_NMSG];

    double last_heard[LAHAR_NROLES];
    double max_gap[LAHAR_NROLES];   /* longest time between two frames heard from a peer */
    double late_max, late_sum;      /* this process's own scheduling gaps seen in wait/poll */
    int64_t peer_step[LAHAR_NROLES];
    double watch_silence[LAHAR_NROLES]; /* 0 = not watched */
    int lost_role;
    double wait_seconds;

    lahar_link_stats stats[LAHAR_NMSG];

    pthread_t hb_thread;
    int hb_running;
    _Atomic int hb_stop;
    pthread_mutex_t hb_lock; /* with hb_wake: the thread sleeps a whole period, woken at once by stop */
    pthread_cond_t hb_wake;
    double hb_period;
    _Atomic int64_t completed_step;
    int64_t hb_seq;

    /* authenticated run (lahar_link_set_auth_key): every frame sent carries a MAC, every frame
     * heard without a valid one is dropped and counted; so is a frame of a message already taken
     * that is not flagged as a re-send, and a heartbeat or NACK not newer than the last */
    int auth;
    uint8_t auth_key[LAHAR_AUTH_KEYBYTES];
    lahar_link_auth_stats auth_stats;
    int64_t last_seq_hb[LAHAR_NROLES], last_seq_nack[LAHAR_NROLES];
};

/* ---- sending ------------------------------------------------------------------------------- */

/* Publish frames [first, last) of an encoded message. Caller holds send_lock. */
static int link_publish_frames(lahar_link *l, int type, int64_t step, int64_t seq, const uint8_t *data,
                               int size, const int32_t *which, int nwhich, int resend)
{
    int nframes = size > 0 ? (size + LAHAR_FRAME_PAYLOAD - 1) / LAHAR_FRAME_PAYLOAD : 1;
    int count = which ? nwhich : nframes;
    int rc = 0;
    for (int i = 0; i < count; i++) {
        int index = which ? which[i] : i;
        if (index < 0 || index >= nframes)
            continue;
        int offset = index * LAHAR_FRAME_PAYLOAD;
        int chunk = size - offset < LAHAR_FRAME_PAYLOAD ? size - offset : LAHAR_FRAME_PAYLOAD;
        lahar_frame_t f = {
            .run_id = atomic_load(&l->run_id), .sender = l->role, .step = step, .type = type,
            .msg_seq = seq, .nframes = nframes, .index = index, .total_size = size,
            .offset = offset, .flags = (int8_t)(resend ? LAHAR_FRAME_T_FLAG_RESEND : 0),
            .size = chunk, .payload = (uint8_t *)(data + offset),
        };
        static const uint8_t no_mac[LAHAR_AUTH_MACBYTES];
        f.mac_size = l->auth ? LAHAR_AUTH_MACBYTES : 0;
        f.mac = (uint8_t *)no_mac;
        int n = lahar_frame_t_encode(l->frame_buf, 0, LINK_FRAME_BUF, &f);
        if (n < 0) {
            rc = -1;
            continue;
        }
        if (l->auth) /* the MAC (the encoding's last bytes) covers everything before mac_size */
            lahar_auth_mac(l->frame_buf + n - LAHAR_AUTH_MACBYTES, l->frame_buf,
                           (size_t)(n - LAHAR_AUTH_MACBYTES - 2), l->auth_key);
        lahar_link_stats *s = &l->stats[type];
        /* A datagram the kernel refuses (a firewall drop, a full buffer) is a lost frame like any
         * other: the receiver NACKs it and the kept copy goes out again. */
        if (lahar_transport_publish(l->t, lahar_link_channel(type), l->frame_buf, (size_t)n) != 0)
            s->send_failures++;
        if (resend) {
            s->frames_resent++;
            s->bytes_resent += (uint64_t)n;
        } else {
            s->frames_sent++;
            s->bytes_sent += (uint64_t)n;
        }
    }
    return rc;
}

void *lahar_link_buffer(lahar_link *l, int size)
{
    return link_buf_reserve(&l->encode, size) == 0 ? l->encode.data : NULL;
}

int lahar_link_send(lahar_link *l, int type, int64_t step, const void *data, int size)
{
    if (type <= 0 || type >= LAHAR_NMSG || size < 0)
        return -1;
    pthread_mutex_lock(&l->send_lock);
    int64_t seq = ++l->next_seq[type];
    link_cached *c = &l->cache[type][l->cache_next[type]];
    int rc = -1;
    if (link_buf_reserve(&c->buf, size) == 0) {
        memcpy(c->buf.data, data, (size_t)size);
        c->used = 1;
        c->step = step;
        c->seq = seq;
        c->size = size;
        c->t_pub = lahar_now();
        l->cache_next[type] = (l->cache_next[type] + 1) % LINK_CACHE_DEPTH;
        l->stats[type].msgs_sent++;
        rc = link_publish_frames(l, type, step, seq, c->buf.data, size, NULL, 0, 0);
    }
    pthread_mutex_unlock(&l->send_lock);
    return rc;
}

/* Newest kept copy of (type, step). Caller holds send_lock. */
static link_cached *link_cache_find(lahar_link *l, int type, int64_t step)
{
    link_cached *best = NULL;
    for (int i = 0; i < LINK_CACHE_DEPTH; i++) {
        link_cached *c = &l->cache[type][i];
        if (c->used && c->step == step && (!best || c->seq > best->seq))
            best = c;
    }
    return best;
}

/* min_age: do not re-publish a copy that went out less than min_age seconds ago. A NACK that
 * waited in the queue while this process computed the message it asks for is answered by the
 * original publication; if that was lost, the requester asks again after its back-off. */
static int link_resend(lahar_link *l, int type, int64_t step, const int32_t *which, int nwhich, double min_age)
{
    pthread_mutex_lock(&l->send_lock);
    link_cached *c = link_cache_find(l, type, step);
    int rc = -1;
    double now = lahar_now();
    if (c && now - c->t_pub >= min_age) {
        c->t_pub = now;
        rc = link_publish_frames(l, type, step, c->seq, c->buf.data, c->size, which, nwhich, 1);
    }
    pthread_mutex_unlock(&l->send_lock);
    return rc;
}

int lahar_link_republish(lahar_link *l, int type, int64_t step)
{
    if (type <= 0 || type >= LAHAR_NMSG)
        return -1;
    return link_resend(l, type, step, NULL, 0, 0.0);
}

/* Ask `target` for its message (type, step); lists the frames still missing when part of it is
 * here already. */
static void link_send_nack(lahar_link *l, int target, int type, int64_t step)
{
    int32_t missing[LINK_MAX_MISSING];
    int nmissing = 0;
    for (int i = 0; i < LINK_SLOTS; i++) {
        link_slot *s = &l->slots[i];
        if (s->used && !s->complete && s->sender == target && s->type == type && s->step == step) {
            for (int f = 0; f < s->nframes && nmissing < LINK_MAX_MISSING; f++)
                if (!s->got.data[f])
                    missing[nmissing++] = f;
            break;
        }
    }
    lahar_nack_t n = {
        .run_id = atomic_load(&l->run_id), .step = step, .requester = l->role, .target = target,
        .channel = (char *)lahar_link_channel(type), .type = type, .nmissing = nmissing,
        .missing = missing,
    };
    int size = lahar_nack_t_encoded_size(&n);
    pthread_mutex_lock(&l->send_lock);
    if (link_buf_reserve(&l->nack_buf, size) == 0 && lahar_nack_t_encode(l->nack_buf.data, 0, size, &n) == size) {
        int64_t seq = ++l->next_seq[LAHAR_FRAME_T_MSG_NACK];
        l->stats[LAHAR_FRAME_T_MSG_NACK].msgs_sent++;
        link_publish_frames(l, LAHAR_FRAME_T_MSG_NACK, step, seq, l->nack_buf.data, size, NULL, 0, 0);
        l->stats[type].nacks_sent++;
    }
    pthread_mutex_unlock(&l->send_lock);
}

/* ---- receiving ----------------------------------------------------------------------------- */

/* seq comes off the wire (any int64): max_seq - seq is formed only when it cannot overflow */
static int link_window_seen(const link_window *w, int64_t seq)
{
    if (seq > w->max_seq)
        return 0;
    if (seq <= w->max_seq - LINK_WINDOW)
        return 1; /* older than the window (max_seq >= 0, so the bound does not overflow) */
    int64_t d = w->max_seq - seq;
    return (int)((w->mask >> d) & 1u);
}

static void link_window_mark(link_window *w, int64_t seq)
{
    if (seq > w->max_seq) {
        int64_t shift = seq - w->max_seq;
        w->mask = shift >= LINK_WINDOW ? 0 : (w->mask << shift);
        w->max_seq = seq;
        w->mask |= 1u;
    } else if (seq > w->max_seq - LINK_WINDOW) {
        w->mask |= (uint64_t)1 << (w->max_seq - seq);
    }
}

static void link_slot_free(link_slot *s)
{
    s->used = 0;
    s->complete = 0;
}

static link_slot *link_slot_for(lahar_link *l, const lahar_frame_t *f)
{
    link_slot *free_slot = NULL, *oldest_partial = NULL, *oldest = NULL;
    for (int i = 0; i < LINK_SLOTS; i++) {
        link_slot *s = &l->slots[i];
        if (i == l->taken)
            continue;
        if (!s->used) {
            if (!free_slot)
                free_slot = s;
            continue;
        }
        if (s->sender == f->sender && s->type == f->type && s->seq == f->msg_seq)
            return s;
        if (!s->complete && (!oldest_partial || s->t_first < oldest_partial->t_first))
            oldest_partial = s;
        if (!oldest || s->t_first < oldest->t_first)
            oldest = s;
    }
    /* Full: drop what is least likely to matter; the sender still keeps a copy for a NACK. */
    link_slot *s = free_slot ? free_slot : (oldest_partial ? oldest_partial : oldest);
    if (!s)
        return NULL;
    if (link_buf_reserve(&s->buf, f->total_size > 0 ? f->total_size : 1) != 0 ||
        link_buf_reserve(&s->got, f->nframes) != 0)
        return NULL;
    memset(s->got.data, 0, (size_t)f->nframes);
    s->used = 1;
    s->complete = 0;
    s->sender = f->sender;
    s->type = f->type;
    s->seq = f->msg_seq;
    s->step = f->step;
    s->nframes = f->nframes;
    s->nrecv = 0;
    s->total = f->total_size;
    s->t_first = lahar_now();
    return s;
}

static void link_on_nack(lahar_link *l, const uint8_t *data, int size)
{
    lahar_nack_t n;
    if (LAHAR_MSG_DECODE(lahar_nack_t, data, size, &n) < 0)
        return;
    if (n.target == l->role && n.type > 0 && n.type < LAHAR_NMSG)
        link_resend(l, n.type, n.step, n.nmissing > 0 ? n.missing : NULL, n.nmissing, LINK_NACK_FIRST / 2);
    lahar_nack_t_decode_cleanup(&n);
}

/* Decode a frame_t without copying its payload (the generated decoder would allocate a copy of
 * every frame): the header is decoded field by field with LCM's own primitives, in the order of
 * lcm_types/frame_t.lcm, and the payload, the last field, is used where it lies. */
static int link_frame_parse(const void *buf, int len, lahar_frame_t *f, int *signed_len)
{
    int pos = 0, n;
    int64_t hash;
#define LINK_DECODE(T, ptr)                                                                        \
    do {                                                                                           \
        if ((n = __##T##_decode_array(buf, pos, len - pos, (ptr), 1)) < 0)                         \
            return -1;                                                                             \
        pos += n;                                                                                  \
    } while (0)
    LINK_DECODE(int64_t, &hash);
    if (hash != __lahar_frame_t_get_hash())
        return -1;
    LINK_DECODE(int64_t, &f->run_id);
    LINK_DECODE(int32_t, &f->sender);
    LINK_DECODE(int64_t, &f->step);
    LINK_DECODE(int32_t, &f->type);
    LINK_DECODE(int64_t, &f->msg_seq);
    LINK_DECODE(int32_t, &f->nframes);
    LINK_DECODE(int32_t, &f->index);
    LINK_DECODE(int32_t, &f->total_size);
    LINK_DECODE(int32_t, &f->offset);
    LINK_DECODE(int8_t, &f->flags);
    LINK_DECODE(int32_t, &f->size);
#undef LINK_DECODE
    if (f->size < 0 || f->size > len - pos)
        return -1;
    f->payload = (uint8_t *)buf + pos;
    pos += f->size;
    *signed_len = pos;
    if ((n = __int16_t_decode_array(buf, pos, len - pos, &f->mac_size, 1)) < 0)
        return -1;
    pos += n;
    if (f->mac_size < 0 || f->mac_size > len - pos)
        return -1;
    f->mac = (uint8_t *)buf + pos;
    return pos + f->mac_size;
}

static void link_on_frame(const char *channel, const void *data, size_t size, void *user)
{
    (void)channel;
    lahar_link *l = user;
    lahar_frame_t f;
    int signed_len;
    if (size > (size_t)INT32_MAX || link_frame_parse(data, (int)size, &f, &signed_len) < 0)
        return;
    if (l->auth && (f.mac_size != LAHAR_AUTH_MACBYTES || !lahar_auth_verify(f.mac, data, (size_t)signed_len, l->auth_key))) {
        l->auth_stats.frames_rejected++; /* forged, altered, or from a run without this key */
        return;
    }
    int64_t run = atomic_load(&l->run_id);
    if (run == 0 && f.sender == LAHAR_ROLE_COORDINATOR && f.type == LAHAR_FRAME_T_MSG_HELLO && f.run_id != 0) {
        atomic_store(&l->run_id, f.run_id); /* a node started by hand joins the first run it hears */
        run = f.run_id;
    }
    if (f.run_id != run || run == 0 || f.sender == l->role || f.sender < 0 || f.sender >= LAHAR_NROLES ||
        f.type <= 0 || f.type >= LAHAR_NMSG || f.nframes <= 0 || f.index < 0 || f.index >= f.nframes ||
        f.total_size < 0 || f.total_size > LINK_MAX_MESSAGE || f.offset < 0 || f.size < 0 ||
        f.offset > f.total_size - f.size || f.nframes != (f.total_size + LAHAR_FRAME_PAYLOAD - 1) / LAHAR_FRAME_PAYLOAD +
                                                             (f.total_size == 0))
        return;

    double heard = lahar_now();
    if (l->last_heard[f.sender] > 0.0 && heard - l->last_heard[f.sender] > l->max_gap[f.sender])
        l->max_gap[f.sender] = heard - l->last_heard[f.sender];
    l->last_heard[f.sender] = heard;
    lahar_link_stats *st = &l->stats[f.type];
    st->frames_heard++;
    st->bytes_heard += (uint64_t)size;
    if (f.flags & LAHAR_FRAME_T_FLAG_RESEND) {
        st->frames_resent_heard++;
        st->bytes_resent_heard += (uint64_t)size;
    }
    else if (f.index == 0)
        st->msgs_heard++;

    if (l->auth && (f.type == LAHAR_FRAME_T_MSG_HEARTBEAT || f.type == LAHAR_FRAME_T_MSG_NACK)) {
        int64_t *last = f.type == LAHAR_FRAME_T_MSG_HEARTBEAT ? &l->last_seq_hb[f.sender] : &l->last_seq_nack[f.sender];
        if (f.msg_seq <= *last) {
            l->auth_stats.frames_replayed++;
            return;
        }
        *last = f.msg_seq;
    }
    if (f.type == LAHAR_FRAME_T_MSG_HEARTBEAT && f.nframes == 1) {
        lahar_heartbeat_t hb;
        if (LAHAR_MSG_DECODE(lahar_heartbeat_t, f.payload, f.size, &hb) >= 0) {
            if (hb.step > l->peer_step[f.sender])
                l->peer_step[f.sender] = hb.step;
            lahar_heartbeat_t_decode_cleanup(&hb);
        }
        return;
    }
    if (f.type == LAHAR_FRAME_T_MSG_NACK) {
        if (f.nframes == 1)
            link_on_nack(l, f.payload, f.size);
        return;
    }
    if (!(l->want & LAHAR_MSG_BIT(f.type)))
        return;
    if (link_window_seen(&l->window[f.sender][f.type], f.msg_seq)) {
        if (l->auth && !(f.flags & LAHAR_FRAME_T_FLAG_RESEND))
            l->auth_stats.frames_replayed++; /* a re-send says so: a first publication comes once */
        return;
    }
    link_slot *s = link_slot_for(l, &f);
    if (!s || s->complete || s->nframes != f.nframes || s->total != f.total_size || s->got.data[f.index])
        return;
    memcpy(s->buf.data + f.offset, f.payload, (size_t)f.size);
    s->got.data[f.index] = 1;
    if (++s->nrecv == s->nframes)
        s->complete = 1;
}

/* ---- waiting ------------------------------------------------------------------------------- */

static void link_release_taken(lahar_link *l)
{
    if (l->taken >= 0) {
        link_slot_free(&l->slots[l->taken]);
        l->taken = -1;
    }
}

static int link_find(lahar_link *l, int sender, int type, int64_t step, lahar_link_msg *out)
{
    link_slot *best = NULL;
    int besti = -1;
    for (int i = 0; i < LINK_SLOTS; i++) {
        link_slot *s = &l->slots[i];
        if (s->used && s->complete && s->sender == sender && s->type == type &&
            (step == LAHAR_LINK_ANY_STEP || s->step == step) && (!best || s->seq < best->seq)) {
            best = s;
            besti = i;
        }
    }
    if (!best)
        return 0;
    link_window_mark(&l->window[sender][type], best->seq);
    l->taken = besti;
    out->sender = sender;
    out->type = type;
    out->step = best->step;
    out->seq = best->seq;
    out->data = best->buf.data;
    out->size = best->total;
    return 1;
}

int lahar_link_take(lahar_link *l, int sender, int type, int64_t step, lahar_link_msg *out)
{
    link_release_taken(l);
    return link_find(l, sender, type, step, out);
}

static volatile sig_atomic_t link_parent_died;
static pid_t link_parent_pid; /* the parent when the watch began */
static void link_on_parent_death(int sig)
{
    (void)sig;
    /* the kernel sends the death signal after the node is given a new parent; a SIGUSR2 while
     * the parent lives (sent to the whole process group by hand or by a batch system) is not it */
    if (getppid() == link_parent_pid)
        return;
    link_parent_died = 1;
    alarm(LAHAR_LINK_PARENT_GRACE_S);
}
void lahar_link_watch_parent(void)
{
    link_parent_pid = getppid();
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = link_on_parent_death;
    sigaction(SIGUSR2, &sa, NULL);
}
int lahar_link_parent_gone(void) { return link_parent_died; }

static int link_check_lost(lahar_link *l, double now)
{
    if (link_parent_died && l->role != LAHAR_ROLE_COORDINATOR) {
        l->lost_role = LAHAR_ROLE_COORDINATOR;
        return 1;
    }
    for (int r = 0; r < LAHAR_NROLES; r++)
        if (l->watch_silence[r] > 0.0 && now - l->last_heard[r] > l->watch_silence[r]) {
            l->lost_role = r;
            return 1;
        }
    return 0;
}

/* Drain what is queued without blocking, then wait at most timeout_ms for more. */
static void link_pump(lahar_link *l, int timeout_ms)
{
    int r = lahar_transport_handle(l->t, timeout_ms);
    while (r > 0)
        r = lahar_transport_handle(l->t, 0);
}

/* link_pump, and a check that this process was running meanwhile: a pump that returns more than
 * LINK_LATE_SLACK after its time-out was descheduled (a machine with more runnable threads than
 * cores). A process that did not run could not hear its peers, so the time it lost is not their
 * silence: the silence clocks of the watched peers move forward by it. The gaps are recorded
 * (lahar_link_sched_gaps). */
static void link_pump_timed(lahar_link *l, int timeout_ms)
{
    double t0 = lahar_now();
    link_pump(l, timeout_ms);
    double now = lahar_now(), late = now - t0 - 1e-3 * (timeout_ms > 0 ? timeout_ms : 0);
    if (late <= LINK_LATE_SLACK)
        return;
    if (late > l->late_max)
        l->late_max = late;
    l->late_sum += late;
    for (int r = 0; r < LAHAR_NROLES; r++)
        if (l->watch_silence[r] > 0.0 && l->last_heard[r] > 0.0)
            l->last_heard[r] = l->last_heard[r] + late < now ? l->last_heard[r] + late : now;
}

/* Read for ms milliseconds whatever arrives (the grace before a peer is called lost). */
static void link_pump_for(lahar_link *l, int ms)
{
    double until = lahar_now() + 1e-3 * ms, now;
    while ((now = lahar_now()) < until)
        link_pump(l, (int)((until - now) * 1e3) + 1);
}

int lahar_link_wait(lahar_link *l, int sender, int type, int64_t step, int timeout_ms, lahar_link_msg *out)
{
    link_release_taken(l);
    double start = lahar_now();
    double deadline = timeout_ms < 0 ? 1e300 : start + 1e-3 * timeout_ms;
    double nack_delay = LINK_NACK_FIRST;
    double next_nack = start + nack_delay;
    int rc;
    for (;;) {
        if (l->role != LAHAR_ROLE_COORDINATOR && !(type == LAHAR_FRAME_T_MSG_STOP) &&
            link_find(l, LAHAR_ROLE_COORDINATOR, LAHAR_FRAME_T_MSG_STOP, LAHAR_LINK_ANY_STEP, out)) {
            rc = LAHAR_LINK_STOP;
            break;
        }
        if (link_find(l, sender, type, step, out)) {
            rc = LAHAR_LINK_OK;
            break;
        }
        double now = lahar_now();
        if (link_check_lost(l, now)) {
            /* Before calling a peer lost, read what has arrived: when this process itself was
             * descheduled (an overloaded machine), the peer's frames wait in the socket, and
             * LCM's receive thread needs to run to hand them over (LINK_LOST_GRACE_MS). */
            link_pump_for(l, LINK_LOST_GRACE_MS);
            if (link_find(l, sender, type, step, out)) {
                rc = LAHAR_LINK_OK;
                break;
            }
            now = lahar_now();
            if (link_check_lost(l, now)) {
                rc = LAHAR_LINK_LOST;
                break;
            }
        }
        if (now >= deadline) {
            rc = LAHAR_LINK_TIMEOUT;
            break;
        }
        if (now >= next_nack) {
            if (atomic_load(&l->run_id) != 0 && step != LAHAR_LINK_ANY_STEP)
                link_send_nack(l, sender, type, step);
            nack_delay = nack_delay * 2 < LINK_NACK_MAX ? nack_delay * 2 : LINK_NACK_MAX;
            next_nack = now + nack_delay;
        }
        double until = next_nack < deadline ? next_nack : deadline;
        int ms = (int)((until - now) * 1e3) + 1;
        link_pump_timed(l, ms);
    }
    l->wait_seconds += lahar_now() - start;
    return rc;
}

void lahar_link_poll(lahar_link *l, int timeout_ms)
{
    link_release_taken(l);
    double start = lahar_now();
    double deadline = start + 1e-3 * timeout_ms;
    double now = start;
    do {
        link_pump_timed(l, (int)((deadline - now) * 1e3) + 1);
        now = lahar_now();
    } while (now < deadline);
    l->wait_seconds += now - start;
}

double lahar_link_wait_seconds(const lahar_link *l) { return l->wait_seconds; }

void lahar_link_watch(lahar_link *l, int role, double silence_s)
{
    if (role >= 0 && role < LAHAR_NROLES) {
        l->watch_silence[role] = silence_s;
        if (l->last_heard[role] <= 0.0)
            l->last_heard[role] = lahar_now();
    }
}

void lahar_link_heard_now(lahar_link *l, int role)
{
    if (role >= 0 && role < LAHAR_NROLES)
        l->last_heard[role] = lahar_now();
}

void lahar_link_unwatch(lahar_link *l, int role)
{
    if (role >= 0 && role < LAHAR_NROLES)
        l->watch_silence[role] = 0.0;
}

int lahar_link_lost_role(const lahar_link *l) { return l->lost_role; }
double lahar_link_last_heard(const lahar_link *l, int role)
{
    return (role >= 0 && role < LAHAR_NROLES) ? l->last_heard[role] : 0.0;
}
double lahar_link_max_silence(const lahar_link *l, int role)
{
    return (role >= 0 && role < LAHAR_NROLES) ? l->max_gap[role] : 0.0;
}
void lahar_link_sched_gaps(const lahar_link *l, double *max_s, double *sum_s)
{
    if (max_s)
        *max_s = l->late_max;
    if (sum_s)
        *sum_s = l->late_sum;
}
int64_t lahar_link_peer_step(const lahar_link *l, int role)
{
    return (role >= 0 && role < LAHAR_NROLES) ? l->peer_step[role] : -1;
}

/* ---- heartbeat ----------------------------------------------------------------------------- */

static void *link_heartbeat_main(void *arg)
{
    lahar_link *l = arg;
    uint8_t buf[256];
    while (!atomic_load(&l->hb_stop)) {
        lahar_heartbeat_t hb = {.run_id = atomic_load(&l->run_id), .step = atomic_load(&l->completed_step), .role = l->role};
        int n = lahar_heartbeat_t_encode(buf, 0, sizeof buf, &hb);
        if (hb.run_id != 0 && n > 0) {
            pthread_mutex_lock(&l->send_lock);
            int64_t seq = ++l->next_seq[LAHAR_FRAME_T_MSG_HEARTBEAT];
            l->stats[LAHAR_FRAME_T_MSG_HEARTBEAT].msgs_sent++;
            link_publish_frames(l, LAHAR_FRAME_T_MSG_HEARTBEAT, hb.step, seq, buf, n, NULL, 0, 0);
            pthread_mutex_unlock(&l->send_lock);
        }
        /* one wake-up per period (a node's OpenMP threads lose a slice to every wake-up of
         * another thread on the machine); lahar_link_heartbeat_stop signals hb_wake */
        struct timespec until;
        clock_gettime(CLOCK_REALTIME, &until);
        long long ns = (long long)until.tv_nsec + (long long)(l->hb_period * 1e9);
        until.tv_sec += (time_t)(ns / 1000000000LL);
        until.tv_nsec = (long)(ns % 1000000000LL);
        pthread_mutex_lock(&l->hb_lock);
        while (!atomic_load(&l->hb_stop))
            if (pthread_cond_timedwait(&l->hb_wake, &l->hb_lock, &until) != 0)
                break; /* timed out: the next beat */
        pthread_mutex_unlock(&l->hb_lock);
    }
    return NULL;
}

int lahar_link_heartbeat_start(lahar_link *l, double period_s)
{
    if (l->hb_running)
        return 0;
    l->hb_period = period_s;
    atomic_store(&l->hb_stop, 0);
    if (pthread_mutex_init(&l->hb_lock, NULL) != 0)
        return -1;
    if (pthread_cond_init(&l->hb_wake, NULL) != 0) {
        pthread_mutex_destroy(&l->hb_lock);
        return -1;
    }
    if (pthread_create(&l->hb_thread, NULL, link_heartbeat_main, l) != 0) {
        pthread_cond_destroy(&l->hb_wake);
        pthread_mutex_destroy(&l->hb_lock);
        return -1;
    }
    l->hb_running = 1;
    return 0;
}

void lahar_link_heartbeat_stop(lahar_link *l)
{
    if (!l->hb_running)
        return;
    pthread_mutex_lock(&l->hb_lock);
    atomic_store(&l->hb_stop, 1);
    pthread_cond_signal(&l->hb_wake);
    pthread_mutex_unlock(&l->hb_lock);
    pthread_join(l->hb_thread, NULL);
    pthread_cond_destroy(&l->hb_wake);
    pthread_mutex_destroy(&l->hb_lock);
    l->hb_running = 0;
}

void lahar_link_set_step(lahar_link *l, int64_t completed_step) { atomic_store(&l->completed_step, completed_step); }

/* ---- life cycle ---------------------------------------------------------------------------- */

lahar_link *lahar_link_create(lahar_transport *t, int role, int64_t run_id, unsigned want, char *err, size_t errlen)
{
    lahar_link *l = calloc(1, sizeof *l);
    if (!l) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    l->t = t;
    l->role = role;
    atomic_store(&l->run_id, run_id);
    atomic_store(&l->completed_step, -1);
    l->want = want;
    l->taken = -1;
    l->lost_role = -1;
    pthread_mutex_init(&l->send_lock, NULL);
    for (int r = 0; r < LAHAR_NROLES; r++)
        l->peer_step[r] = -1;
    int ok = link_buf_reserve(&l->encode, 4096) == 0 && link_buf_reserve(&l->nack_buf, 2048) == 0;
    for (int i = 0; ok && i < LINK_SLOTS; i++)
        ok = link_buf_reserve(&l->slots[i].buf, 4096) == 0 && link_buf_reserve(&l->slots[i].got, 64) == 0;
    for (int ty = 0; ok && ty < LAHAR_NMSG; ty++)
        for (int i = 0; ok && i < LINK_CACHE_DEPTH; i++)
            ok = link_buf_reserve(&l->cache[ty][i].buf, 1024) == 0;
    /* All frames of the run go through one subscription; its queue has to hold the bursts that
     * arrive while this process computes a step. */
    if (!ok || lahar_transport_subscribe(t, "LAHAR_.*", 8192, link_on_frame, l) != 0) {
        snprintf(err, errlen, "cannot set up the link (out of memory or subscription failed)");
        lahar_link_destroy(l);
        return NULL;
    }
    return l;
}

void lahar_link_destroy(lahar_link *l)
{
    if (!l)
        return;
    lahar_link_heartbeat_stop(l);
    free(l->encode.data);
    free(l->nack_buf.data);
    for (int i = 0; i < LINK_SLOTS; i++) {
        free(l->slots[i].buf.data);
        free(l->slots[i].got.data);
    }
    for (int ty = 0; ty < LAHAR_NMSG; ty++)
        for (int i = 0; i < LINK_CACHE_DEPTH; i++)
            free(l->cache[ty][i].buf.data);
    pthread_mutex_destroy(&l->send_lock);
    free(l);
}

int64_t lahar_link_run_id(const lahar_link *l) { return atomic_load(&l->run_id); }

void lahar_link_get_stats(const lahar_link *l, lahar_link_stats out[LAHAR_NMSG])
{
    /* the heartbeat thread counts its frames under the lock */
    pthread_mutex_lock((pthread_mutex_t *)&l->send_lock);
    memcpy(out, l->stats, sizeof l->stats);
    pthread_mutex_unlock((pthread_mutex_t *)&l->send_lock);
}

void lahar_link_set_auth_key(lahar_link *l, const uint8_t key[LAHAR_AUTH_KEYBYTES])
{
    pthread_mutex_lock(&l->send_lock);
    memcpy(l->auth_key, key, LAHAR_AUTH_KEYBYTES);
    l->auth = 1;
    pthread_mutex_unlock(&l->send_lock);
}

int lahar_link_auth(const lahar_link *l, lahar_link_auth_stats *out)
{
    if (out)
        *out = l->auth_stats;
    return l->auth;
}
