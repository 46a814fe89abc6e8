"""The base of every message and service class (the contract between the bus and the generated
message modules under llfsm/msgs/<pkg>/msg|srv/).

Generated classes mirror rclpy's: `Twist()` builds with defaults, fields are typed properties
(`msg.linear.x = 2` stores 2.0; `msg.linear.x = "fast"` raises TypeError), nested messages are
built fresh for each instance.  They also provide `_copy()`, a fast deep copy the bus takes at
publish time, so that a machine may keep mutating and re-publishing one message object, as the
seed machines do, without changing what subscribers already received.
"""

from __future__ import annotations

from typing import Any, ClassVar


class Message:
    """Base of generated message classes.  Subclasses define, as class attributes:

    _TYPE    "geometry_msgs/msg/Twist"
    _FIELDS  (("linear", "geometry_msgs/msg/Vector3"), ("angular", "geometry_msgs/msg/Vector3"))
             ROS field types: bool, byte, char, int8..uint64, float32, float64, string,
             wstring, pkg/msg/Name, and arrays of them: "float64[]", "uint8[3]", "string<=10"...
    __slots__ the private storage of each field ("_linear", "_angular")
    and a property per field, `__init__(**fields)`, `_copy()`.
    """

    __slots__ = ()
    _TYPE: ClassVar[str] = ""
    _FIELDS: ClassVar[tuple[tuple[str, str], ...]] = ()

    def _copy(self) -> Message:  # generated classes override this with a field-by-field copy
        raise NotImplementedError

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return all(getattr(self, f) == getattr(other, f) for f, _ in self._FIELDS)

    __hash__ = None  # type: ignore[assignment]  # mutable, like rclpy messages

    def __repr__(self) -> str:
        args = ", ".join(f"{f}={getattr(self, f)!r}" for f, _ in self._FIELDS)
        return f"{self._TYPE.replace('/', '.')}({args})"

    def to_dict(self) -> dict[str, Any]:
        """Plain data (nested dicts and lists), in field order: for `--echo` and tests."""
        return {f: _plain(getattr(self, f)) for f, _ in self._FIELDS}


def _plain(v: Any) -> Any:
    if isinstance(v, Message):
        return v.to_dict()
    if isinstance(v, list | tuple):
        return [_plain(x) for x in v]
    if isinstance(v, bytes | bytearray):
        return list(v)
    return v


class Service:
    """Base of generated service classes: `Spawn.Request`, `Spawn.Response`, `Spawn._TYPE`."""

    _TYPE: ClassVar[str] = ""
    Request: ClassVar[type[Message]]
    Response: ClassVar[type[Message]]


def is_message_class(obj: object) -> bool:
    return isinstance(obj, type) and issubclass(obj, Message) and obj is not Message


def is_service_class(obj: object) -> bool:
    return isinstance(obj, type) and issubclass(obj, Service) and obj is not Service
