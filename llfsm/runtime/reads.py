"""What each ringlet of a compiled machine can change, read from its generated module's text
(`ast` only, nothing run), so that the monitor judges a property only at the ringlet boundaries
where its value can change (docs/monitor.md, "Cost").

A property reads states, variables, inputs, `suspended`/`finished` and `published` topics.
What changes them, and where llfsm.monitor.run looks:

- a machine's state, `suspended`, `finished`: a ringlet that fires a transition
  (`self._state = K`), enters the suspend state or finishes (what the compiler writes for an
  accepting state); a command, applied by the scheduler's gate;
- a variable: the ringlets whose code can change its value, below; a parameter set from
  outside (the gate);
- an input: the gate (its snapshot), or the bus between rounds;
- `published`: a publish, seen by a tap on the topic.

**A variable's value.**  A ringlet changes `x` when it assigns it (`x = ...`, `x += 1`, `x[0] =
...`, `x.field = ...`, `del x[...]`) or calls a method on it (`x.append(1)`), and it may change
it by way of another name for the same object: `y = x` makes a later `y.append(1)` change `x`.
So every variable a ringlet assigns or mentions other than as a plain value (in a comparison,
an f-string, `len(...)`, a test) is put into one group with the others it touches
so, and a ringlet changes the whole group of anything it changes.  A value handed to a function
or class of the user's own (a helper module beside the machine, imported in Includes.py), or
mixed with a module-level object that can be changed (a list, a dict...), may be kept there and
changed from anywhere; so may anything a callback (a function or lambda defined in machine code,
run by the bus) touches.  (Functions of Python's library, installed packages and llfsm, and
methods, are taken to keep no reference to what they are handed beyond the object they are
called on, which joins the group.)
Such a variable is *escaped*: a property reading it is judged at every boundary.

**A number stepped by a constant.**  A variable that every ringlet changes only by a numeric
literal (`n += 1`, `n -= 2`, `n = 0`) and no OnSuspend/OnResume hook touches stays a number
once it is one (the monitor checks that it is, at the start and wherever the scheduler's gate
sets it from outside): in a ringlet that only steps it one way (`Ringlet.steps`), a bound the
property holds it to on the other side cannot be crossed (llfsm.monitor.variant folds that check
away).
"""

from __future__ import annotations

import ast
import builtins
import os
import sys
import sysconfig
import types
from dataclasses import dataclass, field
from typing import Any

#: Builtins that read a value and keep no reference to it: an argument to them is a plain read.
_VALUE_BUILTINS = frozenset(
    {
        "abs", "bool", "chr", "float", "format", "hash", "hex", "id", "int", "isinstance", "len",
        "oct", "ord", "print", "repr", "round", "str", "type", "bin", "callable", "issubclass",
    }
)  # fmt: skip
_IMMUTABLE = (int, float, complex, str, bytes, bool, type(None), tuple, frozenset, range)
#: sysconfig's paths of Python's library and installed packages.
_LIBRARY_PATHS = ("stdlib", "platstdlib", "purelib", "platlib")


@dataclass
class Ringlet:
    """What one ringlet function can change."""

    name: str
    #: variables it may change (before grouping)
    touches: set[str] = field(default_factory=set)
    #: it may change the machine's state (fires a transition, enters the suspend state)
    moves: bool = False
    #: it may finish the machine (an accepting state's ringlet)
    finishes: bool = False
    #: how it changes each variable it touches, each way: "up" (`x += 1`, `x -= -0.5`),
    #: "down", "set" (`x = 3`: a numeric literal), "other" (anything else)
    changes: dict[str, set[str]] = field(default_factory=dict)
    #: the literals of those changes: what `x += 2` adds (2), `x -= 1` (-1), `x = 3` sets (3)
    literals: dict[str, set[int | float]] = field(default_factory=dict)


@dataclass
class ClassReads:
    """What the ringlets of one machine class can change (see the module's docstring)."""

    ringlets: dict[str, Ringlet]
    variables: tuple[str, ...]
    #: group of each variable (a representative name)
    group: dict[str, str]
    #: the groups whose values may change outside any ringlet of this machine
    escaped: set[str]
    #: the function definitions of the ringlets, by name (what the variant rewrites)
    trees: dict[str, ast.FunctionDef]
    filename: str
    namespace: dict[str, Any]
    #: variables an OnSuspend or OnResume hook may change (the gate runs those)
    hooked: set[str] = field(default_factory=set)

    def changers(self, variable: str) -> set[str]:
        """The ringlets that may change `variable`'s value; None-like empty set if none."""
        g = self.group.get(variable, variable)
        return {r.name for r in self.ringlets.values() if any(self.group.get(t, t) == g for t in r.touches)}

    def is_escaped(self, variable: str) -> bool:
        return self.group.get(variable, variable) in self.escaped

    def numeric(self, variable: str) -> bool:
        """Whether the machine's own code keeps `variable` a number once it is one: it shares
        its object with no other variable, nothing hands it on, and every ringlet changes it by
        numeric literals alone (see the module's docstring)."""
        if variable not in self.variables or variable in self.hooked or self.is_escaped(variable):
            return False
        if any(v != variable and g == self.group[variable] for v, g in self.group.items()):
            return False
        return all(r.changes.get(variable, set()) <= {"up", "down", "set"} for r in self.ringlets.values())

    def integral(self, variable: str) -> bool:
        """Whether the machine's own code keeps `variable` an int once it is one (an int or a
        bool): it keeps it a number, by int literals alone."""
        if not self.numeric(variable):
            return False
        return all(type(v) is int for r in self.ringlets.values() for v in r.literals.get(variable, ()))

    def step(self, ringlet: str, variable: str) -> int:
        """+1 if the ringlet only steps `variable` up by literals (and it is numeric), -1 if only
        down, 0 otherwise (it sets it, changes it otherwise, or does not change it)."""
        kinds = self.ringlets[ringlet].changes.get(variable)
        if kinds == {"up"} and self.numeric(variable):
            return 1
        if kinds == {"down"} and self.numeric(variable):
            return -1
        return 0


def class_reads(cls: type[Any]) -> ClassReads | None:
    """The analysis of a machine class's ringlets, or None when its module's text cannot be
    read as the code that runs (a native build, a module changed on disk since it was loaded):
    then the monitor judges every boundary."""
    module = sys.modules.get(cls.__module__)
    filename = getattr(module, "__file__", None)
    funcs = [f for f in (*cls.ENTER, *cls.STEADY) if f is not None]
    if module is None or not filename or not filename.endswith(".py") or not all(hasattr(f, "__code__") for f in funcs):
        return None
    try:
        with open(filename, encoding="utf-8") as fh:
            tree = ast.parse(fh.read(), filename)
    except (OSError, SyntaxError, ValueError, UnicodeDecodeError):
        return None
    defs = {n.name: n for n in tree.body if isinstance(n, ast.FunctionDef)}
    namespace = vars(module)
    hooks = [f for f in (*getattr(cls, "ON_SUSPEND", ()), *getattr(cls, "ON_RESUME", ())) if f is not None]
    for f in (*funcs, *hooks):
        d = defs.get(getattr(f, "__name__", ""))
        code = getattr(f, "__code__", None)
        if d is None or code is None or d.lineno != code.co_firstlineno or code.co_filename != filename:
            return None  # the text on disk is not what was compiled
    slots = [s for c in type.mro(cls) for s in vars(c).get("__slots__", ())]
    variables = tuple(s for s in slots if not s.startswith("_") and "__" not in s)
    inputs = tuple(i[0] for i in getattr(cls, "INPUTS", ()))
    names = set(variables) | set(inputs)
    own = _own_definitions(namespace)
    parent: dict[str, str] = {v: v for v in names}

    def find(v: str) -> str:
        while parent[v] != v:
            parent[v] = parent[parent[v]]
            v = parent[v]
        return v

    ringlets: dict[str, Ringlet] = {}
    escaped_vars: set[str] = set()
    for f in funcs:
        if f.__name__ in ringlets:
            continue
        scan = _Scan(names, own, namespace)
        scan.visit(defs[f.__name__])
        r = Ringlet(f.__name__, scan.touched, scan.moves, scan.finishes, scan.changes, scan.literals)
        ringlets[f.__name__] = r
        # one group of what the ringlet may make share an object; a numeric literal stepped or
        # set makes no other name for anything (`x += 1` on a shared object is an "other" change
        # of it: a ringlet that joined them, `alias = x`, put them in one group already)
        touched = sorted(v for v in scan.touched if "other" in scan.changes.get(v, {"other"}))
        for a in touched[1:]:
            parent[find(a)] = find(touched[0])
        if scan.escapes:
            escaped_vars |= scan.touched
        escaped_vars |= scan.in_callbacks
    # the initial values (Variables.py, run once by `_initialise`): `alias: list = items` makes
    # one object of two variables, `box: list = SHARED` one a module-level object can change
    for st in _initialiser(tree, cls.__name__):
        scan = _Scan(names, own, namespace)
        scan.visit(st)
        joined = sorted(v for v in scan.touched if "other" in scan.changes.get(v, {"other"}))
        for a in joined[1:]:
            parent[find(a)] = find(joined[0])
        if scan.escapes:
            escaped_vars |= scan.touched
    hooked: set[str] = set()
    for f in hooks:
        scan = _Scan(names, own, namespace)
        scan.visit(defs[f.__name__])
        hooked |= scan.touched
    group = {v: find(v) for v in names}
    escaped = {group[v] for v in escaped_vars if v in group}
    trees = {n: defs[n] for n in ringlets}
    return ClassReads(ringlets, variables, group, escaped, trees, filename, namespace, hooked)


def _initialiser(tree: ast.Module, name: str) -> list[ast.stmt]:
    """The statements of class `name`'s `_initialise` in the generated module."""
    for node in tree.body:
        if isinstance(node, ast.ClassDef) and node.name == name:
            for item in node.body:
                if isinstance(item, ast.FunctionDef) and item.name == "_initialise":
                    return item.body
    return []


def _own_definitions(namespace: dict[str, Any]) -> set[str]:
    """Names of the module bound to a function, class or module of the user's own: a helper
    module beside the machine (docs/machine-format.md, "Helper modules"), anything not from
    Python's library, an installed package or llfsm.  A value handed to one may be kept there."""
    library = {os.path.realpath(p) for k, p in sysconfig.get_paths().items() if k in _LIBRARY_PATHS}
    library.add(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))  # llfsm itself
    out: set[str] = set()
    for name, value in namespace.items():
        if name.startswith("_llfsm_") or not isinstance(value, type | types.FunctionType | types.ModuleType):
            continue
        module = value if isinstance(value, types.ModuleType) else sys.modules.get(getattr(value, "__module__", ""))
        file = getattr(module, "__file__", None)
        if file is None:
            continue  # built in
        real = os.path.realpath(file)
        if not any(real.startswith(root + os.sep) for root in library):
            out.add(name)
    return out


class _Scan(ast.NodeVisitor):
    """One ringlet's function: what it assigns or may change (`touched`), whether it fires a
    transition or finishes, whether anything it touches may escape."""

    def __init__(self, names: set[str], own: set[str], namespace: dict[str, Any]) -> None:
        self.names = names
        self.own = own
        self.namespace = namespace
        self.touched: set[str] = set()
        self.in_callbacks: set[str] = set()
        self.moves = False
        self.finishes = False
        self.escapes = False
        self.depth = 0  # inside a nested function or lambda (a callback)
        self.parents: list[ast.AST] = []
        self.changes: dict[str, set[str]] = {}
        self.literals: dict[str, set[int | float]] = {}
        self._stepped: set[int] = set()  # targets of a numeric step or set (the kinds above)

    def generic_visit(self, node: ast.AST) -> None:
        self.parents.append(node)
        super().generic_visit(node)
        self.parents.pop()

    def visit_FunctionDef(self, node: ast.FunctionDef) -> None:
        nested = bool(self.parents)
        self.depth += nested
        self.generic_visit(node)
        self.depth -= nested

    visit_AsyncFunctionDef = visit_FunctionDef  # type: ignore[assignment]

    def visit_Lambda(self, node: ast.Lambda) -> None:
        self.depth += 1
        self.generic_visit(node)
        self.depth -= 1

    def visit_Assign(self, node: ast.Assign) -> None:
        for t in node.targets:
            if is_self_attr(t, "_state"):
                self.moves = True
        value = number_literal(node.value)
        if len(node.targets) == 1 and value is not None:
            self._numeric_change(node.targets[0], "set", value)
        self.generic_visit(node)

    def visit_AnnAssign(self, node: ast.AnnAssign) -> None:
        value = number_literal(node.value) if node.value is not None else None
        if value is not None:
            self._numeric_change(node.target, "set", value)
        self.generic_visit(node)

    def visit_AugAssign(self, node: ast.AugAssign) -> None:
        value = number_literal(node.value)
        if value and isinstance(node.op, ast.Add | ast.Sub):
            delta = value if isinstance(node.op, ast.Add) else -value
            self._numeric_change(node.target, "up" if delta > 0 else "down", delta)
        self.generic_visit(node)

    def _numeric_change(self, target: ast.expr, kind: str, value: int | float) -> None:
        """`self.x` changed by a numeric literal, in the ringlet's own code (not a callback)."""
        own = isinstance(target, ast.Attribute) and is_self_attr(target, target.attr)
        if own and not self.depth and target.attr in self.names:  # type: ignore[attr-defined]
            self.changes.setdefault(target.attr, set()).add(kind)  # type: ignore[attr-defined]
            self.literals.setdefault(target.attr, set()).add(value)  # type: ignore[attr-defined]
            self._stepped.add(id(target))

    def visit_Call(self, node: ast.Call) -> None:
        f = node.func
        if is_self_attr(f, "_enter_suspend_state"):
            self.moves = True
        elif isinstance(f, ast.Attribute) and f.attr == "finish" and is_self_attr(f.value, "_arr"):
            self.finishes = True
        elif _root_name(f) in self.own and node.args + [k.value for k in node.keywords]:
            self.escapes = True  # a value handed to a function of the user's own may be kept there
        self.generic_visit(node)

    def visit_Name(self, node: ast.Name) -> None:
        if isinstance(node.ctx, ast.Load) and node.id in self.namespace and node.id not in self.own:
            value = self.namespace[node.id]
            if not isinstance(value, (*_IMMUTABLE, type, type(sys))) and not callable(value):
                self.escapes = True  # a module-level object that can be changed (a list...)
        self.generic_visit(node)

    def visit_Attribute(self, node: ast.Attribute) -> None:
        if isinstance(node.value, ast.Name) and node.value.id == "self" and node.attr in self.names:
            if self.depth:
                self.in_callbacks.add(node.attr)
                self.touched.add(node.attr)
                self.changes.setdefault(node.attr, set()).add("other")
            elif not self._plain_read(node):
                self.touched.add(node.attr)
                if id(node) not in self._stepped:
                    self.changes.setdefault(node.attr, set()).add("other")
        self.generic_visit(node)

    def _plain_read(self, node: ast.AST) -> bool:
        """Whether this mention of a variable only reads its value: the chain it heads
        (`x.a[0]`) is loaded and used in a comparison, a test, an f-string,
        or a value builtin's argument, never stored, called, or handed on as an object."""
        chain = node
        k = len(self.parents) - 1
        while k >= 0:
            up = self.parents[k]
            if isinstance(up, ast.Attribute | ast.Subscript) and up.value is chain:
                if not isinstance(up.ctx, ast.Load):
                    return False
                chain, k = up, k - 1
                continue
            break
        if k < 0 or isinstance(getattr(chain, "ctx", None), ast.Store | ast.Del):
            return False
        up = self.parents[k]
        if isinstance(up, ast.Compare | ast.UnaryOp | ast.FormattedValue):
            return True
        if isinstance(up, ast.Subscript) and up.slice is chain:
            return True
        if isinstance(up, ast.If | ast.While | ast.IfExp | ast.Assert) and up.test is chain:
            return True
        if isinstance(up, ast.BoolOp):
            return k > 0 and isinstance(self.parents[k - 1], ast.If | ast.While | ast.Assert)
        if isinstance(up, ast.Call) and chain is not up.func:
            name = up.func.id if isinstance(up.func, ast.Name) else ""
            return name in _VALUE_BUILTINS and name in vars(builtins) and name not in self.namespace
        return False


def number_literal(node: ast.expr) -> int | float | None:
    """The value of a numeric literal (`3`, `-0.5`; not a bool), else None."""
    sign = 1
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub | ast.UAdd):
        sign = -1 if isinstance(node.op, ast.USub) else 1
        node = node.operand
    value = node.value if isinstance(node, ast.Constant) else None
    if type(value) is int or type(value) is float:  # not a bool, which is an int too
        return sign * value
    return None


def _root_name(node: ast.AST) -> str | None:
    """`f` of `f(...)`, `helpers.f(...)`, `helpers.Box.make(...)`."""
    while isinstance(node, ast.Attribute):
        node = node.value
    return node.id if isinstance(node, ast.Name) else None


def is_self_attr(node: ast.AST, attr: str) -> bool:
    """`self.attr` in generated code."""
    return (
        isinstance(node, ast.Attribute)
        and node.attr == attr
        and isinstance(node.value, ast.Name)
        and node.value.id == "self"
    )
