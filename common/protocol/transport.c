/* LCM behind the transport table: udpm:// (processes, multicast inside a private network
 * namespace, see common/protocol/netns.h) and memq:// (threads of one process). */
#include "transport.h"
#include <lcm/lcm.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- shared by both: one lcm_t per endpoint ------------------------------------------------ */
typedef struct {
    lcm_t *lcm;
    lahar_transport_recv_fn fn;
    void *user;
} lcm_endpoint;

static void lcm_endpoint_dispatch(const lcm_recv_buf_t *rbuf, const char *channel, void *user)
{
    lcm_endpoint *ep = user;
    ep->fn(channel, rbuf->data, rbuf->data_size, ep->user);
}

static int lcm_endpoint_subscribe(void *impl, const char *regex, int queue_capacity,
                                  lahar_transport_recv_fn fn, void *user)
{
    lcm_endpoint *ep = impl;
    ep->fn = fn;
    ep->user = user;
    lcm_subscription_t *s = lcm_subscribe(ep->lcm, regex, lcm_endpoint_dispatch, ep);
    if (!s)
        return -1;
    /* LCM drops what does not fit in a subscription's queue; bursts of frames need room. */
    if (queue_capacity > 0)
        lcm_subscription_set_queue_capacity(s, queue_capacity);
    return 0;
}

static int lcm_endpoint_handle(void *impl, int timeout_ms)
{
    lcm_endpoint *ep = impl;
    int r = lcm_handle_timeout(ep->lcm, timeout_ms < 0 ? 0 : timeout_ms);
    return r > 0 ? 1 : (r == 0 ? 0 : -1);
}

static lcm_endpoint *lcm_endpoint_new(const char *url, char *err, size_t errlen)
{
    lcm_endpoint *ep = calloc(1, sizeof *ep);
    if (!ep) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    ep->lcm = lcm_create(url);
    if (!ep->lcm) {
        snprintf(err, errlen, "lcm_create(\"%s\") failed (is there a route for multicast? see lahar run --help)", url);
        free(ep);
        return NULL;
    }
    return ep;
}

static void lcm_endpoint_free(lcm_endpoint *ep)
{
    if (ep) {
        lcm_destroy(ep->lcm);
        free(ep);
    }
}

/* ---- udpm:// ------------------------------------------------------------------------------- */
static void *udpm_open(const char *url, char *err, size_t errlen) { return lcm_endpoint_new(url, err, errlen); }
static int udpm_publish(void *impl, const char *channel, const void *data, size_t size)
{
    lcm_endpoint *ep = impl;
    return lcm_publish(ep->lcm, channel, data, (unsigned)size) == 0 ? 0 : -1;
}
static void udpm_close(void *impl) { lcm_endpoint_free(impl); }

static const lahar_transport_ops udpm_ops = {
    "udpm://", udpm_open, udpm_publish, lcm_endpoint_subscribe, lcm_endpoint_handle, udpm_close,
};

/* ---- memq:// ------------------------------------------------------------------------------- */
/* LCM's memq provider only delivers to the lcm_t it was published on, so a hub fans every
 * message out to all endpoints of the process (like multicast: the sender hears itself too).
 * Publishing under one lock gives every endpoint the same global order. */
#define MEMQ_MAX_ENDPOINTS 16
static pthread_mutex_t memq_lock = PTHREAD_MUTEX_INITIALIZER;
static lcm_endpoint *memq_endpoints[MEMQ_MAX_ENDPOINTS];

static void *memq_open(const char *url, char *err, size_t errlen)
{
    (void)url;
    lcm_endpoint *ep = lcm_endpoint_new("memq://", err, errlen);
    if (!ep)
        return NULL;
    pthread_mutex_lock(&memq_lock);
    int slot = -1;
    for (int i = 0; i < MEMQ_MAX_ENDPOINTS && slot < 0; i++)
        if (!memq_endpoints[i])
            slot = i;
    if (slot >= 0)
        memq_endpoints[slot] = ep;
    pthread_mutex_unlock(&memq_lock);
    if (slot < 0) {
        snprintf(err, errlen, "memq://: more than %d endpoints in one process", MEMQ_MAX_ENDPOINTS);
        lcm_endpoint_free(ep);
        return NULL;
    }
    return ep;
}

static int memq_publish(void *impl, const char *channel, const void *data, size_t size)
{
    (void)impl;
    int rc = 0;
    pthread_mutex_lock(&memq_lock);
    for (int i = 0; i < MEMQ_MAX_ENDPOINTS; i++)
        if (memq_endpoints[i] && lcm_publish(memq_endpoints[i]->lcm, channel, data, (unsigned)size) != 0)
            rc = -1;
    pthread_mutex_unlock(&memq_lock);
    return rc;
}

static void memq_close(void *impl)
{
    pthread_mutex_lock(&memq_lock);
    for (int i = 0; i < MEMQ_MAX_ENDPOINTS; i++)
        if (memq_endpoints[i] == impl)
            memq_endpoints[i] = NULL;
    pthread_mutex_unlock(&memq_lock);
    lcm_endpoint_free(impl);
}

static const lahar_transport_ops memq_ops = {
    "memq://", memq_open, memq_publish, lcm_endpoint_subscribe, lcm_endpoint_handle, memq_close,
};

/* ---- selection ----------------------------------------------------------------------------- */
static const lahar_transport_ops *const transport_impls[] = {&udpm_ops, &memq_ops};

lahar_transport *lahar_transport_open(const char *url, char *err, size_t errlen)
{
    const lahar_transport_ops *ops = NULL;
    for (size_t i = 0; i < sizeof transport_impls / sizeof transport_impls[0]; i++)
        if (strncmp(url, transport_impls[i]->scheme, strlen(transport_impls[i]->scheme)) == 0)
            ops = transport_impls[i];
    if (!ops) {
        snprintf(err, errlen, "unsupported LCM URL '%s' (lahar speaks udpm:// and memq://)", url);
        return NULL;
    }
    lahar_transport *t = calloc(1, sizeof *t);
    if (!t) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    t->ops = ops;
    t->impl = ops->open(url, err, errlen);
    if (!t->impl) {
        free(t);
        return NULL;
    }
    return t;
}

void lahar_transport_close(lahar_transport *t)
{
    if (t) {
        t->ops->close(t->impl);
        free(t);
    }
}
