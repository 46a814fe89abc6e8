"""Issue 22, item 5: a type clash over DDS (a String publisher on /turtle1/cmd_vel while
turtlesim subscribes with Twist) is told as the types differing, naming both, on both sides, as
the in-process bus tells it; not as an incompatible QoS."""

from __future__ import annotations

import signal
import sys
from pathlib import Path

import pytest
from dds_netns import NetNamespace, Watched, until_shown
from helpers import REPO, write_machine

pytestmark = pytest.mark.dds


def chatty(root: Path) -> Path:
    return write_machine(
        root,
        "chatty",
        {"INITIAL": [("SAY", "True")], "SAY": [("END", "not ros.ok()"), ("SAY", "after_ms(100)")], "END": None},
        {
            "INITIAL_OnEntry": (
                "ros.init()\nnode = ros.Node('chatty')\npub = node.create_publisher(String, '/turtle1/cmd_vel', 10)\n"
            ),
            "SAY_OnEntry": "pub.publish(String(data='go'))\n",
        },
        variables="node: ros.Node\npub: ros.Publisher\n",
        includes="from llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import String\n",
    )


def test_a_type_clash_over_dds_names_both_types(netns: NetNamespace, tmp_path: Path) -> None:
    llfsm = [sys.executable, "-m", "llfsm", "run", "--transport", "dds"]
    sim = Watched(netns.popen([*llfsm, "--node", "turtlesim"], cwd=REPO))
    # turtlesim's subscription is on the graph before the publisher comes
    until_shown(netns, "topic", "info", "/turtle1/cmd_vel", needle="Subscription count: 1")
    pub = Watched(netns.popen([*llfsm, chatty(tmp_path)], cwd=REPO))
    pub.wait_for(r"\[chatty\]: cannot publish /turtle1/cmd_vel")
    sim.wait_for(r"\[turtlesim\]: cannot subscribe to /turtle1/cmd_vel")
    status, _, pub_err = pub.finish(60, signal.SIGINT)
    _, _, sim_err = sim.finish(120, signal.SIGTERM)
    assert status == 0, pub_err
    assert (
        "[chatty]: cannot publish /turtle1/cmd_vel as std_msgs/msg/String: a subscription elsewhere takes "
        "geometry_msgs/msg/Twist on it; the types differ, so no messages will be sent to it\n"
    ) in pub_err
    assert (
        "[turtlesim]: cannot subscribe to /turtle1/cmd_vel as geometry_msgs/msg/Twist: a publisher elsewhere "
        "publishes std_msgs/msg/String on it; the types differ, so no messages will be received from it\n"
    ) in sim_err
    assert "incompatible QoS" not in pub_err + sim_err
    assert pub_err.count("the types differ") == 1  # once per other type, not once per match
