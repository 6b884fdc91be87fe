"""Runs in a network namespace with rclpy (scripts/ros2-peers.sh run): starts snaked
(argv[1], config argv[2]) as a ROS 2 node, subscribes as any ROS 2 tool would, and
prints one JSON line of what it saw. Waits for discovery (Fast DDS can take ~3 s)."""
import json
import os
import signal
import subprocess
import sys
import time

import rclpy
from rclpy.node import Node
from rclpy.qos import (DurabilityPolicy, QoSProfile, ReliabilityPolicy,
                       qos_profile_sensor_data)
from sensor_msgs.msg import JointState
from std_msgs.msg import String

snaked, config = sys.argv[1], sys.argv[2]
# The daemon must not inherit the wheels' library path.
env = {k: v for k, v in os.environ.items() if k != "LD_LIBRARY_PATH"}
daemon = subprocess.Popen([snaked, "--emulated", "--config", config], env=env,
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
rclpy.init()
node = Node("snaked_test_listener")
states, descriptions = [], []
node.create_subscription(JointState, "/joint_states", states.append, qos_profile_sensor_data)
latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL,
                     reliability=ReliabilityPolicy.RELIABLE)
node.create_subscription(String, "/robot_description", lambda m: descriptions.append(m.data), latched)
t0 = time.monotonic()
first = None
while time.monotonic() - t0 < 20:
    rclpy.spin_once(node, timeout_sec=0.05)
    if states and first is None:
        first = time.monotonic() - t0
        states.clear()
    if first is not None and time.monotonic() - t0 > first + 2.0:
        break
window = time.monotonic() - t0 - (first or 0)
nodes = node.get_node_names_and_namespaces()
types = dict(node.get_topic_names_and_types())
daemon.send_signal(signal.SIGTERM)
_, err = daemon.communicate(timeout=20)
last = states[-1] if states else None
print(json.dumps({
    "first_after_s": first,
    "rate_hz": len(states) / window if first is not None else 0.0,
    "nodes": [[n, ns] for n, ns in nodes],
    "joint_states_type": types.get("/joint_states"),
    "names": list(last.name) if last else [],
    "positions": list(last.position) if last else [],
    "velocities": len(last.velocity) if last else 0,
    "efforts": len(last.effort) if last else 0,
    "stamp_sec": last.header.stamp.sec if last else 0,
    "description": descriptions[0] if descriptions else "",
    "daemon_exit": daemon.returncode,
    "daemon_stopped_safely": "stopped safely" in err,
}))
