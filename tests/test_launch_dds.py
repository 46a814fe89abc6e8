"""`llfsm launch` over DDS: the course's leader/follower launch file, in a private network
namespace (dds_netns.py), driven and watched from other processes as a user would."""

from __future__ import annotations

import math
import os
import re
import signal
import sys
import time
import uuid
from pathlib import Path

import pytest
from dds_netns import NetNamespace, finish
from helpers import MACHINES, write_machine

pytestmark = pytest.mark.dds


def pose(text: str) -> tuple[float, float]:
    x = re.search(r"^x: (\S+)$", text, re.M)
    y = re.search(r"^y: (\S+)$", text, re.M)
    assert x and y, text
    return float(x.group(1)), float(y.group(1))


def marked(mark: str) -> list[str]:
    """Processes still running with LLFSM_LAUNCH_TEST=mark in their environment."""
    out = []
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            if f"LLFSM_LAUNCH_TEST={mark}".encode() in Path(f"/proc/{pid}/environ").read_bytes().split(b"\0"):
                out.append(Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode())
        except OSError:
            continue
    return out


def test_the_follower_of_the_course_launch_file_moves_after_the_leader(netns: NetNamespace, tmp_path: Path) -> None:
    """(Its YAML twin starts the same processes: test_launch_model.py.)"""
    mark = uuid.uuid4().hex
    launch = netns.popen(
        [sys.executable, "-m", "llfsm", "launch", MACHINES / "turtle_follower.launch.xml"],
        env={"ROS_LOG_DIR": str(tmp_path), "LLFSM_LAUNCH_TEST": mark},
    )
    assert launch.stderr is not None
    seen = []
    while not any("Spawning turtle [turtle2]" in line for line in seen):  # the follower has spawned it
        line = launch.stderr.readline()
        assert line, "".join(seen)
        seen.append(line)
    status, before, err = finish(netns.llfsm("topic", "echo", "/turtle2/pose", "--once", "--timeout", "30"), 60)
    assert status == 0, err
    lead = netns.llfsm(
        "topic", "pub", "/turtle1/cmd_vel", "geometry_msgs/msg/Twist", "{linear: {x: 2.0}, angular: {z: 1.0}}",
        "--rate", "10", "--times", "30",
    )  # fmt: skip
    assert finish(lead, 60)[0] == 0
    # the follower moves turtle2 in its own time (under load, later than the leader's last
    # command): its pose read again until it has moved, or a minute
    deadline = time.monotonic() + 60
    while True:
        status, after, err = finish(netns.llfsm("topic", "echo", "/turtle2/pose", "--once", "--timeout", "30"), 60)
        assert status == 0, err
        (x0, y0), (x1, y1) = pose(before), pose(after)
        if math.hypot(x1 - x0, y1 - y0) > 0.5 or time.monotonic() > deadline:
            break
    assert math.hypot(x1 - x0, y1 - y0) > 0.5, "turtle2 did not follow turtle1"
    launch.send_signal(signal.SIGINT)
    status, out, rest = finish(launch, 60)
    err = "".join(seen) + rest
    assert status == 0, err
    assert "[turtle_follower-3] " in out + err  # its lines, prefixed
    assert (
        "[WARNING] [turtle_teleop_key-2]: a launched process cannot read this terminal (as under ros2 launch): "
        "to drive turtle1 with the arrow keys, run `llfsm run --transport dds --node teleop` in a second terminal"
    ) in err
    assert re.search(r"\[INFO\] \[turtle_follower-3\]: process has finished cleanly", err), err
    assert "Traceback" not in out + err
    assert marked(mark) == []


def test_a_nodes_log_level_in_ros_args_reaches_its_loggers(netns: NetNamespace, tmp_path: Path) -> None:
    """`ros_args="--log-level NAME:=debug"`, as ROS 2 users set a node's verbosity in a launch
    file: the machine's debug lines are printed (prefixed), the other node's INFO lines are not."""
    write_machine(
        tmp_path,
        "talker",
        {"A": [("END", "True")], "END": None},
        {"A_OnEntry": "ros.init()\nnode = ros.Node('talker')\nnode.get_logger().debug('a debug line')\n"},
        variables="node: ros.Node = None\n",
        includes="from llfsm import ros\n",
    )
    f = tmp_path / "levels.launch.xml"
    f.write_text(
        "<launch>\n"
        '  <arg name="log_level" default="info"/>\n'
        '  <node pkg="llfsm" exec="run" args="$(dirname)/talker.machine" output="screen"\n'
        '        ros_args="--log-level talker:=$(var log_level)"/>\n'
        '  <node pkg="turtlesim" exec="turtlesim_node" output="screen" ros_args="--log-level warn"\n'
        '        args="--duration 2s"/>\n'
        "</launch>\n"
    )
    status, out, err = finish(
        netns.llfsm("launch", f, "log_level:=debug", env={"ROS_LOG_DIR": str(tmp_path / "logs")}), 120
    )
    assert status == 0, err
    assert re.search(r"^\[talker-1\] \[DEBUG\] \[[0-9.]+\] \[talker\]: a debug line$", out + err, re.M), out + err
    assert "[turtlesim_node-2] [INFO]" not in out + err  # below its level
    assert "Traceback" not in out + err
