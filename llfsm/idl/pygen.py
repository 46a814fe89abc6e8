"""The Python generator: a package's messages (or services, or actions) as the classes of one
module, llfsm.msgs.<pkg>.msg, .srv or .action, shaped as rclpy's (docs/bus.md, "Messages";
docs/actions.md).

Each field is a property whose setter takes a fast path inline (`value if value.__class__ is
float else _m.check_float64(...)`) and calls the checks of llfsm.msgs._message only for values
to convert or refuse; `_copy()` is a field-by-field deep copy the bus takes at publish time.
The module is laid out by llfsm.idl.codeformat and written through the template msgs.py.j2.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from ..msgs._message import INT_RANGES
from .codeformat import Call, assign, bracketed, conditional, literal, str_literal
from .spec import FLOATS, STRINGS, FieldSpec, FieldType, MessageSpec, PackageSpec

if TYPE_CHECKING:
    import jinja2

    from .spec import Scalar

TEMPLATE = "msgs.py.j2"


@dataclass
class _Names:
    """How the module being generated refers to message classes, and which of its module-level
    aliases its code uses (only those are written)."""

    package: str
    kind: str  # "msg", "srv" or "action"
    imports: set[str] = field(default_factory=set)
    uses: set[str] = field(default_factory=set)  # "_DEFAULT", "_FLOAT32_MAX"

    def ref(self, type_name: str) -> str:
        """A class of this module by its name; a message of another module (always a msg: a
        field holds a message, and an action's derived types hold its own sections) through
        that package's msg module."""
        pkg, kind, name = type_name.split("/")
        if pkg == self.package and kind == self.kind:
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


def _check(t: FieldType, name: str, names: _Names, v: str) -> tuple[str | None, str | Call]:
    """The (fast condition or None, checking call) that validate value `v` for field `name`."""
    q = str_literal(name)
    if t.array is not None:
        element = names.ref(t.base) if t.is_message else str_literal(t.element)
        extra = [f"size={t.size}"] if t.array == "fixed" else [f"bound={t.size}"] if t.array == "bounded" else []
        return None, Call("_m.check_array", [v, "self", q, element, *extra])
    if t.is_message:
        cls = names.ref(t.base)
        return f"{v}.__class__ is {cls}", f"_m.check_message({v}, self, {q}, {cls})"
    if t.base == "float64":
        return f"{v}.__class__ is float", f"_m.check_float64({v}, self, {q})"
    if t.base == "float32":
        names.uses.add("_FLOAT32_MAX")
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


def _scalar_default(t: FieldType) -> Scalar:
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
    setter_value, parts = conditional("value", fast, check) if fast else (check, None)
    setter = assign(f"self._{name}", setter_value, 8, parts)
    if t.array is None and not t.is_message:
        default = f.default if f.default is not None else _scalar_default(t)
        parameter = f"{name}: {annotation} = {literal(default)}"
        init = assign(f"self.{name}", name, 8)
        copy = assign(f"new._{name}", f"self._{name}", 8)
        return FieldView(name, annotation, parameter, init, setter, copy)
    # a nested message or an array: built afresh for each instance, so the default is a marker
    names.uses.add("_DEFAULT")
    parameter = f"{name}: {annotation} = _DEFAULT"
    if t.array is None:
        init = assign(f"self.{name}", f"{element}() if {name} is _DEFAULT else {name}", 8)
        copy = assign(f"new._{name}", f"self._{name}._copy()", 8)
        return FieldView(name, annotation, parameter, init, setter, copy)
    if f.default is not None:
        fresh = literal(f.default)
    elif t.array != "fixed":
        fresh = "[]"
    elif t.is_message:
        fresh = f"_m.repeat({element}, {t.size})"
    else:
        fresh = f"[{literal(_scalar_default(t))}] * {t.size}"
    _, init_check = _check(t, name, names, name)
    value, parts = conditional(fresh, f"{name} is _DEFAULT", init_check)
    init = assign(f"self._{name}", value, 8, parts)
    if t.is_message:
        copy = assign(f"new._{name}", f"[item._copy() for item in self._{name}]", 8)
    else:
        copy = assign(f"new._{name}", f"self._{name}.copy()", 8)
    return FieldView(name, annotation, parameter, init, setter, copy)


def _natural(name: str) -> list[int | str]:
    """The order ruff's RUF023 wants for __slots__ (digits compare as numbers)."""
    return [int(part) if part.isdigit() else part for part in re.split(r"([0-9]+)", name)]


def _message_view(spec: MessageSpec, names: _Names) -> MessageView:
    fields = [_field_view(f, names) for f in spec.fields]
    pairs = [f"({str_literal(f.name)}, {str_literal(f.type.ros)})" for f in spec.fields]
    slots = [str_literal(f"_{n}") for n in sorted((f.name for f in spec.fields), key=_natural)]
    init_def = bracketed("def __init__(", ["self", "*", *(f.parameter for f in fields)], ") -> None:", 4)
    return MessageView(
        name=spec.name,
        type_name=spec.type_name,
        constants=[(c.name, literal(c.value)) for c in spec.constants],
        fields_line=bracketed("_FIELDS = (", pairs, ")", 4, is_tuple=True),
        slots_line=bracketed("__slots__ = (", slots, ")", 4, is_tuple=True),
        init_def=init_def,
        fields=fields,
    )


def render_module(package: PackageSpec, kind: str, header: list[str], env: jinja2.Environment) -> str:
    """The source of llfsm.msgs.<pkg>.msg (kind "msg"), .srv or .action.  An action module holds
    every message of its actions, then their two services, then the action classes, whose
    `Impl` also names action_msgs' cancel service and status array (what rclpy's `Impl` has)."""
    names = _Names(package.name, kind)
    services: list[tuple[str, str]] = []  # (name, type name)
    actions: list[tuple[str, str]] = []
    imports: list[tuple[str, str]] = []
    if kind == "msg":
        messages = [_message_view(m, names) for m in package.messages]
    elif kind == "srv":
        messages = []
        for s in package.services:
            messages += [_message_view(part, names) for part in s.parts]
            services.append((s.name, s.type_name))
    else:
        messages = []
        for a in package.actions:
            messages += [_message_view(m, names) for m in a.messages]
            services += [(s.name, s.type_name) for s in a.services]
            actions.append((a.name, a.type_name))
        names.imports.add("action_msgs")
        imports.append(("llfsm.msgs.action_msgs.srv", "_action_msgs_srv"))
    imports += [(f"llfsm.msgs.{pkg}.msg", f"_{pkg}") for pkg in names.imports]
    source = env.get_template(TEMPLATE).render(
        header=header,
        package=package.name,
        kind=kind,
        imports=sorted(imports),
        uses=names.uses,
        messages=messages,
        services=services,
        actions=actions,
    )
    compile(source, f"<llfsm.msgs.{package.name}.{kind}>", "exec", dont_inherit=True)
    return source
