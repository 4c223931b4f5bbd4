/* A private network namespace for one lahar run, so that LCM multicast never leaves the host
 * and two runs on one machine never hear each other. */
#ifndef LAHAR_NETNS_H
#define LAHAR_NETNS_H
#include <stddef.h>

/* The URL used inside the private namespace: ttl=0 keeps datagrams on the host, an 8 MB receive
 * buffer absorbs bursts of frames (the kernel caps it at net.core.rmem_max). */
#define LAHAR_NETNS_URL "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608"

/* unshare(CLONE_NEWUSER | CLONE_NEWNET) with the caller mapped to root inside, then lo up with
 * multicast on and a route 224.0.0.0/4 via lo. Must be called before any thread is created.
 * Processes forked afterwards inherit the namespace. Returns 0, or -1 with an explanation and
 * the way out (sysctl, --in-process) in err. */
int lahar_netns_enter(char *err, size_t errlen);

/* Bring lo up with multicast and add the multicast route in the current network namespace
 * (what lahar_netns_enter does after unshare). 0 or -1 with err. */
int lahar_netns_setup_loopback(char *err, size_t errlen);

#endif
