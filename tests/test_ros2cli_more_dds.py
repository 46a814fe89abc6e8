"""The verbs a course uses beyond list/echo/pub/call (issue 22, items 12 and 13), over real DDS
in a private network namespace: `node info`, `topic find`, `service type|find`, /rosout, and
the close names a verb offers after waiting in vain for a misspelt one.
"""

# ruff: noqa: F811  (the netns fixture is imported, and test arguments name it)
from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
import yaml
from dds_netns import NetNamespace, finish, netns  # noqa: F401  (netns is a fixture)
from helpers import REPO, Run, on_pty, write_machine
from interop.ros2env import ROS_PYTHON, ros_installed

pytestmark = pytest.mark.dds  # every test talks DDS across processes


def llfsm(ns: NetNamespace, *args: str | os.PathLike[str], timeout: float = 60) -> Run:
    """`llfsm ARGS` in the namespace, to its end."""
    status, out, err = finish(ns.popen([sys.executable, "-m", "llfsm", *map(str, args)], cwd=REPO), timeout)
    return Run(status, out, err)


def start(ns: NetNamespace, *args: str | os.PathLike[str]) -> None:
    """`llfsm ARGS` in the namespace, in the background until the test ends (output dropped)."""
    cmd = [sys.executable, "-m", "llfsm", *map(str, args)]
    ns.popen(cmd, cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def start_python(ns: NetNamespace, code: str, python: str | Path) -> None:
    env = {"RMW_IMPLEMENTATION": "rmw_fastrtps_cpp"}
    ns.popen([str(python), "-c", code], env=env, cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def wait_for(ns: NetNamespace, *args: str, needle: str, timeout: float = 40) -> Run:
    """Repeat `llfsm ARGS` until its output holds `needle` (discovery takes its time)."""
    deadline = time.monotonic() + timeout
    while True:
        r = llfsm(ns, *args, timeout=timeout)
        if needle in r.stdout or time.monotonic() > deadline:
            return r
        time.sleep(0.2)


def turtlesim(ns: NetNamespace) -> None:
    start(ns, "run", "--transport", "dds", "--node", "turtlesim", "--duration", "90s")
    r = wait_for(ns, "topic", "list", needle="/turtle1/pose")
    assert "/turtle1/pose" in r.stdout, r.stderr


def test_node_info_prints_what_ros2_prints(netns: NetNamespace) -> None:
    turtlesim(netns)
    r = wait_for(netns, "node", "info", "/turtlesim", needle="Service Servers")
    assert r.status == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0] == "/turtlesim"
    headings = [line for line in lines if line.startswith("  ") and not line.startswith("    ")]
    assert headings == [
        "  Subscribers:",
        "  Publishers:",
        "  Service Servers:",
        "  Service Clients:",
        "  Action Servers:",
        "  Action Clients:",
    ]

    def section(title: str) -> list[str]:
        at = lines.index(f"  {title}:") + 1
        out = []
        while at < len(lines) and (lines[at].startswith("    ") or lines[at] == ""):
            out.append(lines[at])
            at += 1
        return out

    assert section("Subscribers") == ["    /turtle1/cmd_vel: geometry_msgs/msg/Twist"]
    publishers = section("Publishers")
    assert "    /rosout: rcl_interfaces/msg/Log" in publishers
    assert "    /parameter_events: rcl_interfaces/msg/ParameterEvent" in publishers
    assert "    /turtle1/pose: turtlesim/msg/Pose" in publishers
    assert publishers == sorted(publishers)
    servers = section("Service Servers")
    assert "    /spawn: turtlesim/srv/Spawn" in servers and "    /turtle1/set_pen: turtlesim/srv/SetPen" in servers
    assert "    /turtlesim/get_parameters: rcl_interfaces/srv/GetParameters" in servers
    assert section("Service Clients") == [""]  # ros2 prints an empty section as a blank line
    # an action is named by its feedback topic, its five endpoints hidden (docs/actions.md)
    assert section("Action Servers") == ["    /turtle1/rotate_absolute: turtlesim/action/RotateAbsolute"]
    assert not any("_action" in line for line in lines)
    # without the leading slash, the node is found all the same
    assert llfsm(netns, "node", "info", "turtlesim").stdout == r.stdout


def test_node_info_of_a_misspelt_node_names_the_close_ones(netns: NetNamespace) -> None:
    turtlesim(netns)
    wait_for(netns, "node", "list", needle="/turtlesim")
    r = llfsm(netns, "node", "info", "/turtlesm", "--timeout", "1")
    assert r.status == 1
    assert r.stderr == "llfsm: Unable to find node '/turtlesm'; did you mean '/turtlesim'?\n", r.stderr


def test_topic_find_and_service_type_and_find(netns: NetNamespace) -> None:
    turtlesim(netns)
    r = llfsm(netns, "topic", "find", "geometry_msgs/msg/Twist")
    assert (r.status, r.stdout) == (0, "/turtle1/cmd_vel\n"), r.stderr
    assert llfsm(netns, "topic", "find", "-c", "turtlesim/msg/Pose").stdout == "1\n"
    r = llfsm(netns, "topic", "find", "sensor_msgs/msg/LaserScan")
    assert r.status == 1 and "no topics of type sensor_msgs/msg/LaserScan" in r.stderr
    assert llfsm(netns, "topic", "find", "-c", "sensor_msgs/msg/LaserScan").stdout == "0\n"
    r = wait_for(netns, "service", "type", "/spawn", needle="turtlesim")
    assert (r.status, r.stdout) == (0, "turtlesim/srv/Spawn\n"), r.stderr
    r = llfsm(netns, "service", "find", "turtlesim/srv/TeleportAbsolute")
    assert (r.status, r.stdout) == (0, "/turtle1/teleport_absolute\n"), r.stderr
    r = llfsm(netns, "service", "find", "rcl_interfaces/srv/GetParameters")
    assert "/turtlesim/get_parameters\n" in r.stdout


def test_a_misspelt_topic_or_service_names_the_close_ones_after_the_wait(netns: NetNamespace) -> None:
    turtlesim(netns)
    r = llfsm(netns, "topic", "echo", "/turtle1/cmdvel", "--timeout", "2")
    assert r.status == 1
    assert "topic '/turtle1/cmdvel' not found within 2 s" in r.stderr
    assert r.stderr.rstrip().endswith("did you mean '/turtle1/cmd_vel'?"), r.stderr
    r = llfsm(netns, "topic", "echo", "/turtle1/pos", "turtlesim/msg/Pose", "--once", "--timeout", "2")
    assert r.status == 1 and "did you mean '/turtle1/pose'?" in r.stderr, r.stderr
    r = llfsm(netns, "topic", "type", "cmd_vel", "--timeout", "1")
    assert r.status == 1 and "did you mean '/turtle1/cmd_vel'?" in r.stderr, r.stderr
    r = llfsm(netns, "service", "type", "/spwn", "--timeout", "1")
    assert r.status == 1 and "did you mean '/spawn'?" in r.stderr, r.stderr
    r = llfsm(netns, "service", "call", "/spwn", "turtlesim/srv/Spawn", "--timeout", "1")
    assert r.status == 1 and "did you mean '/spawn'?" in r.stderr, r.stderr
    r = llfsm(netns, "topic", "echo", "/nothing/like/it", "--timeout", "1")
    assert r.status == 1 and "did you mean" not in r.stderr


def _logging_machine(root: Path) -> Path:
    return write_machine(
        root,
        "chatty",
        {"INITIAL": [("TALK", "True")], "TALK": [("TALK", "after_ms(200)")]},
        {
            "INITIAL_OnEntry": "ros.init()\nnode = ros.Node('chatty')\n",
            "TALK_OnEntry": "count += 1\nnode.get_logger().info(f'tick {count}')\n",
        },
        variables="node: object = None\ncount: int = 0\n",
        includes="from llfsm import ros\n",
    )


def test_machine_logs_reach_rosout(netns: NetNamespace, tmp_path: Path) -> None:
    m = _logging_machine(tmp_path)
    start(netns, "run", "--transport", "dds", m, "--duration", "60s")
    r = wait_for(netns, "topic", "echo", "/rosout", "--once", "--timeout", "10", needle="tick")
    assert r.status == 0, r.stderr
    log = yaml.safe_load(r.stdout[: -len("---\n")])
    assert log["name"] == "chatty" and log["level"] == 20 and log["msg"].startswith("tick ")
    assert (log["file"], log["line"]) == ("State_TALK_OnEntry.py", 2)
    r = wait_for(netns, "node", "info", "/chatty", needle="/rosout")
    assert "    /rosout: rcl_interfaces/msg/Log" in r.stdout.splitlines()


ROSOUT_LISTENER = textwrap.dedent(
    """
    import sys, time
    import rclpy
    from rclpy.qos import qos_profile_rosout_default
    from rcl_interfaces.msg import Log
    rclpy.init()
    node = rclpy.create_node("rosout_listener")
    got = []
    node.create_subscription(Log, "/rosout", lambda m: got.append(m) if m.name == "chatty" else None,
                             qos_profile_rosout_default)
    end = time.monotonic() + 40
    while not got and time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.1)
    for m in got[:1]:
        print(m.name, m.level, m.msg, m.file, m.line)
    """
)


@pytest.mark.interop
@pytest.mark.skipif(not ros_installed(), reason="real ROS 2 not installed: run `make .venv-ros/.installed`")
def test_an_rclpy_subscriber_reads_machine_logs_on_rosout(netns: NetNamespace, tmp_path: Path) -> None:
    """`ros2 topic echo /rosout` shows machine logs: rclpy reads llfsm's Log with its own class."""
    m = _logging_machine(tmp_path)
    start(netns, "run", "--transport", "dds", m, "--duration", "60s")
    p = netns.popen([str(ROS_PYTHON), "-c", ROSOUT_LISTENER], env={"RMW_IMPLEMENTATION": "rmw_fastrtps_cpp"})
    status, out, err = finish(p, 60)
    assert status == 0, err
    name, level, word, _n, file, line = out.split()
    assert (name, level, word, file, line) == ("chatty", "20", "tick", "State_TALK_OnEntry.py", "2"), out


RCLPY_NODE = textwrap.dedent(
    """
    import time
    import rclpy
    from std_msgs.msg import String
    from std_srvs.srv import Trigger
    rclpy.init()
    node = rclpy.create_node("rclpy_node")
    node.create_publisher(String, "/chatter", 10)
    node.create_subscription(String, "/heard", lambda m: None, 10)
    node.create_service(Trigger, "/reset", lambda req, resp: resp)
    node.create_client(Trigger, "/other")
    end = time.monotonic() + 60
    while time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.1)
    """
)


@pytest.mark.interop
@pytest.mark.skipif(not ros_installed(), reason="real ROS 2 not installed: run `make .venv-ros/.installed`")
def test_node_info_of_an_rclpy_node(netns: NetNamespace) -> None:
    start_python(netns, RCLPY_NODE, ROS_PYTHON)
    r = wait_for(netns, "node", "info", "/rclpy_node", needle="/reset")
    assert r.status == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[lines.index("  Subscribers:") + 1] == "    /heard: std_msgs/msg/String"
    assert "    /chatter: std_msgs/msg/String" in lines and "    /rosout: rcl_interfaces/msg/Log" in lines
    assert "    /reset: std_srvs/srv/Trigger" in lines
    assert lines[lines.index("  Service Clients:") + 1] == "    /other: std_srvs/srv/Trigger"


def test_waiting_for_a_topic_shows_on_a_terminal_only(netns: NetNamespace) -> None:
    """Item 9: a verb that waits says what for, while it waits, when stderr is a terminal; the
    line is cleared before the verb's own last word, which starts on a clean line."""
    import re

    cmd = ["nsenter", f"--net=/proc/{netns.holder.pid}/ns/net", sys.executable, "-m", "llfsm", "topic", "echo"]
    status, _out, shown = on_pty([*cmd, "/nothing", "--timeout", "2"], cwd=REPO)
    assert status == 1
    parts = shown.split("\r\x1b[K")
    assert any(re.fullmatch(r"waiting for topic '/nothing' to appear\.\.\. [01] s of 2 s", p) for p in parts), parts
    assert parts[-1].startswith("llfsm: topic '/nothing' not found within 2 s")
    status, _out, shown = on_pty([*cmd, "/quiet", "std_msgs/msg/String", "--once", "--timeout", "2"], cwd=REPO)
    assert status == 1
    parts = shown.split("\r\x1b[K")
    assert any(re.fullmatch(r"waiting for a message on '/quiet'\.\.\. [01] s", p) for p in parts), parts
    assert parts[-1].startswith("llfsm: no message on '/quiet' within 2 s")
    r = llfsm(netns, "topic", "echo", "/nothing", "--timeout", "1")  # stderr a pipe: the one line only
    assert r.stderr.count("\n") == 1 and "waiting" not in r.stderr and "\r" not in r.stderr
