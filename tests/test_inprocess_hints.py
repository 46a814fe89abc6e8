"""Issue 22, item 6: a run on the in-process bus that waits for what only another process could
provide says that it is in-process and how to join the others, once per service or topic."""

from __future__ import annotations

from pathlib import Path

from helpers import MACHINES, run_sim, write_machine

WALL = MACHINES / "ros2_wall_turtle_bot.machine"
HINT = "run every side with --transport dds (or LLFSM_TRANSPORT=dds)"


def test_waiting_for_a_service_nobody_in_the_run_serves_says_the_run_is_in_process() -> None:
    r = run_sim(WALL, "--node", "turtlesim")  # no turtle_sensor_poster: SERVICE_FAILS, and the end
    assert r.status == 0, r.stderr
    lines = [x for x in r.stderr.splitlines() if HINT in x]
    assert lines == [
        "llfsm: /turtle_pose_service has no server in this run, which is on the in-process bus: other processes "
        f"cannot reach it. To join nodes in other processes, {HINT}."
    ]
    assert r.stderr.index(HINT) < r.stderr.index("is turtle_sensor_poster running?")  # before the machine's guess


def test_a_served_service_and_a_heard_topic_say_nothing() -> None:
    both = run_sim(WALL, "--node", "turtlesim", "--node", "turtle_sensor_poster", "--duration", "10s")
    assert both.status == 0, both.stderr
    assert HINT not in both.stderr


def test_a_subscription_nothing_published_to_is_named_at_the_end(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "listener",
        {"INITIAL": [("WAIT", "True")], "WAIT": [("WAIT", "False")]},
        {
            "INITIAL_OnEntry": (
                "ros.init()\nnode = ros.Node('listener')\nsub = node.create_subscription(String, '/chat', None, 10)"
            )
        },
        variables="node: ros.Node\nsub: ros.Subscription\n",
        includes="from llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import String\n",
    )
    r = run_sim(m, "--duration", "10ms")
    assert r.status == 0
    assert (
        r.stderr.count(HINT) == 1 and "nothing published /chat, which a machine subscribed to, in this run" in r.stderr
    )
