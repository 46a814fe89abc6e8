"""`llfsm bag record` and `llfsm bag play` over DDS, beside llfsm runs on `--transport dds`.

Every test runs its processes in one private network namespace (dds_netns.py): nothing leaves
this machine.
"""

from __future__ import annotations

import signal
import time
from pathlib import Path

import pytest
import yaml
from dds_netns import NetNamespace, Watched, finish, until_shown
from helpers import MACHINES, llfsm
from rosbags.highlevel import AnyReader


def record_while_it_publishes(ns: NetNamespace, *record: str | Path) -> tuple[int, str]:
    """`llfsm bag record RECORD...` beside ping-pong and turtlesim in another process, while the
    run publishes three times: the recorder's status and stderr.  Started together with
    windows of their own (`--duration`), the two raced: under load a start-up takes seconds, and
    the recorder could end before the run published twice."""
    run = Watched(ns.llfsm("run", "--transport", "dds", MACHINES / "ros2_ping_pong.machine", "--node", "turtlesim"))
    run.wait_for(r"Publishing: ")
    rec = Watched(ns.llfsm("bag", "record", *record))
    until_shown(ns, "topic", "info", "/pingpong", needle="Subscription count: 1")  # the recorder's reader
    published = sum("Publishing: " in line for line in run.err)
    run.wait_for(r"Publishing: ", count=published + 3)
    status, _out, err = rec.finish(60, signal.SIGINT)
    run_status, _out, run_err = run.finish(60, signal.SIGINT)
    assert run_status == 0, run_err
    return status, err


def messages(bag: Path) -> dict[str, list[tuple[int, object]]]:
    out: dict[str, list[tuple[int, object]]] = {}
    with AnyReader([bag]) as r:
        for c, t, data in r.messages():
            out.setdefault(c.topic, []).append((t, r.deserialize(data, c.msgtype)))
    return out


@pytest.mark.dds
def test_bag_record_all_hears_a_run_in_another_process(netns: NetNamespace, tmp_path: Path) -> None:
    before = time.time_ns()
    status, err = record_while_it_publishes(netns, "-a", "-o", tmp_path / "graph")
    assert status == 0 and "Traceback" not in err, err
    got = messages(tmp_path / "graph")
    assert {"/pingpong", "/turtle1/pose"} <= set(got)
    texts = [m.data for _, m in got["/pingpong"]]  # type: ignore[attr-defined]
    assert len(texts) >= 2 and all(t.startswith("The count is ") for t in texts)
    counts = [int(t.rsplit(" ", 1)[1]) for t in texts]
    assert counts == list(range(counts[0], counts[0] + len(counts)))  # none lost in between
    stamps = [t for t, _ in got["/turtle1/pose"]]
    assert before < stamps[0] and stamps == sorted(stamps)  # arrival times, wall clock
    meta = yaml.safe_load((tmp_path / "graph" / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert meta["message_count"] == sum(len(v) for v in got.values())


@pytest.mark.dds
def test_bag_record_named_topics_only(netns: NetNamespace, tmp_path: Path) -> None:
    status, err = record_while_it_publishes(netns, "/pingpong", "-o", tmp_path / "one", "-s", "sqlite3")
    assert status == 0, err
    assert list(messages(tmp_path / "one")) == ["/pingpong"]
    assert (tmp_path / "one" / "one_0.db3").is_file()


@pytest.mark.dds
def test_bag_play_reaches_a_run_in_another_process(netns: NetNamespace, tmp_path: Path) -> None:
    # the bag: a sim run's /pingpong, recorded in process
    bag = tmp_path / "ping"
    r = llfsm("run", "--clock", "sim", MACHINES / "ros2_ping_pong.machine", "--duration", "3.5s", "--record", bag)
    assert r.status == 0
    listener = Watched(netns.llfsm("run", "--transport", "dds", "--echo", "/pingpong", "--node", "teleop"))
    listener.wait_for(r"Reading from keyboard")  # up before the player comes (under load: seconds)
    # played in a loop until a whole pass has come: bag play, as ros2's, publishes without waiting
    # for subscribers, and the --delay of 2 s for discovery was not enough under load (the
    # listener missed count 0)
    player = Watched(netns.llfsm("bag", "play", bag, "--delay", "2", "--rate", "2", "--loop"))
    listener.wait_for(r"^data: The count is 2$", stream="out")
    listener.wait_for(r"^data: The count is 2$", stream="out", count=2)  # a whole pass after the first 0
    status, _out, err = player.finish(60, signal.SIGINT)
    assert status == 0, err
    _status, out, err = listener.finish(60, signal.SIGINT)
    heard = [d.strip() for d in out.split("---") if d.strip()]
    first = heard.index("data: The count is 0")
    # from its first 0 on, the bag's three messages in order, every pass: none lost, none foreign
    assert heard[first:] == [f"data: The count is {n % 3}" for n in range(len(heard) - first)], heard
    assert len(heard) - first >= 3, heard


def test_bag_record_without_topics_is_a_usage_error() -> None:
    r = llfsm("bag", "record", "-o", "x")
    assert r.status == 2 and "name the topics" in r.stderr


@pytest.mark.dds
def test_run_on_dds_records_its_own_topics_and_what_other_processes_send_it(
    netns: NetNamespace, tmp_path: Path
) -> None:
    sim = Watched(netns.llfsm("run", "--transport", "dds", "--node", "turtlesim"))
    sim.wait_for(r"Spawning turtle \[turtle1\]")  # up for the whole of the run (a start-up takes seconds under load)
    run = netns.llfsm("run", "--transport", "dds", MACHINES / "ros2_ping_pong.machine", "--echo", "/turtle1/pose",
                      "--duration", "5", "--record", tmp_path / "mine")  # fmt: skip
    status, _out, err = finish(run, 120)
    assert status == 0, err
    sim.finish(60, signal.SIGINT)
    got = messages(tmp_path / "mine")
    texts = [m.data for _, m in got["/pingpong"]]  # type: ignore[attr-defined]
    assert len(texts) >= 3 and texts == [f"The count is {n}" for n in range(len(texts))]
    assert len(got["/turtle1/pose"]) > 20  # published by turtlesim in the other process
