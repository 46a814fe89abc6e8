"""The lifetime of what machine code creates on the bus: a node, publisher, subscription,
service, client or timer that machine code held and holds no more is destroyed and leaves the
graph, as rclpy's garbage collection and clfsm's `shared_ptr` do.  See docs/bus.md (Lifetimes).

Why not Python's own garbage collection: the bus, the executor and a transport hold every entity
(a topic lists its readers, the executor its timers, DDS its endpoints), and a node and its
entities point at each other, so nothing would ever be freed by reference counts alone, and a
cycle collection runs whenever the interpreter decides: not deterministic under `--clock sim`.
So the owners are the machines' variables.  Between rounds, and only after a round in which
something was created, a machine finished or was restarted, the bus walks what the running
machines' variables reach (into lists, tuples, sets, dicts and plain objects).  What a walk once
found and a later walk does not is destroyed: a node together with its entities, an entity on
its own.  A node is held through any entity of it that is held.  What machine code never kept
in a variable (`node.create_subscription(...)` whose result is dropped, as rclpy code often
does) lives as long as its node, as in rclpy, whose node keeps its entities.
"""

from __future__ import annotations

from collections import deque
from types import BuiltinFunctionType, FunctionType, MethodType, ModuleType
from typing import TYPE_CHECKING, Any

from ..msgs._message import Message
from ..runtime.machine import Machine

if TYPE_CHECKING:
    from .bus import Bus, GraphNode

#: Values with nothing inside them to walk into.
_LEAVES = (
    str,
    bytes,
    bytearray,
    int,
    float,
    complex,
    bool,
    type(None),
    type,
    ModuleType,
    FunctionType,
    BuiltinFunctionType,
    MethodType,
    Message,
)
#: A walk stops after this many objects (a machine holding a huge structure keeps what lies beyond).
WALK_LIMIT = 100_000


class Lifetimes:
    """The bus's record of what the machines' variables hold (see the module docstring)."""

    def __init__(self, bus: Bus) -> None:
        self.bus = bus
        #: Something was created since the last look: look after this round.
        self.dirty = False
        #: What the last look found held, by id: nodes and entities.
        self.held: dict[int, object] = {}

    def created(self) -> None:
        """A node or entity was made: look after this round whether anything was dropped."""
        self.dirty = True
        self.bus.ctx.wake = 0

    def collect(self) -> None:
        """Between rounds: destroy what was held and is held no more; then, with what is left,
        say once of each node name that two nodes of the run share (Bus.same_names)."""
        ctx = self.bus.ctx
        if not (self.dirty or ctx.references_dropped):
            return
        self.dirty = ctx.references_dropped = False
        self._collect(ctx)
        self.bus.same_names()

    def _collect(self, ctx: Any) -> None:
        arr = ctx.arrangement
        if arr is None:
            return
        nodes = {id(n): n for n in self.bus.nodes if not n._destroyed}
        owner: dict[int, GraphNode] = {}
        for n in nodes.values():
            for e in n._entities:
                owner[id(e)] = n
        if not owner and not self.held and not nodes:
            return
        roots: list[object] = []
        for m in arr.machines:
            if not m._finished:
                roots.extend(_variables(m))
        held = _reach(roots, nodes, owner)
        dropped = [obj for key, obj in self.held.items() if key not in held]
        self.held = held
        for obj in dropped:
            node = nodes.get(id(obj))
            if node is not None:
                if not node._destroyed:
                    node.destroy_node()  # type: ignore[attr-defined]  # llfsm.ros.node.Node
                continue
            parent = owner.get(id(obj))
            if parent is not None and not parent._destroyed and id(parent) in held:
                parent._destroy_entity(obj)  # type: ignore[attr-defined]  # llfsm.ros.node.Node


def _attributes(cls: type) -> tuple[str, ...]:
    """The instance attributes a class declares: its `__slots__`, or, for a class compiled by
    mypyc (`--native`), which keeps no `__slots__`, the `__mypyc_attrs__` mypyc lists instead."""
    d = cls.__dict__
    names = d.get("__slots__") or d.get("__mypyc_attrs__") or ()
    return (names,) if isinstance(names, str) else tuple(names)


def _variables(m: object) -> list[object]:
    """The values of a machine's own variables (its class's attributes beyond the base class's,
    and a __dict__ if it has one)."""
    base = set(_attributes(Machine))
    out: list[object] = []
    for cls in type(m).__mro__:
        for name in _attributes(cls):
            if name not in base and hasattr(m, name):
                out.append(getattr(m, name))
    d = getattr(m, "__dict__", None)
    if d:
        out.extend(d.values())
    return out


def _reach(roots: list[object], nodes: dict[int, Any], owner: dict[int, Any]) -> dict[int, object]:
    """The nodes and entities the roots reach: an entity counts for its node too."""
    held: dict[int, object] = {}
    seen: set[int] = set()
    todo = deque(roots)
    while todo and len(seen) < WALK_LIMIT:
        o = todo.pop()
        key = id(o)
        if key in seen or isinstance(o, _LEAVES):
            continue
        seen.add(key)
        if key in nodes:
            held[key] = o
            continue
        parent = owner.get(key)
        if parent is not None:
            held[key] = o
            held[id(parent)] = parent
            continue
        if isinstance(o, (list, tuple, set, frozenset, deque)):
            todo.extend(o)
        elif isinstance(o, dict):
            todo.extend(o.keys())
            todo.extend(o.values())
        else:
            d = getattr(o, "__dict__", None)
            if isinstance(d, dict):
                todo.extend(d.values())
            for cls in type(o).__mro__:
                for name in _attributes(cls):
                    if isinstance(name, str) and hasattr(o, name):
                        todo.append(getattr(o, name))
    return held
