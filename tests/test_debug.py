"""The debugger's machinery on the scheduler (llfsm.debug, docs/debug.md): where a pause happens,
what a step runs, the clock while paused, breakpoints' edges, the history's frames, typed sets,
and the bus while paused.  Commands are handed in by listeners, as the prompt and the page do."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest
from helpers import write_machine

from llfsm import ros
from llfsm.debug.debugger import CONTINUE, ROUND, STEP, DebugError, Debugger
from llfsm.debug.services import answers, offer
from llfsm.debug.variables import typed
from llfsm.msgs.llfsm_msgs.srv import GetVariables
from llfsm.msgs.std_msgs.msg import String
from llfsm.msgs.std_srvs.srv import Trigger
from llfsm.ros.bus import bus_of
from llfsm.ros.control import enable
from llfsm.runtime import Arrangement, RunContext, SimClock, WallClock
from llfsm.runtime.context import activate
from llfsm.targets import load


def _machines(tmp_path: Path) -> list[type]:
    """a: A -> B -> A every ringlet, counting; b: a counter that ends at 3."""
    a = write_machine(
        tmp_path,
        "a",
        {"A": [("B", "True")], "B": [("A", "True")]},
        {"A_OnEntry": "n += 1"},
        variables="n: int = 0\nname: str = 'x'\nxs: list[float] = []\n",
    )
    b = write_machine(
        tmp_path, "b", {"S": [("END", "k >= 3"), ("S", "True")], "END": None}, {"S_OnEntry": "k += 1"}, "k: int = 0\n"
    )
    return [load(str(a)), load(str(b))]


def _script(d: Debugger, steps: list[Callable[[Debugger], Any]]) -> list[str]:
    """At each pause, the next step (a command), and what the pause looked like."""
    seen: list[str] = []
    todo = list(steps)

    def on(dbg: Debugger) -> None:
        if dbg.paused:
            seen.append(dbg.where())
            step = todo.pop(0) if todo else (lambda x: x.resume(CONTINUE))
            dbg.inbox.put(lambda: step(dbg))

    d.listeners.append(on)
    return seen


def test_a_pause_before_the_first_round_then_steps_of_a_ringlet_and_of_a_round(tmp_path: Path) -> None:
    arr = Arrangement(_machines(tmp_path), context=RunContext(SimClock(1_000_000)))
    d = Debugger(arr)
    d.pause("--paused")
    states: list[tuple[str, ...]] = []

    def record(dbg: Debugger) -> None:
        states.append(tuple(m.STATES[m._state] for m in arr.machines))

    seen = _script(
        d,
        [
            lambda x: (record(x), x.resume(STEP)),
            lambda x: (record(x), x.resume(STEP)),
            lambda x: (record(x), x.resume(STEP)),
            lambda x: (record(x), x.resume(ROUND)),
            lambda x: (record(x), x.resume(CONTINUE)),
        ],
    )
    r = arr.run(duration_ns=20_000_000)
    assert r.reason == "finished" or r.reason == "duration"
    assert seen == [
        "paused before the first round (0.000 s): --paused",
        "paused round 0, after a's ringlet (0.000 s): step",
        "paused round 0, after b's ringlet (0.000 s): step",
        "paused round 1, after a's ringlet (0.001 s): step",
        "paused before round 2 (0.002 s): step round",  # the rest of round 1, and the bus after it
    ]
    assert states == [("A", "S"), ("B", "S"), ("B", "S"), ("A", "S"), ("A", "S")]
    assert arr.watcher is None  # continued with nothing to watch: the plain loops again


def test_a_pause_asked_from_another_thread_stops_the_plain_loop_between_rounds(tmp_path: Path) -> None:
    classes = _machines(tmp_path)[:1]
    arr = Arrangement(classes, context=RunContext(SimClock(1_000)))
    d = Debugger(arr)
    assert arr.watcher is None
    paused = threading.Event()

    def on(dbg: Debugger) -> None:
        if dbg.paused:
            paused.set()
            dbg.inbox.put(lambda: dbg.arr.interrupt(0))  # end the run from the pause

    d.listeners.append(on)
    asker = threading.Timer(0.05, d.pause)
    asker.start()
    r = arr.run(duration_ns=10**15, grace_ns=0)
    assert paused.is_set()
    assert r.reason == "interrupted"
    assert d.at is None  # between two rounds: the plain loop has no ringlet boundary to stop at


def test_the_wall_clock_leaves_paused_time_out_of_the_run_time(tmp_path: Path) -> None:
    arr = Arrangement(_machines(tmp_path)[:1], context=RunContext(WallClock(idle_ns=1_000_000)))
    d = Debugger(arr)
    d.pause()
    times: list[int] = []

    def on(dbg: Debugger) -> None:
        if dbg.paused:
            times.append(arr.clock.now)
            time.sleep(0.4)  # a person reading the prompt
            dbg.inbox.put(lambda: dbg.resume(CONTINUE))
        else:
            times.append(arr.clock.read())

    d.listeners.append(on)
    arr.run(duration_ns=50_000_000)
    assert len(times) == 2
    assert times[1] - times[0] < 100_000_000  # the 0.4 s paused are not run time


def test_breakpoints_are_edge_triggered_and_fired_is_an_event(tmp_path: Path) -> None:
    arr = Arrangement(_machines(tmp_path), context=RunContext(SimClock(1_000_000)))
    d = Debugger(arr)
    d.add_break("a.n >= 2")  # true from a's third ringlet on: pauses once
    d.add_break('fired(b, "S", 1)')  # b's self-loop fires at each of its first ringlets
    seen = _script(d, [])
    arr.run(duration_ns=10_000_000)
    assert [s.split(": ", 1)[1] for s in seen] == [
        'break 2: fired(b, "S", 1)',  # round 0: b's S loops (k = 1)
        'break 2: fired(b, "S", 1)',  # round 1 (k = 2); round 2 leaves for END
        "break 1: a.n >= 2",  # round 2: a enters A a second time
    ]
    with pytest.raises(DebugError, match="b has no state T"):
        d.add_break('fired(b, "T", 0)')


def test_history_keeps_n_records_and_rebuilds_the_arrangement_at_any(tmp_path: Path) -> None:
    arr = Arrangement(_machines(tmp_path), context=RunContext(SimClock(1_000_000)))
    d = Debugger(arr, history=5)
    arr.run(duration_ns=4_000_000)
    h = d.history
    assert h is not None and len(h.records) == 5 and h.count == 8
    last = h.last(2)
    assert [(r["machine"], r["before"], r["after"], r["transition"]) for r in last] == [
        ("a", "B", "A", 0),
        ("b", "END", "END", None),
    ]
    assert h.last(4)[0]["changed"] == {"n": [1, 2]}  # ringlet 5: a entered A again
    now, before = h.frame(0), h.frame(4)
    assert [m["state"] for m in now["machines"]] == ["A", "END"]
    assert now["machines"][0]["values"]["n"] == 2
    assert before["record"]["ringlet"] == 4  # round 1, b's ringlet
    assert [m["state"] for m in before["machines"]] == ["A", "S"]
    assert before["machines"][0]["values"]["n"] == 1 and before["machines"][1]["values"]["k"] == 2


def test_a_set_while_paused_is_typed_and_a_refusal_leaves_the_run_be(tmp_path: Path) -> None:
    arr = Arrangement(_machines(tmp_path), context=RunContext(SimClock(1_000_000)))
    d = Debugger(arr, history=10)
    with pytest.raises(DebugError, match="pause the run first"):
        d.set_value("a", "n", "5")
    d.pause()
    answers: list[str] = []

    def commands(dbg: Debugger) -> None:
        for var, text in (("n", "5"), ("n", "5.5"), ("xs", "[1, 2.5]"), ("name", "7"), ("nn", "1")):
            try:
                answers.append(dbg.set_value("a", var, text))
            except DebugError as e:
                answers.append(str(e))
        dbg.resume(CONTINUE)

    _script(d, [commands])
    arr.run(duration_ns=2_000_000)
    assert answers == [
        "a.n = 5",
        "a.n is int: 5.5 is a float, not an int",
        "a.xs = [1.0, 2.5]",
        "a.name is str: 7 is an int, not a string",
        "a has no variable or input nn (did you mean a.n?); it has: n, name, xs",
    ]
    assert d.read("a")["a"]["variables"]["n"] == 6  # set to 5, then one more A entry
    kinds = [r["kind"] for r in d.history.last()]  # type: ignore[union-attr]
    assert kinds.count("set") == 2


@pytest.mark.parametrize(
    ("annotation", "value", "result"),
    [
        ("float", 2, 2.0),
        ("int | None", None, None),
        ("Optional[str]", "x", "x"),
        ("tuple[int, str]", [1, "a"], (1, "a")),
        ("dict[str, float]", {"a": 1}, {"a": 1.0}),
        ("list", [1, "a"], [1, "a"]),
        ("typing.Any", {"x": [1]}, {"x": [1]}),
    ],
)
def test_values_are_typed_by_annotations(annotation: str, value: Any, result: Any) -> None:
    assert typed(annotation, value, {}) == result


def test_a_message_variable_takes_a_mapping_of_its_fields() -> None:
    from llfsm.msgs.geometry_msgs.msg import Twist

    msg = typed("Twist", {"linear": {"x": 2}}, {"Twist": Twist})
    assert isinstance(msg, Twist) and msg.linear.x == 2.0
    with pytest.raises(TypeError, match="cannot be typed in the debugger"):
        typed("ros.Publisher", 1, {})
    with pytest.raises(TypeError, match="not a mapping"):
        typed("Twist", 3, {"Twist": Twist})


@contextmanager
def _on_a_bus(tmp_path: Path) -> Iterator[tuple[Arrangement, Debugger]]:
    """Machine a on a bus with its control services, and its debugger answering them while
    paused; the run's context active meanwhile (for the test's own nodes)."""
    ctx = RunContext(SimClock(1_000_000))
    arr = Arrangement(_machines(tmp_path)[:1], context=ctx)
    prev = activate(ctx)
    try:
        bus = bus_of(ctx)
        ros.init()
        enable(ctx)
        d = Debugger(arr)
        d.attach_bus(bus, lambda: bus.spin_control(answers))
        yield arr, d
    finally:
        activate(prev)


def test_while_paused_the_bus_answers_control_services_and_keeps_callbacks_queued(tmp_path: Path) -> None:
    with _on_a_bus(tmp_path) as (arr, d):
        node = ros.Node("probe")
        heard: list[str] = []
        node.create_subscription(String, "/chat", lambda m: heard.append(m.data), 10)
        pub = node.create_publisher(String, "/chat", 10)
        node.create_service(Trigger, "/llfsm/a/probe", lambda req, res: res)
        node.create_service(Trigger, "/other", lambda req, res: res)
        control_client = node.create_client(Trigger, "/llfsm/a/probe")
        other_client = node.create_client(Trigger, "/other")
    d.pause()
    results: dict[str, Any] = {}

    def on(dbg: Debugger) -> None:
        if not dbg.paused:
            return
        pub.publish(String(data="while paused"))
        results["control"] = control_client.call_async(Trigger.Request())
        results["other"] = other_client.call_async(Trigger.Request())
        dbg._serve_once(0)  # what the pause loop does between commands
        results["control_done"] = results["control"].done()
        results["other_done"] = results["other"].done()
        results["heard"] = list(heard)
        dbg.inbox.put(lambda: dbg.resume(CONTINUE))

    d.listeners.append(on)
    arr.run(duration_ns=3_000_000)
    assert results["control_done"] and not results["other_done"]
    assert results["heard"] == []  # the callback waited for the run to go on
    assert heard == ["while paused"] and results["other"].done()


def _three(tmp_path: Path) -> list[type]:
    """x and z toggle; y goes A -> B -> C -> A, one state a ringlet."""
    x = write_machine(tmp_path, "x", {"P": [("Q", "True")], "Q": [("P", "True")]})
    y = write_machine(tmp_path, "y", {"A": [("B", "True")], "B": [("C", "True")], "C": [("A", "True")]})
    z = write_machine(tmp_path, "z", {"P": [("Q", "True")], "Q": [("P", "True")]})
    return [load(str(p)) for p in (x, y, z)]


def _positions(tmp_path: Path, history: int | None) -> list[tuple[str, tuple[str, ...]]]:
    """Where a state breakpoint and the steps after it pause, and every machine's state there."""
    arr = Arrangement(_three(tmp_path), context=RunContext(SimClock(1_000_000)))
    d = Debugger(arr, history=history)
    d.add_break('state(y) == "C"')
    out: list[tuple[str, tuple[str, ...]]] = []

    def at(dbg: Debugger, mode: str) -> None:
        out.append((dbg.reason, tuple(m.STATES[m._state] for m in arr.machines)))
        dbg.resume(mode)

    _script(d, [lambda x: at(x, STEP), lambda x: at(x, STEP), lambda x: at(x, STEP), lambda x: at(x, ROUND)])
    arr.run(duration_ns=8_000_000)
    return out


def test_a_breakpoint_on_a_state_pauses_and_steps_where_the_watcher_would(tmp_path: Path) -> None:
    marked = _positions(tmp_path / "a", None)  # no history: the transition into C is marked
    watched = _positions(tmp_path / "b", 100)  # history: every boundary is watched
    assert marked == watched
    assert marked[0] == ('break 1: state(y) == "C"', ("P", "C", "Q"))  # round 1: after y's ringlet, before z's
    assert [r for r, _ in marked] == ['break 1: state(y) == "C"', "step", "step", "step"]


def test_marked_ringlets_cost_nothing_elsewhere_and_go_when_the_breakpoint_goes(tmp_path: Path) -> None:
    classes = _three(tmp_path)
    arr = Arrangement(classes, context=RunContext(SimClock(1_000_000)))
    d = Debugger(arr)
    bp = d.add_break('state(y) == "C"')
    assert arr.watcher is None  # a breakpoint on a state needs no watcher
    y = arr.machines[1]
    assert type(y) is not classes[1] and isinstance(y, classes[1])  # its ringlets are marked
    assert type(arr.machines[0]) is classes[0]
    d.remove_break(bp.number)
    assert type(y) is classes[1] and arr.on_release is None
    d.add_break('state(y) == "C" and state(x) == "P"')  # two machines: judged at every boundary
    assert arr.watcher is not None


def test_a_breakpoint_on_a_state_a_command_reaches_pauses_before_it_takes_effect(tmp_path: Path) -> None:
    boss = write_machine(tmp_path, "boss", {"A": [("B", "after_ms(3)")], "B": [("B", "False")]},
                         {"A_OnEntry": 'suspend("w")', "B_OnEntry": 'resume("w")'})  # fmt: skip
    w = write_machine(tmp_path, "w", {"S": [("T", "after_ms(10)")], "T": None})
    arr = Arrangement([load(str(boss)), load(str(w))], context=RunContext(SimClock(1_000_000)))
    d = Debugger(arr)
    d.add_break('state(w) == "S"')
    seen = _script(d, [])
    arr.run(duration_ns=20_000_000)
    assert seen == [
        'paused at w\'s turn, before its command (0.005 s): break 1: state(w) == "S" (the resume of w takes it to S)'
    ]


def test_the_debug_services_answer_on_the_in_process_bus_too(tmp_path: Path) -> None:
    with _on_a_bus(tmp_path) as (arr, d):
        offer(d, arr.ctx.machine_graph, topic=False)
        probe = ros.Node("probe")
        pause = probe.create_client(Trigger, "/llfsm/a/pause")
        read = probe.create_client(GetVariables, "/llfsm/a/variables")
        go = probe.create_client(Trigger, "/llfsm/a/continue")
        once: list[Any] = []

        def ask() -> None:  # once, at 5 ms of run time
            once[0].cancel()
            pause.call_async(Trigger.Request())

        once.append(probe.create_timer(0.005, ask))
    answers_seen: list[Any] = []

    def on(dbg: Debugger) -> None:
        if dbg.paused and not answers_seen:
            answers_seen.append(dbg.where())
            f = read.call_async(GetVariables.Request())
            dbg._serve_once(0)  # the pause loop answers it
            answers_seen.append(f.result())
            g = go.call_async(Trigger.Request())
            dbg._serve_once(0)
            answers_seen.append(g.result().message)

    d.listeners.append(on)
    arr.run(duration_ns=10_000_000)
    where, variables, resumed = answers_seen
    assert where == "paused before round 5 (0.005 s): /llfsm/a/pause called"
    assert variables.paused and "state: " in variables.yaml and "n: " in variables.yaml
    assert resumed == "continuing"
