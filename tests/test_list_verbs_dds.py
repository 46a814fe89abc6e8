"""Issue 22, item 2: `node list`, `service list` and `topic list` do not return before every
participant already discovered has had its ros_discovery_info read and the endpoints it names
seen; against an rclpy (Fast DDS) talker, whose ros_discovery_info can come seconds after its
participant, every run names its node, its services and its topic."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import pytest
from dds_netns import NetNamespace, finish
from helpers import REPO, Run
from interop.ros2env import ROS_PYTHON, ros_installed

pytestmark = [
    pytest.mark.dds,
    pytest.mark.interop,
    pytest.mark.skipif(not ros_installed(), reason="real ROS 2 not installed: run `make .venv-ros/.installed`"),
]

TALKER = textwrap.dedent(
    """
    import time, rclpy
    from std_msgs.msg import String
    rclpy.init()
    node = rclpy.create_node("rclpy_talker")
    pub = node.create_publisher(String, "chatter", 10)
    end = time.monotonic() + 900
    while time.monotonic() < end:
        pub.publish(String(data="hi"))
        rclpy.spin_once(node, timeout_sec=0.1)
    """
)


def llfsm(ns: NetNamespace, *args: str | os.PathLike[str], timeout: float = 60) -> Run:
    status, out, err = finish(ns.popen([sys.executable, "-m", "llfsm", *map(str, args)], cwd=REPO), timeout)
    return Run(status, out, err)


@pytest.mark.parametrize("runs", [2, pytest.param(50, marks=pytest.mark.slow)])
def test_list_verbs_name_an_rclpy_node_every_time(netns: NetNamespace, runs: int) -> None:
    netns.popen([str(ROS_PYTHON), "-c", TALKER], env={"RMW_IMPLEMENTATION": "rmw_fastrtps_cpp"}, cwd=REPO,
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # fmt: skip
    up = llfsm(netns, "topic", "echo", "/chatter", "--once", "--timeout", "30")  # the talker is up
    assert up.status == 0, up.stderr
    for i in range(runs):  # each a new participant, which sees the talker's participant first
        nodes = llfsm(netns, "node", "list")
        assert "/rclpy_talker" in nodes.lines, (i, nodes.stdout, nodes.stderr)
        services = llfsm(netns, "service", "list")
        assert "/rclpy_talker/get_parameters" in services.lines, (i, services.stdout, services.stderr)
        topics = llfsm(netns, "topic", "list")
        assert "/chatter" in topics.lines, (i, topics.stdout, topics.stderr)
