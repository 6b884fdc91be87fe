"""The rclpy subscriber of scripts/ros2-timing.sh: receives /joint_states (sensor-data QoS,
as any ROS 2 tool would) and counts the messages. Run with the ROS 2 peers' python inside
the network namespace (scripts/ros2-peers.sh run). SIGUSR1 opens the measured window,
SIGUSR2 closes it: it then prints one JSON line (messages and rate in the window, the
age of each message, receive wall clock minus its stamp, the time to the first message,
and the node's own counters from /diagnostics where the daemon publishes them) and exits.
Creates the file argv[1] once it is subscribed."""
import json
import signal
import sys
import time

marks = {}
signal.signal(signal.SIGUSR1, lambda *_: marks.setdefault("start", (time.monotonic(), count[0], node[0])))
signal.signal(signal.SIGUSR2, lambda *_: marks.setdefault("end", (time.monotonic(), count[0], node[0])))
count = [0]
node = [None]  # the newest "snaked: ros2 node" of /diagnostics: (stamp s, {key: value})

# Imported after the handlers are in place: a signal must never meet the default action.
from diagnostic_msgs.msg import DiagnosticArray  # noqa: E402
import rclpy  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.qos import qos_profile_sensor_data  # noqa: E402
from rclpy.signals import SignalHandlerOptions  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402

t0 = time.monotonic()
first = []
ages_ms = []


def on_state(msg):
    count[0] += 1
    if not first:
        first.append(time.monotonic() - t0)
    if "start" in marks:
        stamp = msg.header.stamp.sec * 1e9 + msg.header.stamp.nanosec
        ages_ms.append((time.time_ns() - stamp) / 1e6)


def on_diagnostics(msg):
    for st in msg.status:
        if st.name == "snaked: ros2 node":
            node[0] = (msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9,
                       {kv.key: int(kv.value) for kv in st.values if kv.value.isdigit()})


rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
ros = rclpy.create_node("ros2_timing_listener")
ros.create_subscription(JointState, "/joint_states", on_state, qos_profile_sensor_data)
ros.create_subscription(DiagnosticArray, "/diagnostics", on_diagnostics, 10)
executor = SingleThreadedExecutor()
executor.add_node(ros)
open(sys.argv[1], "w").close()
while "end" not in marks:
    executor.spin_once(timeout_sec=0.05)
(ts, cs, n0), (te, ce, n1) = marks.get("start", marks["end"]), marks["end"]
# The node's own counters (/diagnostics, once a second; absent from older daemons).
n_rate = (n1[1].get("published", 0) - n0[1].get("published", 0)) / (n1[0] - n0[0]) \
    if n0 and n1 and n1[0] > n0[0] else None
ages_ms.sort()
pct = lambda p: round(ages_ms[min(len(ages_ms) - 1, int(p * len(ages_ms)))], 3) if ages_ms else None
print(json.dumps({
    "messages": ce - cs,
    "rate_hz": (ce - cs) / (te - ts) if te > ts else 0.0,
    "first_after_s": first[0] if first else None,
    "age_ms_p50": pct(0.5),
    "age_ms_p99": pct(0.99),
    "node_published_hz": n_rate,
    "node": n1[1] if n1 else None,
}))
ros.destroy_node()
rclpy.shutdown()
