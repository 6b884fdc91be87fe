"""A second, independent DDS peer: Cyclone DDS (no ROS), the ROS 2 types declared as IDL
dataclasses with ROS 2's DDS names. Reads rt/joint_states (best effort) and rt/tf
(reliable) for argv[1] seconds, then prints one JSON line of what it read."""
import json
import sys
import time
import os

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "../../../scripts"))
from ros2_idl import JointState, TFMessage  # noqa: E402

seconds = float(sys.argv[1])
dp = DomainParticipant(0)
best_effort = Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(10))
reliable = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(10))
joints = DataReader(dp, Topic(dp, "rt/joint_states", JointState), qos=best_effort)
tf = DataReader(dp, Topic(dp, "rt/tf", TFMessage), qos=reliable)
got_joints, got_tf = [], []
t0 = time.monotonic()
while time.monotonic() - t0 < seconds:
    got_joints.extend(joints.take(N=50))
    got_tf.extend(tf.take(N=50))
    time.sleep(0.02)
j = got_joints[-1] if got_joints else None
pairs = sorted({(t.header.frame_id, t.child_frame_id) for m in got_tf for t in m.transforms})
head = next((t.transform.translation for m in reversed(got_tf) for t in m.transforms
             if t.child_frame_id == "body"), None)
print(json.dumps({
    "joint_states": len(got_joints),
    "names": list(j.name) if j else [],
    "positions": list(j.position) if j else [],
    "tf_messages": len(got_tf),
    "tf_pairs": pairs,
    "head_in_base_link": None if head is None else [head.x, head.y, head.z],
}), flush=True)
