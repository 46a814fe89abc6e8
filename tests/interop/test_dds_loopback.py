"""The generated DDS types on a real DDS bus, inside a private network namespace: Python
cyclonedds to itself, and Python cyclonedds to and from rclpy on Fast DDS (rmw_fastrtps_cpp)."""

from __future__ import annotations

import json

import pytest

from interop.ros2env import python_command, requires_netns, requires_ros, ros_command, run_ros, run_together

pytestmark = [pytest.mark.interop, pytest.mark.dds]

# A cyclonedds writer and reader of geometry_msgs Twist on rt/cmd_vel in one process, with
# XCDR1 asked for explicitly (DataRepresentation), raw CDR through the generated encoder.
_SAME_PROCESS = r"""
import json, time
from cyclonedds.domain import DomainParticipant
from cyclonedds.topic import Topic
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.qos import Qos, Policy
from cyclonedds.core import WaitSet, ReadCondition, SampleState, ViewState, InstanceState
from cyclonedds.util import duration
from llfsm.msgs import _dds
from llfsm.msgs.geometry_msgs.msg import Twist

qos = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(10),
          Policy.DataRepresentation(use_cdrv0_representation=True))
dp = DomainParticipant(0)
topic = Topic(dp, "rt/cmd_vel", _dds.dds_type(Twist), qos=qos)
reader = DataReader(dp, topic, qos=qos)
writer = DataWriter(dp, topic, qos=qos)
sent = []
for i in range(3):
    t = Twist()
    t.linear.x, t.angular.z = float(i), -0.5 * i
    writer.write(_dds.to_dds(t))
    sent.append(t)
got, deadline = [], time.monotonic() + 10
ws = WaitSet(dp)
ws.attach(ReadCondition(reader, SampleState.Any | ViewState.Any | InstanceState.Any))
while len(got) < 3 and time.monotonic() < deadline:
    ws.wait(duration(milliseconds=200))
    got += [_dds.from_dds(s, Twist) for s in reader.take(10)]
print(json.dumps({"same": got == sent, "n": len(got), "repr": _dds.dds_type(Twist).__idl__.idl_transformed_typename,
                  "xcdr1": writer._use_version_2 is False}))
"""


@requires_netns
def test_cyclonedds_writes_and_reads_generated_types() -> None:
    (r,) = run_together([python_command(_SAME_PROCESS)], timeout=60)
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout.strip().splitlines()[-1])
    assert out == {"same": True, "n": 3, "repr": "geometry_msgs::msg::dds_::Twist_", "xcdr1": True}


def test_rclpy_from_wheels_runs_in_a_private_network() -> None:
    if (reason := __import__("interop.ros2env", fromlist=["skip_reason"]).skip_reason()) is not None:
        pytest.skip(reason)
    r = run_ros(
        "import rclpy\nrclpy.init()\nn = rclpy.create_node('probe', namespace='/t')\n"
        "from rclpy.utilities import get_rmw_implementation_identifier as rmw\n"
        "print(rmw(), n.get_fully_qualified_name())\nrclpy.shutdown()\n",
        timeout=60,
    )
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["rmw_fastrtps_cpp", "/t/probe"]


# rclpy side: a subscriber that prints what it gets on /chatter, and a publisher of Twist on
# /cmd_vel, for 14 s at most.
_RCLPY_PEER = r"""
import json, time, rclpy
from rclpy.node import Node
from std_msgs.msg import String
from geometry_msgs.msg import Twist
rclpy.init()
node = Node("rclpy_peer")
got = []
node.create_subscription(String, "chatter", lambda m: got.append(m.data), 10)
pub = node.create_publisher(Twist, "cmd_vel", 10)
deadline, first = time.monotonic() + 14, None
# Publish on for 3 s after the first ping: the other side may match this writer later than
# this side matched its own.
while time.monotonic() < deadline and (len(got) < 3 or time.monotonic() < first + 3):
    if got and first is None:
        first = time.monotonic()
    t = Twist()
    t.linear.x, t.angular.z = 2.0, -1.25
    pub.publish(t)
    rclpy.spin_once(node, timeout_sec=0.1)
print(json.dumps(got[:3]))
"""

# llfsm side (plain cyclonedds with the generated types): writes String on rt/chatter, reads
# Twist from rt/cmd_vel with raw CDR decoded by from_cdr.
_CYCLONE_PEER = r"""
import json, time
from cyclonedds.domain import DomainParticipant
from cyclonedds.topic import Topic
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.qos import Qos, Policy
from cyclonedds.util import duration
from llfsm.msgs import _dds
from llfsm.msgs.std_msgs.msg import String
from llfsm.msgs.geometry_msgs.msg import Twist

qos = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(10),
          Policy.Durability.Volatile, Policy.DataRepresentation(use_cdrv0_representation=True))
dp = DomainParticipant(0)
writer = DataWriter(dp, Topic(dp, "rt/chatter", _dds.dds_type(String), qos=qos), qos=qos)
reader = DataReader(dp, Topic(dp, "rt/cmd_vel", _dds.dds_type(Twist), qos=qos), qos=qos)
twists, i, deadline = [], 0, time.monotonic() + 14
while time.monotonic() < deadline and (i < 40 or not twists):
    writer.write(_dds.to_dds(String(data=f"ping {i}")))
    i += 1
    twists += [_dds.from_dds(s, Twist) for s in reader.take(10) if s.sample_info.valid_data]
    time.sleep(0.1)
print(json.dumps([[t.linear.x, t.angular.z] for t in twists[:1]]))
"""


@requires_ros
def test_rclpy_and_cyclonedds_exchange_generated_types() -> None:
    """Across vendors on ROS 2's names: rclpy (Fast DDS) receives std_msgs/String written by
    cyclonedds with llfsm's type, and cyclonedds reads rclpy's Twist into llfsm's class."""
    ros, cyc = run_together([ros_command(_RCLPY_PEER), python_command(_CYCLONE_PEER)], timeout=40)
    assert ros.returncode == 0, ros.stderr
    assert cyc.returncode == 0, cyc.stderr
    got = json.loads(ros.stdout.strip().splitlines()[-1])
    assert len(got) == 3 and all(g.startswith("ping ") for g in got), ros.stdout
    assert json.loads(cyc.stdout.strip().splitlines()[-1]) == [[2.0, -1.25]]
