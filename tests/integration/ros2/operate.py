"""Runs in a network namespace with rclpy (scripts/ros2-peers.sh run): starts snaked
(argv[1], config argv[2], `[ros2] operate = true`, node `snaked`) and drives and tunes it
as a ROS 2 system would: the parameter services (list, get, set, refusals), Trigger
services, a goal on /goal_pose steered to by poses on /external_pose, /cmd_vel and its
dead-man, watching /snaked/state. Prints one JSON line."""
import json
import os
import signal
import subprocess
import sys
import time

import rclpy
from geometry_msgs.msg import PoseStamped, Twist
from nav_msgs.msg import Odometry
from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
from rcl_interfaces.srv import GetParameters, ListParameters, SetParameters
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from std_msgs.msg import String
from std_srvs.srv import SetBool, Trigger

snaked, config = sys.argv[1], sys.argv[2]
env = {k: v for k, v in os.environ.items() if k != "LD_LIBRARY_PATH"}
daemon = subprocess.Popen([snaked, "--emulated", "--config", config], env=env,
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
rclpy.init()
node = Node("snaked_test_operator")
state, history = {}, []


def on_state(m):
    state.update(json.loads(m.data))
    history.append((time.monotonic(), state.get("motion"), state.get("mode")))


latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL,
                     reliability=ReliabilityPolicy.RELIABLE)
node.create_subscription(String, "/snaked/state", on_state, latched)
cmd_vel = node.create_publisher(Twist, "/cmd_vel", 10)
out = {}


def spin_until(cond, timeout):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        rclpy.spin_once(node, timeout_sec=0.02)
        if cond():
            return round(time.monotonic() - t0, 3)
    return None


clients = {}


def call(ty, name, req, timeout=15.0):
    # One client per service, kept: a new one would wait for discovery again.
    if name not in clients:
        clients[name] = node.create_client(ty, name)
    c = clients[name]
    if not c.wait_for_service(timeout_sec=timeout):
        return None
    f = c.call_async(req)
    rclpy.spin_until_future_complete(node, f, timeout_sec=timeout)
    return f.result()


def first_after(t0, cond):
    """Seconds from t0 to the first state after it for which cond(motion, mode) holds."""
    return next((round(t - t0, 3) for t, motion, mode in history if t > t0 and cond(motion, mode)),
                None)


def trigger(name):
    r = call(Trigger, "/snaked/" + name, Trigger.Request())
    return None if r is None else {"success": r.success, "message": r.message}


def value_of(v):
    return {ParameterType.PARAMETER_DOUBLE: v.double_value,
            ParameterType.PARAMETER_STRING: v.string_value,
            ParameterType.PARAMETER_BOOL: v.bool_value}.get(v.type)


def get(names):
    r = call(GetParameters, "/snaked/get_parameters", GetParameters.Request(names=names))
    return None if r is None else [value_of(v) for v in r.values]


def set_param(name, value):
    v = ParameterValue()
    if isinstance(value, str):
        v.type, v.string_value = ParameterType.PARAMETER_STRING, value
    else:
        v.type, v.double_value = ParameterType.PARAMETER_DOUBLE, float(value)
    r = call(SetParameters, "/snaked/set_parameters",
             SetParameters.Request(parameters=[Parameter(name=name, value=v)]))
    return None if r is None else {"ok": r.results[0].successful, "reason": r.results[0].reason}


odom = {}
node.create_subscription(Odometry, "/odom", lambda m: odom.update(pose=m.pose.pose),
                         qos_profile_sensor_data)
pose_pub = node.create_publisher(PoseStamped, "/external_pose", 10)
goal_pub = node.create_publisher(PoseStamped, "/goal_pose", 10)
SHIFT = (2.0, 1.0)


def stamped(x, y, orientation=None):
    m = PoseStamped()
    m.header.stamp = node.get_clock().now().to_msg()
    m.header.frame_id = "mocap"
    m.pose.position.x, m.pose.position.y = x, y
    if orientation is not None:
        m.pose.orientation = orientation
    return m


def feed_until(cond, timeout, goal=None):
    """A source following /odom (the estimate's world shifted by SHIFT) at about 50 Hz
    until cond(); goal (x, y from where the body is, in the source's world) published
    once the body's first pose has been sent a second."""
    t0, sent, here = time.monotonic(), 0, None
    while time.monotonic() - t0 < timeout:
        spin_until(lambda: False, 0.02)
        if "pose" in odom:
            p = odom["pose"]
            here = (p.position.x + SHIFT[0], p.position.y + SHIFT[1])
            pose_pub.publish(stamped(*here, p.orientation))
            sent += 1
        if goal is not None and sent == 50:
            goal_pub.publish(stamped(here[0] + goal[0], here[1] + goal[1]))
            out["goal_sent_m"] = [here[0] + goal[0], here[1] + goal[1]]
        if cond():
            return round(time.monotonic() - t0, 3)
    return None


def drive(forward, seconds):
    t0 = time.monotonic()
    while time.monotonic() - t0 < seconds:
        m = Twist()
        m.linear.x = forward
        cmd_vel.publish(m)
        spin_until(lambda: False, 0.05)


try:
    out["state_after_s"] = spin_until(lambda: state.get("mode") == "running", 30)
    out["first_state"] = dict(state)
    r = call(ListParameters, "/snaked/list_parameters", ListParameters.Request())
    out["names"] = None if r is None else list(r.result.names)
    speed = "params.temporal_freq_rad_s"
    out["get"] = get(["gait", speed, "no.such"])
    before = out["get"][1] if out["get"] else 1.0
    out["set"] = set_param(speed, round(before * 0.75, 6))
    out["after_set"] = get([speed])
    out["set_out_of_range"] = set_param(speed, 1000.0)
    out["set_bad_gait"] = set_param("gait", "swimming")
    out["set_unknown"] = set_param("no.such", 1.0)
    out["gait_service"] = trigger("gait/slithering")
    out["gait_after_s"] = spin_until(lambda: state.get("gait") == "slithering", 10)
    out["hold"] = trigger("hold")
    out["held_after_s"] = spin_until(lambda: state.get("mode") == "hold", 10)
    out["arm"] = trigger("arm")
    out["armed_after_s"] = spin_until(lambda: state.get("mode") == "running", 10)
    # A goal 4 m ahead in x of the source's world: steered to by position.
    by_position = lambda: (state.get("navigator") or {}).get("by_position") is True
    out["goal_after_s"] = feed_until(by_position, 30, goal=(4.0, 0.0))
    out["goal_state"] = dict(state.get("navigator") or {})
    out["navigate_off"] = call(SetBool, "/snaked/navigate", SetBool.Request(data=False)).success
    # Teleop: the gait's speed follows linear.x (1 rad/s per unit), then the dead-man.
    drive(0.8, 1.5)
    out["driven_motion"] = state.get("motion")
    t_last = time.monotonic()
    out["driven_speed"] = get([speed])
    spin_until(lambda: state.get("mode") == "hold", 10)
    # When the state (published twice a second) first showed each, after the last twist.
    out["stopped_after_s"] = first_after(t_last, lambda motion, mode: motion == "stopped")
    out["held_by_dead_man_after_s"] = first_after(t_last, lambda motion, mode: mode == "hold")
    out["estop"] = trigger("estop")
    out["estopped_after_s"] = spin_until(lambda: state.get("mode") == "e_stop", 10)
    out["last_state"] = dict(state)
finally:
    daemon.send_signal(signal.SIGTERM)
    _, err = daemon.communicate(timeout=30)
    out["daemon_exit"] = daemon.returncode
    out["daemon_stopped_safely"] = "stopped safely" in err
    out["warned_beyond_localhost"] = "beyond localhost" in err
    print(json.dumps(out))
