"""A goal's life as rcl_action keeps it: the status values of action_msgs/msg/GoalStatus, the
events that move a goal between them, and the goal ids (docs/actions.md, "Goal states").

    ACCEPTED --execute--> EXECUTING --succeed/abort--> SUCCEEDED / ABORTED
    ACCEPTED or EXECUTING --cancel_goal--> CANCELING --canceled/succeed/abort--> CANCELED / ...

Any other move is refused, as rcl_action refuses it: a goal that is not being canceled cannot be
`canceled()`, a finished goal cannot finish again.  Both ends of an action use this module:
the server moves its goals, the client names the statuses it hears (`ros2 action send_goal`
prints them).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import random

# action_msgs/msg/GoalStatus (the generated class carries the same constants; these are read
# where importing the message module would be the only reason to)
UNKNOWN, ACCEPTED, EXECUTING, CANCELING, SUCCEEDED, CANCELED, ABORTED = range(7)
NAMES = ("UNKNOWN", "ACCEPTED", "EXECUTING", "CANCELING", "SUCCEEDED", "CANCELED", "ABORTED")
ACTIVE = frozenset((ACCEPTED, EXECUTING, CANCELING))
TERMINAL = frozenset((SUCCEEDED, CANCELED, ABORTED))
#: The states a goal can be in, as a server's status array names them.
KNOWN = ACTIVE | TERMINAL

#: rcl_action's goal state machine: (state, event) -> new state.
TRANSITIONS = {
    (ACCEPTED, "execute"): EXECUTING,
    (ACCEPTED, "cancel_goal"): CANCELING,
    (EXECUTING, "cancel_goal"): CANCELING,
    (EXECUTING, "succeed"): SUCCEEDED,
    (EXECUTING, "abort"): ABORTED,
    (CANCELING, "succeed"): SUCCEEDED,
    (CANCELING, "abort"): ABORTED,
    (CANCELING, "canceled"): CANCELED,
}


_VERBS = {"cancel_goal": "cancel", "canceled": "end as canceled"}


def name(status: int) -> str:
    """ "SUCCEEDED" for 4, as `ros2 action send_goal` prints a status; "UNKNOWN" for a value
    no goal can have (a peer may send anything)."""
    return NAMES[status] if isinstance(status, int) and 0 <= status < len(NAMES) else "UNKNOWN"


class InvalidTransition(RuntimeError):
    """A goal asked to move where rcl_action's state machine does not go."""


def transition(state: int, event: str, goal: str) -> int:
    """The state after `event`, or InvalidTransition saying why not (`goal` names the goal)."""
    new = TRANSITIONS.get((state, event))
    if new is None:
        hint = ""
        if event == "canceled" and state in (ACCEPTED, EXECUTING):
            hint = ": canceled() ends a goal whose cancellation was requested (is_cancel_requested)"
        elif state == ACCEPTED and event in ("succeed", "abort"):
            hint = ": execute() it first"
        elif state in TERMINAL:
            hint = ": it has finished already"
        raise InvalidTransition(f"goal {goal}: cannot {_VERBS.get(event, event)} a goal that is {name(state)}{hint}")
    return new


class GoalIds:
    """Goal ids for one action client: random (uuid4) on the wall clock, as rclpy makes them; a
    fixed sequence per node and action under `--clock sim`, so that two runs send the same ids
    and print the same lines."""

    def __init__(self, seed: str | None) -> None:
        # deferred: start-up (every `from llfsm import ros` loads this module; only a client needs these)
        import random
        import uuid

        self._uuid = uuid
        self._rng: random.Random | None = random.Random(seed) if seed is not None else None

    def new(self) -> list[int]:
        if self._rng is None:
            return list(self._uuid.uuid4().bytes)
        return list(self._uuid.UUID(int=self._rng.getrandbits(128), version=4).bytes)


def text(goal_id: list[int] | bytes) -> str:
    """A goal id as `ros2 action send_goal` prints it: 32 hex digits."""
    return bytes(goal_id).hex()
