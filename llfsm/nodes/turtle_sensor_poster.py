"""The seed's PULL adapter: it listens to `/turtle1/pose` and answers `/turtle_pose_service`
(turtle_sensor_interface/srv/TurtlePosition) with the newest pose, so that a machine can ask
for the turtle's position when it wants it instead of taking every message by callback."""

from __future__ import annotations

from typing import Any

from ..runtime.context import RunContext

NODE_NAME = "turtle_sensor_poster"
POSE_TOPIC = "/turtle1/pose"
SERVICE = "/turtle_pose_service"


class TurtleSensorPoster:
    def __init__(self) -> None:
        # deferred: with the node (importing the node's module loads neither the bus nor its messages)
        from .. import ros
        from ..msgs.turtle_sensor_interface.srv import TurtlePosition
        from ..msgs.turtlesim.msg import Pose

        self.node = ros.Node(NODE_NAME)
        self.reader = self.node.create_subscription(Pose, POSE_TOPIC, None, 10)  # PULL: keep the newest
        self.service = self.node.create_service(TurtlePosition, SERVICE, self.answer)

    def answer(self, request: Any, response: Any) -> Any:
        pose = self.reader.latest
        if pose is not None:
            response.x, response.y, response.theta = pose.x, pose.y, pose.theta
        return response


def start(ctx: RunContext, options: object) -> TurtleSensorPoster:
    return TurtleSensorPoster()
