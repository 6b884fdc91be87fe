#!/usr/bin/env bash
# Runs CMD in a new network namespace whose only interface is loopback, set up for DDS
# discovery, so that no DDS packet can leave the machine (issue 47: every ROS 2 / DDS test
# and script runs this way). Usage: scripts/in-netns.sh CMD [ARG...]; CMD's exit status
# is returned. Needs root (CI and the developers' machines are root).
#
# In the namespace (unshare --net --mount):
#   ip link set lo up
#   ip link set lo multicast on       lo has no MULTICAST flag by default, and RustDDS 0.15
#                                     multicasts its discovery only on interfaces with it:
#                                     without it, a Cyclone DDS peer that started first did not
#                                     find a RustDDS node that came 2 s later (in 8 s); Fast DDS
#                                     and Cyclone DDS work either way
#   ip route add 224.0.0.0/4 dev lo src 127.0.0.1
#                                     multicast sent or joined without naming an interface
#                                     (INADDR_ANY) goes to lo, from 127.0.0.1 (without a route
#                                     such a join fails with ENODEV; without src the source
#                                     address is 0.0.0.0)
#   a private tmpfs on /dev/shm       /dev/shm is not per network namespace: Fast DDS's
#                                     shared-memory ports (fastrtps_port74xx) and participant
#                                     ids would be shared with every other namespace on the
#                                     machine, and segments of killed peers would be left there
# Processes that CMD leaves running stay in the namespace until they exit: stop them in CMD.
set -euo pipefail

if [[ $# -eq 0 || $1 == -h || $1 == --help ]]; then
    sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//' >&2
    exit 2
fi
for tool in unshare ip mount; do
    command -v "$tool" >/dev/null || { echo "in-netns: $tool not found (util-linux, iproute2)" >&2; exit 1; }
done

exec unshare --net --mount --propagation private -- bash -c '
    set -euo pipefail
    ip link set lo up
    ip link set lo multicast on
    ip route add 224.0.0.0/4 dev lo src 127.0.0.1
    if [[ -d /dev/shm ]]; then
        mount -t tmpfs -o mode=1777,nosuid,nodev,size=1g in-netns-shm /dev/shm
    fi
    exec "$@"' in-netns "$@"
