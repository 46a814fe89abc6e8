"""SPEC 16: a violation is a message on /llfsm/monitor (llfsm_msgs/msg/MonitorEvent, shipped as a
.msg), in process and over DDS; the end of the run says the rest there too."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from dds_netns import NetNamespace, finish
from helpers import MACHINES, llfsm
from rosbags.highlevel import AnyReader

PING = MACHINES / "ros2_ping_pong.machine"


def _events(yaml_text: str) -> list[str]:
    return [b for b in yaml_text.split("---\n") if "verdict:" in b]


def test_the_message_type_is_shipped_and_shown() -> None:
    r = llfsm("interface", "show", "llfsm_msgs/msg/MonitorEvent")
    assert r.status == 0
    assert "string VIOLATED=violated" in r.stdout and "uint64 ringlet" in r.stdout
    assert "builtin_interfaces/Time stamp" in r.stdout


def test_a_violation_and_the_end_of_the_run_are_published_in_process(tmp_path: Path) -> None:
    bag = tmp_path / "bag"
    r = llfsm(
        "run", "--clock", "sim", "--duration", "3s", PING, "--echo", "/llfsm/monitor", "--record", bag,
        "--monitor-property", "never: ros2_ping_pong.count >= 2",
        "--monitor-property", 'reachable: state(ros2_ping_pong) == "PUBLISH"',
    )  # fmt: skip
    assert r.status == 0, r.stderr
    (violated,) = _events(r.stdout)  # as it happened, to a reader of the run
    assert "verdict: violated" in violated and "ringlet: 2509" in violated
    assert "stamp:\n  sec: 2\n  nanosec: 508000000" in violated
    assert "variables: ros2_ping_pong.count=2" in violated and "- WAIT_AND_COUNT" in violated
    with AnyReader([bag]) as reader:  # and at the end too: the recorder hears it before the run closes
        conns = [c for c in reader.connections if c.topic == "/llfsm/monitor"]
        got = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages(connections=conns)]
    assert [(m.kind, m.verdict, m.ringlet) for m in got] == [("never", "violated", 2509), ("reachable", "held", 3000)]


@pytest.mark.dds
def test_a_violation_reaches_another_process_over_dds(netns: NetNamespace) -> None:
    run = netns.llfsm(
        "run", "--transport", "dds", "--duration", "6", PING,
        "--monitor-property", "never: ros2_ping_pong.count >= 1", "--on-violation", "stop",
    )  # fmt: skip
    echo = netns.llfsm("topic", "echo", "/llfsm/monitor", "llfsm_msgs/msg/MonitorEvent", "--once", "--timeout", "20")
    status, _, err = finish(run, 40)
    _, out, echo_err = finish(echo, 40)
    assert status == 4, err
    assert "violated at" in err
    (event,) = _events(out)  # the reader may come late: TRANSIENT_LOCAL hands it the violation
    assert "name: 'never: ros2_ping_pong.count >= 1'" in event and "verdict: violated" in event, out + echo_err
    assert re.search(r"ringlet: [1-9]\d*", event)


def test_what_a_peer_sends_on_the_topic_is_bounded_for_the_page() -> None:
    from llfsm.msgs.llfsm_msgs.msg import MonitorEvent
    from llfsm.web.verdicts import MAX_MACHINES, MAX_TEXT, entry

    names = [f"m{i}" for i in range(100_000)]
    huge = MonitorEvent(name="n" * 1_000_000, verdict="violated", machines=names, states=names, reads=names)
    e = entry(huge)
    assert len(e["property"]) == MAX_TEXT and e["property"].endswith("…")
    assert len(e["states"]) == len(e["reads"]) == MAX_MACHINES
