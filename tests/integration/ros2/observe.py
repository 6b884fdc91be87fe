"""Runs in a network namespace with rclpy (scripts/ros2-peers.sh run): starts snaked
(argv[1], config argv[2]) as a ROS 2 node `snake`, subscribes as ROS 2 tools would
(joint states, the URDF, odometry, an IMU, diagnostics, the node's state), publishes an
external pose, and runs a Cyclone DDS reader (cyclone_reader.py) beside it for the joint
states and /tf. Prints one JSON line of what it saw. Waits for discovery (Fast DDS can
take ~3 s)."""
import json
import os
import signal
import subprocess
import sys
import time

import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Odometry
from rclpy.node import Node
from rclpy.qos import (DurabilityPolicy, QoSProfile, ReliabilityPolicy,
                       qos_profile_sensor_data)
from sensor_msgs.msg import Imu, JointState
from std_msgs.msg import String

snaked, config = sys.argv[1], sys.argv[2]
here = os.path.dirname(os.path.abspath(__file__))
# The daemon must not inherit the wheels' library path.
env = {k: v for k, v in os.environ.items() if k != "LD_LIBRARY_PATH"}
daemon = subprocess.Popen([snaked, "--emulated", "--config", config], env=env,
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
cyclone = subprocess.Popen([sys.executable, os.path.join(here, "cyclone_reader.py"), "12"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
rclpy.init()
node = Node("snaked_test_listener")
states, descriptions, odoms, imus, diags, node_state = [], [], [], [], [], []
node.create_subscription(JointState, "/joint_states", states.append, qos_profile_sensor_data)
latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL,
                     reliability=ReliabilityPolicy.RELIABLE)
node.create_subscription(String, "/robot_description", lambda m: descriptions.append(m.data),
                         latched)
node.create_subscription(Odometry, "/odom", odoms.append, qos_profile_sensor_data)
node.create_subscription(Imu, "/imu/module_01/data_raw", imus.append, qos_profile_sensor_data)
node.create_subscription(DiagnosticArray, "/diagnostics", diags.append, 10)
node.create_subscription(String, "/snake/state", lambda m: node_state.append(m.data), latched)
pose = node.create_publisher(PoseStamped, "/external_pose", qos_profile_sensor_data)
t0 = time.monotonic()
first = None
while time.monotonic() - t0 < 20:
    rclpy.spin_once(node, timeout_sec=0.02)
    if states and first is None:
        first = time.monotonic() - t0
        states.clear()
    if first is not None and time.monotonic() - t0 > first + 2.0:
        break
window = time.monotonic() - t0 - (first or 0)
joint_rate = len(states) / window if first is not None else 0.0
# Motion capture: a pose at 50 Hz until the diagnostics count it.
received_poses = None
t1 = time.monotonic()
while time.monotonic() - t1 < 8:
    m = PoseStamped()
    m.header.frame_id = "mocap"
    m.header.stamp = node.get_clock().now().to_msg()
    m.pose.position.x = 1.25
    m.pose.orientation.w = 1.0
    pose.publish(m)
    rclpy.spin_once(node, timeout_sec=0.02)
    for a in diags[-1:]:
        for s in a.status:
            if s.name == "snaked: external pose":
                kv = {k.key: k.value for k in s.values}
                if int(kv.get("received", "0")) > 0:
                    received_poses = int(kv["received"])
    if received_poses:
        break
nodes = node.get_node_names_and_namespaces()
types = dict(node.get_topic_names_and_types())
cyclone_out, cyclone_err = cyclone.communicate(timeout=60)
daemon.send_signal(signal.SIGTERM)
_, err = daemon.communicate(timeout=20)
last = states[-1] if states else None
odom = odoms[-1] if odoms else None
imu = imus[-1] if imus else None
diag = diags[-1] if diags else None
print(json.dumps({
    "first_after_s": first,
    "rate_hz": joint_rate,
    "nodes": [[n, ns] for n, ns in nodes],
    "types": {k: v for k, v in types.items()},
    "names": list(last.name) if last else [],
    "positions": list(last.position) if last else [],
    "velocities": len(last.velocity) if last else 0,
    "efforts": len(last.effort) if last else 0,
    "stamp_sec": last.header.stamp.sec if last else 0,
    "description": descriptions[0] if descriptions else "",
    "odom": None if odom is None else {
        "frame_id": odom.header.frame_id, "child_frame_id": odom.child_frame_id,
        "position": [odom.pose.pose.position.x, odom.pose.pose.position.y],
        "orientation_norm": sum(v * v for v in [
            odom.pose.pose.orientation.x, odom.pose.pose.orientation.y,
            odom.pose.pose.orientation.z, odom.pose.pose.orientation.w]),
        "covariance_diagonal": [odom.pose.covariance[i * 7] for i in range(6)],
        "count": len(odoms)},
    "imu": None if imu is None else {
        "frame_id": imu.header.frame_id,
        "orientation_covariance_0": imu.orientation_covariance[0],
        "accel": [imu.linear_acceleration.x, imu.linear_acceleration.y,
                  imu.linear_acceleration.z],
        "count": len(imus)},
    "diagnostics": None if diag is None else {
        "count": len(diags),
        "status": {s.name: {"level": int.from_bytes(s.level, "little")
                            if isinstance(s.level, bytes) else int(s.level),
                            "message": s.message,
                            "values": {k.key: k.value for k in s.values}} for s in diag.status}},
    "received_poses": received_poses,
    "state": json.loads(node_state[-1]) if node_state else None,
    "cyclone": json.loads(cyclone_out.strip().splitlines()[-1]) if cyclone_out.strip() else
    {"error": cyclone_err[-2000:]},
    "daemon_exit": daemon.returncode,
    "daemon_stopped_safely": "stopped safely" in err,
}))
