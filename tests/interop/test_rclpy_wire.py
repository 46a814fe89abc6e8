"""llfsm's DDS forms against real ROS 2 (rclpy and rosidl from PyPI wheels in .venv-ros):
CDR bytes equal to rclpy's serialize_message, and RIHS01 type hashes equal to the ones rosidl
generated into the wheels' share/<pkg>/<msg|srv|action>/<Name>.json (actions' derived types too)."""

from __future__ import annotations

import importlib
import json
import random
import shutil
from pathlib import Path
from typing import Any

import pytest
from samples import sample, shipped_classes

from interop.ros2env import VENV_ROS, requires_ros
from llfsm.msgs import _dds
from llfsm.msgs._message import Message, is_action_class, is_message_class, is_service_class

pytestmark = [pytest.mark.interop, requires_ros]

SHARE = VENV_ROS / "share"
# Packages both llfsm and the wheels have (turtlesim has no wheel on PyPI).
COMMON = (
    "builtin_interfaces",
    "std_msgs",
    "geometry_msgs",
    "std_srvs",
    "rmw_dds_common",
    "service_msgs",
    "sensor_msgs",
    "nav_msgs",
    "rcl_interfaces",
    "action_msgs",
    "unique_identifier_msgs",
)

# Runs in .venv-ros: reads {ros type: [payload hex]} on stdin; for each payload, rclpy
# deserializes it into its own message class and serializes that again.  Also serializes the
# messages rclpy itself builds in BUILT below.
_RCLPY_ROUND_TRIP = r"""
import importlib, json, sys
from rclpy.serialization import deserialize_message, serialize_message
from geometry_msgs.msg import Twist, PolygonStamped, Point32
from std_msgs.msg import String, Empty, Header
from std_srvs.srv import SetBool, Trigger

# an action's types by the suffix rosidl gives them: (attribute path from the action class)
ACTION_PARTS = {"Goal": "Goal", "Result": "Result", "Feedback": "Feedback",
                "SendGoal_Request": "Impl.SendGoalService.Request",
                "SendGoal_Response": "Impl.SendGoalService.Response",
                "GetResult_Request": "Impl.GetResultService.Request",
                "GetResult_Response": "Impl.GetResultService.Response", "FeedbackMessage": "Impl.FeedbackMessage"}

def cls_of(t):
    pkg, kind, name = t.split("/")
    module = importlib.import_module(f"{pkg}.{kind}")
    if kind == "srv":
        base, _, part = name.rpartition("_")
        return getattr(getattr(module, base), part)
    if kind == "action":
        for suffix, path in ACTION_PARTS.items():
            if name.endswith("_" + suffix):
                obj = getattr(module, name[: -len(suffix) - 1])
                for attr in path.split("."):
                    obj = getattr(obj, attr)
                return obj
    return getattr(module, name)

out = {"round_trip": {}, "built": {}, "default": {}}
for t, payloads in json.load(sys.stdin).items():
    cls = cls_of(t)
    results = []
    for p in payloads:
        try:
            results.append(serialize_message(deserialize_message(bytes.fromhex(p), cls)).hex())
        except Exception as e:
            results.append(f"rclpy cannot read it: {e}")
    out["round_trip"][t] = results
    out["default"][t] = serialize_message(cls()).hex()

twist = Twist()
twist.linear.x, twist.angular.z = 2.0, -1.5
poly = PolygonStamped()
poly.header.frame_id, poly.header.stamp.sec = "base_link", 12
poly.polygon.points = [Point32(x=1.0, y=-2.5, z=0.25), Point32(x=3.0)]
built = {
    "String/hi": String(data="hi"),
    "String/empty": String(data=""),
    "String/unicode": String(data="ünï ✓"),
    "Empty": Empty(),
    "Twist": twist,
    "PolygonStamped": poly,
    "SetBool_Request": SetBool.Request(data=True),
    "SetBool_Response": SetBool.Response(success=True, message="done"),
    "Trigger_Request": Trigger.Request(),
}
out["built"] = {k: serialize_message(v).hex() for k, v in built.items()}
print(json.dumps(out))
"""


def _same_payload(ours: bytes, theirs: bytes) -> bool:
    """Byte for byte equal, but for padding.  rclpy (Fast CDR) leaves alignment gaps as its
    buffer held them, where llfsm writes zeros; and its length is the size it computed
    beforehand, which counts an alignment gap before every empty sequence of 8-byte values that
    the writing itself skips: up to a few bytes of stale tail (readers ignore it)."""
    if ours == theirs:
        return True
    if not len(ours) <= len(theirs) <= len(ours) + 64 + len(ours) // 4:
        return False
    return all(a == b or a == 0 for a, b in zip(ours, theirs, strict=False))


def _rclpy(payloads: dict[str, list[str]]) -> dict[str, Any]:
    import subprocess

    from interop.ros2env import ros_command

    argv, env = ros_command(_RCLPY_ROUND_TRIP)
    r = subprocess.run(argv, env=env, input=json.dumps(payloads), capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


@pytest.fixture(scope="module")
def test_msgs_package(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """ROS 2's own test_msgs definitions (arrays fixed/bounded/unbounded of every primitive,
    strings, bounded strings, wstrings, nested and multi-nested messages, defaults), copied as a
    user's package and compiled by llfsm's interface compiler."""
    root = tmp_path_factory.mktemp("interfaces")
    for kind in ("msg", "srv", "action"):
        (root / "test_msgs" / kind).mkdir(parents=True)
        for f in sorted((SHARE / "test_msgs" / kind).glob(f"*.{kind}")):
            shutil.copy(f, root / "test_msgs" / kind / f.name)
    return root


@pytest.fixture
def user_interfaces(test_msgs_package: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("LLFSM_INTERFACE_PATH", str(test_msgs_package))
    return test_msgs_package


def _test_msgs_classes() -> list[type[Message]]:
    out = []
    for kind in ("msg", "srv", "action"):
        module = importlib.import_module(f"llfsm.msgs.test_msgs.{kind}")
        out += [o for o in vars(module).values() if is_message_class(o) and o.__module__ == module.__name__]
    return out


def test_cdr_equals_rclpy_serialize_message(user_interfaces: Path) -> None:
    """Every shipped class that the wheels also have, and every test_msgs message compiled by
    llfsm: rclpy reads llfsm's payload and writes the same bytes back; and messages built the
    same way on both sides serialize to the same bytes."""
    from llfsm.msgs.geometry_msgs.msg import Point32, PolygonStamped, Twist
    from llfsm.msgs.std_msgs.msg import Empty, String
    from llfsm.msgs.std_srvs.srv import SetBool, Trigger

    classes = [c for c in shipped_classes() if c._TYPE.split("/")[0] in COMMON] + _test_msgs_classes()
    assert len(classes) > 70
    wanted = {"test_msgs/action/Fibonacci_SendGoal_Request", "action_msgs/msg/GoalStatusArray"}
    assert wanted <= {c._TYPE for c in classes}
    messages: dict[str, list[Message]] = {}
    for cls in classes:
        rng = random.Random(cls._TYPE)
        messages[cls._TYPE] = [cls()] + [sample(cls, rng) for _ in range(4)]
    result = _rclpy({t: [_dds.cdr(m).hex() for m in msgs] for t, msgs in messages.items()})

    bad = []
    for t, msgs in messages.items():
        default = bytes.fromhex(result["default"][t])
        if not _same_payload(_dds.cdr(msgs[0]), default):
            bad.append(f"{t} default: llfsm {_dds.cdr(msgs[0]).hex()} rclpy {default.hex()}")
        for msg, theirs in zip(msgs, result["round_trip"][t], strict=True):
            mine = _dds.cdr(msg)
            if theirs.startswith("rclpy") or not _same_payload(mine, bytes.fromhex(theirs)):
                bad.append(f"{t}: llfsm {mine.hex()} rclpy {theirs}")
            elif _dds.from_cdr(bytes.fromhex(theirs), type(msg)) != msg:  # rclpy read what we wrote
                bad.append(f"{t}: rclpy read other values from {mine.hex()}")
    assert not bad, f"{len(bad)} differ:\n" + "\n".join(bad[:8])

    twist = Twist()
    twist.linear.x, twist.angular.z = 2.0, -1.5
    poly = PolygonStamped()
    poly.header.frame_id, poly.header.stamp.sec = "base_link", 12
    poly.polygon.points = [Point32(x=1.0, y=-2.5, z=0.25), Point32(x=3.0)]
    built = {
        "String/hi": String(data="hi"),
        "String/empty": String(data=""),
        "String/unicode": String(data="ünï ✓"),
        "Empty": Empty(),
        "Twist": twist,
        "PolygonStamped": poly,
        "SetBool_Request": SetBool.Request(data=True),
        "SetBool_Response": SetBool.Response(success=True, message="done"),
        "Trigger_Request": Trigger.Request(),
    }
    for key, msg in built.items():
        theirs = bytes.fromhex(result["built"][key])
        assert _same_payload(_dds.cdr(msg), theirs), (key, _dds.cdr(msg).hex(), theirs.hex())
        assert _dds.from_cdr(theirs, type(msg)) == msg


def _wheel_hashes(package: str) -> dict[str, str]:
    hashes = {}
    for kind in ("msg", "srv", "action"):
        for f in sorted((SHARE / package / kind).glob("*.json")):
            data = json.loads(f.read_text())
            hashes.update({h["type_name"]: h["hash_string"] for h in data["type_hashes"]})
    return hashes


def _llfsm_class(type_name: str) -> Any:
    pkg, kind, name = type_name.split("/")
    module = importlib.import_module(f"llfsm.msgs.{pkg}.{kind}")
    return getattr(module, name, None)


def test_type_hashes_equal_rosidl(user_interfaces: Path) -> None:
    """RIHS01 hashes of llfsm's classes equal the ones rosidl computed for the same types:
    the standard packages (llfsm's definitions come from rosbags' Humble store, the wheels'
    from the current release) and ROS 2's test_msgs compiled as a user package."""
    checked, bad, actions = 0, [], 0
    for package in (*COMMON, "test_msgs"):
        for type_name, expected in _wheel_hashes(package).items():
            if not type_name.startswith(f"{package}/") or type_name.endswith("_Event"):
                continue  # referenced types are checked in their own package; events have no class
            cls = _llfsm_class(type_name)
            if cls is None:
                # Types newer than Humble (geometry_msgs/PolygonInstance, VelocityStamped) and
                # test_msgs' IDL-only keyed types have no llfsm class.
                continue
            assert is_message_class(cls) or is_service_class(cls) or is_action_class(cls)
            if _dds.type_hash(cls) != expected:
                bad.append(f"{type_name}: llfsm {_dds.type_hash(cls)} rosidl {expected}")
            checked += 1
            actions += "/action/" in type_name
    assert not bad, "\n".join(bad)
    assert checked > 90
    assert actions >= 22  # test_msgs' Fibonacci and NestedMessage: the action and its 10 types each
