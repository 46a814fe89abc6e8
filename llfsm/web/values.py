"""Message values typed into the page: YAML, as `ros2 topic pub` takes them, never eval.

The text is read with PyYAML's safe loader (plain data only: mappings, lists, scalars); the
message is then filled field by field through its typed properties, so a wrong type, a number
out of range or an unknown field is refused with the message's own error, as rosidl's
`set_message_fields` refuses it.  Type names (`pkg/msg/Name`, `pkg/srv/Name`) are checked
against the identifier rule before anything is imported.
"""

from __future__ import annotations

import importlib
import re
from typing import Any

from ..msgs._message import Message, Service, is_message_class, is_service_class

_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")


class BadValue(ValueError):
    """A value or a type name the user typed is not acceptable (one line for the page)."""


def resolve_type(name: str, kind: str) -> Any:
    """`pkg/msg/Name` (kind "msg") or `pkg/srv/Name` (kind "srv") -> the class."""
    parts = name.strip().split("/")
    if len(parts) == 2:
        parts = [parts[0], kind, parts[1]]
    if len(parts) != 3 or parts[1] != kind or not all(_NAME.match(p) for p in parts):
        example = "std_msgs/msg/String" if kind == "msg" else "std_srvs/srv/Trigger"
        raise BadValue(f"{name!r} is not a {kind} type name such as {example}")
    pkg, _, cls_name = parts
    try:
        module = importlib.import_module(f"llfsm.msgs.{pkg}.{kind}")
    except ImportError:
        raise BadValue(f"unknown type {name}: no interface package {pkg!r}") from None
    cls = getattr(module, cls_name, None)
    ok = is_message_class(cls) if kind == "msg" else is_service_class(cls)
    if not ok:
        raise BadValue(f"unknown type {name}: {pkg} has no {kind} {cls_name}")
    return cls


def parse(text: str) -> dict[str, Any]:
    """YAML text -> a mapping (empty text: no fields)."""
    import yaml

    if not text.strip():
        return {}
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        where = f" (line {mark.line + 1}, column {mark.column + 1})" if mark is not None else ""
        problem = getattr(e, "problem", None) or str(e).splitlines()[0]
        raise BadValue(f"the values are not valid YAML{where}: {problem}") from None
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise BadValue(f"the values must be a YAML mapping such as {{data: hello}}, not {type(data).__name__}")
    return data


def fill(msg: Message, values: dict[str, Any], path: str = "") -> Message:
    """Set msg's fields from plain data, recursively; errors name the field."""
    fields = dict(msg._FIELDS)
    for key, value in values.items():
        where = f"{path}{key}"
        if not isinstance(key, str) or key not in fields:
            known = ", ".join(fields) or "none"
            raise BadValue(f"{msg._TYPE} has no field {where!r} (fields: {known})")
        current = getattr(msg, key)
        try:
            if isinstance(current, Message):
                if not isinstance(value, dict):
                    raise BadValue(f"field {where!r} is a {current._TYPE}: give a mapping")
                fill(current, value, f"{where}.")
                continue
            element = _element_class(type(msg), key, fields[key])
            if element is not None and isinstance(value, list):
                value = [
                    fill(element(), v, f"{where}[{i}].") if isinstance(v, dict) else v for i, v in enumerate(value)
                ]
            setattr(msg, key, value)
        except BadValue:
            raise
        except (TypeError, ValueError) as e:
            raise BadValue(str(e)) from None
    return msg


def _element_class(cls: type[Message], field: str, ros_type: str) -> type[Message] | None:
    """The message class of the elements of an array of messages, if the field is one."""
    base = ros_type.split("[", 1)[0]
    if "[" not in ros_type or "/" not in base:
        return None
    try:
        return resolve_type(base, "msg")
    except BadValue:
        return None


def message(cls: type[Message], text: str) -> Message:
    """A message of class `cls` with the fields given as YAML."""
    return fill(cls(), parse(text))


def request(srv: type[Service], text: str) -> Message:
    return fill(srv.Request(), parse(text))
