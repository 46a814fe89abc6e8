"""`--node turtlesim`: the turtle world of llfsm.sim on the bus, with turtlesim's names.

Topics per turtle: `<turtle>/cmd_vel` (in), `<turtle>/pose` and `<turtle>/color_sensor` (out,
every update); services `spawn`, `kill`, `clear`, `reset` and per turtle `<turtle>/set_pen`,
`<turtle>/teleport_absolute`, `<turtle>/teleport_relative`; the action
`<turtle>/rotate_absolute` (turtlesim/action/RotateAbsolute: every goal and every cancel request
accepted, as turtlesim's); parameters background_r/g/b.  The world updates every 16 ms of run
time with dt = 0.016 s, as turtlesim's timer does.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ..runtime.context import RunContext
from ..sim.world import TurtleError, TurtleWorld
from . import NodeError, NodeOptions

if TYPE_CHECKING:
    from ..ros.action import ActionServer
    from ..ros.publisher import Publisher
    from ..ros.service import ServiceServer
    from ..ros.subscription import Subscription

NODE_NAME = "turtlesim"
UPDATE_PERIOD = 0.016
DEFAULT_BACKGROUND = (69, 86, 255)


class _Turtle:
    """The bus entities of one turtle, so that kill and reset can take them down again."""

    def __init__(self, sim: Turtlesim, name: str) -> None:
        # deferred: with the node (importing the node's module loads neither the bus nor its messages)
        from .. import ros
        from ..msgs.geometry_msgs.msg import Twist
        from ..msgs.turtlesim.action import RotateAbsolute
        from ..msgs.turtlesim.msg import Color, Pose
        from ..msgs.turtlesim.srv import SetPen, TeleportAbsolute, TeleportRelative

        node, world = sim.node, sim.world
        self.name = name
        self.log = sim.log
        self.action = RotateAbsolute
        #: The rotate_absolute goal the world is turning the turtle for, if any.
        self.goal: Any = None

        def on_cmd(msg: Any) -> None:
            delta = world.command(name, msg.linear.x, msg.linear.y, msg.angular.z, sim.clock.now)
            if delta is not None:
                self.log.warning("Velocity command received during rotation goal. Aborting goal")
                self._end_goal("abort", delta)

        def accepted(goal: Any) -> None:
            goal.execute()  # turtlesim's server accepts and executes (ACCEPT_AND_EXECUTE)
            delta = world.rotate_absolute(name, goal.request.theta)
            if delta is not None:
                self.log.warning("Rotation goal received before a previous goal finished. Aborting previous goal")
                self._end_goal("abort", delta)
            self.goal = goal

        def set_pen(req: Any, resp: Any) -> Any:
            world.set_pen(name, req.r, req.g, req.b, req.width, req.off)
            return resp

        def teleport_absolute(req: Any, resp: Any) -> Any:
            world.teleport_absolute(name, req.x, req.y, req.theta)
            return resp

        def teleport_relative(req: Any, resp: Any) -> Any:
            world.teleport_relative(name, req.linear, req.angular)
            return resp

        self.entities: list[Subscription | ServiceServer | Publisher | ActionServer] = [
            ros.ActionServer(
                node,
                RotateAbsolute,
                f"{name}/rotate_absolute",
                goal_callback=lambda goal: ros.GoalResponse.ACCEPT,
                cancel_callback=lambda goal: ros.CancelResponse.ACCEPT,
                handle_accepted_callback=accepted,
            ),
            node.create_subscription(Twist, f"{name}/cmd_vel", on_cmd, 1),
            node.create_service(SetPen, f"{name}/set_pen", set_pen),
            node.create_service(TeleportAbsolute, f"{name}/teleport_absolute", teleport_absolute),
            node.create_service(TeleportRelative, f"{name}/teleport_relative", teleport_relative),
        ]
        self.pose_pub = node.create_publisher(Pose, f"{name}/pose", 10)
        self.color_pub = node.create_publisher(Color, f"{name}/color_sensor", 10)
        self.entities += [self.pose_pub, self.color_pub]
        # One Pose and one Color, filled in and published each update, as a machine may keep
        # one message: publishing copies it for each subscription, and taps (the recorder) and
        # other processes take its bytes there and then, so nobody sees it change afterwards.
        self.pose = Pose()
        self.color = Color()

    def publish(self, world: TurtleWorld, sensing: bool) -> None:
        """`sensing`: whether the colour sensor has a subscription (counted once per update)."""
        pose = self.pose
        # float32 values already (finite, inf or NaN): what the setters would accept unchanged
        pose._x, pose._y, pose._theta, pose._linear_velocity, pose._angular_velocity = world.pose(self.name)
        self.pose_pub.publish(pose)
        if sensing:
            color = self.color
            # bytes of the path image, 0..255 each: what the setters would check cannot fail
            color._r, color._g, color._b = world.color_under(self.name)
            self.color_pub.publish(color)

    def _end_goal(self, how: str, delta: float) -> None:
        """End the goal the world has let go of: "abort", "succeed" or "canceled", with its delta."""
        goal, self.goal = self.goal, None
        if goal is not None and goal.is_active:
            getattr(goal, how)(self.action.Result(delta=delta))

    def before_update(self, world: TurtleWorld) -> None:
        """A cancel request accepted since the last update reaches the world (turtlesim looks
        at it in its update)."""
        if self.goal is not None and self.goal.is_cancel_requested:
            world.cancel_rotation(self.name)

    def rotation_event(self, kind: str, value: float) -> None:
        goal = self.goal
        if goal is None:
            return
        if kind == "feedback":
            goal.publish_feedback(self.action.Feedback(remaining=value))
        elif kind == "succeeded":
            self.log.info("Rotation goal completed successfully")
            self._end_goal("succeed", value)
        else:
            self.log.info("Rotation goal canceled")
            self._end_goal("canceled", value)

    def destroy(self) -> None:
        for e in self.entities:
            e.destroy()


class Turtlesim:
    def __init__(self, ctx: RunContext, options: NodeOptions) -> None:
        # deferred: with the node, as in _Turtle
        from .. import ros
        from ..msgs.std_srvs.srv import Empty
        from ..msgs.turtlesim.srv import Kill, Spawn

        self.ctx = ctx
        self.clock = ctx.clock
        self.node = ros.Node(NODE_NAME)
        self.log = self.node.get_logger()
        # as turtlesim declares them: integers 0..255, each described; `llfsm param set` (or
        # `ros2 param set`) outside that range is refused with rclpy's reason
        self.params = [
            self.node.declare_parameter(f"background_{c}", v, _channel(colour))
            for c, colour, v in zip("rgb", ("Red", "Green", "Blue"), DEFAULT_BACKGROUND, strict=True)
        ]
        self.node.add_post_set_parameters_callback(self._parameters_set)
        self.log.info(f"Starting turtlesim with node name {self.node.get_fully_qualified_name()}")
        self.world = TurtleWorld(background=self._background(), log=self.log.info)
        self.turtles: dict[str, _Turtle] = {}
        self._sync()
        self.node.create_service(Spawn, "spawn", self.spawn)
        self.node.create_service(Kill, "kill", self.kill)
        self.node.create_service(Empty, "clear", self.clear)
        self.node.create_service(Empty, "reset", self.reset)
        self.node.create_timer(UPDATE_PERIOD, self.update)
        self.viewer: Any = None
        if options.view:
            # deferred: optional dependency (pygame, the view extra), only with --view
            try:
                from ..sim.view import Viewer
            except ImportError as e:
                raise NodeError(str(e)) from None
            self.viewer = Viewer(self.world)
            ctx.at_end.append(self.viewer.close)
        if options.image is not None:
            image = options.image
            ctx.at_end.append(lambda: self._write_image(image))

    def _background(self) -> tuple[int, int, int]:
        values = [p.value for p in (self.node.get_parameter(f"background_{c}") for c in "rgb")]
        if not all(isinstance(v, int) and not isinstance(v, bool) and 0 <= v <= 255 for v in values):
            raise NodeError(f"turtlesim: background_r/g/b must be integers 0..255, not {values}")
        return values[0], values[1], values[2]

    def _parameters_set(self, params: list[Any]) -> None:
        """A background parameter changed: the picture (window, --image, web view) takes the new
        colour at once, as turtlesim repaints on a parameter event; the trails stay."""
        if any(p.name.startswith("background_") for p in params) and hasattr(self, "world"):
            self.world.set_background(*self._background())

    def _sync(self) -> None:
        """Bring the per-turtle topics and services in line with the turtles of the world."""
        names = set(self.world.names())
        for gone in set(self.turtles) - names:
            self.turtles.pop(gone).destroy()
        for name in sorted(names - set(self.turtles)):
            self.turtles[name] = _Turtle(self, name)

    # -- services ------------------------------------------------------------------------------
    def spawn(self, req: Any, resp: Any) -> Any:
        try:
            resp.name = self.world.spawn(req.x, req.y, req.theta, req.name)
        except TurtleError as e:
            self.log.error(str(e))
            resp.name = ""
        self._sync()
        return resp

    def kill(self, req: Any, resp: Any) -> Any:
        turtle = self.turtles.get(req.name)
        try:
            delta = self.world.end_rotation(req.name) if req.name in self.world else None
            self.world.kill(req.name)
        except TurtleError as e:
            self.log.error(str(e))
        else:
            if turtle is not None and delta is not None:  # its goal ends with the turtle: aborted
                turtle._end_goal("abort", delta)
        self._sync()
        return resp

    def clear(self, req: Any, resp: Any) -> Any:
        self.world.set_background(*self._background())
        self.world.clear()
        return resp

    def reset(self, req: Any, resp: Any) -> Any:
        for name, turtle in self.turtles.items():  # every turtle goes, and its goal with it
            delta = self.world.end_rotation(name)
            if delta is not None:
                turtle._end_goal("abort", delta)
        self.world.set_background(*self._background())
        self.world.reset()
        self._sync()
        return resp

    # -- the 16 ms update ---------------------------------------------------------------------------
    def update(self) -> None:
        turtles = list(self.turtles.values())
        world = self.world
        for t in turtles:
            t.before_update(world)
        sensing = [t.color_pub.get_subscription_count() > 0 for t in turtles]
        for warning in world.update(self.clock.now, UPDATE_PERIOD, sense=any(sensing)):
            self.log.warning(warning)
        for event in world.rotation_events:
            self.turtles[event.turtle].rotation_event(event.kind, event.value)
        for t, sense in zip(turtles, sensing, strict=True):
            t.publish(world, sense)
        if self.viewer is not None and not self.viewer.closed:
            self.viewer.draw()

    def _write_image(self, path: Any) -> None:
        # deferred: start-up (Pillow, only with --image)
        from ..sim.draw import render

        try:
            render(self.world, path)
        except OSError as e:
            # `llfsm run` reports it and ends with status 1: a picture asked for and not written
            self.ctx.output_errors.append(f"--image {path}: cannot write: {e.strerror or e}")


def _channel(colour: str) -> Any:
    # deferred: with the node, as in _Turtle
    from ..msgs.rcl_interfaces.msg import IntegerRange, ParameterDescriptor

    return ParameterDescriptor(
        description=f"{colour} channel of the background color",
        integer_range=[IntegerRange(from_value=0, to_value=255, step=1)],
    )


def start(ctx: RunContext, options: NodeOptions) -> Turtlesim:
    return Turtlesim(ctx, options)
