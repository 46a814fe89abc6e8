""".action interfaces (llfsm.idl, llfsm.msgs): the shipped RotateAbsolute, action_msgs and
unique_identifier_msgs, users' PKG/action/X.action through the import hook, the types rosidl
derives (X_SendGoal, X_GetResult, X_FeedbackMessage) and their DDS forms.  rclpy's bytes and
rosidl's type hashes for the same types are compared in tests/interop/test_rclpy_wire.py."""

from __future__ import annotations

import importlib
import sys
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType

import pytest

import llfsm.msgs
from llfsm import interface_path
from llfsm.idl import parser
from llfsm.idl.spec import InterfaceError
from llfsm.msgs import _dds
from llfsm.msgs._message import is_action_class, is_message_class, is_service_class
from llfsm.msgs.action_msgs.msg import GoalInfo, GoalStatus, GoalStatusArray
from llfsm.msgs.action_msgs.srv import CancelGoal
from llfsm.msgs.turtlesim.action import RotateAbsolute
from llfsm.msgs.unique_identifier_msgs.msg import UUID

COUNT_ACTION = """\
# count up to a number, one step a second
int32 target
geometry_msgs/Point where
---
Step[] steps
---
int32 current  # the count so far
"""


def _forget(package: str) -> None:
    for mod in [m for m in sys.modules if m == f"llfsm.msgs.{package}" or m.startswith(f"llfsm.msgs.{package}.")]:
        del sys.modules[mod]


@pytest.fixture(scope="module")
def user_actions(tmp_path_factory: pytest.TempPathFactory) -> Iterator[ModuleType]:
    """llfsm.msgs.llfsm_action_pkg: msg Step, action Count (Goal uses another package's message,
    Result an array of its own package's)."""
    root = tmp_path_factory.mktemp("interfaces")
    pkg = root / "llfsm_action_pkg"
    (pkg / "msg").mkdir(parents=True)
    (pkg / "action").mkdir()
    (pkg / "msg" / "Step.msg").write_text("int32 n\nstring note\n")
    (pkg / "action" / "Count.action").write_text(COUNT_ACTION)
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("LLFSM_CACHE_DIR", str(tmp_path_factory.mktemp("cache")))
        llfsm.msgs.add_search_path(root)
        try:
            yield importlib.import_module("llfsm.msgs.llfsm_action_pkg.action")
        finally:
            interface_path._added.remove(str(root))
            _forget("llfsm_action_pkg")


def test_rotate_absolute_is_shaped_as_rclpy_generates_it() -> None:
    assert is_action_class(RotateAbsolute) and not is_message_class(RotateAbsolute)
    assert RotateAbsolute._TYPE == "turtlesim/action/RotateAbsolute"
    assert RotateAbsolute.Goal._FIELDS == (("theta", "float32"),)
    assert RotateAbsolute.Result._FIELDS == (("delta", "float32"),)
    assert RotateAbsolute.Feedback._FIELDS == (("remaining", "float32"),)
    impl = RotateAbsolute.Impl
    assert is_service_class(impl.SendGoalService) and is_service_class(impl.GetResultService)
    assert impl.SendGoalService._TYPE == "turtlesim/action/RotateAbsolute_SendGoal"
    assert impl.SendGoalService.Request._FIELDS == (
        ("goal_id", "unique_identifier_msgs/msg/UUID"),
        ("goal", "turtlesim/action/RotateAbsolute_Goal"),
    )
    assert impl.SendGoalService.Response._FIELDS == (("accepted", "bool"), ("stamp", "builtin_interfaces/msg/Time"))
    assert impl.GetResultService.Request._FIELDS == (("goal_id", "unique_identifier_msgs/msg/UUID"),)
    assert impl.GetResultService.Response._FIELDS == (
        ("status", "int8"),
        ("result", "turtlesim/action/RotateAbsolute_Result"),
    )
    assert impl.FeedbackMessage._FIELDS == (
        ("goal_id", "unique_identifier_msgs/msg/UUID"),
        ("feedback", "turtlesim/action/RotateAbsolute_Feedback"),
    )
    assert impl.CancelGoalService is CancelGoal and impl.GoalStatusMessage is GoalStatusArray
    req = impl.SendGoalService.Request(goal=RotateAbsolute.Goal(theta=1.5))
    assert type(req.goal) is RotateAbsolute.Goal and req.goal.theta == 1.5 and req.goal_id.uuid == [0] * 16
    with pytest.raises(TypeError, match="RotateAbsolute_Goal"):
        req.goal = RotateAbsolute.Result()


def test_action_msgs_as_ros_ships_them() -> None:
    assert [GoalStatus.STATUS_UNKNOWN, GoalStatus.STATUS_ACCEPTED, GoalStatus.STATUS_EXECUTING] == [0, 1, 2]
    assert [GoalStatus.STATUS_CANCELING, GoalStatus.STATUS_SUCCEEDED] == [3, 4]
    assert [GoalStatus.STATUS_CANCELED, GoalStatus.STATUS_ABORTED] == [5, 6]
    assert dict(GoalInfo._FIELDS) == {
        "goal_id": "unique_identifier_msgs/msg/UUID",
        "stamp": "builtin_interfaces/msg/Time",
    }
    assert CancelGoal.Response.ERROR_GOAL_TERMINATED == 3
    assert UUID._FIELDS == (("uuid", "uint8[16]"),)
    with pytest.raises(ValueError, match="exactly 16"):
        UUID(uuid=[1, 2])


def test_dds_names_of_the_derived_types() -> None:
    impl = RotateAbsolute.Impl
    assert _dds.dds_type_name(impl.SendGoalService) == "turtlesim::action::dds_::RotateAbsolute_SendGoal_Request_"
    assert (
        _dds.response_type(impl.GetResultService).__idl_typename__
        == "turtlesim::action::dds_::RotateAbsolute_GetResult_Response_"
    )
    assert _dds.dds_type_name(impl.FeedbackMessage) == "turtlesim::action::dds_::RotateAbsolute_FeedbackMessage_"
    assert _dds.dds_type_name(CancelGoal) == "action_msgs::srv::dds_::CancelGoal_Request_"
    assert _dds.dds_type_name(GoalStatusArray) == "action_msgs::msg::dds_::GoalStatusArray_"
    assert _dds.type_hash(RotateAbsolute).startswith("RIHS01_")


def test_derived_types_round_trip_in_cdr_and_in_the_request_header() -> None:
    impl = RotateAbsolute.Impl
    req = impl.SendGoalService.Request(goal=RotateAbsolute.Goal(theta=-2.25))
    req.goal_id.uuid = list(range(16))
    data = _dds.cdr(req)
    assert data.hex() == "00010000" + bytes(range(16)).hex() + "000010c0"  # 16 id bytes, then theta -2.25f
    assert _dds.from_cdr(data, type(req)) == req
    assert _dds.unwrap(_dds.wrap(req, 7, 9), type(req)) == (7, 9, req)
    status = GoalStatusArray(status_list=[GoalStatus(status=GoalStatus.STATUS_EXECUTING)])
    status.status_list[0].goal_info.goal_id.uuid = [255] * 16
    status.status_list[0].goal_info.stamp.sec = 12
    assert _dds.from_cdr(_dds.cdr(status), GoalStatusArray) == status


def test_user_action_compiles_through_the_hook(user_actions: ModuleType) -> None:
    from llfsm.msgs.llfsm_action_pkg.action import Count
    from llfsm.msgs.llfsm_action_pkg.msg import Step

    from llfsm.msgs.geometry_msgs.msg import Point

    assert Count is user_actions.Count and is_action_class(Count)
    assert Count._TYPE == "llfsm_action_pkg/action/Count"
    goal = Count.Goal(target=3)
    assert type(goal.where) is Point and goal.target == 3
    result = Count.Result(steps=[Step(n=1, note="one")])
    assert result.steps[0].note == "one"
    assert Count.Feedback().current == 0
    request = Count.Impl.SendGoalService.Request(goal=goal)
    assert _dds.from_cdr(_dds.cdr(request), type(request)) == request
    message = Count.Impl.FeedbackMessage(feedback=Count.Feedback(current=2))
    assert _dds.from_cdr(_dds.cdr(message), type(message)).feedback.current == 2
    response = Count.Impl.GetResultService.Response(status=4, result=result)
    assert _dds.unwrap(_dds.wrap(response, 1, 2), type(response))[2] == response


def test_action_needs_two_separators() -> None:
    with pytest.raises(InterfaceError, match=r"A\.action: no '---' line between goal and result"):
        parser.parse_action("int32 a\n", "p/action/A", "A.action")
    with pytest.raises(InterfaceError, match=r"A\.action: no '---' line between result and feedback"):
        parser.parse_action("int32 a\n---\nint32 b\n", "p/action/A", "A.action")
    with pytest.raises(InterfaceError, match=r"A\.action:5: more than two"):
        parser.parse_action("---\n---\nint32 a\n\n---\n", "p/action/A", "A.action")
    a = parser.parse_action("int32 a\n---\n# r\nint32 b\n---\nint32 c\n", "p/action/A", "A.action")
    assert [f.line for part in a.parts for f in part.fields] == [1, 4, 6]
    assert a.send_goal.request.fields[1].type.base == "p/action/A_Goal"


@pytest.mark.parametrize(
    ("text", "line", "message"),
    [
        ("int32 a\n---\nNoSuch r\n---\n", 3, "unknown message type llfsm_bad_action/msg/NoSuch"),
        ("int32 a\n---\n---\nfloat64 x y\n", 4, "invalid float64 value 'y'"),
    ],
)
def test_broken_action_is_an_import_error_naming_file_and_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, text: str, line: int, message: str
) -> None:
    path = tmp_path / "llfsm_bad_action" / "action" / "Bad.action"
    path.parent.mkdir(parents=True)
    path.write_text(text)
    monkeypatch.setenv("LLFSM_INTERFACE_PATH", str(tmp_path))
    try:
        with pytest.raises(ImportError) as e:
            importlib.import_module("llfsm.msgs.llfsm_bad_action.action")
    finally:
        _forget("llfsm_bad_action")
    assert str(e.value).startswith(f"{path}:{line}: ") and message in str(e.value)
