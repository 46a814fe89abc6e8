"""`--node turtlesim` over the bus: the topics and services a machine sees (SPEC §4)."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from llfsm import ros
from llfsm.msgs.geometry_msgs.msg import Twist
from llfsm.msgs.std_srvs.srv import Empty
from llfsm.msgs.turtle_sensor_interface.srv import TurtlePosition
from llfsm.msgs.turtlesim.msg import Color, Pose
from llfsm.msgs.turtlesim.srv import Kill, SetPen, Spawn, TeleportAbsolute, TeleportRelative
from llfsm.nodes import NodeOptions, start
from llfsm.ros.bus import Bus, bus_of
from llfsm.runtime import RunContext, SimClock
from llfsm.runtime.context import activate

CENTRE = 5.544444561004639


class Sim:
    """A run context with turtlesim up, and a client node to talk to it."""

    def __init__(self, bus: Bus, capsys: pytest.CaptureFixture[str]) -> None:
        self.bus = bus
        self.capsys = capsys
        self.node = ros.Node("tester")

    def step(self, ms: int) -> None:
        for _ in range(ms):
            self.bus.clock.now += 1_000_000
            self.bus.spin_some()

    def call(self, srv_type: type, service: str, **fields: object) -> object:
        client = self.node.create_client(srv_type, service)
        return client.call(srv_type.Request(**fields))

    def reader(self, msg: type, topic: str) -> ros.Subscription:
        return self.node.create_subscription(msg, topic, None, 10)


@pytest.fixture
def sim(capsys: pytest.CaptureFixture[str]) -> Iterator[Sim]:
    ctx = RunContext(SimClock())
    prev = activate(ctx)
    try:
        ros.init()
        bus = bus_of(ctx)
        start("turtlesim", ctx, NodeOptions())
        start("turtle_sensor_poster", ctx, NodeOptions())
        yield Sim(bus, capsys)
    finally:
        activate(prev)


def test_pose_is_published_every_16_ms_from_the_start_pose(sim: Sim) -> None:
    pose = sim.reader(Pose, "/turtle1/pose")
    sim.step(100)
    assert pose.count == 6  # updates at 16, 32, 48, 64, 80, 96 ms
    assert (pose.latest.x, pose.latest.y, pose.latest.theta) == (CENTRE, CENTRE, 0.0)


def test_cmd_vel_moves_the_turtle_and_lapses_after_a_second(sim: Sim) -> None:
    pose = sim.reader(Pose, "/turtle1/pose")
    pub = sim.node.create_publisher(Twist, "/turtle1/cmd_vel", 1)
    cmd = Twist()
    cmd.linear.x = 2.0
    pub.publish(cmd)
    sim.step(3000)
    # 2 m/s until the command lapses: updates at 16 ... 992 ms move it (62 of them), 1008 does not
    assert pose.latest.x == pytest.approx(CENTRE + 2.0 * 0.016 * 62, abs=1e-4)
    assert pose.latest.linear_velocity == 0.0


def test_the_wall_is_logged_and_the_pose_clamped(sim: Sim) -> None:
    pose = sim.reader(Pose, "/turtle1/pose")
    sim.call(TeleportAbsolute, "/turtle1/teleport_absolute", x=10.9, y=5.0, theta=0.0)
    pub = sim.node.create_publisher(Twist, "/turtle1/cmd_vel", 1)
    cmd = Twist()
    cmd.linear.x = 2.0
    pub.publish(cmd)
    sim.step(500)
    assert pose.latest.x == pytest.approx(11.088889, abs=1e-5)
    err = sim.capsys.readouterr().err
    assert "[WARN] [" in err and "[turtlesim]: Oh no! I hit the wall! (Clamping from [x=" in err


def test_spawn_with_auto_names_refusal_of_duplicates_and_kill(sim: Sim) -> None:
    assert sim.call(Spawn, "/spawn", x=2.0, y=2.0, theta=0.0, name="").name == "turtle2"
    assert sim.call(Spawn, "/spawn", x=3.0, y=3.0, theta=0.0, name="leader").name == "leader"
    assert sim.call(Spawn, "/spawn", x=3.0, y=3.0, theta=0.0, name="leader").name == ""  # refused
    assert "A turtled named [leader] already exists" in sim.capsys.readouterr().err
    pose2 = sim.reader(Pose, "/turtle2/pose")
    sim.step(20)
    assert pose2.latest.x == pytest.approx(2.0)
    sim.call(Kill, "/kill", name="turtle2")
    assert "/turtle2/teleport_absolute" not in sim.bus.services
    count = pose2.count
    sim.step(50)
    assert pose2.count == count  # no pose for a dead turtle
    sim.call(Kill, "/kill", name="nobody")
    assert "Tried to kill turtle [nobody], which does not exist" in sim.capsys.readouterr().err


def test_reset_brings_back_turtle1_alone_at_the_centre(sim: Sim) -> None:
    sim.call(Spawn, "/spawn", x=2.0, y=2.0, theta=0.0, name="")
    sim.call(TeleportAbsolute, "/turtle1/teleport_absolute", x=1.0, y=1.0, theta=1.0)
    sim.call(Empty, "/reset")
    pose = sim.reader(Pose, "/turtle1/pose")
    sim.step(20)
    assert (pose.latest.x, pose.latest.y) == (CENTRE, CENTRE)
    assert "/turtle2/set_pen" not in sim.bus.services
    assert sim.call(Spawn, "/spawn", x=1.0, y=1.0, theta=0.0, name="").name == "turtle2"  # counter reset


def test_teleport_relative_turns_then_moves(sim: Sim) -> None:
    pose = sim.reader(Pose, "/turtle1/pose")
    sim.call(TeleportRelative, "/turtle1/teleport_relative", linear=1.0, angular=1.5707963)
    sim.step(20)
    assert pose.latest.x == pytest.approx(CENTRE, abs=1e-4)
    assert pose.latest.y == pytest.approx(CENTRE + 1.0, abs=1e-4)


def test_set_pen_colour_sensor_and_clear(sim: Sim) -> None:
    colour = sim.reader(Color, "/turtle1/color_sensor")
    sim.call(SetPen, "/turtle1/set_pen", r=255, g=0, b=0, width=5, off=0)
    pub = sim.node.create_publisher(Twist, "/turtle1/cmd_vel", 1)
    cmd = Twist()
    cmd.linear.x = 1.0
    pub.publish(cmd)
    sim.step(1200)  # it draws a red line until the command lapses, then stands still
    sim.call(TeleportRelative, "/turtle1/teleport_relative", linear=-0.1, angular=0.0)  # back onto the red line
    sim.step(40)
    assert (colour.latest.r, colour.latest.g, colour.latest.b) == (255, 0, 0)
    sim.call(Empty, "/clear")
    sim.step(40)
    # the trail is gone: humble's sensor reads the transparent trail image, white, off any trail
    assert (colour.latest.r, colour.latest.g, colour.latest.b) == (255, 255, 255)


def test_the_pose_service_answers_with_the_newest_pose(sim: Sim) -> None:
    sim.call(TeleportAbsolute, "/turtle1/teleport_absolute", x=3.0, y=4.0, theta=0.5)
    sim.step(40)
    resp = sim.call(TurtlePosition, "/turtle_pose_service")
    assert (resp.x, resp.y, resp.theta) == pytest.approx((3.0, 4.0, 0.5))


PARAMETER_SERVICES = (
    "describe_parameters",
    "get_parameter_types",
    "get_parameters",
    "list_parameters",
    "set_parameters",
    "set_parameters_atomically",
)


def test_background_parameters_are_declared(sim: Sim) -> None:
    turtlesim = next(n for n in sim.bus.nodes if n.get_name() == "turtlesim")
    assert [turtlesim.get_parameter(f"background_{c}").value for c in "rgb"] == [69, 86, 255]
    assert sorted(s for s in sim.bus.services if "/_action/" not in s) == sorted(
        [
            "/clear",
            "/kill",
            "/reset",
            "/spawn",
            "/turtle_pose_service",
            "/turtle1/set_pen",
            "/turtle1/teleport_absolute",
            "/turtle1/teleport_relative",
        ]
        + [f"/{node}/{verb}" for node in ("tester", "turtlesim", "turtle_sensor_poster") for verb in PARAMETER_SERVICES]
    )
    # and the hidden services of the action /turtle1/rotate_absolute, as turtlesim has them
    assert sorted(s for s in sim.bus.services if "/_action/" in s) == [
        f"/turtle1/rotate_absolute/_action/{s}" for s in ("cancel_goal", "get_result", "send_goal")
    ]
