"""The five endpoints of an action, named as rcl_action names them (docs/actions.md, "On the
wire"): three services and two topics under `<action>/_action/`.

    <action>/_action/send_goal     service  <pkg>/action/<Name>_SendGoal
    <action>/_action/cancel_goal   service  action_msgs/srv/CancelGoal
    <action>/_action/get_result    service  <pkg>/action/<Name>_GetResult
    <action>/_action/feedback      topic    <pkg>/action/<Name>_FeedbackMessage (depth 10)
    <action>/_action/status        topic    action_msgs/msg/GoalStatusArray (transient local, depth 1)

`_action` starts with an underscore, so the endpoints are hidden from `ros2 topic list` and
`ros2 service list`.  The graph finds actions as rcl_action does: a topic ending in
`/_action/feedback` whose type ends in `_FeedbackMessage`; its publishers are the servers, its
subscribers the clients.
"""

from __future__ import annotations

SEND_GOAL = "/_action/send_goal"
CANCEL_GOAL = "/_action/cancel_goal"
GET_RESULT = "/_action/get_result"
FEEDBACK = "/_action/feedback"
STATUS = "/_action/status"
FEEDBACK_TYPE_SUFFIX = "_FeedbackMessage"


def action_of_feedback(topic: str) -> str | None:
    """ "/turtle1/rotate_absolute" for "/turtle1/rotate_absolute/_action/feedback", else None."""
    if topic.endswith(FEEDBACK) and len(topic) > len(FEEDBACK):
        return topic[: -len(FEEDBACK)]
    return None


def action_type(feedback_type: str) -> str:
    """ "turtlesim/action/RotateAbsolute" for its feedback message's type (rcl_action trims the
    suffix where it is, and keeps any other type as it is)."""
    if feedback_type.endswith(FEEDBACK_TYPE_SUFFIX):
        return feedback_type[: -len(FEEDBACK_TYPE_SUFFIX)]
    return feedback_type
