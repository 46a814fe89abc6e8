"""turtlesim's `/<turtle>/rotate_absolute` action as humble's turtle.cpp serves it, teleop's goal
keys, and the example machine turtle_rotator (suspending it cancels its goal), in process under
the sim clock.  Over DDS from `llfsm action send_goal`: tests/test_actions_dds.py."""

from __future__ import annotations

import itertools
import math
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from helpers import MACHINES, llfsm_process, run_sim, write_machine

from llfsm import ros
from llfsm.msgs.action_msgs.msg import GoalStatus
from llfsm.msgs.geometry_msgs.msg import Twist
from llfsm.msgs.std_srvs.srv import Empty
from llfsm.msgs.turtlesim.action import RotateAbsolute
from llfsm.msgs.turtlesim.msg import Pose
from llfsm.msgs.turtlesim.srv import Kill, Spawn
from llfsm.nodes import NodeOptions, start
from llfsm.ros.bus import Bus, bus_of
from llfsm.runtime import RunContext, SimClock
from llfsm.runtime.context import activate
from llfsm.sim.world import TurtleWorld, f32

ROTATOR = MACHINES / "turtle_rotator.machine"
SPEED = 1.0  # rad/s: turtlesim turns a rotate_absolute goal at this speed
DT = 0.016
TOLERANCE = 0.02  # rad: how close a goal ends


def normalised(a: float) -> float:
    return a - 2.0 * 3.14159265 * math.floor((a + 3.14159265) / (2.0 * 3.14159265))


# -- the world: a rotation as turtle.cpp steps it -----------------------------------------------------------


def test_a_rotation_turns_at_one_radian_a_second_and_ends_within_tolerance() -> None:
    world = TurtleWorld()
    assert world.rotate_absolute("turtle1", 1.0) is None
    remaining, now = [], 0
    while world.rotating("turtle1"):
        now += 16_000_000
        world.update(now)
        for event in world.rotation_events:
            assert event.turtle == "turtle1"
            if event.kind == "feedback":
                remaining.append(event.value)
            else:
                ended = event
    theta = world.pose("turtle1").theta
    assert ended.kind == "succeeded" and abs(theta - 1.0) < TOLERANCE
    assert ended.value == f32(0.0 - theta)  # delta: where it started, less where it is
    assert remaining[0] == f32(1.0) and remaining[-1] < TOLERANCE
    steps = [a - b for a, b in itertools.pairwise(remaining)]
    assert steps == pytest.approx([SPEED * DT] * len(steps), abs=1e-6)  # 1 rad/s, 16 ms a step
    assert len(remaining) == math.ceil((1.0 - TOLERANCE) / (SPEED * DT)) + 1
    assert world.pose("turtle1").angular_velocity == 0.0  # it stops there


def test_a_rotation_takes_the_short_way_round_across_pi() -> None:
    world = TurtleWorld()
    world.teleport_absolute("turtle1", 5.0, 5.0, 3.0)
    world.update(16_000_000)
    world.rotate_absolute("turtle1", -3.0)  # 0.28 rad the short way, through +pi
    now = 16_000_000
    while world.rotating("turtle1"):
        now += 16_000_000
        world.update(now)
        assert world.pose("turtle1").angular_velocity in (0.0, 1.0)  # never the long way, -1
    assert abs(normalised(world.pose("turtle1").theta + 3.0)) < TOLERANCE
    assert now < 30 * 16_000_000


def test_a_velocity_command_or_a_new_goal_aborts_the_rotation_and_a_cancel_stops_it() -> None:
    world = TurtleWorld()
    world.rotate_absolute("turtle1", 2.0)
    for k in range(1, 11):
        world.update(k * 16_000_000)
    delta = world.command("turtle1", 0.0, 0.0, 0.5, 11 * 16_000_000)
    assert delta == f32(-10 * SPEED * DT + SPEED * DT)  # the delta of the last update: 9 steps turned
    assert not world.rotating("turtle1") and world.command("turtle1", 0, 0, 0, 0) is None
    world.rotate_absolute("turtle1", 2.0)
    world.update(12 * 16_000_000)
    assert world.rotate_absolute("turtle1", -2.0) is not None  # the first goal is replaced
    world.update(13 * 16_000_000)
    assert world.cancel_rotation("turtle1")
    world.update(14 * 16_000_000)
    assert [e.kind for e in world.rotation_events] == ["canceled"]
    held = world.pose("turtle1").theta
    world.update(15 * 16_000_000)
    assert world.pose("turtle1").theta == held and not world.cancel_rotation("turtle1")


# -- the node: the action on the bus ---------------------------------------------------------------------


@pytest.fixture
def bus() -> Iterator[Bus]:
    ctx = RunContext(SimClock())
    prev = activate(ctx)
    try:
        ros.init()
        start("turtlesim", ctx, NodeOptions())
        yield bus_of(ctx)
    finally:
        activate(prev)


def step(bus: Bus, ms: int) -> None:
    for _ in range(ms):
        bus.clock.now += 1_000_000
        bus.spin_some()


def rotate(node: ros.Node, turtle: str, theta: float, feedback: list[Any] | None = None) -> Any:
    client = ros.ActionClient(node, RotateAbsolute, f"/{turtle}/rotate_absolute")
    sent = client.send_goal_async(RotateAbsolute.Goal(theta=theta), feedback.append if feedback is not None else None)
    assert ros.spin_until_future_complete(node, sent) is ros.FutureReturnCode.SUCCESS
    assert sent.result().accepted
    return sent.result()


def test_rotate_absolute_turns_the_turtle_to_the_goal_heading(bus: Bus, capsys: pytest.CaptureFixture[str]) -> None:
    node = ros.Node("tester")
    pose = node.create_subscription(Pose, "/turtle1/pose", None, 1)
    feedback: list[Any] = []
    goal = rotate(node, "turtle1", -1.2, feedback)
    answer = goal.get_result(timeout_sec=5.0)
    assert answer.status == GoalStatus.STATUS_SUCCEEDED
    step(bus, 20)
    assert abs(pose.latest.theta - -1.2) < TOLERANCE and pose.latest.angular_velocity == 0.0
    assert answer.result.delta == f32(0.0 - pose.latest.theta)
    assert feedback[0].feedback.remaining == f32(-1.2) and -TOLERANCE < feedback[-1].feedback.remaining <= 0
    assert "[turtlesim]: Rotation goal completed successfully" in capsys.readouterr().err


def test_cmd_vel_aborts_a_goal_and_a_cancel_request_is_accepted(bus: Bus, capsys: pytest.CaptureFixture[str]) -> None:
    node = ros.Node("tester")
    goal = rotate(node, "turtle1", 3.0)
    result = goal.get_result_async()
    step(bus, 200)
    twist = Twist()
    twist.angular.z = -0.5
    node.create_publisher(Twist, "/turtle1/cmd_vel", 1).publish(twist)
    step(bus, 2)
    assert result.result().status == GoalStatus.STATUS_ABORTED and result.result().result.delta < 0
    assert "[WARN]" in (err := capsys.readouterr().err)
    assert "Velocity command received during rotation goal. Aborting goal" in err
    pose = node.create_subscription(Pose, "/turtle1/pose", None, 1)
    step(bus, 1_100)  # the command lapses
    goal = rotate(node, "turtle1", 0.0)
    step(bus, 200)
    cancel = goal.cancel_goal_async()
    step(bus, 20)
    assert len(cancel.result().goals_canceling) == 1
    assert goal.get_result(timeout_sec=1.0).status == GoalStatus.STATUS_CANCELED
    held = pose.latest.theta
    step(bus, 100)
    assert pose.latest.theta == held and "[turtlesim]: Rotation goal canceled" in capsys.readouterr().err


def test_a_new_goal_aborts_the_one_running(bus: Bus, capsys: pytest.CaptureFixture[str]) -> None:
    node = ros.Node("tester")
    first = rotate(node, "turtle1", 2.0).get_result_async()
    step(bus, 100)
    second = rotate(node, "turtle1", -2.0)
    step(bus, 2)
    assert first.result().status == GoalStatus.STATUS_ABORTED
    assert "Rotation goal received before a previous goal finished. Aborting previous goal" in capsys.readouterr().err
    assert second.get_result(timeout_sec=10.0).status == GoalStatus.STATUS_SUCCEEDED


def test_every_turtle_has_its_action_and_a_kill_or_a_reset_aborts_the_goal(bus: Bus) -> None:
    node = ros.Node("tester")
    node.create_client(Spawn, "/spawn").call(Spawn.Request(x=2.0, y=2.0, name="turtle2"))
    goal = rotate(node, "turtle2", 1.0)
    result = goal.get_result_async()
    step(bus, 50)
    node.create_client(Kill, "/kill").call(Kill.Request(name="turtle2"))
    step(bus, 2)
    assert result.result().status == GoalStatus.STATUS_ABORTED and -0.1 < result.result().result.delta < 0
    assert not ros.ActionClient(node, RotateAbsolute, "/turtle2/rotate_absolute").server_is_ready()
    reset_midway = rotate(node, "turtle1", 2.0).get_result_async()
    step(bus, 500)
    node.create_client(Empty, "/reset").call(Empty.Request())
    step(bus, 2)
    assert reset_midway.result().status == GoalStatus.STATUS_ABORTED and reset_midway.result().result.delta < -0.3
    assert rotate(node, "turtle1", 0.5).get_result(timeout_sec=5.0).status == GoalStatus.STATUS_SUCCEEDED


# -- teleop's keys ---------------------------------------------------------------------------------------------


def test_teleop_keys_send_rotate_goals_and_f_cancels(tmp_path: Path) -> None:
    """R sends 1.5708 (north), then 1.5 s later T 0.7854: R's goal is aborted by turtlesim when
    T's comes; F cancels T's goal 0.3 s later, half-way.  The keys arrive through a pipe, one
    taken every 100 ms."""
    watcher = write_machine(
        tmp_path,
        "watcher",
        {"WAIT": [("SAY", "after(3)")], "SAY": None},
        {"SAY_OnEntry": "print(f'theta {pose.latest.theta:.4f}')"},
        variables="pose: object = None\n",
        includes="from llfsm import ros\nfrom llfsm.msgs.turtlesim.msg import Pose\n",
        yaml_extra="initial: WAIT",
    )
    (watcher / "State_WAIT_OnEntry.py").write_text(
        "ros.init()\npose = ros.Node('watcher').create_subscription(Pose, '/turtle1/pose', None, 1)\n"
    )
    keys = "r" + "x" * 14 + "t" + "x" * 2 + "f"  # x: no key of teleop's, a 100 ms pause
    run = llfsm_process("run", "--clock", "sim", watcher, "--node", "turtlesim", "--node", "teleop", input=keys)
    assert run.status == 0, run.stderr
    assert "Use G|B|V|C|D|E|R|T keys to rotate to absolute orientations. 'F' to cancel a rotation." in run.stderr
    assert "Aborting previous goal" in run.stderr and "Rotation goal canceled" in run.stderr
    theta = float(re.search(r"theta (\S+)", run.stdout).group(1))  # type: ignore[union-attr]
    assert 0.7854 < theta < 1.5708  # turned back toward T's heading, stopped before it


# -- the example machine: goals from a machine, canceled on suspend ------------------------------------------------


def test_turtle_rotator_reaches_each_heading_the_same_way_every_run() -> None:
    first = run_sim(ROTATOR, "--node", "turtlesim", "--echo", "/turtle1/pose")
    assert first.status == 0, first.stderr
    reached = re.findall(r"^reached heading (\S+), turned (\S+)$", first.stdout, re.M)
    assert [float(h) for h, _ in reached] == [1.5708, 3.1416, -1.5708, 0.0]
    thetas = [float(t) for t in re.findall(r"^theta: (\S+)$", first.stdout, re.M)]
    assert abs(thetas[-1] - 0.0) < TOLERANCE  # the turtle ends at the last goal's heading
    assert first.stderr.count("Rotation goal completed successfully") == 4
    assert run_sim(ROTATOR, "--node", "turtlesim", "--echo", "/turtle1/pose").stdout == first.stdout


def test_suspending_turtle_rotator_cancels_its_goal_and_resuming_sends_it_again(tmp_path: Path) -> None:
    pauser = write_machine(
        tmp_path,
        "pauser",
        {
            "WAIT": [("SUSPEND", "after_ms(500)")],
            "SUSPEND": [("HOLD", "is_suspended('turtle_rotator') and after_ms(100)")],
            "HOLD": [("RESUME", "after(2)")],
            "RESUME": None,
        },
        {
            "WAIT_OnEntry": "ros.init()\npose = ros.Node('pauser').create_subscription(Pose, '/turtle1/pose', None, 1)",
            "SUSPEND_OnEntry": "suspend('turtle_rotator')",
            "HOLD_OnEntry": "print(f'held at {pose.latest.theta}')",
            "RESUME_OnEntry": "print(f'still at {pose.latest.theta}')\nresume('turtle_rotator')",
        },
        variables="pose: object = None\n",
        includes="from llfsm import ros\nfrom llfsm.msgs.turtlesim.msg import Pose\n",
        yaml_extra="initial: WAIT",
    )
    run = run_sim(pauser, ROTATOR, "--node", "turtlesim")
    assert run.status == 0, run.stderr
    held = re.search(r"^held at (\S+)$", run.stdout, re.M)
    still = re.search(r"^still at (\S+)$", run.stdout, re.M)
    assert held and still and held.group(1) == still.group(1)  # nothing turned it while suspended
    assert 0.3 < float(held.group(1)) < 0.7  # half a second into its first goal
    assert run.stderr.count("Rotation goal canceled") == 1
    reached = re.findall(r"^reached heading ([^,]+),", run.stdout, re.M)
    assert [float(h) for h in reached] == [1.5708, 3.1416, -1.5708, 0.0]  # the first goal sent again


# -- recording a run with an action ----------------------------------------------------------------------------


def test_a_recorded_run_keeps_the_action_topics_and_plays_them_back(tmp_path: Path) -> None:
    """`--record` writes the feedback topic with its type, the definition ROS tools read and
    rosidl's type hash; `--play` brings the same messages back."""
    import yaml

    from llfsm.msgs import _dds

    bag = tmp_path / "rotations"
    run = run_sim(ROTATOR, "--node", "turtlesim", "--record", bag)
    assert run.status == 0 and "not recorded" not in run.stderr, run.stderr
    info = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    topics = {t["topic_metadata"]["name"]: t for t in info["topics_with_message_count"]}
    feedback = topics["/turtle1/rotate_absolute/_action/feedback"]
    assert feedback["topic_metadata"]["type"] == "turtlesim/action/RotateAbsolute_FeedbackMessage"
    assert feedback["topic_metadata"]["type_description_hash"] == _dds.type_hash(RotateAbsolute.Impl.FeedbackMessage)
    assert feedback["message_count"] > 300
    assert topics["/turtle1/rotate_absolute/_action/status"]["message_count"] >= 12  # 3 changes a goal
    from rosbags.highlevel import AnyReader

    with AnyReader([bag]) as reader:  # rosbags reads the definition in the bag
        connection = next(c for c in reader.connections if c.msgtype.endswith("_FeedbackMessage"))
        assert "MSG: turtlesim/action/RotateAbsolute_Feedback\n" in connection.msgdef.data
        first = next(reader.messages([connection]))
        assert reader.deserialize(first[2], connection.msgtype).feedback.remaining == pytest.approx(1.5708)
    replay = run_sim("--play", bag, "--echo", "/turtle1/rotate_absolute/_action/feedback", "--duration", "9s")
    assert replay.status == 0, replay.stderr
    assert replay.stdout.count("remaining:") == feedback["message_count"]
