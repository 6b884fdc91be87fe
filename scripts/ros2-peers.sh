#!/usr/bin/env bash
# The ROS 2 peers of issue 47's interop tests, with no ROS installation: rclpy of ROS 2 Jazzy
# on Fast DDS (rmw_fastrtps_cpp) and Cyclone DDS's Python binding, from PyPI, every wheel
# pinned by version and sha256 in scripts/ros2-peers.txt (x86-64; CPython 3.11 or 3.12).
#
# Usage:
#   scripts/ros2-peers.sh [install]   installs them into target/ros2-peers/venv unless the
#                                     same pins are already installed there (then does
#                                     nothing), writes target/ros2-peers/env.sh and prints
#                                     its path
#   scripts/ros2-peers.sh env         installs if needed, prints the lines of env.sh
#   scripts/ros2-peers.sh run CMD...  installs if needed, runs CMD with that environment in a
#                                     network namespace of its own (scripts/in-netns.sh)
#   scripts/ros2-peers.sh selftest    installs if needed, runs scripts/ros2-peers-selftest.py
#                                     that way (rclpy topic, graph and service; Cyclone DDS)
#   scripts/ros2-peers.sh pin         re-resolves the top-level pins below on PyPI and
#                                     rewrites scripts/ros2-peers.txt (a maintainer's step)
# Environment: PYTHON (default python3), ROS2_PEERS_DIR (default target/ros2-peers).
#
# The venv's interpreter finds the wheels' shared libraries itself (ros-wheels-bootstrapper
# re-executes it with LD_LIBRARY_PATH set), so a test runs "$ROS2_PEERS_PYTHON" script.py
# with env.sh's variables and needs no LD_LIBRARY_PATH or AMENT_PREFIX_PATH of its own
# (never export the wheels' LD_LIBRARY_PATH to the daemon or cargo). env.sh sets:
#   ROS2_PEERS_PYTHON            the venv's python
#   RMW_IMPLEMENTATION           rmw_fastrtps_cpp (the only RMW installed; said explicitly)
#   FASTDDS_BUILTIN_TRANSPORTS   UDPv4: Fast DDS otherwise adds shared memory between
#                                processes of one host; UDP alone is what RustDDS and Cyclone
#                                speak, and what tcpdump sees (never set it empty: Fast DDS
#                                logs an error and uses its default)
#   ROS_LOG_DIR                  target/ros2-peers/log instead of ~/.ros/log
set -euo pipefail

TOP=(
    'ros-jazzy-rclpy[fastrtps]==7.1.6'
    'ros-jazzy-sensor-msgs==5.3.6'
    'ros-jazzy-geometry-msgs==5.3.6'
    'ros-jazzy-nav-msgs==5.3.6'
    'ros-jazzy-diagnostic-msgs==5.3.6'
    'ros-jazzy-std-srvs==5.3.6'
    'cyclonedds==11.0.1'
)
PY_VERSIONS=(3.11 3.12)  # the wheels whose hashes scripts/ros2-peers.txt lists

root=$(cd "$(dirname "$0")/.." && pwd)
req=$root/scripts/ros2-peers.txt
dir=${ROS2_PEERS_DIR:-$root/target/ros2-peers}
venv=$dir/venv
python=${PYTHON:-python3}
pip_quiet=(-q --disable-pip-version-check --no-input)
# Every module the interop tests import: an install that cannot import them is not one.
# (tf2_msgs is not on PyPI: /tf is read with Cyclone DDS, the type declared in Python.)
IMPORTS='import rclpy, rclpy.parameter_client, cyclonedds.domain, rcl_interfaces.msg'
IMPORTS+=', sensor_msgs.msg, geometry_msgs.msg, nav_msgs.msg, diagnostic_msgs.msg, std_srvs.srv'

log() { echo "ros2-peers: $*" >&2; }

pin() {
    local work
    work=$(mktemp -d)
    trap 'rm -rf "$work"' RETURN
    log "resolving ${TOP[*]} for CPython ${PY_VERSIONS[0]}"
    "$python" -m pip download "${pip_quiet[@]}" -d "$work/resolved" "${TOP[@]}" >&2
    # The full, resolved list of name==version, then every listed version's wheels for
    # each Python version (empy is an sdist only: one hash for all).
    "$python" - "$work/resolved" >"$work/pins.txt" <<'PY'
import os, re, sys
for f in sorted(os.listdir(sys.argv[1])):
    n, v = (f.split("-")[:2] if f.endswith(".whl") else f[:-len(".tar.gz")].rsplit("-", 1))
    print(f"{re.sub(r'[-_.]+', '-', n).lower()}=={v}")
PY
    for v in "${PY_VERSIONS[@]}"; do
        log "wheels for CPython $v"
        grep -v '^empy==' "$work/pins.txt" >"$work/wheels.txt"
        "$python" -m pip download "${pip_quiet[@]}" --no-deps --only-binary=:all: \
            --python-version "$v" --implementation cp --abi "cp${v/./}" --abi abi3 --abi none \
            --platform manylinux_2_28_x86_64 --platform manylinux_2_27_x86_64 \
            --platform manylinux_2_17_x86_64 --platform manylinux2014_x86_64 --platform any \
            -d "$work/cp$v" -r "$work/wheels.txt" >&2
    done
    cp "$work"/resolved/empy-*.tar.gz "$work/cp${PY_VERSIONS[0]}/"
    {
        echo "# Written by scripts/ros2-peers.sh pin: ${TOP[*]}"
        echo "# and all their dependencies, resolved on PyPI on $(date -u +%Y-%m-%d); wheels for"
        echo "# x86-64 CPython ${PY_VERSIONS[*]}. Installed with pip --require-hashes by scripts/ros2-peers.sh."
        "$python" - "$work" "${PY_VERSIONS[@]}" <<'PY'
import hashlib, os, re, sys
work, versions = sys.argv[1], sys.argv[2:]
hashes = {}
for v in versions:
    d = os.path.join(work, "cp" + v)
    for f in sorted(os.listdir(d)):
        n, ver = (f.split("-")[:2] if f.endswith(".whl") else f[:-len(".tar.gz")].rsplit("-", 1))
        key = f"{re.sub(r'[-_.]+', '-', n).lower()}=={ver}"
        with open(os.path.join(d, f), "rb") as fh:
            hashes.setdefault(key, {})[f] = hashlib.sha256(fh.read()).hexdigest()
for key in sorted(hashes):
    lines = [key] + [f"    --hash=sha256:{h}" for _, h in sorted(hashes[key].items())]
    print(" \\\n".join(lines))
PY
    } >"$req"
    log "wrote $req ($(grep -c '==' "$req") packages)"
}

# The lines of the requirements file for one package (its name==version and hash lines).
req_block() {
    awk -v name="$1" '
        $0 ~ "^" name "==" { on = 1 }
        on { print; if ($0 !~ /\\$/) exit }' "$req"
}

# One install at a time: tests run the peers in parallel, each through `run`.
install() {
    mkdir -p "$dir"
    exec {lock}>"$dir/.install.lock"
    flock "$lock"
    install_locked
    flock -u "$lock"
    exec {lock}>&-
}

install_locked() {
    [[ $(uname -m) == x86_64 ]] || { log "the pinned wheels are x86-64 only ($(uname -m))"; exit 1; }
    local pyver stamp
    pyver=$("$python" -c 'import sys; print("%d.%d" % sys.version_info[:2])')
    [[ " ${PY_VERSIONS[*]} " == *" $pyver "* ]] ||
        { log "$python is CPython $pyver; the pins cover ${PY_VERSIONS[*]} (set PYTHON)"; exit 1; }
    stamp="$(sha256sum <"$req" | cut -d' ' -f1) python $pyver $("$python" -c 'import sys; print(sys.base_prefix)')"
    if [[ -f $venv/ros2-peers.stamp && $(cat "$venv/ros2-peers.stamp") == "$stamp" ]] &&
        "$venv/bin/python" -c "$IMPORTS" 2>/dev/null; then
        write_env
        return
    fi
    local start=$SECONDS
    log "installing the pinned ROS 2 peers into $venv"
    rm -rf "$venv"
    mkdir -p "$dir"
    "$python" -m venv "$venv"
    # empy (needed by rosidl_adapter's metadata, never at run time) is an sdist: it is built
    # without build isolation, with the pinned setuptools, so that nothing unhashed is fetched.
    "$venv/bin/python" -m pip install "${pip_quiet[@]}" --require-hashes --no-deps \
        --only-binary=:all: -r <(req_block setuptools) >&2
    "$venv/bin/python" -m pip install "${pip_quiet[@]}" --require-hashes --no-build-isolation \
        --only-binary=:all: --no-binary=empy -r "$req" >&2
    "$venv/bin/python" -c "$IMPORTS"
    echo "$stamp" >"$venv/ros2-peers.stamp"
    log "installed in $((SECONDS - start)) s, $(du -sh "$venv" | cut -f1)"
    write_env
}

write_env() {
    mkdir -p "$dir/log"
    cat >"$dir/env.sh.$$" <<EOF
# Written by scripts/ros2-peers.sh: the environment of the ROS 2 peers (rclpy on Fast DDS,
# Cyclone DDS). Run the peers as "\$ROS2_PEERS_PYTHON" script.py, inside scripts/in-netns.sh.
export ROS2_PEERS_PYTHON='$venv/bin/python'
export RMW_IMPLEMENTATION=rmw_fastrtps_cpp
export FASTDDS_BUILTIN_TRANSPORTS=UDPv4
export ROS_LOG_DIR='$dir/log'
EOF
    mv "$dir/env.sh.$$" "$dir/env.sh"
}

case ${1:-install} in
    install)
        install
        echo "$dir/env.sh"
        ;;
    env)
        install
        grep '^export' "$dir/env.sh"
        ;;
    run)
        shift
        [[ $# -gt 0 ]] || { log "run: no command"; exit 2; }
        install
        # shellcheck source=/dev/null
        . "$dir/env.sh"
        exec "$root/scripts/in-netns.sh" "$@"
        ;;
    selftest)
        install
        # shellcheck source=/dev/null
        . "$dir/env.sh"
        exec "$root/scripts/in-netns.sh" "$ROS2_PEERS_PYTHON" "$root/scripts/ros2-peers-selftest.py"
        ;;
    pin)
        pin
        ;;
    -h | --help)
        sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'
        ;;
    *)
        log "unknown command $1 (install, env, run, selftest, pin)"
        exit 2
        ;;
esac
