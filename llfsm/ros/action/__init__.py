"""Actions, as `rclpy.action`: `ros.ActionClient` and `ros.ActionServer`, their goal handles, and
the goal states of action_msgs (docs/actions.md).

- `client`: ActionClient and ClientGoalHandle (futures all the way: machines poll `done()`);
- `server`: ActionServer and ServerGoalHandle, GoalResponse and CancelResponse;
- `execution`: an execute callback run as a task (generators and coroutines resume where they
  yielded), so serving a goal never holds up the machines;
- `status`: rcl_action's goal state machine, status names, goal ids;
- `names`: the five endpoints of an action, as rcl_action names them.
"""

from __future__ import annotations

from .client import ActionClient, ClientGoalHandle
from .server import (
    ActionServer,
    CancelResponse,
    GoalResponse,
    ServerGoalHandle,
    qos_profile_action_status_default,
)
from .status import InvalidTransition

__all__ = [
    "ActionClient",
    "ActionServer",
    "CancelResponse",
    "ClientGoalHandle",
    "GoalResponse",
    "InvalidTransition",
    "ServerGoalHandle",
    "qos_profile_action_status_default",
]
