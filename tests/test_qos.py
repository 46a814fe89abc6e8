"""rclpy's QoS API in `llfsm.ros`: the policies, QoSProfile and the preset profiles, with
rclpy's names and values; what they change in process (depth, history, durability: reliability
changes nothing, since nothing is lost there); bad values as one clear error; the bag records
each publisher's offered reliability.  Over DDS: tests/test_dds_qos.py, and against real rclpy
tests/interop/test_rclpy_qos.py."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from helpers import run_sim, write_machine

from llfsm import ros
from llfsm.lang.check.ros_habits import ROS_QOS_NAMES
from llfsm.msgs.std_msgs.msg import Int64
from llfsm.ros.bus import Bus


def test_policies_have_rclpys_names_and_values() -> None:
    assert {p.name: int(p) for p in ros.ReliabilityPolicy} == {"SYSTEM_DEFAULT": 0, "RELIABLE": 1, "BEST_EFFORT": 2}
    assert {p.name: int(p) for p in ros.HistoryPolicy} == {"SYSTEM_DEFAULT": 0, "KEEP_LAST": 1, "KEEP_ALL": 2}
    assert {p.name: int(p) for p in ros.DurabilityPolicy} == {"SYSTEM_DEFAULT": 0, "TRANSIENT_LOCAL": 1, "VOLATILE": 2}
    assert ros.QoSReliabilityPolicy is ros.ReliabilityPolicy  # rclpy's older names
    assert ros.QoSHistoryPolicy is ros.HistoryPolicy
    assert ros.QoSDurabilityPolicy is ros.DurabilityPolicy


def test_profile_defaults_and_keywords() -> None:
    q = ros.QoSProfile(depth=3)
    assert (q.history, q.depth, q.reliability, q.durability) == (
        ros.HistoryPolicy.KEEP_LAST,
        3,
        ros.ReliabilityPolicy.RELIABLE,
        ros.DurabilityPolicy.VOLATILE,
    )
    q = ros.QoSProfile(depth=7, reliability=2, durability=ros.DurabilityPolicy.TRANSIENT_LOCAL, deadline=None)
    assert q.reliability is ros.ReliabilityPolicy.BEST_EFFORT  # plain ints become the policy, as in rclpy
    assert q == ros.QoSProfile(
        depth=7, reliability=ros.ReliabilityPolicy.BEST_EFFORT, durability=ros.DurabilityPolicy.TRANSIENT_LOCAL
    )
    assert "BEST_EFFORT" in repr(q)


@pytest.mark.parametrize(
    ("name", "history", "depth", "reliability", "durability"),
    [  # rmw's qos_profiles.h, as rclpy.qos exports them
        ("qos_profile_sensor_data", "KEEP_LAST", 5, "BEST_EFFORT", "VOLATILE"),
        ("qos_profile_system_default", "SYSTEM_DEFAULT", 0, "SYSTEM_DEFAULT", "SYSTEM_DEFAULT"),
        ("qos_profile_services_default", "KEEP_LAST", 10, "RELIABLE", "VOLATILE"),
        ("qos_profile_parameters", "KEEP_LAST", 1000, "RELIABLE", "VOLATILE"),
        ("qos_profile_parameter_events", "KEEP_LAST", 1000, "RELIABLE", "VOLATILE"),
    ],
)
def test_presets_have_rclpys_values(name: str, history: str, depth: int, reliability: str, durability: str) -> None:
    q = getattr(ros, name)
    assert (q.history.name, q.depth, q.reliability.name, q.durability.name) == (
        history,
        depth,
        reliability,
        durability,
    )


@pytest.mark.parametrize(
    ("kw", "message"),
    [
        ({"reliability": 7}, "reliability must be one of ReliabilityPolicy.SYSTEM_DEFAULT, ReliabilityPolicy.RELIABLE"),
        ({"reliability": "best_effort"}, "not 'best_effort'"),
        ({"history": 9}, "history must be one of HistoryPolicy.SYSTEM_DEFAULT"),
        ({"durability": None}, "durability must be one of DurabilityPolicy.SYSTEM_DEFAULT"),
    ],
)
def test_a_bad_policy_is_one_clear_error(kw: dict[str, object], message: str) -> None:
    with pytest.raises(ValueError, match="QoSProfile\\(\\): ") as e:
        ros.QoSProfile(depth=1, **kw)  # type: ignore[arg-type]
    assert message in str(e.value)


def test_a_bad_depth_is_one_clear_error_where_the_profile_is_used(bus: Bus) -> None:
    node = ros.Node("n")
    with pytest.raises(ValueError, match=r"create_subscription\(\): the QoS depth must be an integer >= 1, not 0"):
        node.create_subscription(Int64, "t", None, ros.QoSProfile(depth=0))


def test_best_effort_loses_nothing_in_process(bus: Bus) -> None:
    node = ros.Node("n")
    pub = node.create_publisher(Int64, "scan", ros.qos_profile_sensor_data)
    heard: list[int] = []
    node.create_subscription(Int64, "scan", lambda m: heard.append(m.data), ros.qos_profile_sensor_data)
    strict: list[int] = []
    node.create_subscription(Int64, "scan", lambda m: strict.append(m.data), 10)  # reliable: matches in process
    assert pub.reliability is ros.ReliabilityPolicy.BEST_EFFORT and pub.depth == 5
    for i in range(5):
        pub.publish(Int64(data=i))
    bus.spin_some()
    assert heard == strict == [0, 1, 2, 3, 4]


def test_keep_all_ignores_the_depth_and_keep_last_drops_the_oldest(bus: Bus) -> None:
    node = ros.Node("n")
    pub = node.create_publisher(Int64, "t", 10)
    everything: list[int] = []
    newest: list[int] = []
    keep_all = ros.QoSProfile(depth=2, history=ros.HistoryPolicy.KEEP_ALL)
    node.create_subscription(Int64, "t", lambda m: everything.append(m.data), keep_all)
    node.create_subscription(Int64, "t", lambda m: newest.append(m.data), ros.QoSProfile(depth=2))
    for i in range(6):
        pub.publish(Int64(data=i))
    bus.spin_some()
    assert everything == [0, 1, 2, 3, 4, 5]
    assert newest == [4, 5]


def test_system_default_keeps_the_last_message(bus: Bus) -> None:
    """depth 0 with SYSTEM_DEFAULT history is Cyclone's default: keep last 1."""
    node = ros.Node("n")
    pub = node.create_publisher(Int64, "t", ros.qos_profile_system_default)
    got: list[int] = []
    sub = node.create_subscription(Int64, "t", lambda m: got.append(m.data), ros.qos_profile_system_default)
    assert sub.depth == 1 and pub.depth == 1
    for i in range(3):
        pub.publish(Int64(data=i))
    bus.spin_some()
    assert got == [2]


def test_check_knows_the_names_llfsm_ros_has() -> None:
    """`llfsm check` tells users `ros.NAME` for exactly the rclpy.qos names llfsm.ros has."""
    assert set(ROS_QOS_NAMES) <= set(ros.__all__)
    assert {n for n in ros.__all__ if "QoS" in n or n.startswith("qos_") or n.endswith("Policy")} <= ROS_QOS_NAMES


def test_the_bag_records_each_publishers_offered_reliability(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "sensor",
        {"INITIAL": [("TICK", "True")], "TICK": [("TICK", "after_ms(50)")]},
        {
            "INITIAL_OnEntry": (
                "ros.init()\nnode = ros.Node('sensor')\n"
                "scan = node.create_publisher(Int64, '/scan', ros.qos_profile_sensor_data)\n"
                "cmd = node.create_publisher(Int64, '/cmd', 10)\n"
            ),
            "TICK_OnEntry": "n += 1\nscan.publish(Int64(data=n))\ncmd.publish(Int64(data=n))\n",
        },
        variables="n: int = 0\nscan: ros.Publisher\ncmd: ros.Publisher\nnode: ros.Node\n",
        includes="from llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import Int64\n",
    )
    bag = tmp_path / "bag"
    r = run_sim(m, "--duration", "200ms", "--record", bag, "--record-topic", "/scan", "--record-topic", "/cmd")
    assert r.status == 0, r.stderr
    info = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    offered = {
        t["topic_metadata"]["name"]: t["topic_metadata"]["offered_qos_profiles"]
        for t in info["topics_with_message_count"]
    }
    assert [q["reliability"] for q in offered["/scan"]] == ["best_effort"]
    assert [q["reliability"] for q in offered["/cmd"]] == ["reliable"]
