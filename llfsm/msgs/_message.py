"""The base of every message and service class (the contract between the bus and the generated
message modules under llfsm/msgs/<pkg>/msg|srv/).

Generated classes mirror rclpy's: `Twist()` builds with defaults, fields are typed properties
(`msg.linear.x = 2` stores 2.0; `msg.linear.x = "fast"` raises TypeError), nested messages are
built fresh for each instance.  They also provide `_copy()`, a fast deep copy the bus takes at
publish time, so that a machine may keep mutating and re-publishing one message object, as the
seed machines do, without changing what subscribers already received.
"""

from __future__ import annotations

from typing import Any, ClassVar, TypeGuard


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

    @classmethod
    def get_fields_and_field_types(cls) -> dict[str, str]:
        """rclpy's introspection call, for code ported from rclpy that walks a message."""
        return {f: rclpy_type_name(t) for f, t in cls._FIELDS}


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


class Action:
    """Base of generated action classes, as rclpy's: `RotateAbsolute.Goal`, `.Result`,
    `.Feedback`, and under `Impl` the types on the wire (`SendGoalService`, `GetResultService`,
    `FeedbackMessage`, and action_msgs' `CancelGoalService` and `GoalStatusMessage`)."""

    _TYPE: ClassVar[str] = ""
    Goal: ClassVar[type[Message]]
    Result: ClassVar[type[Message]]
    Feedback: ClassVar[type[Message]]
    Impl: ClassVar[Any]


def is_message_class(obj: object) -> TypeGuard[type[Message]]:
    return isinstance(obj, type) and issubclass(obj, Message) and obj is not Message


def is_service_class(obj: object) -> TypeGuard[type[Service]]:
    return isinstance(obj, type) and issubclass(obj, Service) and obj is not Service


def is_action_class(obj: object) -> TypeGuard[type[Action]]:
    return isinstance(obj, type) and issubclass(obj, Action) and obj is not Action


# -- helpers of the generated classes ----------------------------------------------------------
# Setters take a fast path inline (`value if value.__class__ is float else check_float64(...)`)
# and call these only for values that need converting or rejecting, so that the errors, which
# are rclpy's in spirit and name the message type, live in one place.


class _Default:
    """The default of a constructor argument whose default must be built afresh per instance
    (a nested message, a list): `Twist(linear=None)` then stays an error, as in rclpy."""

    __slots__ = ()

    def __repr__(self) -> str:
        return "<default>"


DEFAULT: Any = _Default()

INT_RANGES: dict[str, tuple[int, int]] = {
    "int8": (-(2**7), 2**7 - 1),
    "uint8": (0, 2**8 - 1),
    "int16": (-(2**15), 2**15 - 1),
    "uint16": (0, 2**16 - 1),
    "int32": (-(2**31), 2**31 - 1),
    "uint32": (0, 2**32 - 1),
    "int64": (-(2**63), 2**63 - 1),
    "uint64": (0, 2**64 - 1),
    # rclpy has bytes and str for these; llfsm keeps them as small ints.
    "byte": (0, 255),
    "char": (0, 255),
}
FLOAT32_MAX = 3.4028234663852886e38


def _field(msg: Message, field: str) -> str:
    return f"The '{field}' field of {msg._TYPE}"


def _got(value: object) -> str:
    return f"not {type(value).__name__!r} ({value!r})"


def check_float64(value: Any, msg: Message, field: str) -> float:
    if isinstance(value, int | float) and not isinstance(value, bool):
        return float(value)
    raise TypeError(f"{_field(msg, field)} must be of type 'float' (or int), {_got(value)}")


def check_float32(value: Any, msg: Message, field: str) -> float:
    value = check_float64(value, msg, field)
    if -FLOAT32_MAX <= value <= FLOAT32_MAX or value != value or value in (float("inf"), float("-inf")):
        return value
    raise ValueError(f"{_field(msg, field)} must be a float32 in [-{FLOAT32_MAX}, {FLOAT32_MAX}], not {value!r}")


def check_int(value: Any, msg: Message, field: str, ros_type: str) -> int:
    if not isinstance(value, int) or isinstance(value, bool):
        raise TypeError(f"{_field(msg, field)} must be of type 'int' ({ros_type}), {_got(value)}")
    lo, hi = INT_RANGES[ros_type]
    if not lo <= value <= hi:
        kind = "an unsigned integer" if lo == 0 else "an integer"
        raise ValueError(f"{_field(msg, field)} must be {kind} in [{lo}, {hi}] ({ros_type}), not {value!r}")
    return int(value)


def check_bool(value: Any, msg: Message, field: str) -> bool:
    if isinstance(value, bool):
        return value
    raise TypeError(f"{_field(msg, field)} must be of type 'bool', {_got(value)}")


def check_string(value: Any, msg: Message, field: str, bound: int | None = None) -> str:
    if not isinstance(value, str):
        raise TypeError(f"{_field(msg, field)} must be of type 'str', {_got(value)}")
    if bound is not None and len(value) > bound:
        raise ValueError(f"{_field(msg, field)} must be a string of at most {bound} characters, not {len(value)}")
    return str(value)


def check_message(value: Any, msg: Message, field: str, cls: type[Message]) -> Message:
    if isinstance(value, cls):
        return value
    raise TypeError(f"{_field(msg, field)} must be of type {cls._TYPE!r} ({_dotted(cls)}), {_got(value)}")


def _dotted(cls: type[Message]) -> str:
    return cls._TYPE.replace("/", ".")


_BYTE_TYPES = frozenset(("uint8", "byte", "char"))
_FAST_TYPES: dict[str, type] = {"float64": float, "float32": float, "bool": bool, "string": str, "wstring": str}


def _scalar_check(element: str) -> Any:
    """The check of one element of a primitive array ("float64", "string<=10"), as a function
    of (value, msg, field)."""
    base, _, bound = element.partition("<=")
    if base in ("string", "wstring"):
        n = int(bound) if bound else None
        return lambda v, m, f: check_string(v, m, f, n)
    if base == "float64":
        return check_float64
    if base == "float32":
        return check_float32
    if base == "bool":
        return check_bool
    if base in INT_RANGES:
        return lambda v, m, f: check_int(v, m, f, base)
    raise ValueError(f"not a primitive ROS type: {element!r}")


def check_array(
    value: Any,
    msg: Message,
    field: str,
    element: str | type[Message],
    size: int | None = None,
    bound: int | None = None,
) -> list[Any]:
    """A validated new list for an array field: `size` for T[N], `bound` for T[<=N]."""
    if isinstance(value, bytes | bytearray) and element in _BYTE_TYPES:
        value = list(value)
    elif not isinstance(value, list | tuple):
        what = element._TYPE if isinstance(element, type) else element
        raise TypeError(f"{_field(msg, field)} must be a list or tuple of {what!r}, {_got(value)}")
    n = len(value)
    if size is not None and n != size:
        raise ValueError(f"{_field(msg, field)} must have exactly {size} elements, not {n}")
    if bound is not None and n > bound:
        raise ValueError(f"{_field(msg, field)} must have at most {bound} elements, not {n}")
    if isinstance(element, type):
        for i, v in enumerate(value):
            check_message(v, msg, f"{field}[{i}]", element)
        return list(value)
    fast = _FAST_TYPES.get(element)
    if fast is not None and all(v.__class__ is fast for v in value):
        return list(value)
    check = _scalar_check(element)
    return [check(v, msg, f"{field}[{i}]") for i, v in enumerate(value)]


def repeat(cls: type[Message], n: int) -> list[Message]:
    """The default of a fixed-size array of messages: n distinct instances."""
    return [cls() for _ in range(n)]


_RCLPY_NAMES = {"float32": "float", "float64": "double", "byte": "octet"}


def rclpy_type_name(ros_type: str) -> str:
    """rclpy's spelling of a field type ("float64[]" -> "sequence<double>"), for
    `get_fields_and_field_types()`."""
    base, array = ros_type, ""
    if ros_type.endswith("]"):
        base, _, array = ros_type[:-1].partition("[")
    name, _, sbound = base.partition("<=")
    if "/" in name:
        pkg, _, rest = name.partition("/msg/")
        name = f"{pkg}/{rest}"
    else:
        name = _RCLPY_NAMES.get(name, name)
        if sbound:
            name = f"{name}<{sbound}>"
    if not ros_type.endswith("]"):
        return name
    if array == "":
        return f"sequence<{name}>"
    if array.startswith("<="):
        return f"sequence<{name}, {array[2:]}>"
    return f"{name}[{array}]"
