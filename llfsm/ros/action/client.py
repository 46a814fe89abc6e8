"""Action clients, as `rclpy.action.ActionClient`: `ros.ActionClient(node, T, name)`, and the goal
handles its goals get (docs/actions.md).

Nothing here blocks: `send_goal_async` returns a future of the goal handle, the handle's
`get_result_async` a future of the result response (`.status`, `.result`) and
`cancel_goal_async` one of the cancel response, so a machine polls `future.done()` in a guard
as it does for a service call, or spins with `ros.spin_until_future_complete`.  Feedback
callbacks run in the executor's turn, as subscription callbacks do.

The client is three service clients and two subscriptions of the node (names.py).  Its goal
handles follow the server's status topic.  With a Fast DDS server, whose replies llfsm matches
to requests by their order (docs/transports.md), a result is asked for only once the status
says the goal has finished: the server then answers at once, so the replies of one client
cannot overtake each other.

Over DDS any process can publish on the action's status and feedback topics.  The client looks
at each sample's bytes before it decodes it (`Subscription.screen`): feedback is decoded only
for a goal of this client that asked for it, and a status array is read for this client's
goals only, without making a message of each entry, so a peer's array of a million entries
costs one pass over its bytes and no memory beyond them.  A status value that names no goal
state is ignored.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Collection, Iterator
from typing import TYPE_CHECKING, Any
from weakref import WeakKeyDictionary

from ...msgs._message import Message, is_action_class
from ..executor import FutureReturnCode
from ..names import type_name
from ..task import Future
from . import status
from .names import CANCEL_GOAL, FEEDBACK, GET_RESULT, SEND_GOAL, STATUS
from .server import qos_profile_action_status_default

if TYPE_CHECKING:
    from ...msgs._message import Action
    from ..bus import Bus
    from ..node import Node


#: One GoalStatus of action_msgs/msg/GoalStatusArray in CDR after the first: the goal id (16
#: bytes), 3 bytes padding, the stamp (8 bytes, not read), the status (int8).  The first entry
#: starts 4-aligned, right after the array's length, so it has no padding after its id.
_ENTRY = struct.Struct("16s3x8xb")
_FIRST, _NEXT = 4, 29  # where the first and second entries start, counted from the CDR body
#: Up to this many goals, statuses_of searches the bytes for each; beyond, it reads every entry.
_SEARCHED = 8


def status_entries(payload: bytes) -> Iterator[tuple[bytes, int]]:
    """(goal id, status) of each entry of a GoalStatusArray's CDR payload (encapsulation header
    first), in order, without decoding the rest; ValueError for a payload that is not one."""
    body, n = _status_body(payload)
    if n == 0:
        return
    yield bytes(body[_FIRST : _FIRST + 16]), struct.unpack_from("b", body, _FIRST + 24)[0]
    yield from _ENTRY.iter_unpack(body[_NEXT : _NEXT + _ENTRY.size * (n - 1)])


def statuses_of(payload: bytes, wanted: Collection[bytes]) -> list[tuple[bytes, int]]:
    """(goal id, status) of the first entry of each goal in `wanted` that a GoalStatusArray's
    CDR payload lists: for a few goals each is searched for in the bytes (a pass in C per goal, a
    hit counts only where an entry starts), for many the entries are read in one pass."""
    if len(wanted) > _SEARCHED:
        seen: dict[bytes, int] = {}
        for goal_id, value in status_entries(payload):
            if goal_id in wanted and goal_id not in seen:
                seen[goal_id] = value
        return list(seen.items())
    _, n = _status_body(payload)
    found = []
    first, nxt = 4 + _FIRST, 4 + _NEXT  # counted from the payload's start, header included
    last = nxt + _ENTRY.size * (n - 2) if n > 1 else first  # where the last entry starts
    for goal_id in wanted:
        at = payload.find(goal_id, first, last + 16) if n else -1
        while at != -1:
            if at == first or (at >= nxt and (at - nxt) % _ENTRY.size == 0):
                found.append((goal_id, struct.unpack_from("b", payload, at + (24 if at == first else 27))[0]))
                break
            at = payload.find(goal_id, at + 1, last + 16)
    return found


def _status_body(payload: bytes) -> tuple[memoryview, int]:
    """A GoalStatusArray payload's CDR body and its number of entries, checked to fit."""
    if len(payload) < 8 or payload[0] != 0 or payload[1] not in (0, 1):
        raise ValueError("not a plain CDR GoalStatusArray")
    (n,) = struct.unpack_from("<I" if payload[1] else ">I", payload, 4)
    body = memoryview(payload)[4:]
    if n and len(body) < _NEXT + _ENTRY.size * (n - 1):
        raise ValueError(f"a status array that declares {n} entries holds fewer")
    return body, n


#: Action clients made so far on each bus, per (node, action): under the sim clock the n-th one
#: draws its goal ids from a sequence of its own, so two runs send the same ids and two clients
#: of one run never send the same.
_clients_made: WeakKeyDictionary[Bus, dict[tuple[str, str], int]] = WeakKeyDictionary()


class ClientGoalHandle:
    """A goal as its client sees it (rclpy's ClientGoalHandle)."""

    __slots__ = ("_client", "_id", "_response", "_result_future", "_status", "goal_id")

    def __init__(self, client: ActionClient, goal_id: Any, response: Any) -> None:
        self._client = client
        self.goal_id = goal_id  # unique_identifier_msgs/msg/UUID
        self._id = bytes(goal_id.uuid)
        self._response = response  # the SendGoal response: accepted, stamp
        self._status = status.UNKNOWN
        self._result_future: Future | None = None

    def __eq__(self, other: object) -> bool:
        return isinstance(other, ClientGoalHandle) and self._id == other._id

    def __hash__(self) -> int:
        return hash(self._id)

    def __repr__(self) -> str:
        return f"ClientGoalHandle <id={status.text(self._id)}, accepted={self.accepted}, status={self._status}>"

    @property
    def accepted(self) -> bool:
        return bool(self._response.accepted)

    @property
    def stamp(self) -> Any:
        """When the server accepted the goal (builtin_interfaces/msg/Time)."""
        return self._response.stamp

    @property
    def status(self) -> int:
        """action_msgs/msg/GoalStatus's value, as the server's status topic (or the result)
        last said: UNKNOWN (0) until then."""
        return self._status

    def get_result_async(self) -> Future:
        """A future of the result response: `.status` (SUCCEEDED, CANCELED, ABORTED, or
        UNKNOWN for a goal the server does not know) and `.result`."""
        return self._client._get_result_async(self)

    def cancel_goal_async(self) -> Future:
        """A future of the cancel response (`.return_code`, `.goals_canceling`)."""
        return self._client._cancel_goal_async(self)

    def get_result(self, timeout_sec: float | None = None) -> Any:
        """Spins until the result response (raises TimeoutError if none can come)."""
        return self._client._wait(self.get_result_async(), timeout_sec, "the result")

    def cancel_goal(self, timeout_sec: float | None = None) -> Any:
        """Spins until the cancel response (raises TimeoutError if none can come)."""
        return self._client._wait(self.cancel_goal_async(), timeout_sec, "the cancel response")


class _ResultRequest:
    """A result request held back until the status says its goal has finished (Fast DDS)."""

    __slots__ = ("future", "handle")

    def __init__(self, handle: ClientGoalHandle, future: Future) -> None:
        self.handle, self.future = handle, future


class ActionClient:
    """A client of an action (rclpy's ActionClient).  QoS keyword arguments are accepted and
    the profiles ROS 2 uses are kept."""

    def __init__(self, node: Node, action_type: type[Action], action_name: str, **_ignored: Any) -> None:
        node._check()
        if not is_action_class(action_type):
            raise TypeError(
                f"ActionClient(): action_type must be an action class such as Fibonacci, not {action_type!r}"
            )
        bus: Bus = node._bus
        name = node.resolve_topic_name(action_name)
        self._bus = bus
        self._node = node
        self._type = action_type
        self._name = name
        self._handles: dict[bytes, ClientGoalHandle] = {}  # accepted goals not yet finished
        self._feedback_callbacks: dict[bytes, Callable[[Any], Any]] = {}
        self._held: list[_ResultRequest] = []
        #: Goals sent and not yet answered -> the status the server's status topic gave them
        #: meanwhile (it can overtake the answer), UNKNOWN while it gave none.
        self._sent: dict[bytes, int] = {}
        seed = None
        if bus.clock.kind == "sim":  # the n-th client of this node and action in the run: its own ids
            made = _clients_made.setdefault(bus, {})
            key = (node.get_fully_qualified_name(), name)
            made[key] = made.get(key, 0) + 1
            seed = f"{key[0]} {name} {made[key]}"
        self._ids = status.GoalIds(seed)
        self._destroyed = False
        impl = action_type.Impl
        at = len(node._entities)
        self._goal_client = node.create_client(impl.SendGoalService, name + SEND_GOAL)
        self._cancel_client = node.create_client(impl.CancelGoalService, name + CANCEL_GOAL)
        self._result_client = node.create_client(impl.GetResultService, name + GET_RESULT)
        self._feedback_sub = node.create_subscription(impl.FeedbackMessage, name + FEEDBACK, self._on_feedback, 10)
        self._status_sub = node.create_subscription(
            impl.GoalStatusMessage, name + STATUS, self._on_status, qos_profile_action_status_default
        )
        self._feedback_sub.screen = self._screen_feedback
        self._status_sub.screen = self._screen_status
        self._parts: list[Any] = [
            self._goal_client,
            self._cancel_client,
            self._result_client,
            self._feedback_sub,
            self._status_sub,
        ]
        node._entities.insert(at, self)

    @property
    def action_type(self) -> type[Action]:
        return self._type

    @property
    def action_name(self) -> str:
        """The action's resolved name ("/turtle1/rotate_absolute")."""
        return self._name

    # -- the server ----------------------------------------------------------------------------------
    def server_is_ready(self) -> bool:
        """A server answers all three of the action's services, and its feedback and status
        reach this client (rcl_action's test): a goal sent then misses none of its feedback."""
        return (
            self._goal_client.service_is_ready()
            and self._cancel_client.service_is_ready()
            and self._result_client.service_is_ready()
            and self._feedback_sub.get_publisher_count() > 0
            and self._status_sub.get_publisher_count() > 0
        )

    def wait_for_server(self, timeout_sec: float | None = None) -> bool:
        """True once a server is ready.  Waits (the sim clock jumps) at most timeout_sec,
        running due timers meanwhile; with no timeout it waits for a server of another process
        (DDS) until Ctrl-C or the run's --duration, and does not block in process (nothing could
        create the server while this machine waits)."""
        if self.server_is_ready():
            return True
        bus = self._bus
        remote = bus.transport.remote
        if timeout_sec is None:
            if not remote:
                return False
            while bus.ok() and (bus.ctx.deadline is None or bus.clock.now < bus.ctx.deadline):
                bus.spin_once(100_000_000)
                if self.server_is_ready():
                    return True
            return False
        if isinstance(timeout_sec, bool) or not isinstance(timeout_sec, int | float) or timeout_sec <= 0:
            return False
        deadline = bus.clock.now + round(timeout_sec * 1e9)
        while bus.clock.now < deadline:
            if remote and not bus.ok():
                return False
            bus.spin_once(deadline - bus.clock.now)
            if self.server_is_ready():
                return True
        return False

    # -- goals ---------------------------------------------------------------------------------------
    def send_goal_async(
        self, goal: Message, feedback_callback: Callable[[Any], Any] | None = None, goal_uuid: Any = None
    ) -> Future:
        """Send a goal: a future of its ClientGoalHandle (`accepted` tells whether the server
        took it).  `feedback_callback(feedback_message)` gets the goal's feedback messages
        (`.feedback` is the action's Feedback), in the executor's turn."""
        if type(goal) is not self._type.Goal:
            raise TypeError(
                f"send_goal_async() on {self._name}: expected a {self._type.Goal._TYPE}, got {type_name(goal)}"
            )
        if feedback_callback is not None and not callable(feedback_callback):
            raise TypeError("send_goal_async(): feedback_callback must be callable (or None)")
        request = self._type.Impl.SendGoalService.Request(goal=goal)
        if goal_uuid is not None:
            request.goal_id = goal_uuid
        else:
            request.goal_id.uuid = self._ids.new()
        goal_id = request.goal_id._copy()
        self._sent[bytes(goal_id.uuid)] = status.UNKNOWN
        if feedback_callback is not None:
            self._feedback_callbacks[bytes(goal_id.uuid)] = feedback_callback
        sent = self._goal_client.call_async(request)
        future = Future(sent._service, sent._remote)
        sent.add_done_callback(lambda done: self._goal_answered(done, goal_id, future))
        return future

    def send_goal(
        self,
        goal: Message,
        feedback_callback: Callable[[Any], Any] | None = None,
        goal_uuid: Any = None,
        timeout_sec: float | None = None,
    ) -> Any:
        """rclpy's synchronous form, for scripts and tests: spins (the sim clock jumps) until the
        goal's result response (`.status`, `.result`).  A rejected goal's result is asked for
        all the same, as rclpy does, and comes back with status UNKNOWN.  `timeout_sec` bounds
        each of the two waits (TimeoutError).  Machine code must not wait in a ringlet: it polls
        `send_goal_async`'s future in a guard instead."""
        handle = self._wait(self.send_goal_async(goal, feedback_callback, goal_uuid), timeout_sec, "the goal")
        return handle.get_result(timeout_sec)

    def _goal_answered(self, sent: Future, goal_id: Any, future: Future) -> None:
        response = sent.result()
        handle = ClientGoalHandle(self, goal_id, response)
        heard = self._sent.pop(handle._id, status.UNKNOWN)
        if handle.accepted:
            # accepted, or further along if the status topic came first (rclpy would say
            # UNKNOWN until the status topic speaks; `ros2 action send_goal` then could not
            # cancel a goal on Ctrl-C)
            handle._status = heard if heard != status.UNKNOWN else status.ACCEPTED
            if handle._status not in status.TERMINAL:
                self._handles[handle._id] = handle
        else:
            self._feedback_callbacks.pop(handle._id, None)
        future.set_result(handle)

    def _get_result_async(self, handle: ClientGoalHandle) -> Future:
        self._result_client.service_is_ready()  # a look at the server tells the transport its kind
        remote = self._result_client._remote
        if remote is not None and getattr(remote, "in_order", False) and handle._status not in status.TERMINAL:
            future = Future(self._result_client.srv_name, remote)
            self._held.append(_ResultRequest(handle, future))
            return future
        return self._ask_result(handle)

    def _ask_result(self, handle: ClientGoalHandle, future: Future | None = None) -> Future:
        request = self._type.Impl.GetResultService.Request(goal_id=handle.goal_id)
        sent = self._result_client.call_async(request)
        sent.add_done_callback(lambda done: self._result_answered(handle, done))
        if future is None:
            return sent
        future._remote = sent._remote
        sent.add_done_callback(lambda done: future.set_result(done.result()))
        return future

    def _result_answered(self, handle: ClientGoalHandle, done: Future) -> None:
        response = done.result()
        if response is None:
            return
        if response.status in status.TERMINAL:
            handle._status = response.status
            self._handles.pop(handle._id, None)
        # rclpy's rule: no feedback after the result; but feedback the server sent before it,
        # queued for the executor or brought in by the same look at the transport as the
        # result (its reader may be looked at after the result's), is still handed over
        goal_id = handle._id
        call_soon = self._bus.call_soon_threadsafe
        call_soon(lambda: call_soon(lambda: self._feedback_callbacks.pop(goal_id, None)))

    def _cancel_goal_async(self, handle: ClientGoalHandle) -> Future:
        request = self._type.Impl.CancelGoalService.Request()
        request.goal_info.goal_id = handle.goal_id
        return self._cancel_client.call_async(request)

    def _wait(self, future: Future, timeout_sec: float | None, what: str) -> Any:
        code = self._bus.spin_until(future, None if timeout_sec is None else round(timeout_sec * 1e9))
        if code is not FutureReturnCode.SUCCESS:
            raise TimeoutError(f"no answer from action {self._name} ({what}, {code.name})")
        return future.result()

    # -- what the server publishes -------------------------------------------------------------------
    def _on_feedback(self, message: Any) -> None:
        callback = self._feedback_callbacks.get(bytes(message.goal_id.uuid))
        if callback is not None:
            callback(message)

    def _screen_feedback(self, payload: bytes) -> bool:
        """Over DDS: decode a feedback message only for a goal of this client that asked for
        feedback (the goal id leads the message, after the 4 bytes of encapsulation)."""
        return bytes(payload[4:20]) in self._feedback_callbacks

    def _screen_status(self, payload: bytes) -> Any:
        """Over DDS: the server's status array, cut down to this client's goals (module
        docstring); nothing to deliver when none of them is in it."""
        handles, sent = self._handles, self._sent
        if not (handles or sent):
            return False
        mine = statuses_of(payload, handles.keys() | sent.keys())
        if not mine:
            return False
        # deferred: start-up (a run that calls no action never loads action_msgs)
        from ...msgs.action_msgs.msg import GoalStatus

        entries = []
        for goal_id, value in mine:
            entry = GoalStatus(status=value)
            entry.goal_info.goal_id.uuid = list(goal_id)
            entries.append(entry)
        return self._type.Impl.GoalStatusMessage(status_list=entries)

    def _on_status(self, array: Any) -> None:
        for entry in array.status_list:
            if entry.status not in status.KNOWN:
                continue  # a peer's array may hold anything: only a goal state moves a goal
            goal_id = bytes(entry.goal_info.goal_id.uuid)
            handle = self._handles.get(goal_id)
            if handle is None:
                if goal_id in self._sent:
                    self._sent[goal_id] = entry.status  # the status overtook the answer to the goal
                continue
            handle._status = entry.status
            if entry.status in status.TERMINAL:
                del self._handles[goal_id]
        if self._held:
            self._release()

    def _release(self) -> None:
        """Ask for the results held back whose goals the status now says have finished."""
        held, self._held = self._held, []
        for request in held:
            if request.handle._status in status.TERMINAL:
                self._ask_result(request.handle, request.future)
            else:
                self._held.append(request)

    def destroy(self) -> None:
        if self._destroyed:
            return
        self._destroyed = True
        for part in self._parts:
            part.destroy()
        self._feedback_callbacks.clear()
        self._held.clear()
        if self in self._node._entities:
            self._node._entities.remove(self)
        self._bus.transport.node_changed(self._node)
