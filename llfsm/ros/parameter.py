"""A parameter and its value, and the exceptions of parameters, as `rclpy.parameter` and the
parameter half of `rclpy.exceptions`: what `ros2 param`, the params files and a node's
ParameterHost (llfsm/ros/parameters.py) all speak.  See docs/parameters.md.
"""

from __future__ import annotations

from enum import IntEnum
from typing import Any

from ..msgs.rcl_interfaces.msg import Parameter as ParameterMsg
from ..msgs.rcl_interfaces.msg import ParameterType, ParameterValue

#: What separates the parts of a nested parameter name (`pid.kp`), as in rclpy.
PARAMETER_SEPARATOR_STRING = "."
#: `ListParameters.Request.DEPTH_RECURSIVE`.
DEPTH_RECURSIVE = 0
#: ros2param's names of the types: what `ros2 param describe` prints, what `--param-type` takes
#: (`llfsm param`, the web view's parameters).
TYPE_NAMES = {
    ParameterType.PARAMETER_BOOL: "boolean",
    ParameterType.PARAMETER_INTEGER: "integer",
    ParameterType.PARAMETER_DOUBLE: "double",
    ParameterType.PARAMETER_STRING: "string",
    ParameterType.PARAMETER_BYTE_ARRAY: "byte array",
    ParameterType.PARAMETER_BOOL_ARRAY: "boolean array",
    ParameterType.PARAMETER_INTEGER_ARRAY: "integer array",
    ParameterType.PARAMETER_DOUBLE_ARRAY: "double array",
    ParameterType.PARAMETER_STRING_ARRAY: "string array",
    ParameterType.PARAMETER_NOT_SET: "not set",
}


# -- exceptions, with rclpy's classes and texts ---------------------------------------------------
class ParameterException(Exception):
    """Base of the parameter errors.  `origin` says where an override that caused it was
    written (`params.yaml:3`, `-p gain:=2`), so a run can blame the file rather than the node."""

    origin: str | None = None
    #: The node that refused it (set when a declare fails).
    node: str | None = None

    def __init__(self, error_msg: str, parameters: str | list[str]) -> None:
        super().__init__(f"{error_msg}: {parameters}")


class ParameterNotDeclaredException(ParameterException):
    def __init__(self, parameters: str | list[str]) -> None:
        super().__init__("Invalid access to undeclared parameter(s)", parameters)


class ParameterAlreadyDeclaredException(ParameterException):
    def __init__(self, parameters: str | list[str]) -> None:
        super().__init__("Parameter(s) already declared", parameters)


class InvalidParameterException(ParameterException):
    def __init__(self, parameter_name: str) -> None:
        super().__init__("Invalid parameter name", parameter_name)


class InvalidParameterTypeException(ParameterException):
    def __init__(self, desired_parameter: Parameter, expected_type: str) -> None:
        try:
            got = Parameter.Type.from_parameter_value(desired_parameter.value).name
        except TypeError:
            got = "unknown"
        super().__init__(
            f"Trying to set parameter '{desired_parameter.name}' to '{desired_parameter.value}' of type "
            f"'{got}', expecting type '{expected_type}'",
            desired_parameter.name,
        )


class InvalidParameterValueException(ParameterException):
    def __init__(self, parameter: str, value: Any, reason: str) -> None:
        super().__init__(f"Invalid parameter value ({value}) for parameter. Reason: {reason}", parameter)


class ParameterImmutableException(ParameterException):
    def __init__(self, parameter_name: str) -> None:
        super().__init__("Attempted to modify read-only parameter", parameter_name)


class ParameterUninitializedException(ParameterException):
    def __init__(self, parameter_name: str) -> None:
        super().__init__(f"The parameter '{parameter_name}' is not initialized", parameter_name)


# -- one parameter ------------------------------------------------------------------------------
class Parameter:
    """A name, a type and a value, as `rclpy.parameter.Parameter`: `Parameter(name, value=2.0)`
    infers the type, `Parameter(name, Parameter.Type.DOUBLE, 2.0)` states it (and must agree)."""

    class Type(IntEnum):
        NOT_SET = ParameterType.PARAMETER_NOT_SET
        BOOL = ParameterType.PARAMETER_BOOL
        INTEGER = ParameterType.PARAMETER_INTEGER
        DOUBLE = ParameterType.PARAMETER_DOUBLE
        STRING = ParameterType.PARAMETER_STRING
        BYTE_ARRAY = ParameterType.PARAMETER_BYTE_ARRAY
        BOOL_ARRAY = ParameterType.PARAMETER_BOOL_ARRAY
        INTEGER_ARRAY = ParameterType.PARAMETER_INTEGER_ARRAY
        DOUBLE_ARRAY = ParameterType.PARAMETER_DOUBLE_ARRAY
        STRING_ARRAY = ParameterType.PARAMETER_STRING_ARRAY

        @classmethod
        def from_parameter_value(cls, parameter_value: Any) -> Parameter.Type:
            """The type of a Python value; TypeError for a value no parameter can hold."""
            if parameter_value is None:
                return cls.NOT_SET
            if isinstance(parameter_value, bool):
                return cls.BOOL
            if isinstance(parameter_value, int):
                return cls.INTEGER
            if isinstance(parameter_value, float):
                return cls.DOUBLE
            if isinstance(parameter_value, str):
                return cls.STRING
            if isinstance(parameter_value, list | tuple):
                for kind, item in (
                    (cls.BYTE_ARRAY, bytes),
                    (cls.BOOL_ARRAY, bool),
                    (cls.INTEGER_ARRAY, int),
                    (cls.DOUBLE_ARRAY, float),
                    (cls.STRING_ARRAY, str),
                ):
                    if all(isinstance(v, item) for v in parameter_value):
                        return kind
                raise TypeError(f"The given value is not a list of one of the allowed types '{parameter_value}'.")
            raise TypeError(f"The given value is not one of the allowed types '{parameter_value}'.")

        def check(self, parameter_value: Any) -> bool:
            """Whether `parameter_value` is a value of this type."""
            T = Parameter.Type
            if self is T.NOT_SET:
                return parameter_value is None
            if self in _SCALAR:
                return _is(parameter_value, _SCALAR[self])
            if not isinstance(parameter_value, list | tuple):
                return False
            if self is T.BYTE_ARRAY:
                return all(isinstance(v, bytes) and len(v) == 1 for v in parameter_value)
            return all(_is(v, _ITEM[self]) for v in parameter_value)

    __slots__ = ("_name", "_type_", "_value")

    def __init__(self, name: str, type_: Parameter.Type | None = None, value: Any = None) -> None:
        if type_ is None:
            type_ = Parameter.Type.from_parameter_value(value)
        if not isinstance(type_, Parameter.Type):
            raise TypeError(f"type must be an instance of '{Parameter.Type!r}'")
        if not type_.check(value):
            raise ValueError(f"Type '{type_}' and value '{value}' do not agree")
        self._name = name
        self._type_ = type_
        self._value = value

    @property
    def name(self) -> str:
        return self._name

    @property
    def type_(self) -> Parameter.Type:
        return self._type_

    @property
    def value(self) -> Any:
        return self._value

    def __repr__(self) -> str:
        return f"Parameter({self._name!r}, Parameter.Type.{self._type_.name}, {self._value!r})"

    @classmethod
    def from_parameter_msg(cls, param_msg: ParameterMsg) -> Parameter:
        """From `rcl_interfaces/msg/Parameter` (a value that came over the wire).  ValueError for
        a type number that is no parameter type (a peer may send anything)."""
        try:
            type_ = Parameter.Type(param_msg.value.type)
        except ValueError:
            raise ValueError(f"unknown parameter type {param_msg.value.type} for {param_msg.name}") from None
        return cls(param_msg.name, type_, _value_of(param_msg.value, type_))

    def get_parameter_value(self) -> ParameterValue:
        """The value as `rcl_interfaces/msg/ParameterValue`."""
        T = Parameter.Type
        pv = ParameterValue(type=int(self._type_))
        value = self._value
        if self._type_ is T.BYTE_ARRAY:
            pv.byte_array_value = [b[0] for b in value]
        elif self._type_ is not T.NOT_SET:
            setattr(pv, _FIELD[self._type_], list(value) if isinstance(value, tuple) else value)
        return pv

    def to_parameter_msg(self) -> ParameterMsg:
        return ParameterMsg(name=self._name, value=self.get_parameter_value())


def _is(value: Any, kind: type) -> bool:
    """isinstance, where an int is no float and a bool no int (as rclpy's types say)."""
    if kind is int:
        return isinstance(value, int) and not isinstance(value, bool)
    return isinstance(value, kind)


_T = Parameter.Type
_SCALAR = {_T.BOOL: bool, _T.INTEGER: int, _T.DOUBLE: float, _T.STRING: str}
_ITEM = {_T.BOOL_ARRAY: bool, _T.INTEGER_ARRAY: int, _T.DOUBLE_ARRAY: float, _T.STRING_ARRAY: str}
_FIELD = {
    _T.BOOL: "bool_value",
    _T.INTEGER: "integer_value",
    _T.DOUBLE: "double_value",
    _T.STRING: "string_value",
    _T.BYTE_ARRAY: "byte_array_value",
    _T.BOOL_ARRAY: "bool_array_value",
    _T.INTEGER_ARRAY: "integer_array_value",
    _T.DOUBLE_ARRAY: "double_array_value",
    _T.STRING_ARRAY: "string_array_value",
}
del _T


def _value_of(pv: ParameterValue, type_: Parameter.Type) -> Any:
    if type_ is Parameter.Type.NOT_SET:
        return None
    if type_ is Parameter.Type.BYTE_ARRAY:
        return [bytes((b,)) for b in pv.byte_array_value]
    value = getattr(pv, _FIELD[type_])
    return list(value) if isinstance(value, list) else value


def parameter_value_to_python(parameter_value: ParameterValue) -> Any:
    """The Python value a `ParameterValue` holds (None for NOT_SET), as rclpy's function of that
    name: arrays as lists, bytes as their numbers.  RuntimeError for an unknown type."""
    try:
        type_ = Parameter.Type(parameter_value.type)
    except ValueError:
        raise RuntimeError(f"unexpected parameter type {parameter_value.type}") from None
    if type_ is Parameter.Type.BYTE_ARRAY:
        return list(parameter_value.byte_array_value)
    return _value_of(parameter_value, type_)


def validate_parameter_name(name: str) -> None:
    """rclpy refuses names it cannot store: empty, or with an empty part between dots."""
    if not isinstance(name, str):
        raise TypeError(f"parameter name must be a str, not {type(name).__name__}")
    if not name or any(not part for part in name.split(PARAMETER_SEPARATOR_STRING)) or not name.isprintable():
        raise InvalidParameterException(name)
