"""Rough edges of recording and replay (issue 22, items 9, 10 and 11): `bag play --topics A B`,
the first message of a publisher that appears while `bag record` runs, types named as ROS names
them, /rosout in a bag, the `bag info` of docs/recording.md, and progress on a terminal.
"""

# ruff: noqa: F811  (the netns fixture is imported, and test arguments name it)
from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest
from dds_netns import NetNamespace, Watched, finish, netns  # noqa: F401  (netns is a fixture)
from helpers import MACHINES, REPO, llfsm, on_pty, run_sim
from rosbags.highlevel import AnyReader

DOC = REPO / "docs" / "recording.md"


def _topics(bag: Path) -> dict[str, int]:
    with AnyReader([bag]) as r:
        out: dict[str, int] = {}
        for c, _t, _d in r.messages():
            out[c.topic] = out.get(c.topic, 0) + 1
        return out


# -- the first message of a publisher that appears --------------------------------------------------


class _Run:
    """One llfsm run on the DDS transport in this process (its context, transport and bus)."""

    def __init__(self) -> None:
        from llfsm.ros.bus import bus_of
        from llfsm.ros.transports.dds import DdsTransport
        from llfsm.runtime import RunContext, WallClock

        self.ctx = RunContext(WallClock())
        self.transport = DdsTransport(97)
        self.ctx.transport = self.transport
        self.bus = bus_of(self.ctx)
        self.bus.initialised = True

    def __enter__(self) -> _Run:
        from llfsm.runtime.context import activate

        self._prev = activate(self.ctx)
        return self

    def __exit__(self, *exc: object) -> None:
        from llfsm.runtime.context import activate

        activate(self._prev)


def _spin_until(cond: Callable[[], object], run: _Run, timeout: float = 5.0) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        run.bus.spin_once(5_000_000)
        if cond():
            return True
    return False


@pytest.mark.dds
def test_a_message_published_once_the_reader_matched_is_sent_before_the_next_poll(monkeypatch) -> None:
    """The race behind "4 of 5 first messages recorded": a DDS writer sent nothing while its own
    count of matched readers, updated when the transport polls (between rounds), was still 0,
    though DDS had matched the recorder's reader already.  A run that publishes right after the
    match (the first message of a publisher that just appeared) lost that message."""
    pytest.importorskip("cyclonedds")
    from llfsm import ros
    from llfsm.msgs.std_msgs.msg import String

    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "OFF")  # this process only
    a, b = _Run(), _Run()
    try:
        with a:
            pub = ros.Node("talker").create_publisher(String, "/first", 10)
        heard: list[str] = []
        with b:
            sub = ros.Node("recorder").create_subscription(String, "/first", lambda m: heard.append(m.data), 10)
        # only the reader's side is polled: DDS matches both ends, the writer's run has not looked
        assert _spin_until(lambda: sub._remote.reader.get_subscription_matched_status().current_count == 1, b)
        assert _spin_until(lambda: pub._remote.writer.get_publication_matched_status().current_count == 1, b)
        with a:
            pub.publish(String(data="first"))
        assert _spin_until(lambda: heard == ["first"], b), heard
    finally:
        a.transport.close()
        b.transport.close()


# -- bag play --topics A B -----------------------------------------------------------------------------


def _two_topic_bag(tmp_path: Path) -> Path:
    bag = tmp_path / "two"
    r = run_sim(MACHINES / "ros2_blind_turtle_bot.machine", "--node", "turtlesim", "--duration", "2s", "--record", bag)
    assert r.status == 0, r.stderr
    return bag


def test_bag_play_takes_several_topics_after_one_topics_option(tmp_path: Path, monkeypatch) -> None:
    import llfsm.bag.dds as dds

    bag = _two_topic_bag(tmp_path)
    played: list[tuple[str, tuple[str, ...]]] = []
    monkeypatch.setattr(dds, "play", lambda path, rate, loop, topics, delay, **kw: played.append((path, tuple(topics))))
    r = llfsm("bag", "play", bag, "--topics", "/turtle1/cmd_vel", "/turtle1/pose", "--rate", "2")
    assert r.status == 0, r.stderr
    assert played == [(str(bag), ("/turtle1/cmd_vel", "/turtle1/pose"))]
    played.clear()
    r = llfsm("bag", "play", bag, "--topics", "/turtle1/pose", "--topics", "/turtle1/cmd_vel")  # as before
    assert (r.status, played) == (0, [(str(bag), ("/turtle1/pose", "/turtle1/cmd_vel"))])
    played.clear()
    r = llfsm("bag", "play", "--topics", "/turtle1/pose", "/turtle1/cmd_vel", "--", bag)
    assert (r.status, played) == (0, [(str(bag), ("/turtle1/pose", "/turtle1/cmd_vel"))]), r.stderr


def test_bag_play_topics_before_the_bag_says_how(tmp_path: Path) -> None:
    bag = _two_topic_bag(tmp_path)
    r = llfsm("bag", "play", "--topics", "/turtle1/pose", bag)
    assert r.status == 2
    assert "DIR" in r.stderr and "--topics" in r.stderr and "Traceback" not in r.stderr


def test_bag_play_names_a_topic_the_bag_lacks(tmp_path: Path) -> None:
    bag = _two_topic_bag(tmp_path)
    r = llfsm("bag", "play", bag, "--topics", "/turtle1/pose", "/turtle1/cmdvel")
    assert r.status == 2
    assert "/turtle1/cmdvel" in r.stderr and "did you mean '/turtle1/cmd_vel'?" in r.stderr, r.stderr


# -- /rosout ---------------------------------------------------------------------------------------------


def test_rosout_is_recorded_from_the_first_line(tmp_path: Path) -> None:
    """turtlesim logs as it starts, before the recorder is attached: /rosout is transient local,
    and the recorder takes what it keeps, as rosbag2's subscription does."""
    bag = tmp_path / "logs"
    r = run_sim("--node", "turtlesim", "--duration", "0.1s", "--record", bag)
    assert r.status == 0, r.stderr
    with AnyReader([bag]) as reader:
        logs = [reader.deserialize(d, c.msgtype) for c, _t, d in reader.messages() if c.topic == "/rosout"]
        types = {c.topic: c.msgtype for c in reader.connections}
    assert types["/rosout"] == "rcl_interfaces/msg/Log"
    assert [m.msg for m in logs][:2] == [
        "Starting turtlesim with node name /turtlesim",
        "Spawning turtle [turtle1] at x=[5.544445], y=[5.544445], theta=[0.000000]",
    ]
    assert {m.name for m in logs} == {"turtlesim"} and logs[0].level == 20


# -- types named as ROS names them -------------------------------------------------------------------------


@pytest.mark.dds
def test_an_unrecordable_type_is_named_pkg_msg_name(netns: NetNamespace, tmp_path: Path) -> None:
    """A topic of a type llfsm has no class for is not recorded, and the line says which type
    in ROS's spelling (pkg/msg/Name), not DDS's (pkg::msg::dds_::Name_)."""
    code = (
        "import time\n"
        "from cyclonedds.domain import DomainParticipant\n"
        "from cyclonedds.idl import IdlStruct\n"
        "from cyclonedds.pub import DataWriter\n"
        "from cyclonedds.topic import Topic\n"
        "from dataclasses import dataclass\n"
        "@dataclass\n"
        "class Reading(IdlStruct, typename='robot_msgs::msg::dds_::Reading_'):\n"
        "    value: int\n"
        "dp = DomainParticipant(0)\n"
        "w = DataWriter(dp, Topic(dp, 'rt/reading', Reading))\n"
        "end = time.monotonic() + 12\n"
        "while time.monotonic() < end:\n"
        "    w.write(Reading(1)); time.sleep(0.1)\n"
    )
    writer = netns.python(code)
    rec = netns.llfsm("bag", "record", "-a", "-o", tmp_path / "a", "--duration", "4")
    status, _out, err = finish(rec, 60)
    writer.kill()
    assert status == 0, err
    assert "/reading is not recorded" in err, err
    assert "robot_msgs/msg/Reading" in err and "::" not in err, err


# -- docs/recording.md's bag info ----------------------------------------------------------------------------

_INFO_BLOCK = re.compile(r"(```console\n\$ llfsm bag info wall_run\n)(.*?)(```\n)", re.S)


def test_the_bag_info_in_the_docs_is_a_real_runs(tmp_path: Path) -> None:
    """docs/recording.md records the wall turtle bot for 30 s of sim time and shows `bag info`
    of it: the same command, run here, prints the same (a sim-clock bag is the same byte for
    byte; only its size may differ with the MCAP library's version)."""
    (tmp_path / "machines").symlink_to(MACHINES)
    env = dict(os.environ, TZ="UTC")
    run = [sys.executable, "-m", "llfsm", "run", "--clock", "sim", "machines/ros2_wall_turtle_bot.machine"]
    run += ["--node", "turtlesim", "--node", "turtle_sensor_poster", "--duration", "30s", "--record", "wall_run"]
    r = subprocess.run(run, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    info = subprocess.run(
        [sys.executable, "-m", "llfsm", "bag", "info", "wall_run"],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
    )
    assert info.returncode == 0, info.stderr
    doc = DOC.read_text(encoding="utf-8")
    m = _INFO_BLOCK.search(doc)
    assert m is not None, "docs/recording.md has no `llfsm bag info wall_run` block"
    if os.environ.get("LLFSM_UPDATE_DOCS") == "1":
        DOC.write_text(doc[: m.start(2)] + info.stdout + doc[m.end(2) :], encoding="utf-8")
        return

    def size_free(text: str) -> str:
        return re.sub(r"^Bag size: .*$", "Bag size: ...", text, flags=re.M)

    assert size_free(m.group(2)) == size_free(info.stdout), "run LLFSM_UPDATE_DOCS=1 pytest -k bag_info_in_the_docs"


# -- progress on a terminal ---------------------------------------------------------------------------------


def _status_lines(shown: str) -> list[str]:
    return [part for part in shown.split("\r\x1b[K") if part and "\n" not in part]


@pytest.mark.dds
def test_bag_record_and_play_say_what_they_do_on_a_terminal(netns: NetNamespace, tmp_path: Path) -> None:
    runner: Callable[..., subprocess.Popen[str]]
    run = Watched(netns.llfsm("run", "--transport", "dds", MACHINES / "ros2_ping_pong.machine"))
    run.wait_for(r"Publishing: ")  # publishing before the recording starts (a start-up takes seconds under load)
    bag = tmp_path / "rec"
    cmd = ["nsenter", f"--net=/proc/{netns.holder.pid}/ns/net", sys.executable, "-m", "llfsm"]
    status, _out, shown = on_pty([*cmd, "bag", "record", "/pingpong", "-o", str(bag), "--duration", "4"], cwd=REPO)
    assert status == 0, shown
    lines = _status_lines(shown)
    assert any(re.fullmatch(r"recording 1 topic to .*rec: \d+ messages? \(/pingpong \d+\), \d+ s", s) for s in lines), (
        lines
    )
    run.finish(60, signal.SIGINT)
    listener = netns.llfsm("run", "--transport", "dds", "--echo", "/pingpong", "--duration", "6")
    time.sleep(1)
    status, _out, shown = on_pty([*cmd, "bag", "play", str(bag), "--delay", "1"], cwd=REPO)
    assert status == 0, shown
    lines = _status_lines(shown)
    assert any(re.fullmatch(r"playing .*rec: \d+ of \d+ messages, \d+\.\d s of \d+\.\d s", s) for s in lines), lines
    finish(listener, 60)
    runner = netns.llfsm  # (the same commands with stderr in a pipe print no status)
    rec = runner("bag", "record", "/pingpong", "-o", tmp_path / "quiet", "--duration", "2")
    _status, _out, err = finish(rec, 60)
    assert "\r" not in err and "recording" not in err
