"""Breakpoints on states that cost nothing until they hit (docs/debug.md, "What it costs").

A breakpoint that reads nothing but one machine's state (`state(m) == "S"`, `state(m) in ("A",
"B")`) becomes true only when that machine takes a transition from a state where it is false
into one where it is true, or when a command (resume, restart) moves it so.  So instead of
judging it after every ringlet (the watcher, which costs the run several times its plain
speed), the debugger marks those transitions: the machine's ringlets are compiled again from
its generated module with a call after each marked transition (`_llfsm_trap(self, X, S)`,
where the generated code has just made S current: runtime/generated.py's contract), and the
machine becomes a variant of its class with them (`variant_class`, `become`, as the monitor's
checks are compiled in).  Every other
transition, and every ringlet of every other machine, runs the code it always ran.  Commands
are seen on the scheduler's rare path (`Arrangement.on_release`).

A module that is not Python source (a native build, `--native`) cannot be marked: such
breakpoints are judged by the watcher, as every other kind is.
"""

from __future__ import annotations

import ast
import sys
from collections.abc import Callable, Sequence
from typing import Any

from ..props.atoms import Atom
from ..runtime.generated import become, enter_ringlet, steady_ringlet, variant_class
from ..runtime.machine import Machine

#: The name of the call added after a marked transition.
TRAP = "_llfsm_trap"
#: What an atom's compiled tree may read for it to be a breakpoint on states alone.
_STATE_ONLY = frozenset({"STATES", "_state"})


class _Stub:
    """A machine for judging an atom on one state alone."""

    __slots__ = ("STATES", "_state")

    def __init__(self, states: tuple[str, ...], state: int) -> None:
        self.STATES = states
        self._state = state


def true_states(atom: Atom, classes: Sequence[type[Machine]]) -> tuple[int, frozenset[int]] | None:
    """(machine index, the states where it holds) of an atom that reads nothing but one machine's
    state, and never holds in its suspend state (a transition into that state is written
    otherwise); None for any other atom."""
    if atom.reads_published or len(atom.machines) != 1 or atom.tree is None:
        return None
    for node in ast.walk(atom.tree):
        if isinstance(node, ast.Attribute) and node.attr not in _STATE_ONLY:
            return None
        if isinstance(node, ast.Name) and node.id == "E":
            return None
    (i,) = atom.machines
    cls = classes[i]
    holds = set()
    for s in range(len(cls.STATES)):
        stubs: list[Any] = [None] * len(classes)
        stubs[i] = _Stub(cls.STATES, s)
        try:
            if atom.fn(stubs, ()):
                holds.add(s)
        except Exception:  # an atom that cannot be judged on a state alone: the watcher's
            return None
    if cls.SUSPENDED in holds:
        return None
    return i, frozenset(holds)


def _source_tree(cls: type[Machine]) -> ast.Module | None:
    module = sys.modules.get(cls.__module__)
    path = getattr(module, "__file__", None) or ""
    if not path.endswith(".py"):
        return None  # a native build: nothing to compile again
    try:
        with open(path, encoding="utf-8") as f:
            return ast.parse(f.read(), path)
    except (OSError, SyntaxError, ValueError):
        return None


class _Mark(ast.NodeTransformer):
    """After `self._run = <enter ringlet of S>` in a ringlet of state X, for each (X, S) wanted,
    a call `_llfsm_trap(self, X, S)`."""

    def __init__(self, source: int, targets: dict[str, int]) -> None:
        self.source = source
        self.targets = targets  # enter ringlet's name -> target state number

    def _body(self, body: list[ast.stmt]) -> list[ast.stmt]:
        out: list[ast.stmt] = []
        for stmt in body:
            out.append(self.visit(stmt))
            target = self._entered(stmt)
            if target is not None:
                call = ast.Call(
                    func=ast.Name(id=TRAP, ctx=ast.Load()),
                    args=[ast.Name(id="self", ctx=ast.Load()), ast.Constant(self.source), ast.Constant(target)],
                    keywords=[],
                )
                out.append(ast.copy_location(ast.Expr(value=call), stmt))
        return out

    def _entered(self, stmt: ast.stmt) -> int | None:
        if not (isinstance(stmt, ast.Assign) and len(stmt.targets) == 1):
            return None
        t, v = stmt.targets[0], stmt.value
        if isinstance(t, ast.Attribute) and t.attr == "_run" and isinstance(v, ast.Name):
            return self.targets.get(v.id)
        return None

    def generic_visit(self, node: ast.AST) -> ast.AST:
        for field in ("body", "orelse", "finalbody"):
            body = getattr(node, field, None)
            if isinstance(body, list) and body and isinstance(body[0], ast.stmt):
                setattr(node, field, self._body(body))
        for handler in getattr(node, "handlers", ()):
            self.generic_visit(handler)
        return node


#: What compiles the history into a machine's ringlets (History's side of recording.py): for a
#: machine, each ringlet node and its state to the node recording it, and what its namespace needs.
Recorder = Callable[[Machine], tuple[Callable[[ast.FunctionDef, int], ast.FunctionDef], dict[str, Any]]]


class Traps:
    """The machines given marked ringlets (and, with `recorder`, recording ones: the debugger's
    history), and how to give them back their own."""

    def __init__(self, hit: Callable[[Machine, int, int], None]) -> None:
        self.hit = hit
        self.own: dict[int, type[Machine]] = {}  # machine id -> its class before it was marked
        self.recorder: Recorder | None = None

    def mark(self, m: Machine, edges: set[tuple[int, int]]) -> bool:
        """Give `m` ringlets that call `hit(m, X, S)` after each transition X -> S of `edges`
        (its own back first), and that record themselves when there is a recorder; False if its
        module cannot be compiled again (native)."""
        self.unmark(m)
        if not edges and self.recorder is None:
            return True
        cls = type(m)
        tree = _source_tree(cls)
        if tree is None:
            return False
        states = cls.STATES
        wanted = {}  # ringlet name -> its source state
        for x, _ in edges:
            wanted[enter_ringlet(states[x])] = wanted[steady_ringlet(states[x])] = x
        record, extra = self.recorder(m) if self.recorder is not None else (None, {})
        ringlets = {}  # ringlet name -> its state, for the recorder: every state's but the suspend state's
        if record is not None:
            for s, name in enumerate(states):
                if s != cls.SUSPENDED:
                    ringlets[enter_ringlet(name)] = ringlets[steady_ringlet(name)] = s
        marked = []
        for node in tree.body:
            if isinstance(node, ast.FunctionDef) and (node.name in wanted or node.name in ringlets):
                if node.name in wanted:
                    x = wanted[node.name]
                    targets = {enter_ringlet(states[s]): s for src, s in edges if src == x}
                    node = _Mark(x, targets).visit(node)
                if record is not None and node.name in ringlets:
                    node = record(node, ringlets[node.name])
                marked.append(node)
        namespace = dict(vars(sys.modules[cls.__module__]))
        namespace[TRAP] = self.hit
        namespace.update(extra)
        module = ast.fix_missing_locations(ast.Module(body=marked, type_ignores=[]))
        exec(compile(module, tree_file(cls), "exec", dont_inherit=True), namespace)  # the marked ringlets
        become(m, variant_class(cls, namespace, {node.name: namespace[node.name] for node in marked}))
        self.own[m._id] = cls
        return True

    def unmark(self, m: Machine) -> None:
        cls = self.own.pop(m._id, None)
        if cls is not None:
            become(m, cls)


def tree_file(cls: type[Machine]) -> str:
    module = sys.modules.get(cls.__module__)
    return str(getattr(module, "__file__", "") or f"<{cls.NAME}>")
