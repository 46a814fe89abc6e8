"""What a client can cost an action server, in process (SPEC §18, docs/actions.md "Bounds"):
a bounded number of unfinished goals, and one status array per executor turn however many goals
the turn moved.  A cancel-all from an rclpy peer beside a 10 Hz machine over DDS:
tests/interop/test_actions_hostile.py."""

from __future__ import annotations

import struct
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from llfsm import ros
from llfsm.msgs import _dds
from llfsm.msgs.action_msgs.msg import GoalStatus, GoalStatusArray
from llfsm.msgs.action_msgs.srv import CancelGoal
from llfsm.msgs.turtlesim.action import RotateAbsolute
from llfsm.ros.action.client import status_entries, statuses_of
from llfsm.ros.action.server import MAX_GOALS
from llfsm.ros.bus import Bus

MS = 1_000_000


def turn(bus: Bus, n: int = 1) -> None:
    """n rounds of 1 ms, each followed by the executor's turn, as the scheduler runs them."""
    for _ in range(n):
        bus.clock.now += MS
        bus.spin_some()


def pull_server(**kw: Any) -> tuple[ros.Node, ros.ActionClient, ros.ActionServer, list[Any]]:
    """A PULL-form server (a machine would take its goals one at a time), cancels accepted, a
    client, and every status array published, in order."""
    node = ros.Node("bounds")
    server = ros.ActionServer(
        node, RotateAbsolute, "turn", None, cancel_callback=lambda _h: ros.CancelResponse.ACCEPT, **kw
    )
    client = ros.ActionClient(node, RotateAbsolute, "turn")
    arrays: list[Any] = []
    node.create_subscription(GoalStatusArray, "/turn/_action/status", arrays.append, 100_000)
    return node, client, server, arrays


def send_many(bus: Bus, client: ros.ActionClient, n: int) -> list[Any]:
    futures = [client.send_goal_async(RotateAbsolute.Goal(theta=float(i))) for i in range(n)]
    turn(bus, 2)
    assert all(f.done() for f in futures)
    return [f.result() for f in futures]


def test_goals_past_the_limit_are_rejected_with_one_warning(bus: Bus, capsys: pytest.CaptureFixture[str]) -> None:
    _, client, server, _ = pull_server(max_goals=3)
    handles = send_many(bus, client, 5)
    assert [h.accepted for h in handles] == [True, True, True, False, False]
    assert server.waiting == 3
    err = capsys.readouterr().err
    assert err.count("holds 3 unfinished goals, the most it keeps (ActionServer(max_goals=3))") == 1, err
    # a goal that finishes makes room for one more
    taken = server.take()
    assert taken is not None
    taken.succeed()
    turn(bus)
    assert [h.accepted for h in send_many(bus, client, 2)] == [True, False]
    assert "unfinished goals" not in capsys.readouterr().err  # said once


def test_the_default_limit_holds_a_thousand_goals(bus: Bus) -> None:
    _, client, _server, arrays = pull_server()
    handles = send_many(bus, client, MAX_GOALS + 2)
    assert sum(h.accepted for h in handles) == MAX_GOALS == 1000 and not handles[-1].accepted
    assert len(arrays[-1].status_list) == MAX_GOALS


@pytest.mark.parametrize("bad", [0, -1, 2.5, True])
def test_max_goals_must_be_a_positive_integer(bus: Bus, bad: Any) -> None:
    with pytest.raises(ValueError, match="max_goals must be an integer >= 1"):
        pull_server(max_goals=bad)


def test_goals_of_one_turn_and_a_cancel_of_all_publish_one_status_array_each(bus: Bus) -> None:
    """rcl_action publishes the whole array on every goal event: a cancel of n goals was n
    arrays of up to n entries (990 goals stalled a run 3.4 s).  Now a turn publishes once."""
    _, client, server, arrays = pull_server()
    send_many(bus, client, 200)
    assert len(arrays) == 1 and len(arrays[0].status_list) == 200  # 200 requests in one turn
    arrays.clear()
    everything = client._cancel_client.call_async(CancelGoal.Request())
    turn(bus, 2)
    assert len(everything.result().goals_canceling) == 200
    assert len(arrays) == 1
    assert {s.status for s in arrays[0].status_list} == {GoalStatus.STATUS_CANCELING}
    arrays.clear()
    # a machine ends the canceled goals, one per ringlet: one array per round at most
    for _ in range(3):
        goal = server.take()
        assert goal is not None and goal.is_cancel_requested
        goal.canceled()
    turn(bus, 2)  # published at the end of the first turn, delivered in the second
    assert len(arrays) == 1
    assert sum(s.status == GoalStatus.STATUS_CANCELED for s in arrays[0].status_list) == 3


def test_the_array_after_a_turn_is_the_state_at_its_end(bus: Bus) -> None:
    """Coalescing never loses a change: the last array of a turn is the state after it."""
    _, client, server, arrays = pull_server()
    (handle,) = send_many(bus, client, 1)
    goal = server.take()
    assert goal is not None
    goal.succeed()  # executing then succeeded within one round
    turn(bus, 2)
    assert [(bytes(s.goal_info.goal_id.uuid), s.status) for s in arrays[-1].status_list] == [
        (bytes(handle.goal_id.uuid), GoalStatus.STATUS_SUCCEEDED)
    ]


# -- what a client reads of a peer's status array and feedback -----------------------------------


@settings(deadline=None, max_examples=50)  # the first example builds the codec
@given(
    st.lists(
        st.tuples(st.binary(min_size=16, max_size=16), st.integers(-128, 127), st.integers(0, 2**31 - 1)), max_size=40
    )
)
def test_status_entries_reads_what_the_codec_wrote(entries: list[tuple[bytes, int, int]]) -> None:
    array = GoalStatusArray()
    for goal_id, value, sec in entries:
        entry = GoalStatus(status=value)
        entry.goal_info.goal_id.uuid = list(goal_id)
        entry.goal_info.stamp.sec, entry.goal_info.stamp.nanosec = sec, sec % 10**9
        array.status_list.append(entry)
    payload = _dds.codec(GoalStatusArray).cdr(array)
    assert list(status_entries(payload)) == [(goal_id, value) for goal_id, value, _ in entries]


@pytest.mark.parametrize(
    "payload",
    [b"", b"\0\1\0\0", b"\0\1\0\0" + struct.pack("<I", 1_000_000) + bytes(40), b"\0\x03\0\0" + bytes(8)],
    ids=["empty", "no length", "declares a million entries", "not plain CDR"],
)
def test_status_entries_refuses_what_is_not_an_array(payload: bytes) -> None:
    with pytest.raises(ValueError):
        list(status_entries(payload))


def test_a_status_that_names_no_goal_state_is_ignored(bus: Bus) -> None:
    """A peer's status array may say anything: 99 for a goal is no state it can be in."""
    node, client, server, _ = pull_server()
    (handle,) = send_many(bus, client, 1)
    spoof = node.create_publisher(GoalStatusArray, "/turn/_action/status", 10)
    entry = GoalStatus(status=99)
    entry.goal_info.goal_id = handle.goal_id
    spoof.publish(GoalStatusArray(status_list=[entry]))
    turn(bus, 2)
    assert handle.status == GoalStatus.STATUS_ACCEPTED
    goal = server.take()
    assert goal is not None
    goal.succeed()
    turn(bus, 3)
    assert handle.status == GoalStatus.STATUS_SUCCEEDED


@settings(deadline=None, max_examples=50)
@given(
    st.lists(st.tuples(st.binary(min_size=16, max_size=16), st.integers(-128, 127)), max_size=30),
    st.lists(st.binary(min_size=16, max_size=16), max_size=12),
    st.randoms(use_true_random=False),
)
def test_statuses_of_finds_the_goals_asked_for(entries: list[tuple[bytes, int]], others: list[bytes], rnd: Any) -> None:
    """Searched for (a few goals) or read entry by entry (many), the same answer: the first
    entry of each goal asked for, never bytes that only look like an id (inside a stamp)."""
    array = GoalStatusArray()
    for goal_id, value in entries:
        entry = GoalStatus(status=value)
        entry.goal_info.goal_id.uuid = list(goal_id)
        stamp = int.from_bytes(rnd.choice([goal_id, *others, bytes(16)])[:8], "little")  # ids hidden in stamps
        entry.goal_info.stamp.sec, entry.goal_info.stamp.nanosec = stamp % 2**31, (stamp >> 32) % 10**9
        array.status_list.append(entry)
    payload = _dds.codec(GoalStatusArray).cdr(array)
    wanted = {goal_id for goal_id, _ in rnd.sample(entries, min(len(entries), 3))} | set(others)
    first: dict[bytes, int] = {}
    for goal_id, value in entries:
        first.setdefault(goal_id, value)
    expected = {g: v for g, v in first.items() if g in wanted}
    assert dict(statuses_of(payload, wanted)) == expected
    many = wanted | {bytes([i]) * 16 for i in range(10)}  # past the searched number: one pass
    assert dict(statuses_of(payload, many)) == {g: v for g, v in first.items() if g in many}


def test_statuses_of_skips_an_id_that_straddles_entries() -> None:
    """The id asked for, spelt by the end of one entry's id and its stamp, is no entry."""
    wanted = bytes(range(16))
    decoy, real = GoalStatus(status=2), GoalStatus(status=5)
    decoy.goal_info.goal_id.uuid = [0] * 8 + list(wanted[:8])
    decoy.goal_info.stamp.sec = int.from_bytes(wanted[8:12], "little")
    decoy.goal_info.stamp.nanosec = int.from_bytes(wanted[12:16], "little")
    real.goal_info.goal_id.uuid = list(wanted)
    payload = _dds.codec(GoalStatusArray).cdr(GoalStatusArray(status_list=[decoy, real]))
    assert payload.find(wanted) < payload.rfind(wanted)  # there it is, twice
    assert statuses_of(payload, {wanted}) == [(wanted, 5)]
