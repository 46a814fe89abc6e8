"""The ros2-style verbs across processes, over real DDS: `llfsm run --transport dds` in one
process, `llfsm topic|node|service ...` in others, as a user runs them in separate terminals.

Every test has a private network namespace of its own (`unshare -n`, loopback up with
multicast), so discovery never leaves it and tests never see each other.  A holder process
keeps the namespace; the test's processes join it with `nsenter`.  Every process has a timeout.
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import textwrap
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml
from conftest import MACHINES, REPO, Run

pytest.importorskip("cyclonedds", reason="the DDS verbs need the cyclonedds package (pip install 'llfsm[dds]')")

NETNS_SETUP = "ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo"


def _skip_reason() -> str | None:
    if not (shutil.which("unshare") and shutil.which("nsenter") and shutil.which("ip")):
        return "needs unshare, nsenter and ip (util-linux, iproute2) for a private network namespace"
    probe = subprocess.run(["unshare", "-n", "sh", "-c", NETNS_SETUP], capture_output=True, text=True, timeout=20)
    if probe.returncode != 0:
        return f"cannot make a private network namespace here: {probe.stderr.strip() or probe.returncode}"
    return None


_REASON = _skip_reason()
pytestmark = pytest.mark.skipif(_REASON is not None, reason=_REASON or "")


class Netns:
    """A private network namespace and the processes started in it."""

    def __init__(self, tmp: Path) -> None:
        self.tmp = tmp
        self.holder = subprocess.Popen(
            ["unshare", "-n", "sh", "-c", f"{NETNS_SETUP} && echo ready && exec sleep 600"],
            stdout=subprocess.PIPE,
            text=True,
        )
        assert self.holder.stdout is not None
        assert self.holder.stdout.readline().strip() == "ready"
        self.prefix = ["nsenter", f"--net=/proc/{self.holder.pid}/ns/net", "--"]
        self.background: list[subprocess.Popen[str]] = []
        self.env = {**os.environ, "ROS_DOMAIN_ID": "0", "PYTHONUNBUFFERED": "1"}
        self.env.pop("CYCLONEDDS_URI", None)
        self.env.pop("ROS_AUTOMATIC_DISCOVERY_RANGE", None)
        self.env.pop("ROS_LOCALHOST_ONLY", None)

    def start(self, *args: str | Path, python: str = sys.executable) -> subprocess.Popen[str]:
        """A process in the namespace, in the background (`llfsm ARGS`, or python -c when args
        start with "-c")."""
        cmd = [python, *map(str, args)] if args[0] == "-c" else [python, "-m", "llfsm", *map(str, args)]
        n = len(self.background)
        p = subprocess.Popen(
            self.prefix + cmd,
            stdout=open(self.tmp / f"bg{n}.out", "w"),  # noqa: SIM115 (closed with the process)
            stderr=open(self.tmp / f"bg{n}.err", "w"),  # noqa: SIM115
            text=True,
            env=self.env,
            cwd=REPO,
        )
        self.background.append(p)
        return p

    def llfsm(self, *args: str | Path, timeout: float = 60) -> Run:
        """`llfsm ARGS` in the namespace, to the end."""
        proc = subprocess.run(
            [*self.prefix, sys.executable, "-m", "llfsm", *map(str, args)],
            capture_output=True,
            text=True,
            timeout=timeout,
            env=self.env,
            cwd=REPO,
        )
        return Run(proc.returncode, proc.stdout, proc.stderr)

    def wait_for(self, *args: str, needle: str, timeout: float = 40) -> Run:
        """Repeat `llfsm ARGS` until its output holds `needle` (discovery takes its time)."""
        deadline = time.monotonic() + timeout
        while True:
            r = self.llfsm(*args, timeout=timeout)
            if needle in r.stdout or time.monotonic() > deadline:
                return r
            time.sleep(0.2)

    def close(self) -> None:
        for p in [*self.background, self.holder]:
            if p.poll() is None:
                p.terminate()
        for p in [*self.background, self.holder]:
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait(timeout=10)


@pytest.fixture
def netns(tmp_path: Path) -> Iterator[Netns]:
    ns = Netns(tmp_path)
    try:
        yield ns
    finally:
        ns.close()


def turtlesim(netns: Netns) -> None:
    netns.start("run", "--transport", "dds", "--node", "turtlesim", "--duration", "90s")
    r = netns.wait_for("topic", "list", needle="/turtle1/pose")
    assert "/turtle1/pose" in r.stdout, r.stderr


def _has_transport_option() -> bool:
    r = subprocess.run([sys.executable, "-m", "llfsm", "run", "--help"], capture_output=True, text=True, timeout=60)
    return "--transport" in r.stdout


needs_run_dds = pytest.mark.skipif(
    not _has_transport_option(), reason="`llfsm run --transport dds` is not on this branch yet"
)


# -- llfsm runs, seen by the verbs -----------------------------------------------------------------


@needs_run_dds
def test_topic_echo_once_prints_the_ping_pong_machines_messages(netns: Netns) -> None:
    netns.start("run", "--transport", "dds", MACHINES / "ros2_ping_pong.machine", "--duration", "60s")
    r = netns.llfsm("topic", "echo", "/pingpong", "--once", "--timeout", "30")
    assert r.status == 0, r.stderr
    assert r.stdout.endswith("\n---\n")
    assert r.stdout.count("---") == 1
    doc = yaml.safe_load(r.stdout[: -len("---\n")])
    assert re.fullmatch(r"The count is \d+", doc["data"]), r.stdout


@needs_run_dds
def test_lists_show_what_a_turtlesim_run_has(netns: Netns) -> None:
    turtlesim(netns)
    r = netns.llfsm("topic", "list", "-t")
    assert r.status == 0, r.stderr
    lines = r.stdout.splitlines()
    assert "/turtle1/pose [turtlesim/msg/Pose]" in lines
    assert "/turtle1/cmd_vel [geometry_msgs/msg/Twist]" in lines
    assert lines == sorted(lines)
    r = netns.wait_for("node", "list", needle="/turtlesim")
    assert "/turtlesim" in r.stdout.splitlines(), r.stderr
    r = netns.llfsm("service", "list", "-t")
    lines = r.stdout.splitlines()
    assert "/spawn [turtlesim/srv/Spawn]" in lines, r.stdout
    assert "/turtle1/teleport_absolute [turtlesim/srv/TeleportAbsolute]" in lines
    assert "/spawn" in netns.llfsm("service", "list").stdout.splitlines()
    r = netns.llfsm("topic", "info", "/turtle1/cmd_vel", "-v")
    assert r.stdout.startswith("Type: geometry_msgs/msg/Twist\n\nPublisher count: 0\n\nSubscription count: 1\n\n")
    assert "Node name: turtlesim\nNode namespace: /\n" in r.stdout
    assert "  Reliability: RELIABLE\n  History (Depth): KEEP_LAST" in r.stdout


@needs_run_dds
def test_service_call_spawn_gets_turtle2(netns: Netns) -> None:
    turtlesim(netns)
    r = netns.llfsm("service", "call", "/spawn", "turtlesim/srv/Spawn", "{x: 2.0, y: 2.0}")
    assert r.status == 0, r.stderr
    assert r.stdout.endswith(
        "requester: making request: turtlesim.srv.Spawn_Request(x=2.0, y=2.0, theta=0.0, name='')\n\n"
        "response:\nturtlesim.srv.Spawn_Response(name='turtle2')\n\n"
    ), r.stdout
    r = netns.wait_for("topic", "list", needle="/turtle2/pose")
    assert "/turtle2/pose" in r.stdout.splitlines()


@needs_run_dds
def test_topic_pub_moves_the_turtle(netns: Netns) -> None:
    turtlesim(netns)
    before = yaml.safe_load(netns.llfsm("topic", "echo", "/turtle1/pose", "--once").stdout[: -len("---\n")])
    r = netns.llfsm("topic", "pub", "/turtle1/cmd_vel", "geometry_msgs/msg/Twist", "{linear: {x: 1.0}}", "--times", "3")
    assert r.status == 0, r.stderr
    twist = (
        "geometry_msgs.msg.Twist(linear=geometry_msgs.msg.Vector3(x=1.0, y=0.0, z=0.0), "
        "angular=geometry_msgs.msg.Vector3(x=0.0, y=0.0, z=0.0))"
    )
    out = r.stdout.removeprefix("Waiting for at least 1 matching subscription(s)...\n")  # as ros2, until matched
    assert out == "publisher: beginning loop\n" + "".join(f"publishing #{i}: {twist}\n\n" for i in (1, 2, 3))
    after = yaml.safe_load(netns.llfsm("topic", "echo", "/turtle1/pose", "--once").stdout[: -len("---\n")])
    assert after["x"] > before["x"] + 1.0  # three commands of 1 m/s, each for up to a second
    assert after["y"] == pytest.approx(before["y"], abs=1e-3)


@needs_run_dds
def test_topic_hz_prints_rate_statistics(netns: Netns) -> None:
    turtlesim(netns)
    r = netns.llfsm("topic", "hz", "/turtle1/pose", "--duration", "3")
    assert r.status == 0, r.stderr
    reports = re.findall(
        r"^average rate: (\d+\.\d{3})\n\tmin: \d+\.\d{3}s max: \d+\.\d{3}s std dev: \d+\.\d{5}s window: (\d+)$",
        r.stdout,
        re.M,
    )
    assert reports, r.stdout
    assert float(reports[-1][0]) > 0 and int(reports[-1][1]) > 1


@needs_run_dds
def test_echo_field_prints_the_fields_python_value(netns: Netns) -> None:
    """--field picks a field; a primitive one prints as ros2 prints it, its Python value."""
    turtlesim(netns)
    r = netns.llfsm("topic", "echo", "/turtle1/pose", "turtlesim/msg/Pose", "--once", "--field", "theta")
    assert r.status == 0, r.stderr
    value, dashes = r.stdout.splitlines()
    assert float(value) == pytest.approx(0.0, abs=1e-6) and dashes == "---"


# -- nothing there, or the wrong thing -------------------------------------------------------------


def test_nothing_found_within_timeout_is_one_line_exit_1(netns: Netns) -> None:
    for args, needle in [
        (["topic", "echo", "/nothing", "--once", "--timeout", "1"], "topic '/nothing' not found within 1 s"),
        (["topic", "echo", "/nothing", "std_msgs/msg/String", "--timeout", "1"], "no message on '/nothing'"),
        (["topic", "list", "--spin-time", "0.5"], "no topics found within 0.5 s"),
        (["node", "list", "--spin-time", "0.5"], "no nodes found"),
        (["service", "list", "--spin-time", "0.5"], "no services found"),
        (["service", "call", "/spawn", "turtlesim/srv/Spawn", "--timeout", "1"], "service '/spawn' not available"),
        (["topic", "pub", "/x", "std_msgs/msg/String", "--once", "--timeout", "1"], "Timed out waiting for"),
        (["topic", "hz", "/nothing", "--timeout", "1"], "topic '/nothing' not found"),
        (["topic", "info", "/nothing", "--timeout", "1"], "Unknown topic '/nothing'"),
    ]:
        r = netns.llfsm(*args, timeout=30)
        assert r.status == 1, (args, r.stderr)
        assert len(r.stderr.splitlines()) == 1 and needle in r.stderr, (args, r.stderr)
        assert "Traceback" not in r.stderr


CLASH = textwrap.dedent(
    """
    import sys, time
    from llfsm import ros
    from llfsm.ros.transports.dds import DdsTransport
    from llfsm.runtime.context import RunContext, activate
    from llfsm.msgs.std_msgs.msg import String, Float64
    ctx = RunContext(); ctx.extras["transport"] = DdsTransport(); activate(ctx)
    ros.init()
    node = ros.Node(sys.argv[1])
    cls = String if sys.argv[1] == "text" else Float64
    pub = node.create_publisher(cls, "/clash", 10)
    end = time.monotonic() + 60
    while time.monotonic() < end:
        pub.publish(cls())
        ros.spin_once(node, timeout_sec=0.1)
    """
)


def test_a_topic_with_two_types_is_named_as_such(netns: Netns) -> None:
    netns.start("-c", CLASH, "text")
    netns.start("-c", CLASH, "number")
    r = netns.wait_for("topic", "list", "-t", needle="std_msgs/msg/Float64, std_msgs/msg/String")
    assert "/clash [std_msgs/msg/Float64, std_msgs/msg/String]" in r.stdout.splitlines(), r.stdout
    r = netns.llfsm("topic", "echo", "/clash", "--once", "--timeout", "10")
    assert r.status == 1
    assert r.stderr.strip() == (
        "llfsm: topic '/clash' has more than one type: [std_msgs/msg/Float64, std_msgs/msg/String]; give TYPE"
    )
    r = netns.llfsm("topic", "echo", "/clash", "std_msgs/msg/Bool", "--once", "--timeout", "10")
    assert r.status == 1 and "not std_msgs/msg/Bool" in r.stderr
    r = netns.llfsm("topic", "echo", "/clash", "std_msgs/msg/String", "--once", "--timeout", "10")
    assert r.status == 1 and "has type std_msgs/msg/Float64, not std_msgs/msg/String" in r.stderr
    r = netns.llfsm("topic", "info", "/clash")
    assert "WARNING: topic '/clash' has more than one type" in r.stdout


# -- real ROS 2 (rclpy in its own virtual environment) ---------------------------------------------


def _ros_python() -> str | None:
    for venv in (os.environ.get("LLFSM_ROS_VENV"), str(REPO / ".venv-ros")):
        if venv and (Path(venv) / "bin" / "python").exists():
            return str(Path(venv) / "bin" / "python")
    return None


TALKER = textwrap.dedent(
    """
    import time, rclpy
    from std_msgs.msg import String
    rclpy.init()
    node = rclpy.create_node("rclpy_talker")
    pub = node.create_publisher(String, "chatter", 10)
    end = time.monotonic() + 60
    i = 0
    while time.monotonic() < end:
        i += 1
        pub.publish(String(data=f"Hello World: {i}"))
        rclpy.spin_once(node, timeout_sec=0.1)
    """
)


@pytest.mark.interop
@pytest.mark.skipif(_ros_python() is None, reason="no rclpy: .venv-ros (or LLFSM_ROS_VENV) is not there")
def test_verbs_see_an_rclpy_node(netns: Netns) -> None:
    netns.start("-c", TALKER, python=_ros_python() or "")
    r = netns.llfsm("topic", "echo", "/chatter", "--once", "--timeout", "30")
    assert r.status == 0, r.stderr
    assert re.fullmatch(r"data: 'Hello World: \d+'\n---\n", r.stdout), r.stdout
    r = netns.wait_for("node", "list", needle="/rclpy_talker")
    assert "/rclpy_talker" in r.stdout.splitlines(), (r.stdout, r.stderr)


STUCK_SERVER = textwrap.dedent(
    """
    import os, sys, time
    from llfsm import ros
    from llfsm.ros.transports.dds import DdsTransport
    from llfsm.runtime.context import RunContext, activate
    from llfsm.msgs.std_srvs.srv import Trigger
    transport = DdsTransport()
    ctx = RunContext(); ctx.extras["transport"] = transport; activate(ctx)
    ros.init()
    node = ros.Node("stuck")

    def answer(request, response):
        if sys.argv[1] == "vanish":  # leave the domain mid-call, as a crashing peer's lease ends
            transport.close()
            os._exit(0)
        time.sleep(120)  # never answers in time
        return response

    node.create_service(Trigger, "/stuck", answer)
    end = time.monotonic() + 90
    while time.monotonic() < end:
        ros.spin_once(node, timeout_sec=0.1)
    """
)


@pytest.mark.parametrize(
    ("mode", "needle"),
    [("sleep", "no response from service '/stuck' within 2 s"), ("vanish", "service '/stuck' went away")],
)
def test_service_call_to_a_server_that_never_answers_ends_with_one_line(netns: Netns, mode: str, needle: str) -> None:
    netns.start("-c", STUCK_SERVER, mode)
    r = netns.wait_for("service", "list", needle="/stuck")
    assert "/stuck" in r.stdout.splitlines(), r.stderr
    r = netns.llfsm("service", "call", "/stuck", "std_srvs/srv/Trigger", "--timeout", "2", timeout=60)
    assert r.status == 1, (r.stdout, r.stderr)
    assert r.stdout.startswith("requester: making request: std_srvs.srv.Trigger_Request()\n\n")
    assert "response:" not in r.stdout
    assert len(r.stderr.splitlines()) == 1 and needle in r.stderr, r.stderr


@needs_run_dds
def test_ctrl_c_ends_echo_quietly(netns: Netns) -> None:
    turtlesim(netns)
    p = subprocess.Popen(
        [*netns.prefix, sys.executable, "-m", "llfsm", "topic", "echo", "/turtle1/pose"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=netns.env,
        cwd=REPO,
    )
    try:
        assert p.stdout is not None
        first = [p.stdout.readline() for _ in range(6)]
        assert first[0].startswith("x: ") and first[5] == "---\n", first
        p.send_signal(signal.SIGINT)
        _, err = p.communicate(timeout=20)
    finally:
        if p.poll() is None:
            p.kill()
            p.wait(timeout=10)
    assert p.returncode == 130
    assert "Traceback" not in err
