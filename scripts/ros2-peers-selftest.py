#!/usr/bin/env python3
"""Self-test of the ROS 2 peers that issue 47's interop tests use (scripts/ros2-peers.sh).

Usage (inside a network namespace, never on the host's network):
    scripts/ros2-peers.sh                      # installs the pinned peers once
    scripts/in-netns.sh python3 scripts/ros2-peers-selftest.py

Runs the peers as separate processes and checks, printing one line per check:
  netns      only `lo` exists, it is up with the MULTICAST flag, and multicast is routed to
             it (refuses otherwise: no DDS traffic may leave loopback)
  topic      an rclpy node publishes sensor_msgs/JointState on /joint_states and a second
             rclpy process receives it (names, positions, velocities, efforts, header)
  graph      the second process sees the first node by name (get_node_names) and the topic
             with its type (get_topic_names_and_types)
  service    a std_srvs/Trigger call from the second process is answered by the first
  parameter  the second process reads, sets and reads back a double parameter of the first
             (rcl_interfaces services via rclpy's AsyncParameterClient); a value the first
             node refuses comes back as a failed set result with its reason
  cyclonedds a Cyclone DDS reader (plain DDS, the ROS type declared as IDL dataclasses
             sensor_msgs::msg::dds_::JointState_ on rt/joint_states) reads the same messages
  cyclonedds_to_rclpy
             a Cyclone DDS writer of geometry_msgs::msg::dds_::Twist_ on rt/cmd_vel is read by
             the rclpy process as geometry_msgs/Twist on /cmd_vel
  transport  the UDP sockets the peers opened and whether Fast DDS used /dev/shm
Closes with 'N passed, N failed'; exits non-zero if any check failed.

When `import rclpy` fails it re-runs itself with the peers' interpreter, ROS2_PEERS_PYTHON or
target/ros2-peers/venv/bin/python, so `python3` may be any interpreter. The peers' own
environment (RMW_IMPLEMENTATION, FASTDDS_BUILTIN_TRANSPORTS, ROS_LOG_DIR) comes from
target/ros2-peers/env.sh; the venv's interpreter finds its libraries without LD_LIBRARY_PATH.
"""

import json
import os
import signal
import subprocess
import sys
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
NAMES = ["joint1", "joint2", "joint3"]
DOMAIN = int(os.environ.get("ROS_DOMAIN_ID", "0"))


def ensure_peers_python():
    try:
        import rclpy  # noqa: F401
        import cyclonedds  # noqa: F401
    except ImportError:
        py = os.environ.get("ROS2_PEERS_PYTHON") or os.path.join(
            ROOT, "target/ros2-peers/venv/bin/python")
        if not os.path.exists(py) or os.environ.get("_ROS2_PEERS_SELFTEST_REEXEC"):
            sys.exit(f"ros2-peers-selftest: rclpy/cyclonedds not importable and no peers "
                     f"interpreter at {py}: run scripts/ros2-peers.sh first")
        os.environ["_ROS2_PEERS_SELFTEST_REEXEC"] = "1"
        os.execv(py, [py, os.path.abspath(__file__)] + sys.argv[1:])


def emit(**kv):
    print(json.dumps(kv), flush=True)


def joint_state(node, i):
    from sensor_msgs.msg import JointState
    m = JointState()
    m.header.stamp = node.get_clock().now().to_msg()
    m.header.frame_id = "base_link"
    m.name = NAMES
    m.position = [0.1 * i, 0.2, -0.3]
    m.velocity = [1.0, 2.0, 3.0]
    m.effort = [-1.5, 0.0, 1.5]
    return m


def role_talker(seconds):
    """rclpy: publishes JointState at 50 Hz, serves std_srvs/Trigger and a parameter, until
    SIGTERM."""
    import rclpy
    from rcl_interfaces.msg import SetParametersResult
    from rclpy.signals import SignalHandlerOptions
    from sensor_msgs.msg import JointState
    from std_srvs.srv import Trigger

    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node("selftest_talker")
    pub = node.create_publisher(JointState, "/joint_states", 10)
    calls = []

    def on_trigger(_req, resp):
        calls.append(time.monotonic())
        resp.success = True
        resp.message = f"triggered {len(calls)}"
        return resp

    node.create_service(Trigger, "/selftest/trigger", on_trigger)

    node.declare_parameter("gain", 1.0)

    def on_set(params):
        for p in params:
            if p.name == "gain" and p.value < 0:
                return SetParametersResult(successful=False, reason="gain must be >= 0")
        return SetParametersResult(successful=True)

    node.add_on_set_parameters_callback(on_set)
    count = [0]

    def tick():
        count[0] += 1
        pub.publish(joint_state(node, count[0]))

    node.create_timer(0.02, tick)
    emit(role="talker", ready=True, rmw=rclpy.get_rmw_implementation_identifier())
    end = time.monotonic() + seconds
    while rclpy.ok() and time.monotonic() < end and not stop:
        rclpy.spin_once(node, timeout_sec=0.05)
    emit(role="talker", published=count[0], trigger_calls=len(calls))
    node.destroy_node()
    rclpy.shutdown()


def role_listener(seconds):
    """rclpy: receives JointState, looks at the graph, calls the Trigger service, gets and
    sets the talker's parameter, receives Cyclone DDS's Twist."""
    import rclpy
    from geometry_msgs.msg import Twist
    from rclpy.parameter import Parameter
    from rclpy.parameter_client import AsyncParameterClient
    from sensor_msgs.msg import JointState
    from std_srvs.srv import Trigger

    t0 = time.monotonic()
    rclpy.init()
    node = rclpy.create_node("selftest_listener")
    got = []
    first = []

    def on_msg(m):
        first or first.append(time.monotonic())
        got.append(m)

    node.create_subscription(JointState, "/joint_states", on_msg, 10)
    twists = []
    node.create_subscription(Twist, "/cmd_vel", twists.append, 10)
    deadline = t0 + seconds

    def spin_until(cond):
        while time.monotonic() < deadline and not cond():
            rclpy.spin_once(node, timeout_sec=0.05)
        return cond()

    ok = spin_until(lambda: len(got) >= 5)
    m = got[-1] if got else None
    emit(role="listener", check="topic", ok=ok and list(m.name) == NAMES
         and list(m.velocity) == [1.0, 2.0, 3.0] and list(m.effort) == [-1.5, 0.0, 1.5]
         and m.header.frame_id == "base_link" and m.header.stamp.sec > 0,
         received=len(got), first_after_s=round(first[0] - t0, 3) if first else None,
         sample=None if m is None else {"name": list(m.name), "position": list(m.position),
                                        "velocity": list(m.velocity), "effort": list(m.effort),
                                        "frame_id": m.header.frame_id,
                                        "stamp": [m.header.stamp.sec, m.header.stamp.nanosec]})

    ok = spin_until(lambda: "selftest_talker" in node.get_node_names())
    types = dict(node.get_topic_names_and_types())
    emit(role="listener", check="graph", ok=ok and types.get("/joint_states") == [
        "sensor_msgs/msg/JointState"], nodes=sorted(node.get_node_names()),
        joint_states_type=types.get("/joint_states"))

    cli = node.create_client(Trigger, "/selftest/trigger")
    t = time.monotonic()
    ready = cli.wait_for_service(timeout_sec=max(0.1, deadline - time.monotonic()))
    resp, tries = None, 0
    while ready and resp is None and time.monotonic() < deadline:
        tries += 1
        fut = cli.call_async(Trigger.Request())
        call_end = min(deadline, time.monotonic() + 3.0)
        while time.monotonic() < call_end and not fut.done():
            rclpy.spin_once(node, timeout_sec=0.05)
        if fut.done():
            resp = fut.result()
        else:
            cli.remove_pending_request(fut)
    emit(role="listener", check="service", ok=resp is not None and resp.success,
         tries=tries, seconds=round(time.monotonic() - t, 3),
         response=None if resp is None else {"success": resp.success, "message": resp.message})

    params = AsyncParameterClient(node, "selftest_talker")

    def wait(fut):
        spin_until(fut.done)
        return fut.result() if fut.done() else None

    detail = {}
    if params.wait_for_services(timeout_sec=max(0.1, deadline - time.monotonic())):
        got_before = wait(params.get_parameters(["gain"]))
        set_ok = wait(params.set_parameters([Parameter("gain", value=2.5)]))
        set_bad = wait(params.set_parameters([Parameter("gain", value=-1.0)]))
        got_after = wait(params.get_parameters(["gain"]))
        detail = {
            "before": got_before and got_before.values[0].double_value,
            "set_2.5": set_ok and [set_ok.results[0].successful, set_ok.results[0].reason],
            "set_-1": set_bad and [set_bad.results[0].successful, set_bad.results[0].reason],
            "after": got_after and got_after.values[0].double_value}
    emit(role="listener", check="parameter", ok=detail.get("before") == 1.0
         and detail.get("set_2.5") == [True, ""] and detail.get("set_-1") is not None
         and detail["set_-1"][0] is False and detail.get("after") == 2.5, **detail)

    ok = spin_until(lambda: len(twists) >= 3)
    t = twists[-1] if twists else None
    emit(role="listener", check="cyclonedds_to_rclpy", ok=ok and t.linear.x == 0.5
         and t.angular.z == -0.25, received=len(twists), sample=None if t is None else {
             "linear": [t.linear.x, t.linear.y, t.linear.z],
             "angular": [t.angular.x, t.angular.y, t.angular.z]})
    node.destroy_node()
    rclpy.shutdown()


def cyclone_types():
    """sensor_msgs/JointState and geometry_msgs/Twist as Cyclone DDS IDL dataclasses."""
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from ros2_idl import JointState, Twist, Vector3

    return JointState, Twist, Vector3


def role_cyclone(seconds):
    """Cyclone DDS (no ROS): reads rt/joint_states, writes rt/cmd_vel until SIGTERM."""
    from cyclonedds.core import Policy, Qos
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic
    from cyclonedds.util import duration

    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    JointState, Twist, Vector3 = cyclone_types()
    dp = DomainParticipant(DOMAIN)
    qos = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(10))
    reader = DataReader(dp, Topic(dp, "rt/joint_states", JointState), qos=qos)
    writer = DataWriter(dp, Topic(dp, "rt/cmd_vel", Twist), qos=qos)
    twist = Twist(linear=Vector3(0.5, 0.0, 0.0), angular=Vector3(0.0, 0.0, -0.25))
    got = []
    t0 = time.monotonic()
    first = None
    reported = False
    # Reports once it has 5 samples or at the deadline, and writes until SIGTERM.
    while not stop and (not reported or time.monotonic() < t0 + 2 * seconds):
        got.extend(reader.take(N=10))
        if got and first is None:
            first = round(time.monotonic() - t0, 3)
        writer.write(twist)
        if not reported and (len(got) >= 5 or time.monotonic() > t0 + seconds):
            emit_cyclone(got, first)
            reported = True
        time.sleep(0.05)


def emit_cyclone(got, first):
    m = got[-1] if got else None
    emit(role="cyclone", check="cyclonedds",
         ok=m is not None and list(m.name) == NAMES and list(m.velocity) == [1.0, 2.0, 3.0]
         and list(m.effort) == [-1.5, 0.0, 1.5] and m.header.frame_id == "base_link",
         received=len(got), first_after_s=first, sample=None if m is None else {
             "name": list(m.name), "position": list(m.position), "velocity": list(m.velocity),
             "effort": list(m.effort), "frame_id": m.header.frame_id,
             "stamp": [m.header.stamp.sec, m.header.stamp.nanosec]})


def netns_check():
    # /proc/net is this process's namespace (/sys/class/net is the one /sys was mounted in).
    links = subprocess.run(["ip", "-o", "link", "show"], capture_output=True,
                           text=True).stdout.splitlines()
    ifaces = sorted(line.split(":")[1].strip().split("@")[0] for line in links)
    lo = next((line for line in links if line.split(":")[1].strip() == "lo"), "")
    flags = lo.split("<")[1].split(">")[0].split(",") if "<" in lo else []
    up = "UP" in flags
    route = subprocess.run(["ip", "route", "get", "239.255.0.1"], capture_output=True,
                           text=True).stdout.split("\n")[0].strip()
    ok = ifaces == ["lo"] and up and "MULTICAST" in flags and " dev lo" in route
    return ok, {"interfaces": ifaces, "lo_flags": flags, "route_239.255.0.1": route}


def shm_files():
    try:
        return set(os.listdir("/dev/shm"))
    except OSError:
        return set()


def udp_sockets(pids):
    """{pid: sorted local addresses of its UDP sockets}, from ss in this namespace."""
    out = subprocess.run(["ss", "-uanpH"], capture_output=True, text=True).stdout
    mine = {p: set() for p in pids}
    for line in out.splitlines():
        for p in pids:
            if f"pid={p}," in line:
                mine[p].add(line.split()[3])
    return {p: sorted(a) for p, a in mine.items()}


def json_lines(text):
    """The JSON lines a role printed (Fast DDS logs to stdout too: skip those lines)."""
    out = []
    for line in text.splitlines():
        if line.startswith("{"):
            try:
                out.append(json.loads(line))
            except ValueError:
                pass
    return out


def orchestrate():
    results = []

    def report(name, ok, detail):
        results.append(ok)
        print(f"{'PASS' if ok else 'FAIL'} {name}: {json.dumps(detail)}", flush=True)

    ok, detail = netns_check()
    report("netns", ok, detail)
    if not ok:
        print("refusing to start DDS outside a namespace with only loopback: "
              "run under scripts/in-netns.sh", flush=True)
        print("0 passed, 1 failed")
        sys.exit(1)
    env_keys = ["RMW_IMPLEMENTATION", "FASTDDS_BUILTIN_TRANSPORTS", "ROS_DOMAIN_ID",
                "ROS_AUTOMATIC_DISCOVERY_RANGE", "ROS_LOG_DIR", "CYCLONEDDS_URI"]
    print("env: " + json.dumps({k: os.environ.get(k) for k in env_keys}), flush=True)

    shm_before = shm_files()
    me = [sys.executable, os.path.abspath(__file__)]
    t0 = time.monotonic()
    talker = subprocess.Popen(me + ["talker", "60"], stdout=subprocess.PIPE, text=True)
    ready = {}
    for line in talker.stdout:
        if json_lines(line):
            ready = json_lines(line)[0]
            break
    cyclone = subprocess.Popen(me + ["cyclone", "30"], stdout=subprocess.PIPE, text=True)
    listener = subprocess.Popen(me + ["listener", "30"], stdout=subprocess.PIPE, text=True)
    lines = {}
    roles = {talker.pid: "talker (rclpy)", listener.pid: "listener (rclpy)",
             cyclone.pid: "cyclonedds"}
    sockets = {name: set() for name in roles.values()}
    shm_during = set()
    while listener.poll() is None:
        for pid, addrs in udp_sockets(list(roles)).items():
            sockets[roles[pid]].update(addrs)
        shm_during |= shm_files() - shm_before
        time.sleep(0.2)
    sockets = {name: sorted(a) for name, a in sockets.items()}
    shm_during = sorted(shm_during)
    for line in cyclone.stdout:  # its JointState report (it writes /cmd_vel until stopped)
        if any(d.get("check") == "cyclonedds" for d in json_lines(line)):
            lines["cyclonedds"] = json_lines(line)[0]
            break
    elapsed = round(time.monotonic() - t0, 2)
    cyclone.terminate()
    talker.terminate()
    ends = {}
    for name, proc in (("listener", listener), ("cyclone", cyclone), ("talker", talker)):
        out, _ = proc.communicate(timeout=30)
        for d in json_lines(out):
            lines[d.get("check")] = d
            ends[name] = d
    talker_end = ends.get("talker", {})

    for check in ("topic", "graph", "service", "parameter", "cyclonedds", "cyclonedds_to_rclpy"):
        d = lines.get(check, {"ok": False, "missing": True})
        ok = bool(d.pop("ok", False))
        d.pop("role", None)
        d.pop("check", None)
        report(check, ok, d)
    # Everything bound is a wildcard, loopback or multicast address: in this namespace lo is
    # the only interface, so no packet can leave it.
    addrs = [a for v in sockets.values() for a in v]
    loopback_only = all(a.startswith(("0.0.0.0:", "127.", "*:", "[::]:", "239.", "[::1]"))
                        for a in addrs)
    report("transport", loopback_only and all(sockets.values()), {
        "rmw": ready.get("rmw"), "udp_sockets": sockets,
        "fastdds_shm_files": [f for f in shm_during if "fast" in f.lower()],
        "talker": talker_end, "peers_seconds": elapsed})
    passed = sum(results)
    print(f"{passed} passed, {len(results) - passed} failed")
    sys.exit(0 if passed == len(results) else 1)


if __name__ == "__main__":
    ensure_peers_python()
    if len(sys.argv) > 1:
        role = {"talker": role_talker, "listener": role_listener, "cyclone": role_cyclone}
        role[sys.argv[1]](float(sys.argv[2]))
    else:
        orchestrate()
