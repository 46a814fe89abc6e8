"""Actions across processes on ROS 2's wire (`--transport dds`) and `llfsm action list|info|
send_goal` (docs/actions.md): turtlesim's rotate_absolute from the command line and from a
machine, a machine that serves a user's .action (cancel, abort, reject, two goals at once),
Ctrl-C cancelling a goal, a server that vanishes mid-goal, and bad input.

Every process runs in one private network namespace (dds_netns.py): real processes talking over
Cyclone DDS, no mocks.  Against rclpy's Fast DDS: tests/interop/test_actions_rclpy.py.
"""

# ruff: noqa: F811  (the netns fixture is imported, and test arguments name it)
from __future__ import annotations

import re
import signal
import sys
import time
from pathlib import Path

import pytest
from dds_netns import NetNamespace, finish, netns  # noqa: F401  (netns is a fixture)
from helpers import MACHINES, llfsm, write_machine

ROTATE = ("/turtle1/rotate_absolute", "turtlesim/action/RotateAbsolute")
#: Peers that vanish without saying goodbye are noticed after the lease: 1 s instead of 10 s.
SHORT_LEASE = {
    "CYCLONEDDS_URI": "<CycloneDDS><Domain><Discovery><LeaseDuration>1s</LeaseDuration></Discovery></Domain>"
    "</CycloneDDS>"
}
COUNT_ACTION = "# count up to target, a number every 100 ms\nint32 target\n---\nint32 total\n---\nint32 current\n"


def wait_for_line(p: object, pattern: str, timeout: float) -> str:
    """Read the process's stdout until a line matches (the lines read so far are returned).  The
    pipe is read a byte at a time from its descriptor, past the text wrapper: a `readline()` after
    `select` takes a whole chunk into the wrapper's buffer, where a line that came with the one
    before it waits unseen by `select` until the process writes again (the cancel test then saw
    "Goal accepted" only once the goal's result had come).  What is left stays in the pipe for
    `finish`."""
    import os
    import select

    fd = p.stdout.fileno()  # type: ignore[attr-defined]
    seen, line = "", b""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if not select.select([fd], [], [], 0.2)[0]:
            continue
        byte = os.read(fd, 1)
        if not byte:
            break
        line += byte
        if byte == b"\n":
            text, line = line.decode(), b""
            seen += text
            if re.search(pattern, text):
                return seen
    seen += line.decode(errors="replace")
    raise AssertionError(f"no line matching {pattern!r} within {timeout} s; got:\n{seen}")


def llfsm_at(ns: NetNamespace, cwd: Path, *args: str | Path, env: dict[str, str] | None = None) -> object:
    """`llfsm ARGS` in the namespace, run from `cwd` (where a user's interface package sits)."""
    return ns.popen([sys.executable, "-m", "llfsm", *map(str, args)], env=env, cwd=cwd)


def theta_of(echo: str) -> float:
    m = re.search(r"^theta: (\S+)$", echo, re.M)
    assert m, echo
    return float(m.group(1))


# -- turtlesim's rotate_absolute -------------------------------------------------------------------------


@pytest.mark.dds
def test_send_goal_turns_turtlesim_in_another_process_as_ros2_prints_it(netns: NetNamespace) -> None:
    sim = netns.llfsm("run", "--transport", "dds", "--node", "turtlesim", "--duration", "25")
    listed = netns.llfsm("action", "list", "-t", "--spin-time", "3")
    assert finish(listed, 20)[1] == "/turtle1/rotate_absolute [turtlesim/action/RotateAbsolute]\n"
    info = finish(netns.llfsm("action", "info", ROTATE[0], "-t", "--spin-time", "2"), 20)
    assert info[1] == (
        "Action: /turtle1/rotate_absolute\n"
        "Action clients: 0\n"
        "Action servers: 1\n"
        "    /turtlesim [turtlesim/action/RotateAbsolute]\n"
    ), info
    status, out, err = finish(netns.llfsm("action", "send_goal", *ROTATE, "{theta: 1.57}", "--feedback"), 30)
    assert status == 0, err
    assert out.startswith("Waiting for an action server to become available...\nSending goal:\n     theta: 1.57\n\n")
    goal_id = re.search(r"^Goal accepted with ID: ([0-9a-f]{32})\n\n", out, re.M)
    assert goal_id, out
    remaining = [float(v) for v in re.findall(r"^Feedback:\n    remaining: (\S+)\n\n", out, re.M)]
    assert remaining[0] == pytest.approx(1.57) and remaining == sorted(remaining, reverse=True)
    assert abs(remaining[-1]) < 0.06  # the last feedback may come after the result, and is then not shown
    assert re.search(r"Result:\n    delta: -1\.5\d*\n\nGoal finished with status: SUCCEEDED\n\Z", out), out
    echo = finish(netns.llfsm("topic", "echo", "/turtle1/pose", "--once"), 20)
    assert abs(theta_of(echo[1]) - 1.57) < 0.02  # the turtle ends at the goal's heading
    sim.send_signal(signal.SIGINT)
    _, _, sim_err = finish(sim, 20)
    assert "[turtlesim]: Rotation goal completed successfully" in sim_err


@pytest.mark.dds
def test_turtle_rotator_in_one_process_turns_turtlesim_in_another(netns: NetNamespace) -> None:
    sim = netns.llfsm("run", "--transport", "dds", "--node", "turtlesim", "--duration", "30")
    rotator = netns.llfsm("run", "--transport", "dds", MACHINES / "turtle_rotator.machine", "--duration", "28")
    status, out, err = finish(rotator, 40)
    assert status == 0, err
    assert [float(h) for h in re.findall(r"^reached heading ([^,]+),", out, re.M)] == [1.5708, 3.1416, -1.5708, 0.0]
    echo = finish(netns.llfsm("topic", "echo", "/turtle1/pose", "--once"), 20)
    assert abs(theta_of(echo[1])) < 0.02
    sim.send_signal(signal.SIGINT)
    assert finish(sim, 20)[2].count("Rotation goal completed successfully") == 4


@pytest.mark.dds
def test_turtle_rotator_ends_with_a_line_when_turtlesim_dies_mid_goal(netns: NetNamespace) -> None:
    env = {**SHORT_LEASE, "PYTHONUNBUFFERED": "1"}
    sim = netns.llfsm("run", "--transport", "dds", "--node", "turtlesim", "--duration", "60", env=env)
    rotator = netns.llfsm("run", "--transport", "dds", MACHINES / "turtle_rotator.machine", "--duration", "60", env=env)
    wait_for_line(rotator, r"^reached heading ", 30)  # the second goal is under way now
    sim.kill()  # no goodbye: the lease tells
    started = time.monotonic()
    status, out, err = finish(rotator, 30)
    assert status == 0 and time.monotonic() - started < 10, err
    lost = "the server of /turtle1/rotate_absolute went away before heading {} was reached"
    assert out.splitlines()[-1] in {lost.format("+3.1416"), lost.format("-1.5708")}, out
    assert "Traceback" not in err


@pytest.mark.dds
def test_topic_hz_and_echo_read_an_actions_hidden_feedback_topic(netns: NetNamespace) -> None:
    """Its type is the action's `RotateAbsolute_FeedbackMessage` (`turtlesim/action/...`), which
    `topic hz` and `topic echo` take from discovery as `ros2 topic` does."""
    sim = netns.llfsm("run", "--transport", "dds", "--node", "turtlesim", "--duration", "30")
    feedback = "/turtle1/rotate_absolute/_action/feedback"
    goal = netns.llfsm("action", "send_goal", *ROTATE, "{theta: 3.1}")
    wait_for_line(goal, r"^Goal accepted with ID", 20)
    hz = netns.llfsm("topic", "hz", feedback, "--duration", "2")
    echo = netns.llfsm("topic", "echo", feedback, "--once")
    status, out, err = finish(hz, 30)
    assert status == 0 and "average rate: " in out, err
    status, out, err = finish(echo, 30)
    assert status == 0 and "feedback:\n  remaining: " in out, err
    finish(goal, 30)
    sim.send_signal(signal.SIGINT)
    finish(sim, 20)


@pytest.mark.dds
def test_ctrl_c_during_send_goal_cancels_the_goal(netns: NetNamespace) -> None:
    sim = netns.llfsm("run", "--transport", "dds", "--node", "turtlesim", "--duration", "25")
    goal = netns.llfsm("action", "send_goal", *ROTATE, "{theta: 3.0}")
    wait_for_line(goal, r"^Goal accepted with ID", 20)
    time.sleep(0.5)
    goal.send_signal(signal.SIGINT)
    status, out, err = finish(goal, 20)
    assert status == 130, err
    assert out.endswith("Canceling goal...\nGoal canceled.\n"), out
    assert "Traceback" not in err
    echo = finish(netns.llfsm("topic", "echo", "/turtle1/pose", "--once"), 20)
    assert 0.1 < theta_of(echo[1]) < 2.9  # stopped on its way
    sim.send_signal(signal.SIGINT)
    assert "[turtlesim]: Rotation goal canceled" in finish(sim, 20)[2]


# -- a machine serving a user's action -----------------------------------------------------------------------


def counting_server(root: Path) -> Path:
    """A user's package llfsm_count_msgs (action Count) and a machine that serves /count in the
    PULL form: it takes one goal at a time, counts to the target, one number per 100 ms with
    feedback; a target of 13 is aborted, a negative one rejected, a cancel request honoured."""
    (root / "llfsm_count_msgs" / "action").mkdir(parents=True)
    (root / "llfsm_count_msgs" / "action" / "Count.action").write_text(COUNT_ACTION)
    return write_machine(
        root,
        "counter",
        {
            "INITIAL": [("END", "not ros.ok()"), ("IDLE", "True")],
            "IDLE": [("END", "not ros.ok()"), ("STEP", "server.waiting > 0")],
            "STEP": [
                ("CANCELED", "goal.is_cancel_requested"),
                ("ABORT", "goal.request.target == 13 and n == 5"),
                ("DONE", "n >= goal.request.target"),
                ("STEP", "after_ms(100)"),
            ],
            "DONE": [("IDLE", "True")],
            "ABORT": [("IDLE", "True")],
            "CANCELED": [("IDLE", "True")],
            "END": None,
        },
        {
            "INITIAL_OnEntry": (
                "ros.init()\n"
                "node = ros.Node('counter')\n"
                "server = ros.ActionServer(node, Count, '/count', None,\n"
                "    goal_callback=lambda g: ros.GoalResponse.ACCEPT if g.target >= 0 else ros.GoalResponse.REJECT,\n"
                "    cancel_callback=lambda handle: ros.CancelResponse.ACCEPT)\n"
            ),
            "IDLE_OnEntry": "goal = None",
            "IDLE_Internal": "pass",
            "STEP_OnEntry": (
                "if goal is None:\n"
                "    goal = server.take()\n"
                "    n = 0\n"
                "else:\n"
                "    n += 1\n"
                "goal.publish_feedback(Count.Feedback(current=n))\n"
            ),
            "DONE_OnEntry": "goal.succeed(Count.Result(total=n))",
            "ABORT_OnEntry": "goal.abort(Count.Result(total=n))",
            "CANCELED_OnEntry": "goal.canceled(Count.Result(total=n))",
        },
        variables="node: object = None\nserver: object = None\ngoal: object = None\nn: int = 0\n",
        includes="from llfsm import ros\nfrom llfsm.msgs.llfsm_count_msgs.action import Count\n",
    )


@pytest.mark.dds
def test_a_machine_serves_goals_of_a_users_action_to_other_processes(netns: NetNamespace, tmp_path: Path) -> None:
    server = llfsm_at(netns, tmp_path, "run", "--transport", "dds", counting_server(tmp_path), "--duration", "40")

    def send(values: str, *flags: str) -> object:
        return llfsm_at(
            netns, tmp_path, "action", "send_goal", "/count", "llfsm_count_msgs/action/Count", values, *flags
        )

    first, second = send("{target: 6}", "-f"), send("{target: 3}")  # two goals at once
    results = [finish(first, 40), finish(second, 40)]
    for (status, out, err), total in zip(results, (6, 3), strict=True):
        assert status == 0, err
        assert f"Result:\n    total: {total}\n\nGoal finished with status: SUCCEEDED\n" in out
    counted = [int(v) for v in re.findall(r"current: (\d+)", results[0][1])]
    assert counted == list(range(len(counted))) and len(counted) >= 6  # the last may come after the result
    aborted = finish(send("{target: 13}"), 40)
    assert aborted[0] == 0 and aborted[1].endswith("Result:\n    total: 5\n\nGoal finished with status: ABORTED\n")
    rejected = finish(send("{target: -1}"), 40)
    assert rejected[0] == 0 and rejected[1].endswith("Goal was rejected.\n")
    canceled = send("{target: 50}")
    wait_for_line(canceled, r"^Goal accepted", 20)
    time.sleep(0.6)
    canceled.send_signal(signal.SIGINT)
    status, out, err = finish(canceled, 20)
    assert status == 130 and out.endswith("Canceling goal...\nGoal canceled.\n"), (out, err)
    listed = finish(netns.llfsm("action", "info", "/count", "--spin-time", "2"), 20)
    assert listed[1] == "Action: /count\nAction clients: 0\nAction servers: 1\n    /counter\n", listed
    server.send_signal(signal.SIGINT)
    assert finish(server, 20)[0] == 0


@pytest.mark.dds
def test_a_server_that_vanishes_mid_goal_ends_send_goal_with_a_clear_line(netns: NetNamespace, tmp_path: Path) -> None:
    server = llfsm_at(netns, tmp_path, "run", "--transport", "dds", counting_server(tmp_path), env=SHORT_LEASE)
    goal = llfsm_at(
        netns,
        tmp_path,
        "action",
        "send_goal",
        "/count",
        "llfsm_count_msgs/action/Count",
        "{target: 100}",
        env=SHORT_LEASE,
    )
    wait_for_line(goal, r"^Goal accepted", 20)
    server.kill()  # no goodbye: the lease tells
    started = time.monotonic()
    status, out, err = finish(goal, 30)
    assert "Result:" not in out
    assert status == 1 and time.monotonic() - started < 10
    assert err.strip().splitlines()[-1] == "llfsm: action '/count' went away before the goal finished", err
    assert "Traceback" not in err


# -- bad input: one line, an exit status, no hang ---------------------------------------------------------------


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["/x", "turtlesim/action/NoSuch", "{}"], "unknown action type 'turtlesim/action/NoSuch'"),
        (["/x", "turtlesim/srv/Spawn", "{}"], "'turtlesim/srv/Spawn' is a service type; an action has an action type"),
        (["/x", "turtlesim/RotateAbsolute", "{theta: [1"], "invalid VALUES"),
        (["/x", "turtlesim/action/RotateAbsolute", "{speed: 1}"], "speed"),
        (["/x", "turtlesim/action/RotateAbsolute", "{theta: fast}"], "theta"),
        (["bad name", "turtlesim/action/RotateAbsolute", "{}"], "invalid action name 'bad name'"),
    ],
)
def test_bad_input_is_one_line_and_status_2(args: list[str], needle: str) -> None:
    r = llfsm("action", "send_goal", *args)
    assert r.status == 2, r.stderr
    assert r.stdout == "" and len(r.stderr.splitlines()) == 1 and needle in r.stderr, r.stderr


@pytest.mark.dds
def test_no_server_is_one_line_and_status_1_after_the_timeout(netns: NetNamespace) -> None:
    started = time.monotonic()
    status, out, err = finish(netns.llfsm("action", "send_goal", *ROTATE, "{}", "--timeout", "1.5"), 30)
    assert status == 1 and time.monotonic() - started < 15
    assert out == "Waiting for an action server to become available...\n"
    assert err.startswith("llfsm: action server '/turtle1/rotate_absolute' not available within 1.5 s (ROS domain")
    assert len(err.splitlines()) == 1
    listed = finish(netns.llfsm("action", "list", "--spin-time", "0.5"), 20)
    assert listed[0] == 1 and "no actions found within 0.5 s" in listed[2]
