"""Reading a paused machine, and setting its variables and inputs (docs/debug.md, "Reading and
setting").

A machine reads as a mapping: its state, the command pending for its next ringlet, its time in
state (run time), its variables and its inputs, as plain values (llfsm.runtime.readout), which
print as YAML.  A set takes YAML text (`3`, `2.5`, `true`, `hello`, `[1, 2]`, `{x: 1.0}`), checks
it against the variable's annotation in Variables.py (or the input's type in machine.yaml), and
refuses with one line what does not fit: an unknown name, a value of another type, an input
bound to a topic (its value comes from there).  Only a paused run is changed, between ringlets,
so a ringlet never sees a value change under it.
"""

from __future__ import annotations

import ast
import difflib
import sys
import typing
from typing import Any

import yaml

from ..msgs._message import is_message_class
from ..msgs._yaml import ValuesError, set_fields
from ..runtime.generated import inputs_of, pending_of, state_of, time_in_state, variables_of
from ..runtime.inputs import TOPIC, TYPE
from ..runtime.machine import Machine
from ..runtime.readout import plain, values_of, variable_names


class SetError(ValueError):
    """A set that is refused: one line saying why (the run goes on)."""


def read(m: Machine, now: int, entered: int | None = None) -> dict[str, Any]:
    """What `m` holds now, as plain values.  `entered`: the run time its current state was
    entered, when the caller followed it (the debugger's history), for a state that keeps none."""
    cls = type(m)
    since = time_in_state(m, now)
    if since is None and entered is not None:
        since = max(0, now - entered)
    return {
        "state": state_of(m),
        "status": "finished" if m._finished else "suspended" if m._suspended else "running",
        "pending": pending_of(m),
        "time_in_state": None if since is None else round(since / 1e9, 9),
        "variables": values_of(m, variable_names(cls)),
        "inputs": values_of(m, inputs_of(cls)),
    }


def as_yaml(data: Any) -> str:
    """Plain data as block YAML, in the order given."""
    return str(yaml.safe_dump(data, sort_keys=False, default_flow_style=False, allow_unicode=True, width=100))


def parse_value(text: str) -> Any:
    """A value typed by a person: YAML (SetError when it is not)."""
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as e:
        problem = getattr(e, "problem", None) or str(e).splitlines()[0]
        raise SetError(f"not a value: {text!r} ({problem}); write YAML, such as 3, 2.5, true, hello, [1, 2]") from None
    except RecursionError:
        raise SetError("not a value: it nests too deeply") from None


def assign(m: Machine, name: str, text: str) -> Any:
    """Set `m`'s variable or input `name` to the value `text` says, typed; returns the value set
    (SetError, with the reason, when it is refused)."""
    cls = type(m)
    value = parse_value(text)
    inputs = {entry[0]: (k, entry) for k, entry in enumerate(cls.INPUTS)}
    if name in inputs:
        k, entry = inputs[name]
        if entry[TOPIC] is not None:
            raise SetError(
                f"{m.NAME}.{name} is an input bound to {entry[TOPIC]}: its value comes from there "
                f"(publish on {entry[TOPIC]} to change it)"
            )
        typed = _check(name, m, entry[TYPE], value, {})
        if m._inputs is not None:
            m._inputs.values[k] = typed
        setattr(m, name, typed)
        return typed
    annotations = dict(variables_of(cls))
    if name not in annotations:
        known = list(variable_names(cls)) + list(inputs)
        close = difflib.get_close_matches(name, known, n=1)
        hint = f" (did you mean {m.NAME}.{close[0]}?)" if close else ""
        raise SetError(f"{m.NAME} has no variable or input {name}{hint}; it has: {', '.join(known) or 'none'}")
    module = sys.modules.get(cls.__module__)
    typed = _check(name, m, annotations[name], value, vars(module) if module is not None else {})
    setattr(m, name, typed)
    return typed


def _check(name: str, m: Machine, annotation: str, value: Any, namespace: dict[str, Any]) -> Any:
    try:
        return typed(annotation, value, namespace)
    except TypeError as e:
        raise SetError(f"{m.NAME}.{name} is {annotation}: {e}") from None


def typed(annotation: str, value: Any, namespace: dict[str, Any]) -> Any:
    """`value` (plain data, as YAML gives it) as a value of the type `annotation` names, or
    TypeError saying why not.  Understood: bool, int, float (an int is taken), str, None,
    unions (`X | None`, Optional, Union), list, tuple, set, dict (with item types or not),
    Any and object, and message classes (a mapping of fields).  Anything else (a node, a
    publisher, a class of the user's) cannot be typed from text."""
    try:
        tree = ast.parse(annotation, mode="eval").body
    except SyntaxError:
        raise TypeError("an annotation the debugger cannot read") from None
    return _typed(tree, value, namespace)


_SIMPLE: dict[str, type] = {"bool": bool, "int": int, "float": float, "str": str}
_ANY = ("Any", "object", "typing.Any")


def _describe(value: Any) -> str:
    shown = repr(plain(value))
    return f"{shown if len(shown) <= 40 else shown[:40] + '…'} is {_kind(value)}"


def _kind(value: Any) -> str:
    if value is None:
        return "null"
    return {bool: "a bool", int: "an int", float: "a float", str: "a string", list: "a list", dict: "a mapping"}.get(
        type(value), f"a {type(value).__name__}"
    )


def _typed(node: ast.expr, value: Any, ns: dict[str, Any]) -> Any:
    text = ast.unparse(node)
    if isinstance(node, ast.Constant) and node.value is None:
        if value is None:
            return None
        raise TypeError(f"{_describe(value)}, not null")
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.BitOr):
        return _union([node.left, node.right], value, ns)
    if isinstance(node, ast.Subscript):
        return _generic(node, value, ns)
    if text in _ANY:
        return value
    simple = _SIMPLE.get(text)
    if simple is not None:
        if simple is float and type(value) is int:
            return float(value)
        if type(value) is not simple:
            raise TypeError(f"{_describe(value)}, not {_kind(simple())}")
        return value
    if text in ("list", "List", "tuple", "Tuple", "set", "Set", "dict", "Dict"):
        return _container(text.lower(), value, None, ns)
    cls = _resolve(text, ns)
    if isinstance(cls, type) and is_message_class(cls):
        if isinstance(value, cls):
            return value
        if not isinstance(value, dict):
            raise TypeError(f"{_describe(value)}, not a mapping of {cls._TYPE}'s fields, such as {{x: 1.0}}")
        msg = cls()
        try:
            set_fields(msg, value)
        except (ValuesError, TypeError, ValueError) as e:
            raise TypeError(str(e)) from None
        return msg
    raise TypeError(f"a value of this type cannot be typed in the debugger (set {text} in the machine's code)")


def _union(options: list[ast.expr], value: Any, ns: dict[str, Any]) -> Any:
    reasons = []
    for option in options:
        try:
            return _typed(option, value, ns)
        except TypeError as e:
            reasons.append(str(e))
    raise TypeError(reasons[-1] if len(set(reasons)) == 1 else f"{_describe(value)}, which fits none of its types")


def _generic(node: ast.Subscript, value: Any, ns: dict[str, Any]) -> Any:
    base = ast.unparse(node.value).removeprefix("typing.")
    args = list(node.slice.elts) if isinstance(node.slice, ast.Tuple) else [node.slice]
    if base == "Optional":
        return _union([*args, ast.Constant(None)], value, ns)
    if base == "Union":
        return _union(args, value, ns)
    if base.lower() in ("list", "tuple", "set", "dict", "sequence", "mapping"):
        kind = {"sequence": "list", "mapping": "dict"}.get(base.lower(), base.lower())
        return _container(kind, value, args, ns)
    raise TypeError(
        f"a value of this type cannot be typed in the debugger (set {ast.unparse(node)} in the machine's code)"
    )


def _container(kind: str, value: Any, args: list[ast.expr] | None, ns: dict[str, Any]) -> Any:
    if kind == "dict":
        if not isinstance(value, dict):
            raise TypeError(f"{_describe(value)}, not a mapping")
        if not args or len(args) != 2:
            return dict(value)
        return {_typed(args[0], k, ns): _typed(args[1], v, ns) for k, v in value.items()}
    if not isinstance(value, list):
        raise TypeError(f"{_describe(value)}, not a list")
    if kind == "tuple" and args:
        if len(args) == 2 and isinstance(args[1], ast.Constant) and args[1].value is Ellipsis:
            return tuple(_typed(args[0], v, ns) for v in value)
        if len(args) != len(value):
            raise TypeError(f"{_describe(value)}, not {len(args)} items")
        return tuple(_typed(a, v, ns) for a, v in zip(args, value, strict=True))
    items = [_typed(args[0], v, ns) for v in value] if args else list(value)
    return {"list": list, "tuple": tuple, "set": set}[kind](items)


def _resolve(dotted: str, ns: dict[str, Any]) -> Any:
    """What a dotted annotation names in the machine module's globals (None if nothing)."""
    first, *rest = dotted.split(".")
    obj = ns.get(first, typing if first == "typing" else None)
    for part in rest:
        obj = getattr(obj, part, None)
    return obj
