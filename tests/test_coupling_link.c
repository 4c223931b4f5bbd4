/* The link layer over memq:// with a transport that loses datagrams on purpose: every message
 * (small, and larger than one frame) arrives complete, bit for bit and exactly once; NACKs and
 * re-sends are what repairs the losses; frames of another run are ignored. */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "link.h"
#include "transport.h"

#define NMSG 24
#define RUN 0x1234
#include "test_util.h"

/* ---- a transport that drops every n-th datagram it is asked to publish ---------------------- */
typedef struct {
    lahar_transport *inner;
    int drop_every, count, dropped;
} lossy;

static void *lossy_open(const char *url, char *err, size_t n) { (void)url; (void)err; (void)n; return NULL; }
static int lossy_publish(void *impl, const char *ch, const void *data, size_t size)
{
    lossy *l = impl;
    if (++l->count % l->drop_every == 0) {
        l->dropped++;
        return 0; /* silently lost, like a datagram dropped on the way */
    }
    return lahar_transport_publish(l->inner, ch, data, size);
}
static int lossy_subscribe(void *impl, const char *re, int cap, lahar_transport_recv_fn fn, void *user)
{
    return lahar_transport_subscribe(((lossy *)impl)->inner, re, cap, fn, user);
}
static int lossy_handle(void *impl, int ms) { return lahar_transport_handle(((lossy *)impl)->inner, ms); }
static void lossy_close(void *impl) { (void)impl; }
static const lahar_transport_ops lossy_ops = {"lossy://", lossy_open, lossy_publish, lossy_subscribe, lossy_handle, lossy_close};

static int msg_size(int k) { return k % 3 == 2 ? 3 * LAHAR_FRAME_PAYLOAD + 1234 : 100 + 37 * k; }
static void msg_fill(uint8_t *p, int k, int size)
{
    for (int i = 0; i < size; i++)
        p[i] = (uint8_t)(i * 131 + k * 7 + (i >> 8));
}

static lahar_link *sender_link;
static void *sender_main(void *arg)
{
    (void)arg;
    lahar_link *l = sender_link;
    lahar_link_watch(l, LAHAR_ROLE_COORDINATOR, 10.0);
    for (int k = 0; k < NMSG; k++) {
        int size = msg_size(k);
        uint8_t *p = lahar_link_buffer(l, size);
        msg_fill(p, k, size);
        lahar_link_send(l, LAHAR_FRAME_T_MSG_LOADS, k, p, size);
        /* the receiver acknowledges with its own message (like STATUS answers STEP) */
        lahar_link_msg m;
        int rc = lahar_link_wait(l, LAHAR_ROLE_COORDINATOR, LAHAR_FRAME_T_MSG_STATUS, k, 10000, &m);
        CHECK(rc == LAHAR_LINK_OK, "sender: no acknowledgement of message %d (rc %d)", k, rc);
        if (rc != LAHAR_LINK_OK)
            break;
    }
    lahar_link_poll(l, 300); /* answer NACKs for the last acknowledgement's peer */
    return NULL;
}

int main(void)
{
    char err[256];
    lahar_transport *ta = lahar_transport_open("memq://", err, sizeof err);
    lahar_transport *tb = lahar_transport_open("memq://", err, sizeof err);
    lahar_transport *tc = lahar_transport_open("memq://", err, sizeof err);
    if (!ta || !tb || !tc) {
        fprintf(stderr, "memq: %s\n", err);
        return 1;
    }
    lossy la = {ta, 3, 0, 0}, lb = {tb, 5, 0, 0};
    lahar_transport wa = {&lossy_ops, &la}, wb = {&lossy_ops, &lb};
    sender_link = lahar_link_create(&wa, LAHAR_ROLE_DEM, RUN, LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_STATUS), err, sizeof err);
    lahar_link *rx = lahar_link_create(&wb, LAHAR_ROLE_COORDINATOR, RUN, LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_LOADS), err,
                                       sizeof err);
    lahar_link *other = lahar_link_create(tc, LAHAR_ROLE_SPH, RUN + 1, 0, err, sizeof err);
    if (!sender_link || !rx || !other)
        return 1;

    /* another run on the same bus: must never be delivered */
    uint8_t junk[64] = {1, 2, 3};
    lahar_link_send(other, LAHAR_FRAME_T_MSG_LOADS, 0, junk, sizeof junk);

    pthread_t th;
    pthread_create(&th, NULL, sender_main, NULL);
    lahar_link_watch(rx, LAHAR_ROLE_DEM, 10.0);
    uint8_t *expect = malloc(3 * LAHAR_FRAME_PAYLOAD + 1234);
    for (int k = 0; k < NMSG; k++) {
        lahar_link_msg m;
        int rc = lahar_link_wait(rx, LAHAR_ROLE_DEM, LAHAR_FRAME_T_MSG_LOADS, k, 10000, &m);
        CHECK(rc == LAHAR_LINK_OK, "message %d not received (rc %d)", k, rc);
        if (rc != LAHAR_LINK_OK)
            break;
        int size = msg_size(k);
        msg_fill(expect, k, size);
        CHECK(m.size == size && memcmp(m.data, expect, (size_t)size) == 0, "message %d corrupted (size %d, expected %d)",
              k, m.size, size);
        uint8_t ack[16] = {(uint8_t)k};
        lahar_link_send(rx, LAHAR_FRAME_T_MSG_STATUS, k, ack, sizeof ack);
    }
    /* keep serving NACKs for the last acknowledgement while the sender finishes */
    lahar_link_poll(rx, 300);
    pthread_join(th, NULL);
    lahar_link_msg m;
    CHECK(!lahar_link_take(rx, LAHAR_ROLE_DEM, LAHAR_FRAME_T_MSG_LOADS, LAHAR_LINK_ANY_STEP, &m),
          "a message was delivered twice (step %lld)", (long long)m.step);
    CHECK(!lahar_link_take(rx, LAHAR_ROLE_SPH, LAHAR_FRAME_T_MSG_LOADS, LAHAR_LINK_ANY_STEP, &m),
          "a message of another run was delivered");

    lahar_link_stats sa[LAHAR_NMSG], sb[LAHAR_NMSG];
    lahar_link_get_stats(sender_link, sa);
    lahar_link_get_stats(rx, sb);
    uint64_t resent = sa[LAHAR_FRAME_T_MSG_LOADS].frames_resent;
    printf("link: %d messages, %d + %d datagrams dropped, %llu LOADS frames re-sent, %llu NACKs for LOADS\n", NMSG,
           la.dropped, lb.dropped, (unsigned long long)resent, (unsigned long long)sb[LAHAR_FRAME_T_MSG_LOADS].nacks_sent);
    CHECK(la.dropped > 0 && lb.dropped > 0, "the lossy transport dropped nothing");
    CHECK(resent > 0, "no frame was re-sent although frames were dropped");

    free(expect);
    lahar_link_destroy(sender_link);
    lahar_link_destroy(rx);
    lahar_link_destroy(other);
    lahar_transport_close(ta);
    lahar_transport_close(tb);
    lahar_transport_close(tc);
    if (failures)
        return 1;
    printf("PASS test_coupling_link\n");
    return 0;
}
