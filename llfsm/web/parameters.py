"""Each node's parameters on the page, and its editor (docs/view.md, "Parameters").

The page reads and sets parameters as `llfsm param` and `ros2 param` do, through the node's
own parameter services (`<node>/list_parameters`, `get_parameters`, `describe_parameters`,
`set_parameters`; rcl_interfaces), so it reaches llfsm's nodes and rclpy's alike, in this
process through the bus and in others over DDS.  A value typed into the page is read as
`param set` reads its VALUE (llfsm.ros.parameter_files.guess_value: `2` an integer, `2.0` a
double, `true` a boolean, `[1, 2]` an integer array, anything else a string), and the node
itself checks it: a value of the wrong type, out of its range or refused by a callback is
refused with the node's own reason, rclpy's words.

The values shown are written so that the same text set again gives the same value (a string
that would read as a number is quoted), and what a node answers is bounded before it reaches
the page (a peer on a DDS domain may answer anything).
"""

from __future__ import annotations

import math
import struct
from typing import Any

from ..msgs.rcl_interfaces.msg import Parameter as ParameterMsg
from ..msgs.rcl_interfaces.msg import ParameterEvent, ParameterType
from ..ros.names import InvalidNameError, normalise_namespace, validate_node_name
from ..ros.parameter import TYPE_NAMES
from ..ros.parameter_files import guess_value
from ..ros.parameters import Parameter, parameter_value_to_python

#: Parameters of one node shown at most, and characters of a value's text.
MAX_PARAMETERS = 500
MAX_TEXT = 4000


class ParameterInputError(ValueError):
    """A node name or value from the page that cannot be sent (one line for the page)."""


def node_name(text: str) -> str:
    """`turtlesim` -> `/turtlesim`, checked as ROS checks a node's name and namespace."""
    text = text.strip()
    full = text if text.startswith("/") else "/" + text
    ns, _, base = full.rpartition("/")
    try:
        validate_node_name(base)
        normalise_namespace(ns or "/")
    except InvalidNameError as e:
        raise ParameterInputError(
            str(e) if str(e).startswith("invalid") else f"invalid node name {text!r}: {e}"
        ) from None
    return full


def message(name: str, text: str) -> ParameterMsg:
    """The rcl_interfaces/msg/Parameter that `param set NODE NAME TEXT` would send."""
    if not name.strip():
        raise ParameterInputError("give the parameter's name")
    try:
        value = Parameter(name, value=guess_value(text)).get_parameter_value()
    except (TypeError, ValueError) as e:
        raise ParameterInputError(f"invalid value {text!r}: {e}") from None
    return ParameterMsg(name=name, value=value)


def value_text(value: Any) -> str:
    """A parameter's value as the page shows it in its editor: text that `guess_value` reads
    back as the same value (YAML's spelling of booleans and floats; a string quoted when it
    would read as something else)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return _float(value)
    if isinstance(value, str):
        return value if guess_value(value) == value and value == value.strip() else _quoted(value)
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_quoted(v) if isinstance(v, str) else value_text(v) for v in value) + "]"
    return "" if value is None else str(value)


def _float(x: float) -> str:
    """repr, written as YAML 1.1 (PyYAML) reads a float: a dot always, a signed exponent."""
    if math.isnan(x):
        return ".nan"
    if math.isinf(x):
        return ".inf" if x > 0 else "-.inf"
    text = repr(x)
    mantissa, e, exponent = text.partition("e")
    if "." not in mantissa:
        mantissa += ".0"
    if e and exponent[0] not in "+-":
        exponent = "+" + exponent
    return mantissa + (f"e{exponent}" if e else "")


def _quoted(text: str) -> str:
    return "'" + text.replace("'", "''") + "'"


def rows(names: list[str], values: list[Any], descriptors: list[Any]) -> list[dict[str, Any]]:
    """The page's rows for a node's parameters: name, type, value (as text), description,
    read-only, range.  The three answers come from three calls, so they may disagree (a
    parameter declared in between; rclpy answers an empty list when one name is unknown):
    what is missing shows as not set."""
    by_name = {getattr(d, "name", ""): d for d in descriptors}
    out = []
    for i, name in enumerate(names[:MAX_PARAMETERS]):
        pv = values[i] if i < len(values) and len(values) == len(names) else None
        d = by_name.get(name)
        kind = pv.type if pv is not None else ParameterType.PARAMETER_NOT_SET
        try:
            value = parameter_value_to_python(pv) if pv is not None else None
        except RuntimeError:  # a type number no parameter has: a peer's mistake, shown as such
            value, kind = None, ParameterType.PARAMETER_NOT_SET
        text = value_text(value)
        ranges = [*getattr(d, "floating_point_range", []), *getattr(d, "integer_range", [])] if d else []
        out.append(
            {
                "name": name[:MAX_TEXT],
                "type": TYPE_NAMES.get(kind, str(kind)),
                "value": text if len(text) <= MAX_TEXT else text[: MAX_TEXT - 1] + "…",
                "description": (d.description if d is not None else "")[:MAX_TEXT],
                "read_only": bool(d.read_only) if d is not None else False,
                "range": (
                    {"from": ranges[0].from_value, "to": ranges[0].to_value, "step": ranges[0].step} if ranges else None
                ),
            }
        )
    return out


def result_text(result: Any) -> tuple[bool, str]:
    """`param set`'s words for a SetParametersResult."""
    said = f": {result.reason}" if result.reason else ""
    if result.successful:
        return True, "Set parameter successful" + said
    return False, "Setting parameter failed" + said


#: A node name longer than this in a parameter event is no node's (a ROS name is far shorter):
#: the event is not counted, and its name never held (llfsm.web.source).
MAX_EVENT_NAME = 256


def event_node(payload: bytes) -> Any:
    """A peer's rcl_interfaces/msg/ParameterEvent as the page needs it (a screen of the DDS
    reader: llfsm.ros.subscription.Subscription.screen): its node's name, read from the CDR
    without decoding the parameters (a peer's event may list thousands), or False for a name
    longer than MAX_EVENT_NAME; ValueError for a payload that holds no name."""
    if len(payload) < 16 or payload[0] != 0 or payload[1] not in (0, 1):
        raise ValueError("not a plain CDR ParameterEvent")
    (size,) = struct.unpack_from("<I" if payload[1] else ">I", payload, 12)  # after the stamp
    if size == 0 or size - 1 > MAX_EVENT_NAME:
        return False
    if 16 + size > len(payload):
        raise ValueError("a node name longer than its sample")
    return ParameterEvent(node=payload[16 : 16 + size - 1].decode("utf-8"))
