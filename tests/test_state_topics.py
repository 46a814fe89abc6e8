"""Machines on the graph (SPEC §8): /llfsm/M/state, /llfsm/M/description and the control
services, in process under the sim clock."""

from __future__ import annotations

import io
import json
from collections.abc import Iterator
from pathlib import Path

import pytest
from helpers import run_sim, write_machine

from llfsm import ros
from llfsm.msgs.std_msgs.msg import String
from llfsm.msgs.std_srvs.srv import Trigger
from llfsm.ros.control import LATCHED, enable
from llfsm.runtime import Arrangement, RunContext, SimClock, Tracer
from llfsm.runtime.context import activate
from llfsm.targets import load

CYCLE = {
    "A": [("B", "after_ms(2)")],
    "B": [("C", "after_ms(3)")],
    "C": [("A", "after_ms(1)"), ("END", "False")],
    "END": None,
}


@pytest.fixture
def ctx() -> Iterator[RunContext]:
    c = RunContext(SimClock())
    prev = activate(c)
    try:
        yield c
    finally:
        activate(prev)


def _arrangement(ctx: RunContext, *machines: Path, verbose: io.StringIO | None = None) -> Arrangement:
    tracer = Tracer(verbose=verbose) if verbose is not None else None
    arr = Arrangement([load(str(m)) for m in machines], context=ctx, tracer=tracer)
    ros.init()
    enable(ctx)
    return arr


def _cycle(tmp_path: Path) -> Path:
    return write_machine(tmp_path, "cycle", CYCLE)


def test_a_late_subscriber_gets_the_current_state_at_once(tmp_path: Path, ctx: RunContext) -> None:
    arr = _arrangement(ctx, _cycle(tmp_path))
    watcher = ros.Node("watcher")
    seen: dict[str, object] = {}

    def join() -> None:  # at 4 ms, with no reader before: the machine is in B by then
        sub = watcher.create_subscription(String, "/llfsm/cycle/state", None, LATCHED)
        seen["latched"] = sub.latest.data if sub.latest is not None else None
        seen["actual"] = arr.by_name["cycle"].state_name()
        volatile = watcher.create_subscription(String, "/llfsm/cycle/state", None, 1)
        seen["volatile"] = volatile.latest
        timer.cancel()

    timer = watcher.create_timer(0.004, join)
    arr.run(duration_ns=10_000_000)
    assert seen["actual"] == "B"
    assert seen["latched"] == "B"  # brought up to date although nothing was published while unheard
    assert seen["volatile"] is None  # as in ROS, a volatile subscription gets no history


def test_state_changes_are_seen_in_order_and_match_the_trace(tmp_path: Path, ctx: RunContext) -> None:
    v = io.StringIO()
    arr = _arrangement(ctx, _cycle(tmp_path), verbose=v)
    got: list[str] = []
    ros.Node("watcher").create_subscription(String, "/llfsm/cycle/state", lambda m: got.append(m.data), LATCHED)
    arr.run(duration_ns=30_000_000)
    entered = [line.rsplit(" - ", 1)[1] for line in v.getvalue().splitlines()]
    assert got[:4] == ["A", "B", "C", "A"]
    # every state entered, in order; the last change may not have been entered yet when the run ended
    assert got[: len(entered)] == entered and len(got) - len(entered) in (0, 1)


def test_the_description_carries_states_transitions_and_guards(tmp_path: Path, ctx: RunContext) -> None:
    _arrangement(ctx, _cycle(tmp_path))
    sub = ros.Node("watcher").create_subscription(String, "/llfsm/cycle/description", None, LATCHED)
    d = json.loads(sub.latest.data)
    assert [s["name"] for s in d["states"]] == ["A", "B", "C", "END", "SUSPENDED"]
    assert d["states"][2]["transitions"] == [
        {"index": 0, "target": "A", "guard": "after_ms(1)"},
        {"index": 1, "target": "END", "guard": "False"},
    ]
    assert d["initial"] == "A" and d["suspend"] == "SUSPENDED"
    assert [s["accepting"] for s in d["states"]] == [False, False, False, True, False]


def test_bad_commands_say_why_and_change_nothing(tmp_path: Path, ctx: RunContext) -> None:
    arr = _arrangement(ctx, _cycle(tmp_path))
    node = ros.Node("caller")

    def call(verb: str) -> tuple[bool, str]:
        fut = node.create_client(Trigger, f"/llfsm/cycle/{verb}").call_async(Trigger.Request())
        assert ros.spin_until_future_complete(node, fut) is ros.FutureReturnCode.SUCCESS
        return fut.result().success, fut.result().message

    m = arr.by_name["cycle"]
    assert call("resume") == (False, "cycle is not suspended")
    ok, message = call("suspend")
    assert ok and "pending" in message
    assert m._pending == "suspend" and not m._suspended  # pending until the machine's next ringlet
    assert call("suspend") == (False, "cycle is already suspended")
    arr.run(duration_ns=2_000_000)
    assert m._suspended and m.state_name() == "SUSPENDED"
    assert call("suspend") == (False, "cycle is already suspended")
    assert call("resume")[0]
    assert call("resume") == (False, "cycle is not suspended")
    m._finished = True  # as after an accepting state
    assert call("suspend") == (False, "cycle has finished; only restart brings it back")
    assert call("restart")[0]
    assert ros.Node("x").create_client(Trigger, "/llfsm/nope/suspend").service_is_ready() is False


# -- through the command line: the services have the macros' semantics ------------------------------


def _worker(root: Path) -> Path:
    return write_machine(
        root,
        "worker",
        {"A": [("END", "False")], "END": None, "SUSPENDED": None},
        {
            "A_OnEntry": "n += 1\nprint('A entry', n, current().clock.now // 10**6)",
            "A_Internal": "print('A internal', current().clock.now // 10**6)",
            "A_OnExit": "print('A exit')",
            "A_OnSuspend": "print('A suspend')",
            "A_OnResume": "print('A resume')",
            "SUSPENDED_OnEntry": "print('SUSPENDED entry')",
            "SUSPENDED_OnResume": "print('SUSPENDED resume')",
        },
        variables="n: int = 0\n",
        includes="from llfsm.runtime import current\n",
    )


def _boss(root: Path, through_services: bool) -> Path:
    """Suspends the worker at 3 ms, resumes it at 8 ms, restarts it at 13 ms: by the macros, or
    through /llfsm/worker/<verb> (the call returns within the same ringlet)."""

    def command(verb: str) -> str:
        if not through_services:
            return f'{verb}("worker")\nprint("boss: {verb}")'
        return (
            f"fut = node.create_client(Trigger, '/llfsm/worker/{verb}').call_async(Trigger.Request())\n"
            "ros.spin_until_future_complete(node, fut)\n"
            f'print("boss: {verb}")\n'
            "print('svc', fut.result().success)"
        )

    return write_machine(
        root,
        "boss",
        {
            "WAIT": [("STOP", "after_ms(3)")],
            "STOP": [("GO", "after_ms(5)")],
            "GO": [("AGAIN", "after_ms(5)")],
            "AGAIN": [("END", "after_ms(2)")],
            "END": None,
        },
        {
            "WAIT_OnEntry": "ros.init()\nnode = ros.Node('boss')",
            "STOP_OnEntry": command("suspend"),
            "GO_OnEntry": command("resume"),
            "AGAIN_OnEntry": command("restart"),
        },
        variables="node: ros.Node\n",
        includes="from llfsm import ros\nfrom llfsm.msgs.std_srvs.srv import Trigger\n",
    )


def test_suspend_resume_restart_through_the_services_act_as_the_macros(tmp_path: Path) -> None:
    macro = run_sim(_boss(tmp_path / "m", False), _worker(tmp_path / "m"), "--duration", "20ms", "-v")
    service = run_sim(_boss(tmp_path / "s", True), _worker(tmp_path / "s"), "--duration", "20ms", "-v")
    assert macro.status == service.status == 0, service.stderr
    assert [x for x in service.lines if x.startswith("svc")] == ["svc True"] * 3
    assert [x for x in service.lines if not x.startswith("svc")] == macro.lines
    assert service.stderr == macro.stderr  # the -v trace too
    out = macro.lines
    i = out.index("boss: suspend")
    assert out[i + 1 : i + 3] == ["A suspend", "SUSPENDED entry"]
    assert "A exit" not in out


def test_verbose_output_is_unchanged_while_someone_watches_the_state(tmp_path: Path) -> None:
    boss, worker = _boss(tmp_path, True), _worker(tmp_path)
    plain = run_sim(boss, worker, "--duration", "20ms", "-v")
    watched = run_sim(boss, worker, "--duration", "20ms", "-v", "--echo", "/llfsm/worker/state")
    assert watched.stderr == plain.stderr
    states = [x.removeprefix("data: ") for x in watched.lines if x.startswith("data: ")]
    assert states == ["A", "SUSPENDED", "A", "A"]  # the first, suspended, resumed, restarted
