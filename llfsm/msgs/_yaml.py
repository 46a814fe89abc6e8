"""Messages as `ros2 topic echo` prints them, without importing PyYAML; and VALUES, the YAML
that `ros2 topic pub` and `ros2 service call` take, into a message.

`ros2 topic echo` prints rosidl_runtime_py's `message_to_yaml(msg)`: the message as an ordered
mapping through `yaml.dump(..., allow_unicode=True, width=sys.maxsize, default_flow_style=False)`.
`llfsm run --echo` must stay light, so this is a port of the few parts of PyYAML's emitter that
such a document uses: block mappings and (indentless) sequences, `{}` and `[]` for empty ones,
and PyYAML's choice between plain, single-quoted and double-quoted strings.  The tests compare it
with yaml.dump on generated data.

Reading VALUES (`from_yaml`, `set_fields`) does import PyYAML, when it is called: it follows
rosidl_runtime_py's `set_message_fields` (a mapping of field names, nested mappings for nested
messages, lists for arrays, `auto` for a header and `now` for a time stamp) but turns every
mistake into one ValuesError line naming the field, where rosidl converts quietly or raises
from deep inside.
"""

from __future__ import annotations

import importlib
import re
from collections.abc import Callable
from typing import Any

from ._message import Message

_BREAKS = "\n\x85\u2028\u2029"
_SPACE_OR_BREAK = "\0 \t\r\n\x85\u2028\u2029"
_ESCAPES = {
    "\0": "0",
    "\x07": "a",
    "\x08": "b",
    "\x09": "t",
    "\x0a": "n",
    "\x0b": "v",
    "\x0c": "f",
    "\x0d": "r",
    "\x1b": "e",
    '"': '"',
    "\\": "\\",
    "\x85": "N",
    "\xa0": "_",
    "\u2028": "L",
    "\u2029": "P",
}
_resolvers: dict[str, list[re.Pattern[str]]] | None = None


def to_yaml(msg: Message | dict[str, Any], truncate_length: int | None = None) -> str:
    """The text `ros2 topic echo` prints for a message, before its `---` line.  A dict (as from
    `msg.to_dict()`) prints the same way.  With `truncate_length` (`ros2 topic echo` uses 128),
    longer strings and arrays are cut there and end in '...', as rosidl_runtime_py cuts them."""
    if truncate_length is not None:
        msg = _truncated(msg if isinstance(msg, dict) else msg.to_dict(), truncate_length)
    items = _items(msg)
    if not items:
        return "{}\n"
    out: list[str] = []
    _mapping(items, 0, "", out)
    return "\n".join(out) + "\n"


def _truncated(value: Any, n: int) -> Any:
    if isinstance(value, bytes | bytearray):
        value = "".join(map(chr, value))
    if isinstance(value, str):
        return value[:n] + "..." if len(value) > n else value
    if isinstance(value, list | tuple):
        items = [_truncated(v, n) for v in value[:n]]
        return [*items, "..."] if len(value) > n else items
    if isinstance(value, dict):
        return {k: _truncated(v, n) for k, v in value.items()}
    return value


def _items(value: Any) -> list[tuple[str, Any]]:
    if isinstance(value, Message):
        return [(f, getattr(value, f)) for f, _ in value._FIELDS]
    return list(value.items())


def _mapping(items: list[tuple[str, Any]], indent: int, first: str, out: list[str]) -> None:
    """A non-empty block mapping whose keys sit at column `indent`; `first` replaces the
    indentation of its first line (the "- " of a sequence item)."""
    pad = " " * indent
    for i, (key, value) in enumerate(items):
        head = f"{first if i == 0 else pad}{_string(str(key), indent, key=True)}:"
        if isinstance(value, Message | dict):
            sub = _items(value)
            if sub:
                out.append(head)
                _mapping(sub, indent + 2, " " * (indent + 2), out)
            else:
                out.append(f"{head} {{}}")
        elif isinstance(value, list | tuple):
            if value:
                out.append(head)
                _sequence(value, indent, out)  # indentless, as PyYAML writes a sequence in a mapping
            else:
                out.append(f"{head} []")
        else:
            out.append(f"{head} {_scalar(value, indent + 2)}")


def _sequence(values: list[Any] | tuple[Any, ...], indent: int, out: list[str]) -> None:
    dash = " " * indent + "- "
    for value in values:
        if isinstance(value, Message | dict):
            sub = _items(value)
            if sub:
                _mapping(sub, indent + 2, dash, out)
            else:
                out.append(f"{dash}{{}}")
        else:
            out.append(f"{dash}{_scalar(value, indent + 2)}")


def _scalar(value: Any, indent: int) -> str:
    if isinstance(value, str):
        return _string(value, indent)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return _float(value)
    if isinstance(value, bytes | bytearray):  # rclpy's byte fields, echoed as characters
        return _string("".join(map(chr, value)), indent)
    if value is None:
        return "null"
    return _string(str(value), indent)


def _float(value: float) -> str:
    """PyYAML's represent_float."""
    if value != value:
        return ".nan"
    if value == float("inf"):
        return ".inf"
    if value == float("-inf"):
        return "-.inf"
    text = repr(value).lower()
    if "." not in text and "e" in text:
        text = text.replace("e", ".0e", 1)
    return text


# -- strings: PyYAML's Emitter.analyze_scalar and choose_scalar_style, block context ----------


def _string(s: str, indent: int, key: bool = False) -> str:
    plain, single, multiline = _analyze(s)
    if not (key and (not s or multiline)) and plain and _resolves_to_str(s):
        return s
    if single and not (key and multiline):
        return _single_quoted(s, indent)
    return _double_quoted(s)


def _analyze(s: str) -> tuple[bool, bool, bool]:
    """(plain allowed, single quotes allowed, has line breaks) for a block-context scalar."""
    if not s:
        return True, True, False
    block_indicators = s.startswith(("---", "..."))
    line_breaks = special = False
    leading_space = leading_break = trailing_space = trailing_break = False
    break_space = space_break = False
    preceded_by_whitespace = True
    followed_by_whitespace = len(s) == 1 or s[1] in _SPACE_OR_BREAK
    previous_space = previous_break = False
    last = len(s) - 1
    for index, ch in enumerate(s):
        if index == 0:
            if ch in "#,[]{}&*!|>'\"%@`":
                block_indicators = True
            if ch in "?:" and followed_by_whitespace:
                block_indicators = True
            if ch == "-" and followed_by_whitespace:
                block_indicators = True
        elif (ch == ":" and followed_by_whitespace) or (ch == "#" and preceded_by_whitespace):
            block_indicators = True
        if ch in _BREAKS:
            line_breaks = True
        if not (ch == "\n" or "\x20" <= ch <= "\x7e") and not (
            (
                ch == "\x85"
                or "\xa0" <= ch <= "\ud7ff"
                or "\ue000" <= ch <= "\ufffd"
                or "\U00010000" <= ch < "\U0010ffff"
            )
            and ch != "\ufeff"
        ):
            special = True
        if ch == " ":
            leading_space = leading_space or index == 0
            trailing_space = trailing_space or index == last
            break_space = break_space or previous_break
            previous_space, previous_break = True, False
        elif ch in _BREAKS:
            leading_break = leading_break or index == 0
            trailing_break = trailing_break or index == last
            space_break = space_break or previous_space
            previous_space, previous_break = False, True
        else:
            previous_space = previous_break = False
        preceded_by_whitespace = ch in _SPACE_OR_BREAK
        followed_by_whitespace = index + 2 > last or s[index + 2] in _SPACE_OR_BREAK
    plain = single = True
    if leading_space or leading_break or trailing_space or trailing_break:
        plain = False
    if break_space:
        plain = single = False
    if space_break or special:
        plain = single = False
    if line_breaks or block_indicators:
        plain = False
    return plain, single, line_breaks


def _resolves_to_str(s: str) -> bool:
    """True when a plain `s` would read back as a string, not a bool, number, null, date..."""
    global _resolvers
    if _resolvers is None:
        _resolvers = _implicit_resolvers()
    return not any(r.match(s) for r in _resolvers.get(s[:1], ()))


def _implicit_resolvers() -> dict[str, list[re.Pattern[str]]]:
    """PyYAML's implicit resolvers (YAML 1.1), by first character."""
    table: dict[str, list[re.Pattern[str]]] = {}

    def add(pattern: str, first: str | list[str]) -> None:
        regex = re.compile(pattern, re.X)
        for ch in first:
            table.setdefault(ch, []).append(regex)

    add(r"^(?:yes|Yes|YES|no|No|NO|true|True|TRUE|false|False|FALSE|on|On|ON|off|Off|OFF)$", "yYnNtTfFoO")
    add(
        r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+][0-9]+)?
        |\.[0-9][0-9_]*(?:[eE][-+][0-9]+)?
        |[-+]?[0-9][0-9_]*(?::[0-5]?[0-9])+\.[0-9_]*
        |[-+]?\.(?:inf|Inf|INF)
        |\.(?:nan|NaN|NAN))$""",
        "-+0123456789.",
    )
    add(
        r"""^(?:[-+]?0b[0-1_]+
        |[-+]?0[0-7_]+
        |[-+]?(?:0|[1-9][0-9_]*)
        |[-+]?0x[0-9a-fA-F_]+
        |[-+]?[1-9][0-9_]*(?::[0-5]?[0-9])+)$""",
        "-+0123456789",
    )
    add(r"^(?:<<)$", "<")
    add(r"^(?: ~ |null|Null|NULL | )$", ["~", "n", "N", ""])
    add(
        r"""^(?:[0-9][0-9][0-9][0-9]-[0-9][0-9]-[0-9][0-9]
        |[0-9][0-9][0-9][0-9] -[0-9][0-9]? -[0-9][0-9]?
        (?:[Tt]|[ \t]+)[0-9][0-9]?
        :[0-9][0-9] :[0-9][0-9] (?:\.[0-9]*)?
        (?:[ \t]*(?:Z|[-+][0-9][0-9]?(?::[0-9][0-9])?))?)$""",
        "0123456789",
    )
    add(r"^(?:=)$", "=")
    add(r"^(?:!|&|\*)$", "!&*")
    return table


def _single_quoted(s: str, indent: int) -> str:
    """PyYAML's write_single_quoted with no width limit: a line break is written doubled when
    it is a newline, and each run of breaks is followed by the scalar's indentation."""
    out = ["'"]
    spaces = breaks = False
    start = 0
    n = len(s)
    for end in range(n + 1):
        ch = s[end] if end < n else None
        if spaces:
            if ch != " ":
                out.append(s[start:end])
                start = end
        elif breaks:
            if ch is None or ch not in _BREAKS:
                if s[start] == "\n":
                    out.append("\n")
                out.extend(s[start:end])
                out.append(" " * indent)
                start = end
        elif (ch is None or ch in " \n\x85\u2028\u2029'") and start < end:
            out.append(s[start:end])
            start = end
        if ch == "'":
            out.append("''")
            start = end + 1
        if ch is not None:
            spaces = ch == " "
            breaks = ch in _BREAKS
    out.append("'")
    return "".join(out)


def _double_quoted(s: str) -> str:
    out = ['"']
    for ch in s:
        if ch in '"\\\x85\u2028\u2029\ufeff' or not (
            "\x20" <= ch <= "\x7e" or "\xa0" <= ch <= "\ud7ff" or "\ue000" <= ch <= "\ufffd"
        ):
            if ch in _ESCAPES:
                out.append("\\" + _ESCAPES[ch])
            elif ch <= "\xff":
                out.append(f"\\x{ord(ch):02X}")
            elif ch <= "\uffff":
                out.append(f"\\u{ord(ch):04X}")
            else:
                out.append(f"\\U{ord(ch):08X}")
        else:
            out.append(ch)
    out.append('"')
    return "".join(out)


# -- VALUES: YAML into a message (rosidl_runtime_py's set_message_fields, with clear errors) ---


class ValuesError(ValueError):
    """VALUES that cannot fill the message: malformed YAML, an unknown field, a wrong type."""


StampSetter = Callable[[int, int], None]


def from_yaml(cls: type[Message], text: str) -> tuple[Message, list[StampSetter]]:
    """A new `cls` filled from VALUES (`"{linear: {x: 2.0}}"`, `"data: hello"`; empty means
    defaults), and the setters of the stamps VALUES asked to be `now` (a header `auto`), which
    the caller calls with (sec, nanosec) each time it sends the message."""
    import yaml  # deferred: start-up (`--echo` prints messages without PyYAML; only VALUES need it)

    try:
        data = yaml.safe_load(text) if text.strip() else {}
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        where = f" (line {mark.line + 1}, column {mark.column + 1})" if mark is not None else ""
        problem = getattr(e, "problem", None) or str(e).splitlines()[0]
        raise ValuesError(f"not valid YAML: {problem}{where}") from None
    except RecursionError:  # PyYAML's composer recurses once per level: `[[[[...` deep enough
        raise ValuesError("not valid YAML here: it nests deeper than any message does") from None
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ValuesError(f"must be a YAML mapping of field names, such as '{{data: hello}}', not {text!r}")
    msg = cls()
    stamps: list[StampSetter] = []
    set_fields(msg, data, "", stamps)
    return msg, stamps


def set_fields(msg: Message, values: dict[Any, Any], path: str = "", stamps: list[StampSetter] | None = None) -> None:
    """Set `msg`'s fields from a mapping, nested mappings for nested messages."""
    fields = dict(msg._FIELDS)
    for key, value in values.items():
        name = str(key)
        where = f"{path}{name}"
        if name not in fields:
            import difflib  # deferred: start-up (only a mistake looks for a close name)

            close = difflib.get_close_matches(name, list(fields), n=1)
            hint = f"; did you mean '{close[0]}'?" if close else f" (its fields: {', '.join(fields) or 'none'})"
            raise ValuesError(f"{msg._TYPE} has no field '{where}'{hint}")
        ros_type = fields[name]
        try:
            _set(msg, name, ros_type, value, where, stamps)
        except ValuesError:
            raise
        except (TypeError, ValueError) as e:
            raise ValuesError(f"{where}: {e}") from None


def _message_class(ros_type: str) -> type[Message]:
    pkg, kind, name = ros_type.split("/")
    return getattr(importlib.import_module(f"llfsm.msgs.{pkg}.{kind}"), name)


def _set(msg: Message, name: str, ros_type: str, value: Any, where: str, stamps: list[StampSetter] | None) -> None:
    element, is_array = ros_type, ros_type.endswith("]")
    if is_array:
        element = ros_type[: ros_type.index("[")]
    if "/" in element:
        cls = _message_class(element)
        if is_array:
            if not isinstance(value, list):
                raise ValuesError(f"{where}: {ros_type} takes a list, not {value!r}")
            setattr(msg, name, [_build(cls, v, f"{where}[{i}]", stamps) for i, v in enumerate(value)])
            return
        sub = getattr(msg, name)
        if value == "auto" and element == "std_msgs/msg/Header":
            if stamps is not None:
                stamps.append(_stamp_setter(sub.stamp))
            return
        if value == "now" and element == "builtin_interfaces/msg/Time":
            if stamps is not None:
                stamps.append(_stamp_setter(sub))
            return
        if not isinstance(value, dict):
            raise ValuesError(f"{where}: {element} takes a mapping of its fields, not {value!r}")
        set_fields(sub, value, f"{where}.", stamps)
        return
    if element.startswith(("string", "wstring")):  # rosidl writes str(value): `data: 42` is "42"
        value = [_as_text(v) for v in value] if is_array and isinstance(value, list) else _as_text(value)
    setattr(msg, name, value)


def _as_text(value: Any) -> Any:
    return str(value) if isinstance(value, int | float) and not isinstance(value, bool) else value


def _build(cls: type[Message], value: Any, where: str, stamps: list[StampSetter] | None) -> Message:
    if not isinstance(value, dict):
        raise ValuesError(f"{where}: {cls._TYPE} takes a mapping of its fields, not {value!r}")
    msg = cls()
    set_fields(msg, value, f"{where}.", stamps)
    return msg


def _stamp_setter(time_msg: Any) -> StampSetter:
    def set_stamp(sec: int, nanosec: int) -> None:
        time_msg.sec = sec
        time_msg.nanosec = nanosec

    return set_stamp
