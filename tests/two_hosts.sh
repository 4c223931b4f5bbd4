# Two "hosts" for the runs across machines, sourced (`. two_hosts.sh`) by a bash that already runs
# in a private user + network namespace (`unshare --user --map-root-user --net`): host A is that
# namespace, host B a network namespace inside it (a sleeping process holds it), joined by the
# veth pair lahar_a (10.231.7.1) - lahar_b (10.231.7.2), each end up with multicast on and
# 224.0.0.0/4 routed through it, lo up on both. Nothing leaves the private namespace.
# Sets host_b (the pid holding host B; killed on exit) and host_b_ns, its network namespace: a
# process started with `nsenter --net=$host_b_ns CMD &` runs in host B, and $! is CMD's own pid
# (nsenter execs it), so the caller can signal it.
ip link set lo up
unshare --net sleep 600 &
host_b=$!
trap 'kill $host_b 2>/dev/null' EXIT
for _ in $(seq 50); do # until the sleeper is in its own namespace
    [ "$(readlink /proc/$host_b/ns/net)" != "$(readlink /proc/self/ns/net)" ] && break
    sleep 0.02
done
ip link add lahar_a type veth peer name lahar_b netns $host_b
ip addr add 10.231.7.1/24 dev lahar_a
ip link set lahar_a up multicast on
ip route add 224.0.0.0/4 dev lahar_a
host_b_ns=/proc/$host_b/ns/net
nsenter --net=$host_b_ns sh -c '
    ip link set lo up
    ip addr add 10.231.7.2/24 dev lahar_b
    ip link set lahar_b up multicast on
    ip route add 224.0.0.0/4 dev lahar_b'
