"""ROS interface definitions (.msg, .srv) become message and service modules.

Two uses.  `python -m llfsm.idl.package` (or `make msgs`) regenerates the built-in
packages under llfsm/msgs/, committed to the repository: std_msgs, geometry_msgs and
builtin_interfaces from the definitions rosbags carries for ROS 2 Humble, and the .msg/.srv
files shipped in llfsm/msgs/_interfaces/ (std_srvs, turtlesim, turtle_sensor_interface).  And the
import hook of llfsm.msgs calls `build_package` to compile a user's package into its cache.

Beside each generated msg/srv module goes its DDS form, `_dds.py` (llfsm.idl.ddsgen: cyclonedds
types named as ROS 2 names them, XCDR1 encoders and decoders, RIHS01 type hashes), from the same
parsed definitions and the template msgs_dds.py.j2.

The parser is our own rather than rosbags': rosbags drops default values (`float64 x 1.5`) and
does not know wstring, and our own can point at the file and line of a mistake.  Generated
modules import only llfsm.msgs._message and other generated modules, so running a machine never
loads rosbags, jinja2 or this file.
"""

from __future__ import annotations

import argparse
import keyword
import math
import os
import re
import sys
import tempfile
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

import jinja2

from ..msgs._message import FLOAT32_MAX, INT_RANGES
from ..templating import comment_text, environment, header_lines

LLFSM_DIR = Path(__file__).resolve().parent.parent
MSGS_DIR = LLFSM_DIR / "msgs"
SHIPPED_DIR = MSGS_DIR / "_interfaces"
TEMPLATES = Path(__file__).resolve().parent / "templates"
TEMPLATE = "msgs.py.j2"

# Taken from rosbags' ROS 2 Humble store; every other built-in package is a folder of SHIPPED_DIR.
STANDARD_PACKAGES = ("builtin_interfaces", "std_msgs", "geometry_msgs")
# Default values of standard messages, which rosbags' field definitions do not carry.
STANDARD_DEFAULTS: dict[str, dict[str, Any]] = {
    "geometry_msgs/msg/Quaternion": {"w": 1.0},
}

LINE_LIMIT = 120  # the project's ruff line-length: generated code is formatted as ruff would

FLOATS = ("float32", "float64")
INTS = ("int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64", "byte", "char")
STRINGS = ("string", "wstring")
PRIMITIVES = frozenset((*FLOATS, *INTS, *STRINGS, "bool"))
# ROS 1 spellings that ROS 2 tools still accept in .msg files.
ALIASES = {"time": "builtin_interfaces/msg/Time", "duration": "builtin_interfaces/msg/Duration"}

PACKAGE_NAME = re.compile(r"^(?!.*__)(?!.*_\Z)[a-z][a-z0-9_]*\Z")
TYPE_NAME = re.compile(r"^[A-Z][A-Za-z0-9]*\Z")
FIELD_NAME = re.compile(r"^(?!.*__)(?!.*_\Z)[a-z][a-z0-9_]*\Z")
CONSTANT_NAME = re.compile(r"^[A-Z](?:[A-Z0-9_]*[A-Z0-9])?\Z")
# Names a field cannot take: they would break the generated class (its __init__ has a `self`
# parameter and its body uses the `property` decorator) or are not valid identifiers.
RESERVED_FIELDS = frozenset(("self", "property"))
_TYPE_TOKEN = re.compile(
    r"^(?P<base>[A-Za-z][A-Za-z0-9_]*(?:/[A-Za-z][A-Za-z0-9_]*){0,2})"
    r"(?:<=(?P<sbound>[0-9]+))?"
    r"(?:\[(?P<bounded><=)?(?P<size>[0-9]*)\])?\Z"
)
_CONSTANT = re.compile(r"^(?P<name>[A-Za-z_][A-Za-z0-9_]*)\s*=\s*(?P<value>.*)\Z")


class InterfaceError(ImportError):
    """A definition that cannot be compiled, with the file and line to fix."""

    def __init__(self, path: str, line: int | None, message: str) -> None:
        where = f"{path}:{line}" if line else path
        super().__init__(f"{where}: {message}")
        self.path = path
        self.line = line
        self.message = message


# -- the definitions ---------------------------------------------------------------------------


@dataclass(frozen=True)
class FieldType:
    """One field's ROS type: a primitive or "pkg/msg/Name", maybe bounded, maybe an array."""

    base: str
    string_bound: int | None = None
    array: str | None = None  # None, "fixed" (T[N]), "bounded" (T[<=N]) or "unbounded" (T[])
    size: int | None = None  # N of T[N] and T[<=N]

    @property
    def is_message(self) -> bool:
        return "/" in self.base

    @property
    def element(self) -> str:
        """The ROS spelling of one element: "float64", "string<=10", "geometry_msgs/msg/Point"."""
        return self.base if self.string_bound is None else f"{self.base}<={self.string_bound}"

    @property
    def ros(self) -> str:
        if self.array is None:
            return self.element
        if self.array == "fixed":
            return f"{self.element}[{self.size}]"
        if self.array == "bounded":
            return f"{self.element}[<={self.size}]"
        return f"{self.element}[]"


@dataclass
class FieldSpec:
    name: str
    type: FieldType
    default: Any = None  # a value given in the definition (list for arrays), or None
    line: int | None = None


@dataclass
class ConstantSpec:
    name: str
    type: FieldType
    value: Any
    line: int | None = None


@dataclass
class MessageSpec:
    type_name: str  # "geometry_msgs/msg/Twist", "turtlesim/srv/Spawn_Request"
    fields: list[FieldSpec] = field(default_factory=list)
    constants: list[ConstantSpec] = field(default_factory=list)
    path: str = ""  # where the definition came from, for errors

    @property
    def name(self) -> str:
        return self.type_name.rsplit("/", 1)[1]


@dataclass
class ServiceSpec:
    type_name: str  # "turtlesim/srv/Spawn"
    request: MessageSpec
    response: MessageSpec
    path: str = ""

    @property
    def name(self) -> str:
        return self.type_name.rsplit("/", 1)[1]


@dataclass
class PackageSpec:
    name: str
    messages: list[MessageSpec] = field(default_factory=list)
    services: list[ServiceSpec] = field(default_factory=list)
    source: str = ""  # shown in the header of the generated modules


# -- parsing .msg and .srv ---------------------------------------------------------------------


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


def _strip_comment(line: str) -> str:
    """The line without its `# comment`; a # inside a quoted value is kept."""
    return next((line[:i] for i, ch in _outside_quotes(line) if ch == "#"), line)


def _parse_type(token: str, package: str, local: set[str], fail: Callable[[str], Exception]) -> FieldType:
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


def _parse_scalar(text: str, ftype: FieldType, fail: Callable[[str], Exception]) -> Any:
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
            value = int(text)  # decimal, leading zeros allowed as rosidl reads them
        except ValueError:
            try:
                value = int(text, 0)  # 0x1F, 0b101, 0o17
            except ValueError:
                raise fail(f"invalid {base} value {text!r}") from None
        lo, hi = INT_RANGES[base]
        if not lo <= value <= hi:
            raise fail(f"value {value} out of range for {base} [{lo}, {hi}]")
        return value
    if base in FLOATS:
        try:
            value = float(text)
        except ValueError:
            raise fail(f"invalid {base} value {text!r}") from None
        if base == "float32" and math.isfinite(value) and abs(value) > FLOAT32_MAX:
            raise fail(f"value {text} out of range for float32")
        return value
    raise fail(f"a {base} field cannot have a default value")


def _parse_value(text: str, ftype: FieldType, fail: Callable[[str], Exception]) -> Any:
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
    """A .msg definition (or one half of a .srv).  `local` holds the message names of the same
    package, which a bare `Header` then means instead of std_msgs/Header."""
    package = type_name.split("/", 1)[0]
    local = set(local)
    spec = MessageSpec(type_name, path=path)
    seen: set[str] = set()
    for number, raw in enumerate(text.splitlines(), start=first_line):

        def fail(message: str, number: int = number) -> InterfaceError:
            return InterfaceError(path, number, message)

        line = _strip_comment(raw).strip()
        if not line:
            continue
        parts = line.split(None, 1)
        if len(parts) < 2:
            raise fail(f"expected 'TYPE NAME', got {line!r}")
        type_token, rest = parts
        ftype = _parse_type(type_token, package, local, fail)
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


def parse_service(text: str, type_name: str, path: str, *, local: Iterable[str] = ()) -> ServiceSpec:
    lines = text.splitlines()
    cut = [i for i, line in enumerate(lines) if _strip_comment(line).strip() == "---"]
    if len(cut) != 1:
        what = "no '---' line between request and response" if not cut else "more than one '---' line"
        raise InterfaceError(path, cut[1] + 1 if len(cut) > 1 else None, what)
    i = cut[0]
    request = parse_message("\n".join(lines[:i]), f"{type_name}_Request", path, local=local)
    response = parse_message("\n".join(lines[i + 1 :]), f"{type_name}_Response", path, local=local, first_line=i + 2)
    return ServiceSpec(type_name, request, response, path)


def _definition_files(package_dir: Path, kind: str) -> list[Path]:
    folder = package_dir / kind
    if not folder.is_dir():
        return []
    return sorted(p for p in folder.iterdir() if p.suffix == f".{kind}" and p.is_file())


def read_package(package_dir: Path, source: str | None = None) -> PackageSpec:
    """Every .msg of PKG/msg and .srv of PKG/srv."""
    name = package_dir.name
    if not PACKAGE_NAME.match(name):
        raise InterfaceError(str(package_dir), None, f"invalid package name {name!r}")
    spec = PackageSpec(name, source=source or str(package_dir))
    msg_files = _definition_files(package_dir, "msg")
    local = {p.stem for p in msg_files}
    for kind, files in (("msg", msg_files), ("srv", _definition_files(package_dir, "srv"))):
        for p in files:
            if not TYPE_NAME.match(p.stem):
                raise InterfaceError(str(p), None, f"invalid {kind} name {p.stem!r}: names are CamelCase")
            try:
                text = p.read_text(encoding="utf-8")
            except (OSError, UnicodeDecodeError) as e:
                raise InterfaceError(str(p), None, f"cannot read: {e}") from None
            type_name = f"{name}/{kind}/{p.stem}"
            if kind == "msg":
                spec.messages.append(parse_message(text, type_name, str(p), local=local))
            else:
                spec.services.append(parse_service(text, type_name, str(p), local=local))
    return spec


def standard_package(name: str) -> PackageSpec:
    """A package from rosbags' ROS 2 Humble type store (only needed to regenerate built-ins)."""
    from rosbags.typesys import Stores, get_typestore  # heavy: only for `make msgs`

    fielddefs = get_typestore(Stores.ROS2_HUMBLE).fielddefs
    spec = PackageSpec(name, source="rosbags (ROS 2 Humble)")
    for type_name in sorted(t for t in fielddefs if t.startswith(f"{name}/msg/")):
        constants, fields = fielddefs[type_name]
        msg = MessageSpec(type_name, path=f"rosbags:{type_name}")
        defaults = STANDARD_DEFAULTS.get(type_name, {})
        for cname, ctype, value in constants:
            msg.constants.append(ConstantSpec(cname, FieldType(ctype), value))
        for fname, desc in fields:
            if fname == "structure_needs_at_least_one_member":
                continue  # rosbags' stand-in member of an empty message (IDL needs one); rclpy hides it
            msg.fields.append(FieldSpec(fname, _rosbags_type(desc), defaults.get(fname)))
        spec.messages.append(msg)
    return spec


def _rosbags_type(desc: tuple[Any, Any]) -> FieldType:
    # rosbags' Nodetype: BASE=1 (type, string bound), NAME=2, ARRAY=3 (element, size),
    # SEQUENCE=4 (element, bound, 0 for none).
    kind, detail = int(desc[0]), desc[1]
    if kind == 1:
        base, bound = detail
        return FieldType(base, bound or None)
    if kind == 2:
        return FieldType(detail)
    element = _rosbags_type(detail[0])
    if kind == 3:
        return FieldType(element.base, element.string_bound, "fixed", detail[1])
    if detail[1]:
        return FieldType(element.base, element.string_bound, "bounded", detail[1])
    return FieldType(element.base, element.string_bound, "unbounded")


def check_references(package: PackageSpec, exists: Callable[[str, str], bool]) -> None:
    """Every message a field names must exist: `exists(pkg, Name)` answers for other packages."""
    own = {m.name for m in package.messages}
    for msg in [*package.messages, *(p for s in package.services for p in (s.request, s.response))]:
        for f in msg.fields:
            if not f.type.is_message:
                continue
            pkg, _, name = f.type.base.split("/")
            if (pkg == package.name and name in own) or (pkg != package.name and exists(pkg, name)):
                continue
            hint = f" (did you mean {name.lower()}?)" if name.lower() in PRIMITIVES else ""
            raise InterfaceError(msg.path, f.line, f"field {f.name}: unknown message type {pkg}/msg/{name}{hint}")


# -- rendering ---------------------------------------------------------------------------------


def _str_literal(s: str) -> str:
    """A string literal quoted as ruff would: double quotes unless the text holds some."""
    r = repr(s)
    if r.startswith("'") and '"' not in s:
        r = '"' + r[1:-1].replace("\\'", "'") + '"'
    return r


def _literal(value: Any) -> str:
    if isinstance(value, str):
        return _str_literal(value)
    if isinstance(value, float) and not math.isfinite(value):
        return f'float("{value}")'
    if isinstance(value, list):
        return "[" + ", ".join(_literal(v) for v in value) + "]"
    return repr(value)


def _fits(text: str, indent: int) -> bool:
    return all(indent + len(line) <= LINE_LIMIT for line in text.split("\n"))


def _bracketed(head: str, items: list[str], tail: str, indent: int, *, is_tuple: bool = False) -> str:
    """`head(a, b)tail` on one line if it fits, else one item a line with a trailing comma:
    the two layouts ruff keeps as they are."""
    one = f"{head}{', '.join(items)}{',' if is_tuple and len(items) == 1 else ''}{tail}"
    if _fits(one, indent) or not items:
        return one
    return head + "\n" + "".join(f"    {item},\n" for item in items) + tail


def _assign(target: str, value: str, indent: int, parts: tuple[str, str, str] | None = None) -> str:
    """`target = value`, wrapped in parentheses as ruff does when too long; `parts` are the
    (body, condition, alternative) of a conditional value, split one a line if still too long."""
    one = f"{target} = {value}"
    if _fits(one, indent):
        return one
    if _fits(value, indent + 4) or parts is None:
        return f"{target} = (\n    {value}\n)"
    body, cond, alt = parts
    return f"{target} = (\n    {body}\n    if {cond}\n    else {alt}\n)"


def _conditional(body: str, cond: str, alt: str) -> tuple[str, tuple[str, str, str]]:
    return f"{body} if {cond} else {alt}", (body, cond, alt)


@dataclass
class _Names:
    """How the module being generated refers to message classes."""

    package: str
    kind: str  # "msg" or "srv"
    imports: set[str] = field(default_factory=set)

    def ref(self, type_name: str) -> str:
        pkg, _, name = type_name.split("/")
        if pkg == self.package and self.kind == "msg":
            return name
        self.imports.add(pkg)
        return f"_{pkg}.{name}"


def _element_annotation(t: FieldType, names: _Names) -> str:
    if t.is_message:
        return names.ref(t.base)
    if t.base in FLOATS:
        return "float"
    if t.base in INT_RANGES:
        return "int"
    if t.base in STRINGS:
        return "str"
    return "bool"


def _check(t: FieldType, name: str, names: _Names, v: str) -> tuple[str | None, str]:
    """The (fast condition or None, checking call) that validate value `v` for field `name`."""
    q = _str_literal(name)
    if t.array is not None:
        element = names.ref(t.base) if t.is_message else _str_literal(t.element)
        extra = f", size={t.size}" if t.array == "fixed" else f", bound={t.size}" if t.array == "bounded" else ""
        return None, f"_m.check_array({v}, self, {q}, {element}{extra})"
    if t.is_message:
        cls = names.ref(t.base)
        return f"{v}.__class__ is {cls}", f"_m.check_message({v}, self, {q}, {cls})"
    if t.base == "float64":
        return f"{v}.__class__ is float", f"_m.check_float64({v}, self, {q})"
    if t.base == "float32":
        fast = f"{v}.__class__ is float and -_FLOAT32_MAX <= {v} <= _FLOAT32_MAX"
        return fast, f"_m.check_float32({v}, self, {q})"
    if t.base in INT_RANGES:
        lo, hi = INT_RANGES[t.base]
        return f"{v}.__class__ is int and {lo} <= {v} <= {hi}", f'_m.check_int({v}, self, {q}, "{t.base}")'
    if t.base in STRINGS:
        if t.string_bound is not None:
            return None, f"_m.check_string({v}, self, {q}, {t.string_bound})"
        return f"{v}.__class__ is str", f"_m.check_string({v}, self, {q})"
    return f"{v}.__class__ is bool", f"_m.check_bool({v}, self, {q})"


def _scalar_default(t: FieldType) -> Any:
    if t.base in FLOATS:
        return 0.0
    if t.base in INT_RANGES:
        return 0
    if t.base in STRINGS:
        return ""
    return False


@dataclass
class FieldView:
    name: str
    annotation: str
    parameter: str  # "x: float = 0.0"
    init: str  # the statement(s) of __init__ that set it
    setter: str
    copy: str


@dataclass
class MessageView:
    name: str
    type_name: str
    constants: list[tuple[str, str]]
    fields_line: str
    slots_line: str
    init_def: str
    fields: list[FieldView]


def _field_view(f: FieldSpec, names: _Names) -> FieldView:
    t, name = f.type, f.name
    element = _element_annotation(t, names)
    annotation = element if t.array is None else f"list[{element}]"
    fast, check = _check(t, name, names, "value")
    setter_value, parts = _conditional("value", fast, check) if fast else (check, None)
    setter = _assign(f"self._{name}", setter_value, 8, parts)
    if t.array is None and not t.is_message:
        default = f.default if f.default is not None else _scalar_default(t)
        parameter = f"{name}: {annotation} = {_literal(default)}"
        init = _assign(f"self.{name}", name, 8)
        copy = _assign(f"new._{name}", f"self._{name}", 8)
    elif t.array is None:
        parameter = f"{name}: {annotation} = _DEFAULT"
        init = _assign(f"self.{name}", f"{element}() if {name} is _DEFAULT else {name}", 8)
        copy = _assign(f"new._{name}", f"self._{name}._copy()", 8)
    else:
        parameter = f"{name}: {annotation} = _DEFAULT"
        if f.default is not None:
            fresh = _literal(f.default)
        elif t.array != "fixed":
            fresh = "[]"
        elif t.is_message:
            fresh = f"_m.repeat({element}, {t.size})"
        else:
            fresh = f"[{_literal(_scalar_default(t))}] * {t.size}"
        _, init_check = _check(t, name, names, name)
        value, parts = _conditional(fresh, f"{name} is _DEFAULT", init_check)
        init = _assign(f"self._{name}", value, 8, parts)
        if t.is_message:
            copy = _assign(f"new._{name}", f"[item._copy() for item in self._{name}]", 8)
        else:
            copy = _assign(f"new._{name}", f"self._{name}.copy()", 8)
    return FieldView(name, annotation, parameter, init, setter, copy)


def _natural(name: str) -> list[Any]:
    """The order ruff's RUF023 wants for __slots__ (digits compare as numbers)."""
    return [int(part) if part.isdigit() else part for part in re.split(r"([0-9]+)", name)]


def _message_view(spec: MessageSpec, names: _Names) -> MessageView:
    fields = [_field_view(f, names) for f in spec.fields]
    pairs = [f"({_str_literal(f.name)}, {_str_literal(f.type.ros)})" for f in spec.fields]
    slots = [_str_literal(f"_{n}") for n in sorted((f.name for f in spec.fields), key=_natural)]
    init_def = _bracketed("def __init__(", ["self", "*", *(f.parameter for f in fields)], ") -> None:", 4)
    return MessageView(
        name=spec.name,
        type_name=spec.type_name,
        constants=[(c.name, _literal(c.value)) for c in spec.constants],
        fields_line=_bracketed("_FIELDS = (", pairs, ")", 4, is_tuple=True),
        slots_line=_bracketed("__slots__ = (", slots, ")", 4, is_tuple=True),
        init_def=init_def,
        fields=fields,
    )


@cache
def _env() -> jinja2.Environment:
    return environment(TEMPLATES, py=_literal)


def render_module(package: PackageSpec, kind: str, header: list[str]) -> str:
    """The source of llfsm.msgs.<pkg>.msg (kind "msg") or llfsm.msgs.<pkg>.srv."""
    names = _Names(package.name, kind)
    if kind == "msg":
        messages = [_message_view(m, names) for m in package.messages]
        services = []
    else:
        messages, services = [], []
        for s in package.services:
            messages += [_message_view(s.request, names), _message_view(s.response, names)]
            services.append((s.name, s.type_name))
    imports = sorted(names.imports)
    source = (
        _env()
        .get_template(TEMPLATE)
        .render(
            header=header,
            package=package.name,
            kind=kind,
            imports=imports,
            messages=messages,
            services=services,
        )
    )
    compile(source, f"<llfsm.msgs.{package.name}.{kind}>", "exec", dont_inherit=True)
    return source


def render_package(
    package: PackageSpec, header: list[str], lookup: Callable[[str], MessageSpec] | None = None
) -> dict[str, str]:
    """Relative path -> source, for the package's __init__.py, msg/__init__.py, srv/__init__.py,
    and their DDS forms msg/_dds.py, srv/_dds.py (llfsm.idl.ddsgen).  `lookup` finds the
    definition of a message of another package by type name; by default the installed message
    class tells it."""
    from . import ddsgen as dds

    out = {"__init__.py": "\n".join([*header, f'"""ROS interfaces of {package.name}: see .msg and .srv."""', ""])}
    find = lookup or installed_spec
    for kind, present in (("msg", package.messages), ("srv", package.services)):
        if present:
            out[f"{kind}/__init__.py"] = render_module(package, kind, header)
            out[f"{kind}/_dds.py"] = dds.render_dds_module(package, kind, find, header, _env())
    return out


def installed_spec(type_name: str) -> MessageSpec:
    """The definition of an importable message class, read back from its `_FIELDS` (how a
    user's package learns the layout of the messages it uses from other packages)."""
    import importlib

    pkg, kind, name = type_name.split("/")
    cls = getattr(importlib.import_module(f"llfsm.msgs.{pkg}.{kind}"), name)

    def fail(message: str) -> InterfaceError:
        return InterfaceError(type_name, None, message)

    fields = [FieldSpec(f, _parse_type(t, pkg, set(), fail)) for f, t in cls._FIELDS]
    return MessageSpec(type_name, fields, path=type_name)


# -- writing -----------------------------------------------------------------------------------


def write_atomic(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="\n") as f:
            f.write(text)
        os.chmod(tmp, 0o644)  # mkstemp's 0600 would hide committed modules from other users
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def builtin_packages() -> list[PackageSpec]:
    shipped = [
        read_package(d, source=d.relative_to(LLFSM_DIR.parent).as_posix())
        for d in sorted(SHIPPED_DIR.iterdir())
        if d.is_dir() and not d.name.startswith((".", "_"))
    ]
    packages = [standard_package(name) for name in STANDARD_PACKAGES] + shipped
    known = {(p.name, m.name) for p in packages for m in p.messages}
    for p in packages:
        check_references(p, lambda pkg, name: (pkg, name) in known)
    return packages


def builtin_sources() -> dict[Path, str]:
    """Every committed module under llfsm/msgs/, as regeneration produces it."""
    out: dict[Path, str] = {}
    packages = builtin_packages()
    specs = {m.type_name: m for p in packages for m in p.messages}
    for package in packages:
        # llfsm's own packages: the source is a path inside llfsm, not a user's; escaped all
        # the same, which leaves such a path as it is (so the committed modules do not change)
        header = [
            f"# Generated by llfsm from {comment_text(package.source)}: do not edit.",
            "# Regenerate with `python -m llfsm.idl.package` (make msgs).",
        ]
        for rel, text in render_package(package, header, specs.__getitem__).items():
            out[MSGS_DIR / package.name / rel] = text
    return out


def generate_builtins(check: bool = False) -> list[Path]:
    """Write the built-in modules that differ from regeneration; with `check`, only list them."""
    stale = []
    for path, text in builtin_sources().items():
        try:
            current = path.read_text(encoding="utf-8")
        except OSError:
            current = None
        if current != text:
            stale.append(path)
            if not check:
                write_atomic(path, text)
    return stale


def _exists_anywhere(pkg: str, name: str) -> bool:
    """A message that a user's package references: built in, or in the interface search path."""
    if (MSGS_DIR / pkg / "msg" / "__init__.py").exists():
        import importlib

        return hasattr(importlib.import_module(f"llfsm.msgs.{pkg}.msg"), name)
    from ..msgs import find_package

    where = find_package(pkg)
    return where is not None and (where / "msg" / f"{name}.msg").is_file()


def build_package(package_dir: Path, out_dir: Path, fingerprint: str) -> None:
    """Compile a user's interface package into `out_dir` (which must not exist yet): the import
    hook's compiler.  Raises InterfaceError (an ImportError) naming the file and line at fault."""
    package = read_package(package_dir)
    check_references(package, _exists_anywhere)
    # the folder is a user's: never on line 1 or 2 (PEP 263), and escaped onto one line
    header = header_lines(
        "Generated by llfsm from a package's .msg/.srv files: edit the definitions, not this file.",
        Fingerprint=fingerprint,
        Source=package_dir,
    )
    for rel, text in render_package(package, header).items():
        write_atomic(out_dir / rel, text)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m llfsm.idl.package",
        description="Regenerate llfsm's built-in message modules (llfsm/msgs/<pkg>/msg|srv).",
    )
    parser.add_argument("--check", action="store_true", help="only report stale modules (exit 1 if any)")
    args = parser.parse_args(argv)
    try:
        stale = generate_builtins(check=args.check)
    except InterfaceError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    except ModuleNotFoundError as e:
        if e.name != "rosbags":
            raise
        print("error: regenerating needs rosbags (pip install 'rosbags>=0.10')", file=sys.stderr)
        return 2
    root = LLFSM_DIR.parent
    for p in stale:
        print(f"{'stale' if args.check else 'wrote'}: {p.relative_to(root).as_posix()}")
    if not stale:
        print("built-in message modules are up to date")
    return 1 if args.check and stale else 0


if __name__ == "__main__":
    sys.exit(main())
