"""LF051: a field a message does not have, on a variable of a message type (`msg: Twist =
Twist()` in Variables.py, then `msg.linear.X = 2.0`).  Generated message classes have slots, so
the typo passes `ast.parse` and stops the machine with an AttributeError when the line runs.

What a variable holds is known from its annotation (machine and state variables, a section's
annotated local) or, for a section's local, from the one constructor call that binds it
(`message = String()`, the how-to's habit), resolved through the imports of Includes.py and
of the file itself.  Fields come from the definitions' text (llfsm.lang.check.definitions):
nothing is imported.  A name that a function, lambda, class or comprehension binds again is
that scope's own and left alone.
"""

from __future__ import annotations

import ast
import os
from collections.abc import Iterator, Mapping
from typing import TYPE_CHECKING

from ...interface_path import folders_around
from ..model import Code, Machine, State
from ..positions import char_col
from ..scopes import child_nodes
from .checking import Checking
from .definitions import message_spec

if TYPE_CHECKING:
    from ...idl.spec import MessageSpec

MSGS = "llfsm.msgs"
#: The sections of a service's or an action's type that are messages (`Spawn.Request`).
_SECTIONS = {"srv": ("Request", "Response"), "action": ("Goal", "Result", "Feedback")}
#: What every message has besides its fields and constants (llfsm.msgs._message.Message).
_MEMBERS = frozenset({"to_dict", "get_fields_and_field_types"})
#: Nodes with a scope of their own: a name they bind is theirs, not the section's.
_NESTED = frozenset(
    {ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef, ast.ListComp, ast.SetComp, ast.DictComp}
    | {ast.GeneratorExp}
)
#: At most this many fields are listed after "its fields:".
LISTED = 12


def imported_paths(tree: ast.Module | None) -> dict[str, str]:
    """What the top-level imports of a file bind, as dotted paths: `Twist` ->
    `llfsm.msgs.geometry_msgs.msg.Twist`, `gm` -> `llfsm.msgs.geometry_msgs.msg`."""
    out: dict[str, str] = {}
    for stmt in tree.body if tree is not None else ():
        if isinstance(stmt, ast.ImportFrom) and not stmt.level and stmt.module:
            for a in stmt.names:
                out[a.asname or a.name] = f"{stmt.module}.{a.name}"
        elif isinstance(stmt, ast.Import):
            for a in stmt.names:
                if a.asname:
                    out[a.asname] = a.name
                else:
                    top = a.name.split(".")[0]
                    out[top] = top
    return out


def _dotted(node: ast.expr) -> list[str] | None:
    parts: list[str] = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if not isinstance(node, ast.Name):
        return None
    parts.append(node.id)
    return parts[::-1]


def message_type(node: ast.expr, paths: Mapping[str, str]) -> str | None:
    """The message type (`pkg/msg/Name`, `pkg/srv/Name_Request`) an annotation or a called
    class names through `paths`, or None (not a message, or not known)."""
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.BitOr):  # `Twist | None`
        for side, other in ((node.left, node.right), (node.right, node.left)):
            if isinstance(other, ast.Constant) and other.value is None:
                return message_type(side, paths)
        return None
    if isinstance(node, ast.Subscript) and _dotted(node.value) in (["Optional"], ["typing", "Optional"]):
        return message_type(node.slice, paths)
    parts = _dotted(node)
    if parts is None or parts[0] not in paths:
        return None
    full = [*paths[parts[0]].split("."), *parts[1:]]
    if full[:2] != MSGS.split(".") or len(full) < 5:
        return None
    pkg, kind, name, *rest = full[2:]
    if kind == "msg" and not rest:
        return f"{pkg}/msg/{name}"
    if kind in _SECTIONS and len(rest) == 1 and rest[0] in _SECTIONS[kind]:
        return f"{pkg}/{kind}/{name}_{rest[0]}"
    if kind in _SECTIONS and not rest and name.rpartition("_")[2] in _SECTIONS[kind]:
        return f"{pkg}/{kind}/{name}"  # `from llfsm.msgs.std_srvs.srv import Trigger_Request`
    return None


def _annotated(variables: list, paths: Mapping[str, str]) -> dict[str, str]:  # type: ignore[type-arg]
    out = {}
    for v in variables:
        if "." in v.annotation or v.annotation in paths or "|" in v.annotation or "[" in v.annotation:
            try:
                node = ast.parse(v.annotation, mode="eval").body
            except (SyntaxError, ValueError, RecursionError, MemoryError):
                continue
            t = message_type(node, paths)
            if t is not None:
                out[v.name] = t
    return out


def _locals(tree: ast.Module, paths: Mapping[str, str]) -> dict[str, str]:
    """A section's own message-typed names: annotated at its top level, or bound only by calls
    of one message class there (`message = String()`), never otherwise."""
    out: dict[str, str] = {}
    spoilt: set[str] = set()
    typed_targets: set[int] = set()
    for stmt in tree.body:
        if isinstance(stmt, ast.AnnAssign) and isinstance(stmt.target, ast.Name):
            node, target = stmt.annotation, stmt.target
        elif isinstance(stmt, ast.Assign) and len(stmt.targets) == 1 and isinstance(stmt.value, ast.Call):
            node, target = stmt.value.func, stmt.targets[0]  # type: ignore[assignment]
        else:
            continue
        t = message_type(node, paths) if isinstance(target, ast.Name) else None
        if t is None:
            continue
        if out.setdefault(target.id, t) != t:
            spoilt.add(target.id)
        typed_targets.add(id(target))
    if out:  # any other binding of such a name (a loop, `with`, another value): it may hold anything
        for n in ast.walk(tree):
            if (
                isinstance(n, ast.Name)
                and not isinstance(n.ctx, ast.Load)
                and n.id in out
                and id(n) not in typed_targets
            ):
                spoilt.add(n.id)
    return {k: v for k, v in out.items() if k not in spoilt}


def _bound(node: ast.AST) -> set[str]:
    """Every name a nested scope binds (over-approximated: what it binds anywhere inside)."""
    out = set()
    for n in ast.walk(node):
        if isinstance(n, ast.Name) and not isinstance(n.ctx, ast.Load):
            out.add(n.id)
        elif isinstance(n, ast.arg):
            out.add(n.arg)
        elif isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            out.add(n.name)
    return out


def chains(tree: ast.AST, names: Mapping[str, str]) -> Iterator[tuple[str, list[ast.Attribute]]]:
    """Each attribute chain on one of `names` (`msg.linear.x`: msg, [.linear, .x]), where the
    name is the section's, not a nested scope's own."""
    stack: list[tuple[ast.AST, frozenset[str]]] = [(tree, frozenset())]
    attribute, nested = ast.Attribute, _NESTED
    while stack:
        node, hidden = stack.pop()
        t = type(node)
        if t is attribute:
            chain: list[ast.Attribute] = []
            root = node
            while isinstance(root, attribute):
                chain.append(root)
                root = root.value
            if isinstance(root, ast.Name) and root.id in names and root.id not in hidden:
                yield root.id, chain[::-1]
                continue
        elif t in nested:
            hidden = hidden | _bound(node)
        stack.extend((child, hidden) for child in child_nodes(node))


def message_fields(c: Checking, m: Machine, s: State, code: Code, tree: ast.Module) -> None:
    """LF051 for one section or guard of state `s`.  Every file of every machine comes here, so
    a file that no import of a message reaches costs a few lookups."""
    if c.message_paths is None:  # once per machine
        c.message_paths = _of_messages(imported_paths(c.read.trees.get("Includes.py")))
        c.message_variables = _annotated(m.variables, c.message_paths)
    text, paths = code.text, c.message_paths
    if "import" in text:
        paths = {**paths, **_of_messages(imported_paths(tree))}
    if not paths:
        return  # nothing here can name a message type
    typed = {k: v for k, v in (c.message_variables or {}).items() if f"{k}." in text}
    if s.variables:
        typed.update((k, v) for k, v in _annotated(s.variables, paths).items() if f"{k}." in text)
    if "=" in text:
        typed.update((k, v) for k, v in _locals(tree, paths).items() if f"{k}." in text)
    if not typed:
        return
    if c.interface_roots is None:  # where `llfsm run` finds a user's packages (as LF042 looks)
        c.interface_roots = folders_around(os.fspath(c.path))
    for name, chain in chains(tree, typed):
        _check_chain(c, code, name, typed[name], chain)


def _of_messages(paths: dict[str, str]) -> dict[str, str]:
    """The imports that may lead to a message type: of llfsm.msgs, or of llfsm itself."""
    return {k: v for k, v in paths.items() if v == "llfsm" or v.startswith(MSGS)}


def _spec(c: Checking, type_name: str) -> MessageSpec | None:
    """The definition, looked up once per machine (a definition that cannot be read: None; the
    import reports it, or the run)."""
    if type_name not in c.message_specs:
        try:
            c.message_specs[type_name] = message_spec(type_name, c.interface_roots or ())
        except ImportError:
            c.message_specs[type_name] = None
    spec: MessageSpec | None = c.message_specs[type_name]
    return spec


def _check_chain(c: Checking, code: Code, name: str, type_name: str, chain: list[ast.Attribute]) -> None:
    current = type_name
    for n, node in enumerate(chain):
        spec = _spec(c, current)
        if spec is None or node.attr.startswith("_") or node.attr in _MEMBERS:
            return
        found = next((f for f in spec.fields if f.name == node.attr), None)
        if found is None:
            if any(k.name == node.attr for k in spec.constants):
                return
            fields = [f.name for f in spec.fields]
            listed = ", ".join(fields[:LISTED]) + (", ..." if len(fields) > LISTED else "") or "none"
            written = ".".join([name, *(a.attr for a in chain[: n + 1])])
            line = node.end_lineno or node.lineno
            col = char_col(code.text, line, (node.end_col_offset or 0) - len(node.attr.encode()))
            c.add(
                "LF051",
                code.file,
                line,
                col,
                f"`{written}`: {current} has no field {node.attr!r}{c.suggest.alike(node.attr, fields)}; "
                f"its fields: {listed}",
            )
            return
        if not found.type.is_message or found.type.array is not None:
            return  # a number, a string or a list: Python's own attributes from here
        current = found.type.base
