"""LF041: rclpy spellings that llfsm does not take, each with the llfsm spelling.

Machines written for rclpy (or from the clfsm how-to) import `rclpy`, `std_msgs.msg` and the
like; llfsm has the same names under `llfsm.ros` and `llfsm.msgs`.  The front end knows those
names as lists, never by importing the bus (the front end sits below it, and `check` must stay
light); tests keep the lists in step with `llfsm.ros` (tests/test_qos.py, tests/test_check.py).
"""

from __future__ import annotations

import ast
import re

from ..model import Code
from ..positions import node_col
from .checking import Checking
from .scan import Scanned

#: Names rclpy code uses that llfsm spells otherwise (read without an import: LF040's hint).
ROS_NAMES = {
    "rclpy": "`from llfsm import ros` in Includes.py, then ros.Node(...), ros.ok()",
    "QoSPresetProfiles": "a preset such as `ros.qos_profile_sensor_data`, or `ros.QoSProfile(depth=10)`",
}
#: rclpy.qos names that `llfsm.ros` has under the same name (tests/test_qos.py keeps this in
#: step with ros.__all__; a list, so `check` never imports the bus).
ROS_QOS_NAMES = frozenset(
    {
        "QoSProfile",
        "ReliabilityPolicy",
        "HistoryPolicy",
        "DurabilityPolicy",
        "QoSReliabilityPolicy",
        "QoSHistoryPolicy",
        "QoSDurabilityPolicy",
        "qos_profile_sensor_data",
        "qos_profile_system_default",
        "qos_profile_services_default",
        "qos_profile_parameters",
        "qos_profile_parameter_events",
        "qos_profile_action_status_default",
        "qos_profile_rosout_default",
    }
)
#: The public attributes of the time `node.get_clock().now()` returns in llfsm (`llfsm.ros.Time`;
#: tests/test_check.py keeps this in step with it).  rclpy's Time has `to_msg()`; llfsm's, so
#: far, has not, and LF041 says how to make the message instead.
CLOCK_TIME_ATTRIBUTES = frozenset({"nanoseconds", "seconds_nanoseconds"})
_ROS_MESSAGE_MODULE = re.compile(r"(?P<pkg>[a-z][a-z0-9_]*)\.(?P<kind>msg|srv|action)(?:\.(?P<rest>.*))?\Z")


def ros_import_hint(module: str, stmt: ast.Import | ast.ImportFrom) -> str | None:
    """The llfsm spelling of an rclpy-style import, or None if the import is not one."""
    top = module.split(".")[0]
    if top == "rclpy":
        names = [a.name for a in stmt.names] if isinstance(stmt, ast.ImportFrom) else []
        same = [n for n in names if n in ROS_QOS_NAMES]
        if same:
            name = same[0]
            return f"`{name}` comes from rclpy, which llfsm machines do not use: `from llfsm import ros`, then `ros.{name}`"  # noqa: E501
        qos = [n for n in names if n in ROS_NAMES and n != "rclpy"]
        if qos:
            return f"`{qos[0]}` comes from rclpy, which llfsm machines do not use: pass {ROS_NAMES[qos[0]]}"
        return f"`{module}` is rclpy; llfsm machines use `from llfsm import ros` (ros.Node, ros.ok(), ...)"
    m = _ROS_MESSAGE_MODULE.match(module)
    if m is None:
        return None
    if isinstance(stmt, ast.ImportFrom):
        imported = ", ".join(a.name for a in stmt.names)
        spelled = f"from llfsm.msgs.{module} import {imported}"
    else:
        spelled = f"import llfsm.msgs.{module}"
    return f"ROS messages of {m['pkg']} come from llfsm.msgs: `{spelled}`"


def ros_habits(c: Checking, code: Code, scan: Scanned) -> None:
    """LF041 for the imports and `now().to_msg()` calls of one code file."""
    for stmt in scan.imports:
        modules = [stmt.module or ""] if isinstance(stmt, ast.ImportFrom) else [a.name for a in stmt.names]
        if isinstance(stmt, ast.ImportFrom) and stmt.level:
            continue
        for mod in modules:
            if is_helper(c, mod):
                continue
            hint = ros_import_hint(mod, stmt)
            if hint is not None:
                c.add("LF041", code.file, stmt.lineno, node_col(code.text, stmt), hint)
                break
    for attr in scan.to_msg:
        now = attr.value
        if (
            isinstance(now, ast.Call)
            and isinstance(now.func, ast.Attribute)
            and now.func.attr == "now"
            and "to_msg" not in CLOCK_TIME_ATTRIBUTES
        ):
            c.add(
                "LF041",
                code.file,
                attr.lineno,
                node_col(code.text, attr),
                "llfsm's clock time has no to_msg(): `s, ns = node.get_clock().now().seconds_nanoseconds()` "
                "then `Time(sec=s, nanosec=ns)` (from llfsm.msgs.builtin_interfaces.msg import Time)",
            )


def is_helper(c: Checking, module: str) -> bool:
    """Whether `module` names a helper module or package of the user's, beside the machine
    (where `llfsm run` lets machines import them): `my_msgs.msg` is then theirs, not ROS's."""
    top = module.split(".")[0]
    if not top.isidentifier():
        return False
    parent = c.path.parent
    return (parent / top).is_dir() or (parent / f"{top}.py").is_file()
