"""Rules on a machine's inputs (SPEC 11, docs/machine-format.md "Inputs"): each declaration is
a usable name of a known type with values of that type (LF047, LF048), a binding names a
message type and a field that exist and fit the input's type (LF049), and no code assigns an
input (LF046): an input is a snapshot of the world, read-only for the machine.

Message definitions are read as text (llfsm.lang.check.definitions): the shipped ones from the
folder they are generated from, a user's from the interface search path.  Nothing is imported.
"""

from __future__ import annotations

import ast
import math
from collections.abc import Iterator

from ...runtime.machine import MACROS, RESERVED
from ..bindings import find
from ..model import INPUT_TYPES, Code, Input, Loc, Machine, is_valid_name
from ..positions import char_col
from .checking import Checking
from .definitions import message_spec
from .variables import GENERATED_PREFIXES

#: The ROS field types each input type can take its value from.
_INTS = ("int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64", "byte", "char")
FIELD_TYPES: dict[str, tuple[str, ...]] = {
    "bool": ("bool",),
    "int": _INTS,
    "float": ("float32", "float64", *_INTS),
    "str": ("string", "wstring"),
}


def _where(i: Input, key: str) -> Loc:
    return i.locs.get(key, i.loc)


def declarations(c: Checking, m: Machine) -> None:
    """LF047, LF048, LF049 for every input machine.yaml declares."""
    names = {v.name for v in m.variables}
    state_vars = {v.name: s.name for s in m.states for v in s.variables}
    generated = {f"{p}{s.name}" for s in m.states for p in GENERATED_PREFIXES}
    for i in m.inputs:
        if not _name_ok(c, i, names, state_vars, generated):
            continue
        if i.type not in INPUT_TYPES:
            c.at("LF048", _where(i, "type"), f"input {i.name}: type {i.type!r} is not one of bool, int, float, str")
            continue
        _values(c, i)
        _binding(c, i)


def _name_ok(c: Checking, i: Input, names: set[str], state_vars: dict[str, str], generated: set[str]) -> bool:
    if not is_valid_name(i.name):
        c.at("LF047", i.loc, f"input name {i.name!r} must be a Python identifier and not a keyword")
    elif i.name in RESERVED or i.name in MACROS or i.name.startswith(("_llfsm", "__")) or i.name in generated:
        c.at("LF047", i.loc, f"input name {i.name!r} is reserved by llfsm; choose another name")
    elif i.name in names:
        c.at("LF047", i.loc, f"input {i.name} has the name of a machine variable; rename one of them")
    elif i.name in state_vars:
        c.at("LF047", i.loc, f"input {i.name} has the name of a variable of state {state_vars[i.name]}; rename one")
    else:
        return True
    return False


def _fits(value: object, kind: str) -> bool:
    """Whether a YAML value is a value of an input of type `kind` (an int is a float too; an
    infinity or NaN is no value a machine can be verified with)."""
    if kind == "float":
        return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)
    if kind == "int":
        return isinstance(value, int) and not isinstance(value, bool)
    return isinstance(value, INPUT_TYPES[kind])


def _values(c: Checking, i: Input) -> None:
    """LF048: the default and the domain hold values of the input's type; a domain is not empty
    and names no value twice."""
    if i.default is not None and not _fits(i.default, i.type):
        c.at(
            "LF048",
            _where(i, "default"),
            f"input {i.name}: default {i.default!r} is not a {i.type} (a {type(i.default).__name__})",
        )
    if i.domain is None:
        return
    if not i.domain:
        c.at("LF048", _where(i, "domain"), f"input {i.name}: the domain is empty; list the values verify explores")
        return
    seen: list[object] = []
    for v in i.domain:
        if not _fits(v, i.type):
            c.at("LF048", _where(i, "domain"), f"input {i.name}: domain value {v!r} is not a {i.type}")
            return
        if any(v == s and type(v) is type(s) for s in seen):
            c.at("LF048", _where(i, "domain"), f"input {i.name}: domain value {v!r} is listed twice")
            return
        seen.append(v)


def _binding(c: Checking, i: Input) -> None:
    """LF049: `topic`, `msg` and `field` come together; the message type exists (shipped, or
    in the interface search path) and has the field, of a type the input can hold."""
    given = [k for k in ("topic", "msg", "field") if getattr(i, k) is not None]
    if not given:
        return
    if len(given) < 3:
        missing = [k for k in ("topic", "msg", "field") if k not in given]
        c.at(
            "LF049",
            _where(i, given[0]),
            f"input {i.name}: a binding needs topic, msg and field together; add {', '.join(missing)}",
        )
        return
    assert i.msg is not None and i.field is not None and i.topic is not None
    if not _topic_ok(i.topic):
        c.at("LF049", _where(i, "topic"), f"input {i.name}: {i.topic!r} is not a valid topic name")
        return
    try:
        kind = field_type(i.msg, i.field)
    except LookupError as e:
        key, _, why = str(e.args[0]).partition(": ")
        c.at("LF049", _where(i, key), f"input {i.name}: {why}")
        return
    if kind not in FIELD_TYPES[i.type]:
        article = "an" if i.type == "int" else "a"
        c.at(
            "LF049",
            _where(i, "field"),
            f"input {i.name}: field {i.field} of {i.msg} is a {kind}, which {article} {i.type} input cannot hold",
        )


def _topic_ok(topic: str) -> bool:
    """ROS 2's rule for a topic name, roughly (the bus checks it exactly when the run starts)."""
    body = topic.removeprefix("~/").lstrip("/")
    parts = body.split("/")
    return bool(body) and all(p and (p[0].isalpha() or p[0] == "_") and p.replace("_", "").isalnum() for p in parts)


def field_type(msg: str, field: str) -> str:
    """The ROS type of `field` (dotted for a nested one) of message `msg` ("pkg/msg/Name"), from
    the definitions' text; LookupError says what is missing ("msg: ..." or "field: ...")."""
    # deferred: start-up (only a machine with an input bound to a message reads definitions)
    from ...idl.spec import InterfaceError

    parts = msg.split("/")
    if len(parts) != 3 or parts[1] != "msg":
        raise LookupError(f"msg: {msg!r} is not a message type (write pkg/msg/Name, e.g. std_msgs/msg/Bool)")
    current = msg
    path = field.split(".")
    for n, name in enumerate(path):
        try:
            spec = message_spec(current)
        except InterfaceError as e:
            raise LookupError(f"msg: the definition of {current} cannot be read: {e.message}") from None
        if spec is None:
            raise LookupError(f"msg: unknown message type {current} (not shipped, not in the interface search path)")
        found = next((f for f in spec.fields if f.name == name), None)
        if found is None:
            known = ", ".join(f.name for f in spec.fields) or "none"
            raise LookupError(f"field: {current} has no field {name!r} (its fields: {known})")
        if found.type.array is not None:
            raise LookupError(f"field: {'.'.join(path[: n + 1])} of {msg} is an array; an input holds one value")
        if n == len(path) - 1:
            return "message" if found.type.is_message else found.type.base
        if not found.type.is_message:
            raise LookupError(f"field: {'.'.join(path[: n + 1])} of {msg} is a {found.type.base}, not a message")
        current = found.type.base
    raise AssertionError("unreachable")  # pragma: no cover


def assignments(c: Checking, m: Machine) -> None:
    """LF046: code that assigns, augments, deletes, or changes an attribute or item of, an
    input where the name is the machine's input (a lambda parameter of the same name is the
    lambda's own)."""
    variables = {v.name for v in m.variables} | {v.name for s in m.states for v in s.variables}
    names = {i.name for i in m.inputs} - variables  # a clash is LF047 already
    if not names:
        return
    mapping = {n: f"self.{n}" for n in names}
    codes: list[Code] = [code for s in m.states for code in s.sections.values()]
    codes += [t.guard for s in m.states for t in s.transitions if t.guard is not None]
    codes += [code for code in (m.variables_file, *(s.variables_file for s in m.states)) if code is not None]
    for code in codes:
        tree = c.read.trees.get(code.file)
        if tree is None or not any(n in code.text for n in names):
            continue
        edits, _bad = find(tree, mapping)
        machine_uses = {(e.line, e.start) for e in edits}
        for node, how in _changes(tree):
            if (node.lineno, node.col_offset) in machine_uses:
                col = char_col(code.text, node.lineno, node.col_offset)
                c.add(
                    "LF046",
                    code.file,
                    node.lineno,
                    col,
                    f"{how} the input {node.id}: inputs are read-only (a snapshot taken at the start of each "
                    "ringlet); keep a value of your own in a variable",
                )


def _changes(tree: ast.AST) -> Iterator[tuple[ast.Name, str]]:
    """Each Name that is assigned, deleted, or whose attribute or item is assigned or deleted."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            yield node, "assigns"
        elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Del):
            yield node, "deletes"
        elif isinstance(node, ast.AugAssign) and isinstance(node.target, ast.Name):
            pass  # its target is a Store Name, reported above
        elif isinstance(node, ast.Attribute | ast.Subscript) and isinstance(node.ctx, ast.Store | ast.Del):
            base = node.value
            while isinstance(base, ast.Attribute | ast.Subscript):
                base = base.value
            if isinstance(base, ast.Name):
                yield base, "changes a part of"
