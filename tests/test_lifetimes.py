"""Issue 22, item 1: what machine code creates on the bus lives as long as the machine's
variables hold it (rclpy's garbage collection, clfsm's shared_ptr): a restart that re-runs
INITIAL, a state entered again, a machine finishing and `destroy_node()` leave no duplicates in
the graph (docs/bus.md, Lifetimes)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from helpers import run_sim, write_machine

from llfsm import ros
from llfsm.msgs.geometry_msgs.msg import Twist
from llfsm.msgs.std_srvs.srv import Trigger
from llfsm.ros.bus import bus_of
from llfsm.ros.control import enable
from llfsm.runtime import Arrangement, RunContext, SimClock
from llfsm.runtime.context import activate
from llfsm.targets import load

INCLUDES = "from llfsm import ros\nfrom llfsm.msgs.geometry_msgs.msg import Twist\n"


@pytest.fixture
def ctx() -> Iterator[RunContext]:
    c = RunContext(SimClock())
    prev = activate(c)
    try:
        yield c
    finally:
        activate(prev)


def _bot(root: Path, states: dict[str, list[tuple[str, str]] | None], code: dict[str, str]) -> Path:
    return write_machine(root, "bot", states, code, variables="node: ros.Node\npub: ros.Publisher\n", includes=INCLUDES)


def _arrangement(ctx: RunContext, *machines: Path) -> Arrangement:
    arr = Arrangement([load(str(m)) for m in machines], context=ctx)
    ros.init()
    enable(ctx)
    return arr


def _users(ctx: RunContext, node: str = "/wall_bot", topic: str = "/turtle1/cmd_vel") -> tuple[int, int]:
    """How many nodes of that name the graph lists, and the topic's publishers."""
    g = bus_of(ctx).graph()
    return g["nodes"].count(node), g["topics"].get(topic, {}).get("publishers", 0)


CREATE = "ros.init()\nnode = ros.Node('wall_bot')\npub = node.create_publisher(Twist, '/turtle1/cmd_vel', 10)\n"


def test_a_restart_through_the_control_service_leaves_one_node_and_one_publisher(
    tmp_path: Path, ctx: RunContext
) -> None:
    arr = _arrangement(
        ctx,
        _bot(tmp_path, {"INITIAL": [("DRIVE", "True")], "DRIVE": [("DRIVE", "False")]}, {"INITIAL_OnEntry": CREATE}),
    )
    caller = ros.Node("caller")
    client = caller.create_client(Trigger, "/llfsm/bot/restart")
    calls: list[ros.Future] = []
    caller.create_timer(0.003, lambda: calls.append(client.call_async(Trigger.Request())))  # at 3, 6, 9 ms
    arr.run(duration_ns=10_000_000)
    assert [f.result().success for f in calls] == [True, True, True]
    assert _users(ctx) == (1, 1)
    assert arr.by_name["bot"].node.get_fully_qualified_name() == "/wall_bot"


def test_a_state_entered_again_replaces_its_publisher(tmp_path: Path, ctx: RunContext) -> None:
    bot = _bot(
        tmp_path,
        {"INITIAL": [("DRIVE", "True")], "DRIVE": [("DRIVE", "after_ms(1)")]},
        {
            "INITIAL_OnEntry": "ros.init()\nnode = ros.Node('wall_bot')\n",
            "DRIVE_OnEntry": "pub = node.create_publisher(Twist, '/turtle1/cmd_vel', 10)\npub.publish(Twist())\n",
        },
    )
    arr = _arrangement(ctx, bot)
    got: list[object] = []
    ros.Node("watcher").create_subscription(Twist, "/turtle1/cmd_vel", got.append, 10)
    arr.run(duration_ns=20_000_000)
    assert len(got) > 5  # DRIVE was entered again and again, and each publisher was heard
    assert _users(ctx) == (1, 1)


def test_a_finished_machine_releases_its_node(tmp_path: Path, ctx: RunContext) -> None:
    bot = _bot(tmp_path, {"INITIAL": [("END", "after_ms(2)")], "END": None}, {"INITIAL_OnEntry": CREATE})
    arr = _arrangement(ctx, bot)
    seen: list[tuple[int, int]] = []
    ros.Node("watcher").create_timer(0.001, lambda: seen.append(_users(ctx)))
    arr.serve_forever = True  # the run goes on without machines, so the graph can be looked at after
    arr.run(duration_ns=6_000_000)
    assert seen[0] == (1, 1)  # while the machine runs
    assert seen[-1] == (0, 0)  # after it finished


def test_destroy_node_takes_the_node_out_of_the_graph(tmp_path: Path, ctx: RunContext) -> None:
    bot = _bot(
        tmp_path,
        {"INITIAL": [("STOP", "after_ms(2)")], "STOP": [("END", "after_ms(5)")], "END": None},
        {"INITIAL_OnEntry": CREATE, "STOP_OnEntry": "node.destroy_node()\n"},
    )
    arr = _arrangement(ctx, bot)
    seen: list[tuple[int, int]] = []
    ros.Node("watcher").create_timer(0.001, lambda: seen.append(_users(ctx)))
    arr.run(duration_ns=6_000_000)
    assert seen[0] == (1, 1)
    assert seen[-1] == (0, 0)
    with pytest.raises(RuntimeError, match="has been destroyed"):
        arr.by_name["bot"].node.create_publisher(Twist, "/x", 10)


def test_what_machine_code_never_kept_lives_with_its_node(tmp_path: Path) -> None:
    """rclpy's node keeps its entities: a subscription whose result was not kept still gets its
    messages, rounds after it was made."""
    bot = write_machine(
        tmp_path,
        "bot",
        {"INITIAL": [("TALK", "after_ms(1)")], "TALK": [("TALK", "after_ms(1)")]},
        {
            "INITIAL_OnEntry": (
                "ros.init()\nnode = ros.Node('bot')\n"
                "node.create_subscription(String, '/chat', lambda m: print('heard', m.data), 10)\n"
                "pub = node.create_publisher(String, '/chat', 10)\n"
            ),
            "TALK_OnEntry": "n += 1\npub.publish(String(data=str(n)))\n",
        },
        variables="n: int = 0\nnode: ros.Node\npub: ros.Publisher\n",
        includes="from llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import String\n",
    )
    r = run_sim(bot, "--duration", "30ms")
    assert r.status == 0, r.stderr
    heard = [x for x in r.lines if x.startswith("heard")]
    assert len(heard) >= 8 and heard == [f"heard {i}" for i in range(1, len(heard) + 1)]
