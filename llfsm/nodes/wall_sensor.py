"""`--node wall_sensor`: a "wall close" sensor for turtle1, the input of machines/wall_follower
(docs/verify.md, "An example with an input").  From each `/turtle1/pose` it publishes
`/turtle1/wall_close` (std_msgs/msg/Bool): true when the point `LOOK_AHEAD` metres ahead of the
turtle is less than `MARGIN` from a wall of turtlesim's world.  A machine binds an input to it
(`topic: /turtle1/wall_close`, `field: data`) and never reads the bus itself, so `llfsm verify`
can explore the machine with both values of the sensor at every ringlet."""

from __future__ import annotations

import math
from typing import Any

from ..runtime.context import RunContext
from ..sim.world import WORLD_SIZE

NODE_NAME = "wall_sensor"
POSE_TOPIC = "/turtle1/pose"
TOPIC = "/turtle1/wall_close"
#: How far ahead of the turtle it looks, and how near a wall counts as close (metres).
LOOK_AHEAD = 1.0
MARGIN = 0.5


def wall_close(x: float, y: float, theta: float) -> bool:
    """Whether the point ahead of a turtle at (x, y) heading theta is near a wall."""
    ax, ay = x + LOOK_AHEAD * math.cos(theta), y + LOOK_AHEAD * math.sin(theta)
    return not (MARGIN <= ax <= WORLD_SIZE - MARGIN and MARGIN <= ay <= WORLD_SIZE - MARGIN)


class WallSensor:
    def __init__(self) -> None:
        # deferred: start-up (the nodes' registry imports no node's bus before it starts)
        from .. import ros
        from ..msgs.std_msgs.msg import Bool
        from ..msgs.turtlesim.msg import Pose

        self.node = ros.Node(NODE_NAME)
        self.out = Bool()
        self.pub = self.node.create_publisher(Bool, TOPIC, 10)
        self.sub = self.node.create_subscription(Pose, POSE_TOPIC, self.on_pose, 10)

    def on_pose(self, pose: Any) -> None:
        self.out.data = wall_close(pose.x, pose.y, pose.theta)
        self.pub.publish(self.out)


def start(ctx: RunContext, options: object) -> WallSensor:
    return WallSensor()
