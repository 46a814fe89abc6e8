"""Actions on the in-process bus (SPEC §12, docs/actions.md): `ros.ActionClient` and
`ros.ActionServer` as rclpy's, under the sim clock (deterministic, no sleeping).  Over DDS:
tests/test_actions_dds.py; against rclpy: tests/interop/test_actions_rclpy.py."""

from __future__ import annotations

from collections.abc import Callable, Generator
from typing import Any

import pytest

from llfsm import ros
from llfsm.msgs.action_msgs.msg import GoalStatus, GoalStatusArray
from llfsm.msgs.action_msgs.srv import CancelGoal
from llfsm.msgs.geometry_msgs.msg import Twist
from llfsm.msgs.std_srvs.srv import Trigger
from llfsm.msgs.turtlesim.action import RotateAbsolute
from llfsm.ros.action import InvalidTransition
from llfsm.ros.bus import Bus, bus_of
from llfsm.runtime import RunContext, SimClock
from llfsm.runtime.context import activate

Goal, Result, Feedback = RotateAbsolute.Goal, RotateAbsolute.Result, RotateAbsolute.Feedback
MS = 1_000_000


def advance(bus: Bus, ms: int) -> None:
    """What the scheduler does between 1 ms rounds: move the clock on, then let the executor run."""
    for _ in range(ms):
        bus.clock.now += MS
        bus.spin_some()


def counting(goal_handle: Any) -> Generator[Any, None, Any]:
    """An execute callback in the generator form: feedback every 100 ms, `theta` tenths of a
    second in all; ends canceled when asked to."""
    steps = round(goal_handle.request.theta * 10)
    for left in range(steps, 0, -1):
        if goal_handle.is_cancel_requested:
            goal_handle.canceled()
            return Result(delta=float(left))
        goal_handle.publish_feedback(Feedback(remaining=left / 10))
        yield 0.1
    goal_handle.succeed()
    return Result(delta=goal_handle.request.theta)


def accept(_handle: Any) -> ros.CancelResponse:
    return ros.CancelResponse.ACCEPT


def client_and_server(
    execute: Callable[[Any], Any] | None = counting, **server_kw: Any
) -> tuple[ros.Node, ros.ActionClient, ros.ActionServer]:
    node = ros.Node("actions")
    server = ros.ActionServer(node, RotateAbsolute, "count", execute, **server_kw)
    client = ros.ActionClient(node, RotateAbsolute, "count")
    return node, client, server


def send(bus: Bus, client: ros.ActionClient, theta: float, feedback: list[Any] | None = None) -> Any:
    """Send a goal and let the executor answer: its goal handle."""
    future = client.send_goal_async(Goal(theta=theta), feedback.append if feedback is not None else None)
    advance(bus, 2)
    assert future.done()
    return future.result()


# -- the rclpy API ----------------------------------------------------------------------------------


def test_a_goal_is_accepted_gives_feedback_and_succeeds_with_its_result(bus: Bus) -> None:
    _, client, server = client_and_server()
    assert client.server_is_ready() and client.wait_for_server(timeout_sec=1.0)
    assert (client.action_name, server.action_name) == ("/count", "/count")
    feedback: list[Any] = []
    handle = send(bus, client, 0.3, feedback)
    assert handle.accepted and len(bytes(handle.goal_id.uuid)) == 16
    result = handle.get_result_async()
    assert not result.done()
    advance(bus, 150)
    assert not result.done() and handle.status == GoalStatus.STATUS_EXECUTING
    advance(bus, 200)
    assert result.done()
    assert result.result().status == GoalStatus.STATUS_SUCCEEDED and result.result().result.delta == pytest.approx(0.3)
    assert handle.status == GoalStatus.STATUS_SUCCEEDED
    assert [m.feedback.remaining for m in feedback] == pytest.approx([0.3, 0.2, 0.1])
    assert all(bytes(m.goal_id.uuid) == bytes(handle.goal_id.uuid) for m in feedback)
    assert [f"{m.feedback.remaining}" for m in feedback] == ["0.3", "0.2", "0.1"]


def test_spin_until_future_complete_waits_the_goal_out_on_the_sim_clock(bus: Bus) -> None:
    node, client, _ = client_and_server()
    sent = client.send_goal_async(Goal(theta=0.5))
    assert ros.spin_until_future_complete(node, sent) is ros.FutureReturnCode.SUCCESS
    start = bus.clock.now
    result = sent.result().get_result_async()
    assert ros.spin_until_future_complete(node, result) is ros.FutureReturnCode.SUCCESS
    assert result.result().status == GoalStatus.STATUS_SUCCEEDED
    assert 500 * MS <= bus.clock.now - start < 510 * MS  # five pauses of 100 ms, the sim clock jumping
    assert sent.result().get_result().result.delta == pytest.approx(0.5)  # the synchronous form


def test_send_goal_waits_for_the_result_as_rclpy_s_synchronous_form(bus: Bus) -> None:
    _, client, _ = client_and_server(
        goal_callback=lambda goal: ros.GoalResponse.REJECT if goal.theta < 0 else ros.GoalResponse.ACCEPT
    )
    feedback: list[Any] = []
    start = bus.clock.now
    answer = client.send_goal(Goal(theta=0.3), feedback_callback=feedback.append)
    assert answer.status == GoalStatus.STATUS_SUCCEEDED and answer.result.delta == pytest.approx(0.3)
    assert [m.feedback.remaining for m in feedback] == pytest.approx([0.3, 0.2, 0.1])
    assert 300 * MS <= bus.clock.now - start < 310 * MS  # the sim clock jumped the pauses
    assert client.send_goal(Goal(theta=-1.0)).status == GoalStatus.STATUS_UNKNOWN  # rejected, as rclpy answers it
    nobody = ros.ActionClient(ros.Node("lonely"), RotateAbsolute, "nobody")
    with pytest.raises(TimeoutError, match="no answer from action /nobody"):
        nobody.send_goal(Goal(), timeout_sec=1.0)


def test_the_three_forms_of_execute_callback(bus: Bus) -> None:
    """A plain function, a generator and a coroutine (awaiting a service's future) all serve."""
    node = ros.Node("forms")
    node.create_service(Trigger, "ask", lambda req, resp: setattr(resp, "message", "0.75") or resp)
    ask = node.create_client(Trigger, "ask")

    def plain(goal: Any) -> Any:
        goal.succeed()
        return Result(delta=1.0)

    async def coroutine(goal: Any) -> Any:
        answer = await ask.call_async(Trigger.Request())
        goal.succeed()
        return Result(delta=float(answer.message))

    results = []
    for name, execute in (("plain", plain), ("generator", counting), ("coroutine", coroutine)):
        ros.ActionServer(node, RotateAbsolute, name, execute)
        client = ros.ActionClient(node, RotateAbsolute, name)
        sent = client.send_goal_async(Goal(theta=0.2))
        ros.spin_until_future_complete(node, sent)
        answer = sent.result().get_result(timeout_sec=5.0)
        results.append((answer.status, answer.result.delta))
    assert results == [(4, 1.0), (4, pytest.approx(0.2)), (4, 0.75)]


def test_two_goals_at_once_run_side_by_side_each_with_its_feedback(bus: Bus) -> None:
    _, client, _ = client_and_server()
    first_feedback: list[Any] = []
    second_feedback: list[Any] = []
    first = send(bus, client, 0.4, first_feedback)
    second = send(bus, client, 0.2, second_feedback)
    assert first.goal_id != second.goal_id
    results = [first.get_result_async(), second.get_result_async()]
    advance(bus, 250)
    assert results[1].done() and not results[0].done()  # the shorter goal ends first
    advance(bus, 200)
    assert [r.result().result.delta for r in results] == pytest.approx([0.4, 0.2])
    assert [m.feedback.remaining for m in first_feedback] == pytest.approx([0.4, 0.3, 0.2, 0.1])
    assert [m.feedback.remaining for m in second_feedback] == pytest.approx([0.2, 0.1])


def _goal_ids() -> list[bytes]:
    """The ids of the goals one run sends: three from a client, one from a second client of the
    same node and action, one from a client of another node."""
    ctx = RunContext(SimClock())
    prev = activate(ctx)
    try:
        ros.init()
        bus = bus_of(ctx)
        _, client, _ = client_and_server()
        second = ros.ActionClient(client._node, RotateAbsolute, "count")
        other = ros.ActionClient(ros.Node("actions", namespace="/other"), RotateAbsolute, "/count")
        clients = [client, client, client, second, other]
        return [bytes(send(bus, c, 0.1).goal_id.uuid) for c in clients]
    finally:
        activate(prev)


def test_goal_ids_repeat_from_run_to_run_under_the_sim_clock() -> None:
    ids = _goal_ids()
    assert len(set(ids)) == 5 and all(i[6] >> 4 == 4 for i in ids)  # version 4, as uuid4's
    assert _goal_ids() == ids


def test_a_rejected_goal_and_a_goal_callback_that_answers_nonsense(
    bus: Bus, capsys: pytest.CaptureFixture[str]
) -> None:
    _, client, _ = client_and_server(goal_callback=lambda goal: ros.GoalResponse.REJECT if goal.theta < 0 else None)
    rejected = send(bus, client, -1.0)
    assert not rejected.accepted
    assert not send(bus, client, 1.0).accepted  # None is not a GoalResponse: rclpy rejects it
    assert "Goal request callback did not return a GoalResponse type. Rejecting goal." in capsys.readouterr().err
    unknown = rejected.get_result_async()
    advance(bus, 2)
    assert unknown.result().status == GoalStatus.STATUS_UNKNOWN  # the server does not know the goal


def test_a_goal_id_already_in_use_is_rejected(bus: Bus) -> None:
    _, client, _ = client_and_server()
    first = send(bus, client, 0.1)
    again = client.send_goal_async(Goal(theta=0.1), goal_uuid=first.goal_id)
    advance(bus, 2)
    assert not again.result().accepted


# -- cancel and abort -----------------------------------------------------------------------------------


def test_cancel_is_refused_by_default_as_in_rclpy(bus: Bus) -> None:
    _, client, _ = client_and_server()
    handle = send(bus, client, 0.3)
    cancel = handle.cancel_goal_async()
    advance(bus, 2)
    assert cancel.result().return_code == CancelGoal.Response.ERROR_REJECTED
    assert cancel.result().goals_canceling == []
    assert handle.get_result(timeout_sec=1.0).status == GoalStatus.STATUS_SUCCEEDED


def test_an_accepted_cancel_ends_the_goal_canceled(bus: Bus) -> None:
    _, client, _ = client_and_server(cancel_callback=accept)
    handle = send(bus, client, 0.5)
    result = handle.get_result_async()
    advance(bus, 120)
    cancel = handle.cancel_goal_async()
    advance(bus, 2)
    assert cancel.result().return_code == CancelGoal.Response.ERROR_NONE
    assert [bytes(g.goal_id.uuid) for g in cancel.result().goals_canceling] == [bytes(handle.goal_id.uuid)]
    assert handle.status == GoalStatus.STATUS_CANCELING
    advance(bus, 100)  # the generator sees the request at its next step
    assert result.result().status == GoalStatus.STATUS_CANCELED
    assert result.result().result.delta == 3.0  # what the callback returned when it stopped
    again = handle.cancel_goal_async()
    advance(bus, 2)
    assert again.result().return_code == CancelGoal.Response.ERROR_GOAL_TERMINATED


def test_cancel_by_id_by_time_and_all(bus: Bus) -> None:
    _, client, _ = client_and_server(cancel_callback=accept)
    goals = [send(bus, client, 1.0) for _ in range(3)]
    unknown = CancelGoal.Request()
    unknown.goal_info.goal_id.uuid = [7] * 16
    by_id = client._cancel_client.call_async(unknown)
    advance(bus, 2)
    assert by_id.result().return_code == CancelGoal.Response.ERROR_UNKNOWN_GOAL_ID
    up_to_second = CancelGoal.Request()
    up_to_second.goal_info.stamp = goals[1].stamp  # every goal accepted at or before it
    by_time = client._cancel_client.call_async(up_to_second)
    advance(bus, 2)
    assert {bytes(g.goal_id.uuid) for g in by_time.result().goals_canceling} == {
        bytes(g.goal_id.uuid) for g in goals[:2]
    }
    everything = client._cancel_client.call_async(CancelGoal.Request())  # no id, no stamp: all
    advance(bus, 2)
    assert [bytes(g.goal_id.uuid) for g in everything.result().goals_canceling] == [bytes(goals[2].goal_id.uuid)]
    advance(bus, 120)
    assert [g.get_result(timeout_sec=1.0).status for g in goals] == [GoalStatus.STATUS_CANCELED] * 3


def test_abort_and_a_callback_that_ends_without_a_state(bus: Bus, capsys: pytest.CaptureFixture[str]) -> None:
    def abort(goal: Any) -> Any:
        goal.abort(Result(delta=-1.0))

    def forgets(goal: Any) -> Any:
        yield
        return Result(delta=2.0)

    node = ros.Node("n")
    ros.ActionServer(node, RotateAbsolute, "abort", abort)
    ros.ActionServer(node, RotateAbsolute, "forgets", forgets)
    answers = []
    for name in ("abort", "forgets"):
        client = ros.ActionClient(node, RotateAbsolute, name)
        sent = client.send_goal_async(Goal())
        ros.spin_until_future_complete(node, sent)
        answers.append(sent.result().get_result(timeout_sec=1.0))
    assert [(a.status, a.result.delta) for a in answers] == [(6, -1.0), (6, 2.0)]
    assert "Goal state not set, assuming aborted. Goal ID: " in capsys.readouterr().err


def test_moves_the_goal_state_machine_refuses(bus: Bus) -> None:
    handles: list[Any] = []
    _, client, _ = client_and_server(None, handle_accepted_callback=handles.append)
    send(bus, client, 1.0)
    (goal,) = handles
    assert goal.status == GoalStatus.STATUS_ACCEPTED and goal.is_active
    with pytest.raises(InvalidTransition, match="cannot succeed a goal that is ACCEPTED: execute"):
        goal.succeed()
    goal.execute()
    with pytest.raises(
        InvalidTransition, match=r"cannot end as canceled a goal that is EXECUTING: canceled\(\) ends a goal"
    ):
        goal.canceled()
    goal.succeed(Result(delta=0.5))
    with pytest.raises(InvalidTransition, match="SUCCEEDED: it has finished already"):
        goal.abort()
    with pytest.raises(TypeError, match=r"succeed\(\) takes a turtlesim/action/RotateAbsolute_Result"):
        goal.succeed(Feedback())
    with pytest.raises(TypeError, match=r"publish_feedback\(\) on action /count: expected a turtlesim/action/"):
        goal.publish_feedback(Result())


def test_an_exception_in_the_execute_callback_aborts_the_goal_and_ends_the_spin(bus: Bus) -> None:
    def broken(goal: Any) -> Any:
        yield 0.05
        raise ZeroDivisionError("the callback's own bug")

    _, client, _ = client_and_server(broken)
    handle = send(bus, client, 1.0)
    result = handle.get_result_async()
    with pytest.raises(ZeroDivisionError, match="own bug"):
        advance(bus, 100)
    advance(bus, 2)
    assert result.result().status == GoalStatus.STATUS_ABORTED


@pytest.mark.parametrize(
    ("yielded", "error"),
    [("text", "yields nothing, a number of seconds or a future"), (float("inf"), "cannot pause forever")],
)
def test_a_callback_yielding_nonsense_hears_of_it_where_it_yielded(bus: Bus, yielded: Any, error: str) -> None:
    seen: list[str] = []

    def execute(goal: Any) -> Any:
        try:
            yield yielded
        except (TypeError, ValueError) as e:
            seen.append(str(e))
        goal.succeed()
        return Result()

    _, client, _ = client_and_server(execute)
    handle = send(bus, client, 1.0)
    advance(bus, 3)
    assert error in seen[0] and handle.get_result(timeout_sec=1.0).status == GoalStatus.STATUS_SUCCEEDED


# -- a machine is the execution: the PULL form ------------------------------------------------------------


def test_goals_wait_in_take_for_a_machine_to_execute_them(bus: Bus) -> None:
    _, client, server = client_and_server(None, cancel_callback=accept)
    assert server.take() is None and server.waiting == 0
    first, second = send(bus, client, 1.0), send(bus, client, 2.0)
    assert server.waiting == 2 and first.status == GoalStatus.STATUS_ACCEPTED
    goal = server.take()
    assert goal is not None and goal.request.theta == 1.0 and goal.status == GoalStatus.STATUS_EXECUTING
    feedback: list[Any] = []
    client._feedback_callbacks[bytes(first.goal_id.uuid)] = feedback.append
    goal.publish_feedback(Feedback(remaining=0.5))
    advance(bus, 2)
    assert [m.feedback.remaining for m in feedback] == [0.5] and first.status == GoalStatus.STATUS_EXECUTING
    goal.succeed(Result(delta=-1.0))
    assert first.get_result(timeout_sec=1.0).result.delta == -1.0
    second.cancel_goal_async()  # canceled while it waits: the machine still takes it, to end it
    advance(bus, 2)
    waiting = server.take()
    assert waiting is not None and waiting.is_cancel_requested
    waiting.canceled()
    assert second.get_result(timeout_sec=1.0).status == GoalStatus.STATUS_CANCELED
    assert server.take() is None


# -- servers that are not there, or go away ------------------------------------------------------------------


def test_no_server_never_hangs(bus: Bus) -> None:
    node = ros.Node("lonely")
    client = ros.ActionClient(node, RotateAbsolute, "nobody")
    assert not client.server_is_ready()
    start = bus.clock.now
    assert not client.wait_for_server(timeout_sec=1.5)
    assert bus.clock.now - start == 1_500 * MS
    assert not client.wait_for_server()  # in process, nothing could make one while we wait
    sent = client.send_goal_async(Goal())
    assert ros.spin_until_future_complete(node, sent, timeout_sec=10.0) is ros.FutureReturnCode.TIMEOUT
    assert bus.clock.now - start == 1_500 * MS  # at once


def test_a_server_destroyed_mid_goal_aborts_it(bus: Bus) -> None:
    node, client, server = client_and_server()
    handle = send(bus, client, 1.0)
    result = handle.get_result_async()
    advance(bus, 50)
    server.destroy()
    advance(bus, 2)
    assert result.result().status == GoalStatus.STATUS_ABORTED
    assert not client.server_is_ready()
    late = client.send_goal_async(Goal())
    assert ros.spin_until_future_complete(node, late) is ros.FutureReturnCode.TIMEOUT
    assert "/count/_action/send_goal" not in bus.services
    again = ros.ActionServer(node, RotateAbsolute, "count", counting)  # the name is free again
    assert client.server_is_ready()
    again.destroy()


def test_destroy_node_ends_the_goals_and_takes_the_endpoints_down(bus: Bus) -> None:
    node, client, _ = client_and_server()
    handle = send(bus, client, 1.0)
    result = handle.get_result_async()
    watcher = ros.Node("watcher")
    watch = ros.ActionClient(watcher, RotateAbsolute, "/count")
    watched = send(bus, watch, 1.0).get_result_async()
    advance(bus, 2)  # both result requests are with the server
    node.destroy_node()
    assert not any(name.startswith("/count/") for name in bus.services)
    assert not watch.server_is_ready()
    advance(bus, 2)
    assert result.result().status == watched.result().status == GoalStatus.STATUS_ABORTED


def test_results_are_forgotten_after_the_result_timeout(bus: Bus) -> None:
    _, client, _ = client_and_server(result_timeout=2)
    handle = send(bus, client, 0.1)
    assert handle.get_result(timeout_sec=1.0).status == GoalStatus.STATUS_SUCCEEDED
    advance(bus, 1_500)
    assert handle.get_result(timeout_sec=1.0).status == GoalStatus.STATUS_SUCCEEDED  # still kept
    advance(bus, 1_000)
    send(bus, client, 0.1)  # requests are where the server forgets
    assert handle.get_result(timeout_sec=1.0).status == GoalStatus.STATUS_UNKNOWN


def test_one_server_per_action_and_bad_arguments(bus: Bus) -> None:
    node, _, _ = client_and_server()
    with pytest.raises(ValueError, match="action /count already has a server"):
        ros.ActionServer(node, RotateAbsolute, "count", counting)
    with pytest.raises(TypeError, match="action_type must be an action class"):
        ros.ActionClient(node, Twist, "x")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="action_type must be an action class"):
        ros.ActionServer(node, Trigger, "x", counting)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="execute_callback must be callable"):
        ros.ActionServer(node, RotateAbsolute, "x", "not a function")  # type: ignore[arg-type]
    with pytest.raises(ros.InvalidNameError):
        ros.ActionClient(node, RotateAbsolute, "bad name")
    client = ros.ActionClient(node, RotateAbsolute, "count")
    with pytest.raises(TypeError, match="expected a turtlesim/action/RotateAbsolute_Goal, got turtlesim/action/"):
        client.send_goal_async(Result())  # type: ignore[arg-type]


def test_names_follow_the_node_namespace_and_remapping(bus: Bus) -> None:
    bus.remaps = [ros.Remap.parse("/robot/spin:=/robot/turn")]
    node = ros.Node("n", namespace="robot")
    server = ros.ActionServer(node, RotateAbsolute, "spin", counting)
    assert server.action_name == "/robot/turn"
    assert "/robot/turn/_action/send_goal" in bus.services
    topics = set(bus.topics)
    assert {"/robot/turn/_action/feedback", "/robot/turn/_action/status"} <= topics
    assert ros.ActionClient(node, RotateAbsolute, "~/x").action_name == "/robot/n/x"


def test_the_status_array_lists_unfinished_goals_and_the_recent_finished_ones(bus: Bus) -> None:
    """Every goal not finished is listed; of the finished ones the latest STATUS_FINISHED only
    (their results stay available for the result timeout)."""
    from llfsm.ros.action.server import STATUS_FINISHED

    node, client, server = client_and_server(None)  # the PULL form: the test takes the goals
    statuses: list[Any] = []
    node.create_subscription(GoalStatusArray, "/count/_action/status", statuses.append, 100)
    finished = [send(bus, client, 0.0) for _ in range(STATUS_FINISHED + 6)]
    while (taken := server.take()) is not None:
        taken.succeed()
    waiting = send(bus, client, 1.0)
    advance(bus, 2)
    listed = [(bytes(s.goal_info.goal_id.uuid), s.status) for s in statuses[-1].status_list]
    assert (bytes(waiting.goal_id.uuid), GoalStatus.STATUS_ACCEPTED) in listed
    assert len(listed) == STATUS_FINISHED + 1
    assert {i for i, _ in listed[1:]} == {bytes(h.goal_id.uuid) for h in finished[-STATUS_FINISHED:]}
    assert finished[0].get_result(timeout_sec=1.0).status == GoalStatus.STATUS_SUCCEEDED  # still kept
