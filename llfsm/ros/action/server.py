"""Action servers, as `rclpy.action.ActionServer`: `ros.ActionServer(node, T, name,
execute_callback, goal_callback=, cancel_callback=, handle_accepted_callback=)` and the goal
handles it gives out (docs/actions.md).

An action is three services and two topics of the node (names.py), made with the node's own
publishers and servers, so both transports carry it as ROS 2 does.  A goal request asks the goal
callback (accept or reject); an accepted goal is handed to the handle-accepted callback, which by
default executes it; a cancel request asks the cancel callback (rclpy's default: reject);
a result request is answered once the goal has finished, which may be long after it came
(the get_result service answers later, the one server of the bus that does).

Three ways to serve a goal, none of which holds up the machines:
- rclpy's execute callback, run as a task of the executor (execution.py): a plain function
  runs at once, a generator or coroutine resumes where it yielded; what it returns is the
  result;
- rclcpp's and turtlesim's: a handle-accepted callback keeps the handle, and whatever owns it
  later calls `publish_feedback(...)` and `succeed(result)` (or `abort`, `canceled`);
- llfsm's PULL form, for a machine that *is* the execution: no execute callback, and accepted
  goals wait in `server.take()`, as a PULL subscription's messages wait in `sub.take()`.  The
  machine takes a goal (it is then executing), publishes feedback from its states, and ends it
  from an accepting state.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from enum import Enum
from typing import TYPE_CHECKING, Any

from ...msgs._message import Message, is_action_class
from ..names import type_name
from ..qos import DurabilityPolicy, QoSProfile
from ..service import ServiceServer
from ..task import Future
from . import status
from .execution import Execution
from .names import CANCEL_GOAL, FEEDBACK, GET_RESULT, SEND_GOAL, STATUS

if TYPE_CHECKING:
    from ...msgs._message import Action
    from ..bus import Bus
    from ..node import Node

#: rclpy's qos_profile_action_status_default (rcl_action's): the last status array stays with
#: the writer for clients that come later.
qos_profile_action_status_default = QoSProfile(1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
#: How long (s of run time) a finished goal's result is kept for late result requests: rclpy's
#: default since Humble.
RESULT_TIMEOUT = 900.0
#: Finished goals a server remembers at most (their results and statuses), oldest forgotten
#: first: a client sending goals in a loop must not grow the server without bound.
MAX_FINISHED = 1000
#: Finished goals the status array lists, the most recent ones, beside every goal not finished.
#: rcl_action lists every goal it remembers, so each status message grows with the goals of
#: the last result_timeout (15 min) and costs every publish and every client that much; a
#: client needs a goal's terminal status once, and asks for an older one's with get_result.
STATUS_FINISHED = 64
#: Unfinished goals (accepted, executing or being canceled) a server holds at most; a goal
#: request past it is rejected, with one warning.  A server that executes one goal at a time
#: (a machine in the PULL form) would otherwise let any client pile goals up without bound, and
#: each status array, cancel request and result lookup costs in proportion to them.
MAX_GOALS = 1000


class GoalResponse(Enum):
    """What a goal callback answers (rclpy's)."""

    REJECT = 1
    ACCEPT = 2


class CancelResponse(Enum):
    """What a cancel callback answers (rclpy's)."""

    REJECT = 1
    ACCEPT = 2


def default_goal_callback(goal_request: Any) -> GoalResponse:
    """Accept every goal (rclpy's default)."""
    return GoalResponse.ACCEPT


def default_cancel_callback(goal_handle: Any) -> CancelResponse:
    """Refuse every cancellation (rclpy's default)."""
    return CancelResponse.REJECT


class ServerGoalHandle:
    """An accepted goal, as the server's code sees it (rclpy's ServerGoalHandle; `succeed`,
    `abort` and `canceled` also take the result, as rclcpp's do)."""

    __slots__ = ("_entry", "_id", "_request", "_result", "_server", "_stamp", "_stamp_ns", "_status", "goal_id")

    def __init__(self, server: ActionServer, goal_id: Any, stamp: Any, request: Message) -> None:
        self._server = server
        self.goal_id = goal_id  # unique_identifier_msgs/msg/UUID
        self._id = bytes(goal_id.uuid)
        self._stamp = stamp  # builtin_interfaces/msg/Time: when it was accepted
        self._stamp_ns = stamp.sec * 1_000_000_000 + stamp.nanosec
        self._request = request
        self._status = status.ACCEPTED
        self._result: Message | None = None
        #: Its entry in the status array (action_msgs/msg/GoalStatus), made once.
        self._entry = server._goal_status(status=status.ACCEPTED)
        self._entry.goal_info.goal_id = goal_id
        self._entry.goal_info.stamp = stamp

    def __repr__(self) -> str:
        return f"<ServerGoalHandle {status.text(self._id)} {status.name(self._status)}>"

    @property
    def request(self) -> Any:
        """The goal (the action's Goal message)."""
        return self._request

    @property
    def status(self) -> int:
        """action_msgs/msg/GoalStatus's value: ACCEPTED (1) ... ABORTED (6)."""
        return self._status

    @property
    def is_active(self) -> bool:
        return self._status in status.ACTIVE

    @property
    def is_cancel_requested(self) -> bool:
        """True once a client's cancel request was accepted: the goal should stop and end with
        `canceled()` (or still `succeed()` / `abort()`)."""
        return self._status == status.CANCELING

    def execute(self, execute_callback: Callable[[Any], Any] | None = None) -> None:
        """Start executing: the goal becomes EXECUTING (unless a cancel request came first, as
        in rclpy) and the execute callback, this one or the server's, runs as a task."""
        if self._status != status.CANCELING:
            self._event("execute")
        callback = execute_callback if execute_callback is not None else self._server._execute_callback
        if callback is not None:
            self._server._start(self, callback)

    def publish_feedback(self, feedback: Message) -> None:
        server = self._server
        if type(feedback) is not server._type.Feedback:
            raise TypeError(
                f"publish_feedback() on action {server._name}: expected a {server._type.Feedback._TYPE}, "
                f"got {type_name(feedback)}"
            )
        if self._status not in status.ACTIVE:
            return  # rclpy ignores feedback of a goal that has finished
        server._feedback.publish(server._type.Impl.FeedbackMessage(goal_id=self.goal_id, feedback=feedback))

    def succeed(self, result: Message | None = None) -> None:
        self._event("succeed", result)

    def abort(self, result: Message | None = None) -> None:
        self._event("abort", result)

    def canceled(self, result: Message | None = None) -> None:
        self._event("canceled", result)

    def _event(self, event: str, result: Message | None = None) -> None:
        server = self._server
        if result is not None:
            server._check_result(result, event)
        self._status = status.transition(self._status, event, status.text(self._id))
        if result is not None:
            self._result = result
        server._publish_status()
        if self._status in status.TERMINAL and self._id not in server._running:
            server._finish(self, self._result)


class _LaterService(ServiceServer):
    """A server whose callback may answer later: it returns the response, or a Future of it
    (the get_result service, which answers when the goal has finished).  The bus and the
    transports reply when that future is done."""

    def _answer(self, request: Message) -> Any:
        return self.callback(request, self.type.Response())


class _Accepted:
    """Executor work: a goal just accepted, handed on after its acceptance has been answered."""

    __slots__ = ("handle", "server")

    def __init__(self, server: ActionServer, handle: ServerGoalHandle) -> None:
        self.server, self.handle = server, handle

    def _run(self) -> None:
        server, handle = self.server, self.handle
        if server._destroyed or handle._status not in status.ACTIVE:
            return
        if server._handle_accepted_callback is not None:
            server._handle_accepted_callback(handle)
        elif server._execute_callback is not None:
            handle.execute()
        else:
            server._waiting.append(handle)  # the PULL form: a machine takes it


class ActionServer:
    """A server of an action (rclpy's ActionServer; see the module docstring for the forms of
    execution).  QoS keyword arguments are accepted and the profiles ROS 2 uses are kept."""

    def __init__(
        self,
        node: Node,
        action_type: type[Action],
        action_name: str,
        execute_callback: Callable[[Any], Any] | None = None,
        *,
        goal_callback: Callable[[Any], Any] | None = None,
        handle_accepted_callback: Callable[[Any], Any] | None = None,
        cancel_callback: Callable[[Any], Any] | None = None,
        result_timeout: float = RESULT_TIMEOUT,
        max_goals: int = MAX_GOALS,
        **_ignored: Any,
    ) -> None:
        node._check()
        if not is_action_class(action_type):
            raise TypeError(
                f"ActionServer(): action_type must be an action class such as Fibonacci, not {action_type!r}"
            )
        for what, fn in (
            ("execute_callback", execute_callback),
            ("goal_callback", goal_callback),
            ("handle_accepted_callback", handle_accepted_callback),
            ("cancel_callback", cancel_callback),
        ):
            if fn is not None and not callable(fn):
                raise TypeError(f"ActionServer(): {what} must be callable (or None), not {fn!r}")
        if isinstance(result_timeout, bool) or not isinstance(result_timeout, int | float) or result_timeout < 0:
            raise ValueError(f"ActionServer(): result_timeout must be a number of seconds >= 0, not {result_timeout!r}")
        if isinstance(max_goals, bool) or not isinstance(max_goals, int) or max_goals < 1:
            raise ValueError(f"ActionServer(): max_goals must be an integer >= 1, not {max_goals!r}")
        bus: Bus = node._bus
        name = node.resolve_topic_name(action_name)
        for suffix in (SEND_GOAL, CANCEL_GOAL, GET_RESULT):
            if node.resolve_service_name(name + suffix) in bus.services:
                raise ValueError(f"ActionServer(): action {name} already has a server; an action has exactly one")
        self._bus = bus
        self._node = node
        self._type = action_type
        self._name = name
        self._execute_callback = execute_callback
        self._goal_callback = goal_callback or default_goal_callback
        self._handle_accepted_callback = handle_accepted_callback
        self._cancel_callback = cancel_callback or default_cancel_callback
        self._result_timeout_ns = round(result_timeout * 1e9)
        self._max_goals = max_goals
        self._full_warned = False
        self._status_due = False  # a status array is queued for the end of the executor's turn
        self._goals: dict[bytes, ServerGoalHandle] = {}  # every goal not yet forgotten, oldest first
        self._unfinished: dict[bytes, ServerGoalHandle] = {}  # goals whose result is still to come
        self._results: dict[bytes, Future] = {}  # each goal's GetResult response, once finished
        self._finished: deque[tuple[bytes, int]] = deque()  # (goal, run time it finished), in order
        self._recent: deque[bytes] = deque(maxlen=STATUS_FINISHED)  # the finished goals the status lists
        self._running: dict[bytes, Execution] = {}
        self._waiting: deque[ServerGoalHandle] = deque()
        self._destroyed = False
        self._logger = node.get_logger().get_child("action_server")
        impl = action_type.Impl
        # deferred: start-up (a run that serves no action never loads action_msgs)
        from ...msgs.action_msgs.msg import GoalStatus

        self._goal_status = GoalStatus
        at = len(node._entities)
        self._parts: list[Any] = [
            node.create_service(impl.SendGoalService, name + SEND_GOAL, self._on_goal),
            node.create_service(impl.CancelGoalService, name + CANCEL_GOAL, self._on_cancel),
        ]
        results = _LaterService(
            bus, node, impl.GetResultService, node.resolve_service_name(name + GET_RESULT), self._on_result
        )
        node._entities.append(results)
        self._feedback = node.create_publisher(impl.FeedbackMessage, name + FEEDBACK, 10)
        self._status = node.create_publisher(impl.GoalStatusMessage, name + STATUS, qos_profile_action_status_default)
        self._parts += [results, self._feedback, self._status]
        node._entities.insert(at, self)  # destroy_node ends the goals before it takes the endpoints down
        bus.transport.node_changed(node)

    @property
    def action_type(self) -> type[Action]:
        return self._type

    @property
    def action_name(self) -> str:
        """The action's resolved name ("/turtle1/rotate_absolute")."""
        return self._name

    # -- the PULL form -----------------------------------------------------------------------------
    def take(self) -> ServerGoalHandle | None:
        """The oldest accepted goal waiting for a machine to execute it, now EXECUTING; None if
        none waits.  Only without an execute callback and a handle-accepted callback: those
        hand the goals out themselves."""
        while self._waiting:
            handle = self._waiting.popleft()
            if handle._status == status.ACCEPTED:
                handle.execute()
                return handle
            if handle._status == status.CANCELING:
                return handle  # canceled before it started: the machine still ends it (canceled())
        return None

    @property
    def waiting(self) -> int:
        """Accepted goals that `take()` would hand out."""
        return sum(1 for h in self._waiting if h._status in (status.ACCEPTED, status.CANCELING))

    # -- requests --------------------------------------------------------------------------------
    def _on_goal(self, request: Any, response: Any) -> Any:
        self._expire()
        goal_id = bytes(request.goal_id.uuid)
        accepted = False
        if len(self._unfinished) >= self._max_goals:
            self._full()
        elif goal_id not in self._goals:
            answer = self._goal_callback(request.goal)
            if isinstance(answer, GoalResponse):
                accepted = answer is GoalResponse.ACCEPT
            else:
                self._logger.warning("Goal request callback did not return a GoalResponse type. Rejecting goal.")
        if accepted:
            sec, nanosec = self._bus.stamp()
            response.stamp.sec, response.stamp.nanosec = sec, nanosec
            handle = ServerGoalHandle(self, request.goal_id, response.stamp._copy(), request.goal)
            self._goals[goal_id] = self._unfinished[goal_id] = handle
            self._results[goal_id] = Future(self._name + GET_RESULT)  # set when the goal ends
            self._publish_status()
            self._bus.queue(_Accepted(self, handle))
        response.accepted = accepted
        return response

    def _on_cancel(self, request: Any, response: Any) -> Any:
        """rcl_action's policy: a goal id and no stamp cancels that goal; a stamp cancels the
        goals accepted at or before it (and the goal named, if any); neither cancels all."""
        codes = self._type.Impl.CancelGoalService.Response
        self._expire()
        info = request.goal_info
        wanted = bytes(info.goal_id.uuid)
        before = info.stamp.sec * 1_000_000_000 + info.stamp.nanosec
        cancelable = (status.ACCEPTED, status.EXECUTING)
        if any(wanted) and before == 0:
            handle = self._goals.get(wanted)
            if handle is None:
                code, candidates = codes.ERROR_UNKNOWN_GOAL_ID, []
            elif handle._status in cancelable:
                code, candidates = codes.ERROR_NONE, [handle]
            else:
                code, candidates = codes.ERROR_GOAL_TERMINATED, []
        else:
            code = codes.ERROR_NONE
            if not any(wanted) and before == 0:
                before = 1 << 63
            candidates = [
                h
                for h in self._goals.values()
                if h._status in cancelable and (h._stamp_ns <= before or h._id == wanted)
            ]
        canceling = []
        for handle in candidates:
            if self._cancel_callback(handle) is not CancelResponse.ACCEPT:
                continue
            try:
                handle._event("cancel_goal")
            except status.InvalidTransition:
                continue  # the callback itself finished the goal
            info_type = type(request.goal_info)
            canceling.append(info_type(goal_id=handle.goal_id, stamp=handle._stamp))
        if candidates and not canceling and code == codes.ERROR_NONE:
            code = codes.ERROR_REJECTED  # as rclcpp answers when every goal refused
        response.return_code = code
        response.goals_canceling = canceling
        return response

    def _on_result(self, request: Any, response: Any) -> Any:
        self._expire()
        goal_id = bytes(request.goal_id.uuid)
        future = self._results.get(goal_id)
        if future is None:
            self._logger.warning(f"Sending result response for unknown or expired goal ID: {status.text(goal_id)}")
            response.status = status.UNKNOWN
            return response
        return future  # answered when the goal finishes (now, if it has)

    def _full(self) -> None:
        """A goal request past max_goals: rejected (rclpy's answer to a refused goal), said once."""
        if not self._full_warned:
            self._full_warned = True
            self._logger.warning(
                f"action {self._name} holds {len(self._unfinished)} unfinished goals, the most it keeps "
                f"(ActionServer(max_goals={self._max_goals})): further goals are rejected until some finish "
                "(said once)"
            )

    # -- goals ---------------------------------------------------------------------------------------
    def _start(self, handle: ServerGoalHandle, callback: Callable[[Any], Any]) -> None:
        if handle._id in self._running:
            raise RuntimeError(f"goal {status.text(handle._id)} of action {self._name} is executing already")
        execution = Execution(
            self._bus,
            lambda: callback(handle),
            lambda value: self._executed(handle, value),
            lambda error: self._execution_failed(handle),
        )
        self._running[handle._id] = execution
        execution.start()

    def _executed(self, handle: ServerGoalHandle, value: Any) -> None:
        """The execute callback returned `value`, the result (rclpy's rule)."""
        self._running.pop(handle._id, None)
        if handle._status in status.ACTIVE:
            self._logger.warning(f"Goal state not set, assuming aborted. Goal ID: {status.text(handle._id)}")
            handle._status = status.ABORTED  # rclpy's rule, from any active state
            self._publish_status()
        if value is not None:
            self._check_result(value, "return")
        self._finish(handle, value if value is not None else handle._result)

    def _execution_failed(self, handle: ServerGoalHandle) -> None:
        """The execute callback raised: the goal is aborted (clients get their answer) before
        the exception ends the run."""
        self._running.pop(handle._id, None)
        if handle._status in status.ACTIVE:
            handle._status = status.ABORTED
            self._publish_status()
        self._finish(handle, handle._result)

    def _check_result(self, result: Any, how: str) -> None:
        if type(result) is not self._type.Result:
            what = "the execute callback must return" if how == "return" else f"{how}() takes"
            raise TypeError(
                f"action {self._name}: {what} a {self._type.Result._TYPE} (or None), not {type_name(result)}"
            )

    def _finish(self, handle: ServerGoalHandle, result: Message | None) -> None:
        """The goal has ended: its result answers the result requests, now and later."""
        future = self._results.get(handle._id)
        if future is None or future.done():
            return
        response = self._type.Impl.GetResultService.Response(status=handle._status)
        response.result = result if result is not None else self._type.Result()
        self._unfinished.pop(handle._id, None)
        self._finished.append((handle._id, self._bus.clock.now))
        self._recent.append(handle._id)
        future.set_result(response)

    def _expire(self) -> None:
        """Forget finished goals older than the result timeout, and the oldest beyond
        MAX_FINISHED (rcl_action's expiry, plus a bound)."""
        finished = self._finished
        horizon = self._bus.clock.now - self._result_timeout_ns
        dropped = False
        while finished and (finished[0][1] < horizon or len(finished) > MAX_FINISHED):
            goal_id, _ = finished.popleft()
            self._goals.pop(goal_id, None)
            self._results.pop(goal_id, None)
            dropped = True
        if dropped:
            self._publish_status()

    def _publish_status(self) -> None:
        """The status array changed: publish it at the end of the executor's turn, once however
        many goals the turn moved (a cancel of a thousand goals is one message, not a thousand
        growing ones; a status published per goal cost a run seconds of its rounds)."""
        if not self._status_due and not self._destroyed:
            self._status_due = True
            self._bus.queue_last(self)

    def _run(self) -> None:
        """Executor work (queued by _publish_status): the status array as it is now."""
        self._status_due = False
        self._send_status()

    def _send_status(self) -> None:
        if self._destroyed:
            return
        goals = self._goals
        shown = list(self._unfinished.values())
        shown += [goals[goal_id] for goal_id in self._recent if goal_id in goals]
        entries = []
        for h in shown:
            entry = h._entry
            entry.status = h._status
            entries.append(entry)
        self._status.publish(self._type.Impl.GoalStatusMessage(status_list=entries))

    # -- lifecycle ---------------------------------------------------------------------------------------
    def destroy(self) -> None:
        """Take the action down.  Goals still active end as ABORTED first (their clients get
        that answer), and executions stop where they are."""
        if self._destroyed:
            return
        for execution in list(self._running.values()):
            execution.close()
        self._running.clear()
        ended = False
        for handle in self._goals.values():
            if handle._status in status.ACTIVE:
                handle._status = status.ABORTED
                self._finish(handle, handle._result)
                ended = True
        if ended:
            self._send_status()  # now: the endpoints go next
        self._destroyed = True
        for part in self._parts:
            part.destroy()
        self._waiting.clear()
        if self in self._node._entities:
            self._node._entities.remove(self)
        self._bus.transport.node_changed(self._node)
