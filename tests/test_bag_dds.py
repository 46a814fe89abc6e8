"""`llfsm bag record` and `llfsm bag play` over DDS, beside llfsm runs on `--transport dds`.

Every test runs its processes in one private network namespace (dds_netns.py): nothing leaves
this machine.
"""

from __future__ import annotations

import time
from pathlib import Path

import pytest
import yaml
from dds_netns import NetNamespace, finish
from helpers import MACHINES, llfsm
from rosbags.highlevel import AnyReader


def messages(bag: Path) -> dict[str, list[tuple[int, object]]]:
    out: dict[str, list[tuple[int, object]]] = {}
    with AnyReader([bag]) as r:
        for c, t, data in r.messages():
            out.setdefault(c.topic, []).append((t, r.deserialize(data, c.msgtype)))
    return out


@pytest.mark.dds
def test_bag_record_all_hears_a_run_in_another_process(netns: NetNamespace, tmp_path: Path) -> None:
    before = time.time_ns()
    rec = netns.llfsm("bag", "record", "-a", "-o", tmp_path / "graph", "--duration", "7")
    run = netns.llfsm("run", "--transport", "dds", MACHINES / "ros2_ping_pong.machine", "--node", "turtlesim",
                      "--duration", "6")  # fmt: skip
    status, _out, err = finish(run, 60)
    assert status == 0, err
    status, _out, err = finish(rec, 60)
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
    rec = netns.llfsm("bag", "record", "/pingpong", "-o", tmp_path / "one", "--duration", "6", "-s", "sqlite3")
    run = netns.llfsm("run", "--transport", "dds", MACHINES / "ros2_ping_pong.machine", "--node", "turtlesim",
                      "--duration", "5")  # fmt: skip
    assert finish(run, 60)[0] == 0
    status, _out, err = finish(rec, 60)
    assert status == 0, err
    assert list(messages(tmp_path / "one")) == ["/pingpong"]
    assert (tmp_path / "one" / "one_0.db3").is_file()


@pytest.mark.dds
def test_bag_play_reaches_a_run_in_another_process(netns: NetNamespace, tmp_path: Path) -> None:
    # the bag: a sim run's /pingpong, recorded in process
    bag = tmp_path / "ping"
    r = llfsm("run", "--clock", "sim", MACHINES / "ros2_ping_pong.machine", "--duration", "3.5s", "--record", bag)
    assert r.status == 0
    listener = netns.llfsm("run", "--transport", "dds", "--echo", "/pingpong", "--node", "teleop", "--duration", "8")
    player = netns.llfsm("bag", "play", bag, "--delay", "2", "--rate", "2")
    status, _out, err = finish(player, 60)
    assert status == 0, err
    status, out, err = finish(listener, 60)
    assert [d.strip() for d in out.split("---") if d.strip()] == [f"data: The count is {n}" for n in range(3)]


def test_bag_record_without_topics_is_a_usage_error() -> None:
    r = llfsm("bag", "record", "-o", "x")
    assert r.status == 2 and "name the topics" in r.stderr


@pytest.mark.dds
def test_run_on_dds_records_its_own_topics_and_what_other_processes_send_it(
    netns: NetNamespace, tmp_path: Path
) -> None:
    sim = netns.llfsm("run", "--transport", "dds", "--node", "turtlesim", "--duration", "7")
    run = netns.llfsm("run", "--transport", "dds", MACHINES / "ros2_ping_pong.machine", "--echo", "/turtle1/pose",
                      "--duration", "5", "--record", tmp_path / "mine")  # fmt: skip
    status, _out, err = finish(run, 60)
    assert status == 0, err
    finish(sim, 60)
    got = messages(tmp_path / "mine")
    texts = [m.data for _, m in got["/pingpong"]]  # type: ignore[attr-defined]
    assert len(texts) >= 3 and texts == [f"The count is {n}" for n in range(len(texts))]
    assert len(got["/turtle1/pose"]) > 20  # published by turtlesim in the other process
