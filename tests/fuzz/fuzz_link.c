/* Harness: the receive path of the link layer (common/protocol/link.c): frame parsing, the MAC check of
 * authenticated runs, run-id adoption, reassembly slots, the duplicate window, heartbeats and
 * NACKs (answered from kept copies), and the typed decoder of every message it completes.
 *
 * The link runs over a transport of this file (the function table of common/protocol/transport.h) that
 * hands it the input's datagrams one at a time; nothing touches a socket. Input:
 *   byte 0      configuration: role = bits 0-1 (mod 3), bit 2 authenticated (fuzz_auth_key),
 *               bit 3 run id known (else adopted from the first coordinator HELLO)
 *   then records, each an op byte:
 *     op < 0xc0   a datagram: 2 bytes length (little-endian, cut to what is left), the bytes
 *     op >= 0xc0  take a complete message: sender op % 3, type (op >> 2) % 10, any step; its
 *                 bytes go through that type's decoder (fuzz_decode.c)
 * tests/fuzz/make_seeds.c writes inputs in this format from the frames of real messages. */
#include <stdlib.h>
#include <string.h>
#include "fuzz.h"
#include "link.h"

#define FUZZ_RUN_ID 0x1a2b3c4d5e6fLL

typedef struct {
    lahar_transport_recv_fn fn;
    void *user;
    const uint8_t *pending;
    size_t npending;
    int has_pending;
    long published;
} fuzz_transport;

static void *ft_open(const char *url, char *err, size_t errlen)
{
    (void)url;
    (void)err;
    (void)errlen;
    return NULL;
}

static int ft_publish(void *impl, const char *channel, const void *data, size_t size)
{
    (void)channel;
    (void)data;
    (void)size;
    ((fuzz_transport *)impl)->published++;
    return 0;
}

static int ft_subscribe(void *impl, const char *regex, int cap, lahar_transport_recv_fn fn, void *user)
{
    (void)regex;
    (void)cap;
    fuzz_transport *t = impl;
    t->fn = fn;
    t->user = user;
    return 0;
}

static int ft_handle(void *impl, int timeout_ms)
{
    (void)timeout_ms;
    fuzz_transport *t = impl;
    if (!t->has_pending || !t->fn)
        return 0;
    t->has_pending = 0;
    /* a datagram of its exact size, so that ASan sees a read past its end */
    uint8_t *copy = malloc(t->npending ? t->npending : 1);
    if (!copy)
        return -1;
    memcpy(copy, t->pending, t->npending);
    t->fn("LAHAR_FUZZ", copy, t->npending, t->user);
    free(copy);
    return 1;
}

static void ft_close(void *impl) { (void)impl; }

static const lahar_transport_ops fuzz_ops = {"fuzz://", ft_open, ft_publish, ft_subscribe, ft_handle, ft_close};

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1 || size > (1u << 22))
        return 0;
    fuzz_transport ft;
    memset(&ft, 0, sizeof ft);
    lahar_transport t = {&fuzz_ops, &ft};
    int role = (data[0] & 3) % 3;
    char err[256];
    unsigned want = 0;
    for (int ty = 1; ty < LAHAR_NMSG; ty++)
        want |= LAHAR_MSG_BIT(ty);
    lahar_link *l = lahar_link_create(&t, role, (data[0] & 8) ? FUZZ_RUN_ID : 0, want, err, sizeof err);
    FUZZ_ASSERT(l != NULL);
    if (data[0] & 4)
        lahar_link_set_auth_key(l, fuzz_auth_key);
    /* kept copies for NACKs to ask for: one small message per type at steps 0 and 1 */
    static const uint8_t body[64];
    for (int ty = 1; ty <= 7; ty++)
        for (int k = 0; k < 2; k++)
            lahar_link_send(l, ty, k, body, 8 * ty);
    size_t pos = 1;
    while (pos < size) {
        uint8_t op = data[pos++];
        if (op < 0xc0) {
            size_t len = 0;
            if (pos + 2 <= size) {
                len = (size_t)data[pos] | ((size_t)data[pos + 1] << 8);
                pos += 2;
            } else {
                pos = size;
            }
            if (len > size - pos)
                len = size - pos;
            ft.pending = data + pos;
            ft.npending = len;
            ft.has_pending = 1;
            pos += len;
            lahar_link_poll(l, 0);
            FUZZ_ASSERT(!ft.has_pending);
        } else {
            lahar_link_msg m;
            int sender = op % 3, type = (op >> 2) % 10;
            if (lahar_link_take(l, sender, type, LAHAR_LINK_ANY_STEP, &m)) {
                FUZZ_ASSERT(m.sender == sender && m.type == type && m.size >= 0);
                fuzz_decode_message(type, m.data, m.size);
            }
        }
    }
    lahar_link_destroy(l);
    return 0;
}
