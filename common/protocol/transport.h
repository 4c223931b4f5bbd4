/* The byte transport under the lahar protocol: a small table of function pointers so that the
 * link layer (common/protocol/link.h) does not care whether messages travel as UDP multicast between
 * processes (LCM udpm://) or between threads of one process (LCM memq://, fanned out by an
 * in-process hub). Both implementations sit on liblcm; only the link layer calls this. */
#ifndef LAHAR_TRANSPORT_H
#define LAHAR_TRANSPORT_H
#include <stddef.h>

typedef void (*lahar_transport_recv_fn)(const char *channel, const void *data, size_t size, void *user);

typedef struct lahar_transport lahar_transport;

typedef struct {
    const char *scheme; /* URL prefix this implementation serves, e.g. "udpm://" */
    /* Open an endpoint; NULL and a message in err on failure. */
    void *(*open)(const char *url, char *err, size_t errlen);
    /* Send one datagram-sized message on a channel; 0 on success. Thread safe. */
    int (*publish)(void *impl, const char *channel, const void *data, size_t size);
    /* Deliver every message whose channel matches the regex to fn (called from handle()).
     * queue_capacity: messages kept while nobody calls handle(). 0 on success. */
    int (*subscribe)(void *impl, const char *channel_regex, int queue_capacity,
                     lahar_transport_recv_fn fn, void *user);
    /* Dispatch at most one waiting message, waiting up to timeout_ms for one.
     * Returns 1 if a message was dispatched, 0 on timeout, -1 on error. */
    int (*handle)(void *impl, int timeout_ms);
    void (*close)(void *impl);
} lahar_transport_ops;

struct lahar_transport {
    const lahar_transport_ops *ops;
    void *impl;
};

/* Pick the implementation from the URL scheme ("udpm://...", "memq://"). NULL on failure. */
lahar_transport *lahar_transport_open(const char *url, char *err, size_t errlen);
void lahar_transport_close(lahar_transport *t);

static inline int lahar_transport_publish(lahar_transport *t, const char *channel, const void *data, size_t size)
{
    return t->ops->publish(t->impl, channel, data, size);
}
static inline int lahar_transport_subscribe(lahar_transport *t, const char *regex, int queue_capacity,
                                            lahar_transport_recv_fn fn, void *user)
{
    return t->ops->subscribe(t->impl, regex, queue_capacity, fn, user);
}
static inline int lahar_transport_handle(lahar_transport *t, int timeout_ms)
{
    return t->ops->handle(t->impl, timeout_ms);
}

#endif
