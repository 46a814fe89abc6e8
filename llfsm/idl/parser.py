"""`.msg`, `.srv` and `.action` text into specs (llfsm.idl.spec), with the file and line of each
mistake.

Our own parser rather than rosbags': rosbags drops default values (`float64 x 1.5`) and does
not know wstring, and ours can point at the line to fix (docs/bus.md, "Your own interfaces").
A definition of several sections (a .srv, an .action) is cut at its `---` lines and each
section read as a message, so a new kind needs only its row in spec.SECTIONS.

Light on purpose (re, math, keyword, the spec types): `ros2 interface show` parses with it
without loading a template engine.
"""

from __future__ import annotations

import keyword
import math
import re
from collections.abc import Callable, Iterable, Iterator

from ..msgs._message import FLOAT32_MAX, INT_RANGES
from .spec import (
    CONSTANT_NAME,
    FIELD_NAME,
    FLOATS,
    PACKAGE_NAME,
    PRIMITIVES,
    RESERVED_FIELDS,
    SECTIONS,
    STRINGS,
    TYPE_NAME,
    ActionSpec,
    ConstantSpec,
    FieldSpec,
    FieldType,
    InterfaceError,
    MessageSpec,
    Scalar,
    ServiceSpec,
    Value,
)

# ROS 1 spellings that ROS 2 tools still accept in .msg files.
ALIASES = {"time": "builtin_interfaces/msg/Time", "duration": "builtin_interfaces/msg/Duration"}

_TYPE_TOKEN = re.compile(
    r"^(?P<base>[A-Za-z][A-Za-z0-9_]*(?:/[A-Za-z][A-Za-z0-9_]*){0,2})"
    r"(?:<=(?P<sbound>[0-9]+))?"
    r"(?:\[(?P<bounded><=)?(?P<size>[0-9]*)\])?\Z"
)
_CONSTANT = re.compile(r"^(?P<name>[A-Za-z_][A-Za-z0-9_]*)\s*=\s*(?P<value>.*)\Z")
_COUNTS = {1: "one", 2: "two"}

Fail = Callable[[str], Exception]


def _outside_quotes(text: str) -> Iterator[tuple[int, str]]:
    """(index, character) of each character of `text` outside '...' and "..." (with \\
    escapes); the quotes themselves are left out.  Comments and list items split there."""
    quote, escaped = "", False
    for i, ch in enumerate(text):
        if quote:
            if escaped:
                escaped = False
            elif ch == "\\":
                escaped = True
            elif ch == quote:
                quote = ""
        elif ch in "'\"":
            quote = ch
        else:
            yield i, ch


def strip_comment(line: str) -> str:
    """The line without its `# comment`; a # inside a quoted value is kept."""
    return next((line[:i] for i, ch in _outside_quotes(line) if ch == "#"), line)


def parse_type(token: str, package: str, local: set[str], fail: Fail) -> FieldType:
    """A field's type as written (`float64[<=3]`, `Header`, `geometry_msgs/Point`), with a bare
    message name resolved in `package` (or std_msgs for a Header that `local` does not hold)."""
    m = _TYPE_TOKEN.match(token)
    if not m:
        raise fail(f"invalid type {token!r}")
    base = m["base"]
    if base in ALIASES:
        base = ALIASES[base]
    elif base in PRIMITIVES:
        pass
    elif "/" not in base:
        if base == "Header" and base not in local:
            base = "std_msgs/msg/Header"  # as ROS tools read a bare Header
        elif TYPE_NAME.match(base):
            base = f"{package}/msg/{base}"
        else:
            raise fail(f"unknown type {base!r} (primitive types are {', '.join(sorted(PRIMITIVES))})")
    else:
        parts = base.split("/")
        if len(parts) == 3 and parts[1] != "msg":
            raise fail(f"invalid type {token!r}: a field can only hold a message (pkg/msg/Name)")
        pkg, name = parts[0], parts[-1]
        if not PACKAGE_NAME.match(pkg) or not TYPE_NAME.match(name):
            raise fail(f"invalid type {token!r}")
        base = f"{pkg}/msg/{name}"
    string_bound = None
    if m["sbound"] is not None:
        if base not in STRINGS:
            raise fail(f"invalid type {token!r}: only string and wstring take a bound (<=N)")
        string_bound = int(m["sbound"])
    array = size = None
    if m["size"] is not None:  # the type has brackets
        if m["bounded"]:
            if not m["size"]:
                raise fail(f"invalid type {token!r}: a bounded array needs its bound, T[<=N]")
            array, size = "bounded", int(m["size"])
        elif m["size"]:
            array, size = "fixed", int(m["size"])
            if size == 0:
                raise fail(f"invalid type {token!r}: a fixed array needs at least one element")
        else:
            array = "unbounded"
    return FieldType(base, string_bound, array, size)


def _unquote(text: str) -> str | None:
    if len(text) >= 2 and text[0] == text[-1] and text[0] in "'\"":
        q = text[0]
        return re.sub(r"\\(.)", lambda m: m[1] if m[1] in (q, "\\") else m[0], text[1:-1])
    return None


def _split_list(text: str) -> list[str]:
    """The items of `[a, "b, c", 3]`, quotes kept."""
    items: list[str] = []
    start = 0
    for i, ch in _outside_quotes(text):
        if ch == ",":
            items.append(text[start:i].strip())
            start = i + 1
    last = text[start:].strip()
    if last or items:
        items.append(last)
    return items


def _parse_scalar(text: str, ftype: FieldType, fail: Fail) -> Scalar:
    base = ftype.base
    if base in STRINGS:
        quoted = _unquote(text)
        value = text if quoted is None else quoted
        if ftype.string_bound is not None and len(value) > ftype.string_bound:
            raise fail(f"value {value!r} is longer than the bound {ftype.string_bound}")
        return value
    if base == "bool":
        low = text.lower()
        if low in ("true", "1"):
            return True
        if low in ("false", "0"):
            return False
        raise fail(f"invalid bool value {text!r} (true, false, 1 or 0)")
    if base in INT_RANGES:
        try:
            number = int(text)  # decimal, leading zeros allowed as rosidl reads them
        except ValueError:
            try:
                number = int(text, 0)  # 0x1F, 0b101, 0o17
            except ValueError:
                raise fail(f"invalid {base} value {text!r}") from None
        lo, hi = INT_RANGES[base]
        if not lo <= number <= hi:
            raise fail(f"value {number} out of range for {base} [{lo}, {hi}]")
        return number
    if base in FLOATS:
        try:
            real = float(text)
        except ValueError:
            raise fail(f"invalid {base} value {text!r}") from None
        if base == "float32" and math.isfinite(real) and abs(real) > FLOAT32_MAX:
            raise fail(f"value {text} out of range for float32")
        return real
    raise fail(f"a {base} field cannot have a default value")


def _parse_value(text: str, ftype: FieldType, fail: Fail) -> Value:
    if ftype.array is None:
        return _parse_scalar(text, ftype, fail)
    if not (text.startswith("[") and text.endswith("]")):
        raise fail(f"the default of an array must be a list, [a, b, ...], not {text!r}")
    element = FieldType(ftype.base, ftype.string_bound)
    values = [_parse_scalar(item, element, fail) for item in _split_list(text[1:-1])]
    if ftype.array == "fixed" and len(values) != ftype.size:
        raise fail(f"the default has {len(values)} elements, the array {ftype.size}")
    if ftype.array == "bounded" and ftype.size is not None and len(values) > ftype.size:
        raise fail(f"the default has {len(values)} elements, more than the bound {ftype.size}")
    return values


def parse_message(
    text: str, type_name: str, path: str, *, local: Iterable[str] = (), first_line: int = 1
) -> MessageSpec:
    """A .msg definition (or one section of a .srv).  `local` holds the message names of the
    same package, which a bare `Header` then means instead of std_msgs/Header."""
    package = type_name.split("/", 1)[0]
    local = set(local)
    spec = MessageSpec(type_name, path=path)
    seen: set[str] = set()
    for number, raw in enumerate(text.splitlines(), start=first_line):

        def fail(message: str, number: int = number) -> InterfaceError:
            return InterfaceError(path, number, message)

        line = strip_comment(raw).strip()
        if not line:
            continue
        parts = line.split(None, 1)
        if len(parts) < 2:
            raise fail(f"expected 'TYPE NAME', got {line!r}")
        type_token, rest = parts
        ftype = parse_type(type_token, package, local, fail)
        constant = _CONSTANT.match(rest)
        if constant:
            name = constant["name"]
            if not CONSTANT_NAME.match(name):
                raise fail(f"invalid constant name {name!r}: constants are UPPER_CASE")
            if ftype.is_message or ftype.array is not None:
                raise fail(f"constant {name} must be of a primitive type, not {ftype.ros}")
            value_text = constant["value"].strip()
            if not value_text:
                raise fail(f"constant {name} has no value")
            value = _parse_scalar(value_text, ftype, fail)
            if name in seen:
                raise fail(f"{name} is defined twice")
            seen.add(name)
            spec.constants.append(ConstantSpec(name, ftype, value, number))
            continue
        name, *more = rest.split(None, 1)
        default_text = more[0].strip() if more else ""
        if not FIELD_NAME.match(name):
            raise fail(f"invalid field name {name!r}: field names are lower_snake_case")
        if keyword.iskeyword(name) or name in RESERVED_FIELDS:
            raise fail(f"field name {name!r} is reserved in Python")
        if name in seen:
            raise fail(f"{name} is defined twice")
        seen.add(name)
        default = None
        if default_text:
            if ftype.is_message:
                raise fail(f"field {name}: a message field cannot have a default value")
            default = _parse_value(default_text, ftype, fail)
        spec.fields.append(FieldSpec(name, ftype, default, number))
    return spec


def parse_sections(text: str, kind: str, type_name: str, path: str, *, local: Iterable[str] = ()) -> list[MessageSpec]:
    """The messages of a definition that `---` lines cut into the sections of its kind
    (spec.SECTIONS): `<type_name>_<Section>` each, with line numbers of the whole file."""
    sections = SECTIONS[kind]
    lines = text.splitlines()
    cuts = [i for i, line in enumerate(lines) if strip_comment(line).strip() == "---"]
    needed = len(sections) - 1
    if len(cuts) < needed:
        before, after = sections[len(cuts)].lower(), sections[len(cuts) + 1].lower()
        raise InterfaceError(path, None, f"no '---' line between {before} and {after}")
    if len(cuts) > needed:
        plural = "s" if needed > 1 else ""
        raise InterfaceError(path, cuts[needed] + 1, f"more than {_COUNTS[needed]} '---' line{plural}")
    bounds = [-1, *cuts, len(lines)]
    return [
        parse_message(
            "\n".join(lines[bounds[i] + 1 : bounds[i + 1]]),
            f"{type_name}_{section}",
            path,
            local=local,
            first_line=bounds[i] + 2,
        )
        for i, section in enumerate(sections)
    ]


def parse_service(text: str, type_name: str, path: str, *, local: Iterable[str] = ()) -> ServiceSpec:
    """A .srv definition: its request and response, cut at the one `---` line."""
    request, response = parse_sections(text, "srv", type_name, path, local=local)
    return ServiceSpec(type_name, request, response, path)


def parse_action(text: str, type_name: str, path: str, *, local: Iterable[str] = ()) -> ActionSpec:
    """An .action definition: its goal, result and feedback, cut at the two `---` lines."""
    goal, result, feedback = parse_sections(text, "action", type_name, path, local=local)
    return ActionSpec(type_name, goal, result, feedback, path)
