"""SPEC 16: `llfsm bag check BAG --property ... | FILE.verify.yaml` judges a recorded bag over
`state(m)` (from /llfsm/m/state) and `published(topic)`: on a bag llfsm recorded, on bags another
recorder wrote (rosbags' writer, MCAP and sqlite3, as `ros2 bag record` lays them out), and on
hostile ones (SPEC 18: one clear line, the rest read on, or a clean stop)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from helpers import MACHINES, llfsm

PING = MACHINES / "ros2_ping_pong.machine"
P = "ros2_ping_pong"
T0 = 1_700_000_000_000_000_000


def _other_recorder(path: Path, storage: str, extra: list[tuple[str, str, bytes]] | None = None) -> None:
    """A bag written as ROS 2's recorder writes one, no description topic: a machine `door`
    going CLOSED -> OPENING -> OPEN -> CLOSED, a `/bell` rung twice, and `extra` messages
    (topic, type, CDR) 1 s after the start."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    String = store.types["std_msgs/msg/String"]
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3

    def cdr(text: str) -> bytes:
        return bytes(store.serialize_cdr(String(data=text), "std_msgs/msg/String"))

    with Writer(path, version=9, storage_plugin=plugin) as w:
        state = w.add_connection("/llfsm/door/state", "std_msgs/msg/String", typestore=store)
        bell = w.add_connection("/bell", "std_msgs/msg/String", typestore=store)
        timeline = [
            (0.0, state, cdr("CLOSED")),
            (0.5, bell, cdr("ring")),
            (0.6, state, cdr("OPENING")),
            (2.0, state, cdr("OPEN")),
            (3.0, bell, cdr("ring")),
            (4.0, state, cdr("CLOSED")),
        ]
        conns: dict[str, object] = {"/llfsm/door/state": state}
        for topic, msgtype, data in extra or []:
            if topic not in conns:
                conns[topic] = w.add_connection(topic, msgtype, typestore=store)
            timeline.append((1.0, conns[topic], data))
        for t, conn, data in sorted(timeline, key=lambda x: x[0]):
            w.write(conn, T0 + int(t * 1e9), data)


def _check(bag: Path, *properties: str):  # type: ignore[no-untyped-def]
    args: list[str] = []
    for p in properties:
        args += ["--property", p]
    return llfsm("bag", "check", bag, *args)


def test_a_bag_llfsm_recorded(tmp_path: Path) -> None:
    bag = tmp_path / "bag"
    assert llfsm("run", "--clock", "sim", "--duration", "3s", PING, "--record", bag).status == 0
    r = _check(
        bag,
        f'never: state({P}) == "END"',
        f'reachable: state({P}) == "PUBLISH"',
        f'always: state({P}) != "WAIT_AND_COUNT"',
        f'leads_to: [published("/pingpong"), state({P}) == "WAIT_AND_COUNT"]',
    )
    assert r.status == 1, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0].startswith(f'never: state({P}) == "END": holds (')
    assert lines[1] == f'reachable: state({P}) == "PUBLISH": held at some message'
    # the boundary where it entered WAIT_AND_COUNT, 1.503 s of run time after the bag's first message
    assert lines[2].startswith(f'always: state({P}) != "WAIT_AND_COUNT" violated at 1.50')
    assert lines[2].endswith(f": {P} WAIT_AND_COUNT")
    assert lines[3].startswith("leads_to: ") and ": holds (" in lines[3]
    # a verification file's properties, as the file says them
    f = tmp_path / "p.verify.yaml"
    f.write_text(f'machines: [{PING}]\nproperties:\n  - name: it ends\n    eventually: state({P}) == "END"\n')
    r = llfsm("bag", "check", bag, f)
    assert r.status == 1 and r.stdout == "it ends: not seen in the bag\n"


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_bag_another_recorder_wrote(tmp_path: Path, storage: str) -> None:
    bag = tmp_path / "bag"
    _other_recorder(bag, storage)
    r = _check(
        bag,
        'never: published("/bell") and state(door) == "OPEN"',  # rung at 3.0 s while open: violated
        'never: published("/bell") and state(door) == "LOCKED"',  # a state the bag never shows: fine
        'leads_to: [state(door) == "OPENING", state(door) == "OPEN"]',
        'ltl: G (state(door) == "OPEN" -> F state(door) == "CLOSED")',
    )
    assert r.status == 1, r.stderr
    assert r.stdout.splitlines() == [
        'never: published("/bell") and state(door) == "OPEN" violated at 3.000 s, message 5: door OPEN',
        'never: published("/bell") and state(door) == "LOCKED": holds (6 messages)',
        'leads_to: [state(door) == "OPENING", state(door) == "OPEN"]: holds (6 messages)',
        'ltl: G (state(door) == "OPEN" -> F state(door) == "CLOSED"): pending at the end of the bag '
        "(neither violated nor satisfied so far)",
    ]
    assert r.stderr == ""


def test_what_a_bag_does_not_hold_is_a_clear_refusal(tmp_path: Path) -> None:
    bag = tmp_path / "bag"
    _other_recorder(bag, "mcap")
    r = _check(bag, "never: door.count > 2")
    assert r.status == 2 and "a bag holds each machine's state and what was published" in r.stderr
    r = _check(bag, "never: suspended(door)")
    assert r.status == 2 and "not suspended(m)" in r.stderr
    r = _check(bag, 'never: state(window) == "OPEN"')
    assert r.status == 2 and "no machine named window" in r.stderr
    r = llfsm("bag", "check", bag)
    assert r.status == 2 and "give a property" in r.stderr
    r = _check(tmp_path / "nothing", "never: state(door) == 'X'")
    assert r.status == 2 and "no such bag" in r.stderr
    assert "Traceback" not in r.stderr


def test_hostile_bags_are_one_line_each_and_the_rest_is_judged(tmp_path: Path) -> None:
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    Int32 = store.types["std_msgs/msg/Int32"]
    three = bytes(store.serialize_cdr(Int32(data=3), "std_msgs/msg/Int32"))
    String = store.types["std_msgs/msg/String"]
    huge = bytes(store.serialize_cdr(String(data="S" * 200_000), "std_msgs/msg/String"))
    bad_utf8 = bytes([0, 1, 0, 0, 4, 0, 0, 0, 0xFF, 0xFE, 0xFD, 0])  # a CDR string that is not UTF-8
    bag = tmp_path / "bag"
    _other_recorder(
        bag,
        "mcap",
        extra=[
            ("/llfsm/lamp/state", "std_msgs/msg/Int32", three),
            ("/llfsm/door/state", "std_msgs/msg/String", huge),
            ("/llfsm/door/state", "std_msgs/msg/String", bad_utf8),
        ],
    )
    r = _check(bag, 'never: published("/bell") and state(door) == "OPEN"')
    assert r.status == 1
    assert r.stdout.startswith('never: published("/bell") and state(door) == "OPEN" violated at 3.000 s')
    err = r.stderr.splitlines()
    assert "llfsm: bag check: /llfsm/lamp/state: of type std_msgs/msg/Int32, not std_msgs/msg/String: left out" in err
    assert any(
        re.search(r"/llfsm/door/state: a state message of 200,0\d\d bytes \(at most 4,096\): left out", x) for x in err
    )
    assert any("/llfsm/door/state: a message that is not a string (malformed" in x for x in err), err
    assert "Traceback" not in r.stderr and len(err) == 3
    # the machine whose state topic was of another type cannot be named: a clean stop
    r = _check(bag, 'never: state(lamp) == "ON"')
    assert r.status == 2 and "no machine named lamp" in r.stderr
