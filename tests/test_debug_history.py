"""The debugger's history recorded inside the compiled ringlets (llfsm.debug.recording, docs/debug.md
"History"): it reads back exactly as the watcher's recording of every boundary does (every field of
every record, and the arrangement at any of them), on the how-to pair driving turtlesim and on a
machine whose variables change in place; large values are cut and say so; memory is bounded by N."""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

import pytest
from helpers import MACHINES, write_machine

import llfsm.debug.debugger as debugger_module
from llfsm.debug.debugger import Debugger
from llfsm.ros.inputs import bind
from llfsm.runtime import Arrangement, RunContext, SimClock
from llfsm.runtime.context import activate
from llfsm.runtime.inputs import TOPIC
from llfsm.targets import load


def _history(
    classes: list[type],
    compiled: bool,
    size: int,
    ms: int,
    turtlesim: bool,
    monkeypatch: Any,
    nodes: tuple[str, ...] = (),
) -> Any:
    """Run `classes` for `ms` rounds of 1 ms with a history of `size`, recorded by the ringlets
    (compiled) or by the watcher at every boundary (as where the ringlets cannot be compiled
    again: a native build, a machine the monitor compiled its checks into)."""
    ctx = RunContext(SimClock(1_000_000))
    bus = None
    if turtlesim:
        from llfsm.nodes import NodeOptions, start
        from llfsm.ros.bus import bus_of

        prev = activate(ctx)
        try:
            bus = bus_of(ctx)
            bus.log_stream = io.StringIO()
            bus.init()
            for node in ("turtlesim", *nodes):
                start(node, ctx, NodeOptions())
        finally:
            activate(prev)
    arr = Arrangement(classes, context=ctx)
    with monkeypatch.context() as m:
        if not compiled:
            m.setattr(debugger_module, "class_reads", lambda cls: None)
        d = Debugger(arr, history=size)
    assert d.history is not None and d.history.compiled is compiled
    if bus is not None:
        d.attach_bus(bus, lambda: None)
        if any(e[TOPIC] for c in classes for e in c.INPUTS):
            bind(arr, bus)  # inputs from their topics, as `llfsm run` binds them
    arr.run(duration_ns=ms * 1_000_000)
    return d.history


def _same(a: Any, b: Any) -> None:
    """Every record, every field, and the arrangement at several of them."""
    assert a.count == b.count
    assert a.last() == b.last()
    n = len(a.records)
    for back in sorted({0, 1, 2, 7, n // 3, n // 2, n - 1, n}):
        assert a.frame(back) == b.frame(back), back


def test_the_how_to_pair_with_turtlesim_records_the_same_history_compiled(monkeypatch: pytest.MonkeyPatch) -> None:
    pair = [load(str(MACHINES / f"{n}.machine")) for n in ("ros2_turtle_suspend_resume", "ros2_blind_turtle_bot")]
    compiled = _history(pair, True, 5000, 4500, True, monkeypatch)
    watched = _history(pair, False, 5000, 4500, True, monkeypatch)
    _same(compiled, watched)
    records = compiled.last()
    # what a user reads in it: suspends and resumes (a turn with no ringlet), transitions, the
    # bot's Twist changing, the topics published
    assert {r["machine"] for r in records} == {"ros2_turtle_suspend_resume", "ros2_blind_turtle_bot"}
    assert any(r["state"] is None and r["before"] == r["after"] == "SUSPENDED" for r in records)
    assert any(r["before"] == "SUSPENDED" and r["state"] not in (None, "SUSPENDED") for r in records)
    assert any("/turtle1/cmd_vel" in r["published"] for r in records)
    turns = [r for r in records if r["after"] == "TURN_RIGHT" and r["before"] == "STRAIGHT"]
    assert turns and all(r["transition"] == 1 for r in turns)
    assert any(r["changed"].get("msg", [None, None])[1] == {
        "linear": {"x": 0.0, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": -2.0}
    } for r in records)  # fmt: skip


def test_a_machine_with_an_input_from_a_sensor_records_the_same_history_compiled(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    wall = [load(str(MACHINES / "wall_follower.machine"))]
    compiled = _history(wall, True, 4000, 12000, True, monkeypatch, ("wall_sensor",))
    watched = _history(wall, False, 4000, 12000, True, monkeypatch, ("wall_sensor",))
    _same(compiled, watched)
    assert any(r["changed"].get("wall_close") == [False, True] for r in compiled.last())  # the gate's snapshot


def _lists(tmp_path: Path) -> list[type]:
    """grow: a list appended to, a string and a dict that grow, a tuple replaced, every ringlet;
    other: a counter that suspends and resumes grow."""
    grow = write_machine(
        tmp_path,
        "grow",
        {"A": [("B", "True")], "B": [("A", "len(xs) < 100")]},
        {
            "A_OnEntry": "xs.append(len(xs))\nlabel += 'abc'\n",
            "B_OnEntry": "seen[str(len(xs))] = len(xs) * 2\npair = (len(xs), -len(xs))\n",
        },
        variables="xs: list[int] = []\nlabel: str = ''\nseen: dict[str, int] = {}\n"
        "pair: tuple = (0, 0)\nquiet: int = 7\n",
    )
    boss = write_machine(
        tmp_path,
        "boss",
        {"S": [("S", "True")]},
        {"S_OnEntry": "k += 1\nif k % 10 == 3:\n    suspend('grow')\nif k % 10 == 6:\n    resume('grow')\n"},
        variables="k: int = 0\n",
    )
    return [load(str(grow)), load(str(boss))]


def test_values_changed_in_place_read_back_the_same_and_large_ones_say_they_are_cut(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    classes = _lists(tmp_path)
    compiled = _history(classes, True, 1000, 300, False, monkeypatch)
    watched = _history(classes, False, 1000, 300, False, monkeypatch)
    _same(compiled, watched)
    changed = [r["changed"] for r in compiled.last() if r["machine"] == "grow" and "xs" in r["changed"]]
    assert changed[0]["xs"] == [[], [0]]  # the list as it was, not the object it became
    grow = compiled.machines[0]
    assert len(grow.xs) > 40
    old, new = changed[-1]["xs"]
    assert new[-1] == f"… ({len(grow.xs)} items, truncated)" and len(new) == 33  # cut at 32 items, and says so
    assert old[-1] == f"… ({len(grow.xs) - 1} items, truncated)"
    label = [r["changed"]["label"] for r in compiled.last() if "label" in r["changed"]][-1]
    assert label[1].endswith(f"({len(grow.label)} characters, truncated)") and len(grow.label) > 200
    assert any(r["before"] == "SUSPENDED" for r in compiled.last() if r["machine"] == "grow")
    assert compiled.frame(len(compiled.records))["machines"][0]["values"]["quiet"] == 7


def test_a_variable_a_callback_changes_between_rounds_records_the_same_compiled(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A subscription's callback appends to a list between rounds (escaped: every ringlet of the
    machine takes it, and the change shows in the next one's record)."""
    d = write_machine(
        tmp_path,
        "heard",
        {"INITIAL": [("TALK", "True")], "TALK": [("TALK", "True")]},
        {
            "INITIAL_OnEntry": "ros.init()\nnode = ros.Node('heard')\n"
            "sub = node.create_subscription(String, '/said', lambda m: got.append(m.data), 10)\n"
            "pub = node.create_publisher(String, '/said', 10)\n",
            "TALK_OnEntry": "n += 1\nif n % 3 == 0:\n    pub.publish(String(data=str(n)))\n",
        },
        variables="n: int = 0\ngot: list = []\nnode: ros.Node = None\nsub: ros.Subscription = None\n"
        "pub: ros.Publisher = None\n",
        includes="from llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import String\n",
    )
    classes = [load(str(d))]
    compiled = _history(classes, True, 500, 200, True, monkeypatch)
    watched = _history(classes, False, 500, 200, True, monkeypatch)
    _same(compiled, watched)
    heard = [r for r in compiled.last() if "got" in r["changed"]]
    assert heard and heard[0]["changed"]["got"] == [[], ["3"]]
    assert any("/said" in r["published"] for r in compiled.last())


@pytest.mark.parametrize("rounds", [30, 101, 1234])
def test_the_history_keeps_the_last_n_records_and_memory_bounded_by_n(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, rounds: int
) -> None:
    classes = _lists(tmp_path)
    h = _history(classes, True, 50, rounds, False, monkeypatch)
    total = 2 * rounds
    assert h.count == total
    kept = h.last()
    assert len(kept) == len(h.records) == min(50, total)
    assert [r["ringlet"] for r in kept] == list(range(total - len(kept) + 1, total + 1))
    assert [r["round"] for r in kept[-2:]] == [rounds - 1, rounds - 1]
    assert len(h.records) == 50  # the oldest freed as each new one comes
    assert len(h.published) <= 50 and len(h._gated) <= 50


def test_a_spin_call_that_moves_the_sim_clock_records_the_same_times_compiled(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A ringlet that waits in a spin call moves the sim clock on in the middle of a round: its
    own record and those after it in that round carry the new time, as the watcher sees it."""
    waiter = write_machine(
        tmp_path,
        "waiter",
        {"INITIAL": [("WAIT", "True")], "WAIT": [("WAIT", "True")]},
        {
            "INITIAL_OnEntry": "ros.init()\nnode = ros.Node('waiter')\n",
            "WAIT_OnEntry": "n += 1\nif n % 4 == 0:\n    ros.spin_once(node, timeout_sec=0.0025)\n",
        },
        variables="n: int = 0\nnode: ros.Node = None\n",
        includes="from llfsm import ros\n",
    )
    after = write_machine(
        tmp_path, "after", {"S": [("S", "k % 3 == 0")]}, {"S_Internal": "k += 1\n"}, variables="k: int = 0\n"
    )
    classes = [load(str(waiter)), load(str(after))]
    compiled = _history(classes, True, 300, 100, True, monkeypatch)
    watched = _history(classes, False, 300, 100, True, monkeypatch)
    _same(compiled, watched)
    records = compiled.last()
    # the waiter's 4th WAIT (round 4, due at 4 ms) waits 2.5 ms: its record and the other
    # machine's after it in that round are at 6.5 ms, the next round at 7.5 ms
    assert [(r["machine"], r["round"], r["t"]) for r in records[7:11]] == [
        ("after", 3, 0.003), ("waiter", 4, 0.0065), ("after", 4, 0.0065), ("waiter", 5, 0.0075)
    ]  # fmt: skip
