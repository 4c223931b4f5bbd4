/* Private user + network namespace (see netns.h). Plain syscalls and ioctls; no `ip` needed. */
#define _GNU_SOURCE
#include "netns.h"
#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <net/if.h>
#include <net/route.h>
#include <netinet/in.h>
#include <sched.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

static int netns_write_file(const char *path, const char *text)
{
    int fd = open(path, O_WRONLY | O_CLOEXEC);
    if (fd < 0)
        return -1;
    size_t n = strlen(text);
    int rc = write(fd, text, n) == (ssize_t)n ? 0 : -1;
    close(fd);
    return rc;
}

static int netns_read_int(const char *path, int *value)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return -1;
    int rc = fscanf(f, "%d", value) == 1 ? 0 : -1;
    fclose(f);
    return rc;
}

int lahar_netns_setup_loopback(char *err, size_t errlen)
{
    int fd = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (fd < 0) {
        snprintf(err, errlen, "socket: %s", strerror(errno));
        return -1;
    }
    struct ifreq ifr;
    memset(&ifr, 0, sizeof ifr);
    snprintf(ifr.ifr_name, sizeof ifr.ifr_name, "lo");
    if (ioctl(fd, SIOCGIFFLAGS, &ifr) != 0) {
        snprintf(err, errlen, "reading the flags of lo: %s", strerror(errno));
        close(fd);
        return -1;
    }
    ifr.ifr_flags |= IFF_UP | IFF_MULTICAST;
    if (ioctl(fd, SIOCSIFFLAGS, &ifr) != 0) {
        snprintf(err, errlen, "bringing lo up with multicast: %s", strerror(errno));
        close(fd);
        return -1;
    }
    /* 224.0.0.0/4 via lo: without it a namespace with only lo has no route for multicast. */
    struct rtentry rt;
    memset(&rt, 0, sizeof rt);
    struct sockaddr_in *dst = (struct sockaddr_in *)&rt.rt_dst;
    struct sockaddr_in *mask = (struct sockaddr_in *)&rt.rt_genmask;
    dst->sin_family = AF_INET;
    dst->sin_addr.s_addr = htonl(0xE0000000u);
    mask->sin_family = AF_INET;
    mask->sin_addr.s_addr = htonl(0xF0000000u);
    rt.rt_flags = RTF_UP;
    rt.rt_dev = ifr.ifr_name;
    if (ioctl(fd, SIOCADDRT, &rt) != 0 && errno != EEXIST) {
        snprintf(err, errlen, "adding the route 224.0.0.0/4 dev lo: %s", strerror(errno));
        close(fd);
        return -1;
    }
    close(fd);
    return 0;
}

int lahar_netns_enter(char *err, size_t errlen)
{
    uid_t uid = getuid();
    gid_t gid = getgid();
    if (unshare(CLONE_NEWUSER | CLONE_NEWNET) != 0) {
        int e = errno;
        int userns_clone = -1, max_userns = -1, apparmor = -1;
        netns_read_int("/proc/sys/kernel/unprivileged_userns_clone", &userns_clone);
        netns_read_int("/proc/sys/user/max_user_namespaces", &max_userns);
        netns_read_int("/proc/sys/kernel/apparmor_restrict_unprivileged_userns", &apparmor);
        const char *why = "";
        if (userns_clone == 0)
            why = " kernel.unprivileged_userns_clone is 0: enable it with `sudo sysctl -w kernel.unprivileged_userns_clone=1`.";
        else if (apparmor == 1)
            why = " AppArmor restricts unprivileged user namespaces: `sudo sysctl -w kernel.apparmor_restrict_unprivileged_userns=0`"
                  " (or an AppArmor profile allowing userns for lahar).";
        else if (max_userns == 0)
            why = " user.max_user_namespaces is 0: `sudo sysctl -w user.max_user_namespaces=15000`.";
        else if (e == ENOSPC)
            why = " The limit of user namespaces is reached (user.max_user_namespaces, or 32 nested levels):"
                  " raise it with `sudo sysctl -w user.max_user_namespaces=15000` or run lahar less deeply nested.";
        else if (e == EINVAL)
            why = " (the process already runs threads, or the kernel lacks user namespaces).";
        else if (e == EPERM)
            why = " (inside a container, run it with user namespaces allowed, e.g. a seccomp profile permitting unshare).";
        snprintf(err, errlen,
                 "cannot create a private network namespace: unshare(CLONE_NEWUSER|CLONE_NEWNET): %s.%s "
                 "Alternatives: `lahar run --in-process` (one process, no network), or "
                 "`--lcm-url URL` to use a network you set up yourself.",
                 strerror(e), why);
        return -1;
    }
    char map[64];
    /* setgroups must be denied before an unprivileged process may write gid_map. */
    netns_write_file("/proc/self/setgroups", "deny");
    snprintf(map, sizeof map, "0 %u 1\n", (unsigned)uid);
    if (netns_write_file("/proc/self/uid_map", map) != 0) {
        snprintf(err, errlen, "writing /proc/self/uid_map in the new user namespace: %s", strerror(errno));
        return -1;
    }
    snprintf(map, sizeof map, "0 %u 1\n", (unsigned)gid);
    if (netns_write_file("/proc/self/gid_map", map) != 0) {
        snprintf(err, errlen, "writing /proc/self/gid_map in the new user namespace: %s", strerror(errno));
        return -1;
    }
    return lahar_netns_setup_loopback(err, errlen);
}
