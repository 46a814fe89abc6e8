"""Atoms: Python boolean expressions over an arrangement (SPEC 11), checked with `ast` and
compiled to functions `fn(machines, published)`.

`machines` is the arrangement's machine objects in load order and `published` the topics
published in the step just taken (any container with `in`): the same function reads a live
run's machines (the monitor, the debugger's `--break`) and the machine objects verify has put a
configuration into (llfsm.verify.step), so an atom costs one call of a small compiled lambda
either way.  `Atom.machines` and `Atom.reads_published` say what an atom reads, so that a
caller evaluates it only after ringlets that could change it.

What an atom may use: the names of the arrangement's machines (`p.count`, `state(p)`), the
functions `state`, `suspended`, `finished`, `published` and a few pure builtins (`len`, `abs`,
`min`, `max`, `round`, `int`, `float`, `bool`, `str`), constants, arithmetic, comparisons and
subscripts; no attribute that starts with `_`, no other call, no lambda, comprehension or
assignment.  A machine, state or variable that does not exist is one clear error, as is
anything else.  The checked tree is then rewritten to read the machine objects (`state(p)`
becomes the name of machine p's current state) and compiled: user text is never `eval`ed as it
is written.

Bounds (SPEC 18): a text of at most MAX_TEXT characters nested at most MAX_DEPTH levels; a
string or sequence repeated (`*`) or formatted (`%`) is refused when its constants already ask
for more than MAX_SEQUENCE items, and checked where it is evaluated otherwise (`*` and `%` on a
sequence go through `_repeat` and `_format`, which raise RepeatError past the bound).
"""

from __future__ import annotations

import ast
import difflib
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

#: Longest property text, and deepest nesting, accepted.
MAX_TEXT = 10_000
MAX_DEPTH = 100
#: The most items (characters, elements) a repetition in an atom may make.
MAX_SEQUENCE = 100_000

_SEQUENCES = (str, bytes, tuple, list)


class PropertyError(ValueError):
    """A property that does not parse or names what does not exist: one line for the user."""


class RepeatError(ValueError):
    """An atom repeated a sequence beyond MAX_SEQUENCE where it was evaluated."""


def _repeat(a: Any, b: Any) -> Any:
    """`a * b`, refusing a sequence repeated into more than MAX_SEQUENCE items."""
    if isinstance(a, _SEQUENCES) and isinstance(b, int):
        if len(a) * b > MAX_SEQUENCE:
            raise RepeatError(f"a sequence of {len(a):,} repeated {b:,} times (at most {MAX_SEQUENCE:,} items)")
    elif isinstance(b, _SEQUENCES) and isinstance(a, int) and len(b) * a > MAX_SEQUENCE:
        raise RepeatError(f"a sequence of {len(b):,} repeated {a:,} times (at most {MAX_SEQUENCE:,} items)")
    return a * b


def _format(a: Any, b: Any) -> Any:
    """`a % b`: numbers only (a string formatted with `%` can be made as long as a width says)."""
    if isinstance(a, str | bytes):
        raise RepeatError("`%` formatting of text is not allowed in a property (a width can repeat it without bound)")
    return a % b


#: Builtins an atom may call (pure functions of their arguments).
PURE: dict[str, Any] = {
    "len": len,
    "abs": abs,
    "min": min,
    "max": max,
    "round": round,
    "int": int,
    "float": float,
    "bool": bool,
    "str": str,
}
#: The functions of the property language.
FUNCTIONS = ("state", "suspended", "finished", "published")
#: The bounded `*` and `%` an atom's tree calls by these names (whoever compiles the tree again needs them).
HELPERS = {"_repeat": _repeat, "_format": _format}


@dataclass
class MachineInfo:
    """What an atom may name of one machine."""

    index: int
    name: str
    states: tuple[str, ...]
    variables: tuple[str, ...]  # machine variables, then inputs
    #: `states` are all of them (a state compared with `state(m)` is checked against them); False
    #: where only some are known (a bag without the machine's description)
    known_states: bool = True
    #: how many transitions each state has (empty: unknown, `fired` then checks no index)
    transitions: tuple[int, ...] = ()


@dataclass
class Atom:
    text: str
    #: the compiled atom: fn(machines, published) is true or false (a caller reports an
    #: exception with the atom's text and `where`)
    fn: Callable[[Sequence[Any], Any], Any]
    where: str = "--property"
    #: the load indices of the machines it reads
    machines: frozenset[int] = frozenset()
    #: whether it reads `published(...)` (then it changes with every step, not only with machines)
    reads_published: bool = False
    #: the checked and rewritten expression, over `M` (machines) and `E` (published)
    tree: ast.expr | None = field(default=None, repr=False)


def infos_of(classes: Iterable[Any], variables: Callable[[Any], Iterable[str]] | None = None) -> dict[str, MachineInfo]:
    """What atoms may name of each machine class of an arrangement (a live run's): its states,
    and its variables (by default the class's slots, or a native build's attributes, that are
    neither llfsm's nor a state variable's, which hold `STATE__name`) then its inputs."""
    out = {}
    for k, cls in enumerate(classes):
        if variables is not None:
            names = tuple(variables(cls))
        else:
            slots = [s for c in type.mro(cls) for s in vars(c).get("__slots__", ())]
            slots += getattr(cls, "__mypyc_attrs__", ())  # a class built native (--native) has these instead
            names = tuple(dict.fromkeys(s for s in slots if not s.startswith("_") and "__" not in s))
        inputs = tuple(entry[0] for entry in getattr(cls, "INPUTS", ()))
        counts = tuple(len(ts) for ts in getattr(cls, "TRANSITIONS", ()) or ())
        readable = names + tuple(i for i in inputs if i not in names)
        out[cls.NAME] = MachineInfo(k, cls.NAME, tuple(cls.STATES), readable, transitions=counts)
    return out


def compile_atom(
    text: str, machines: dict[str, MachineInfo], where: str = "--property", *, fired: bool = False
) -> Atom:
    """The atom of `text` over the arrangement `machines` (PropertyError if it is not one).
    With `fired`, the debugger's `fired(m, "S", N)` is allowed too (transition N of m's state S
    fired in the last ringlet): it reads `("fired", m's index, S's index, N) in E`, so the
    caller puts that tuple among the step's events."""
    return _Compiler(machines, where, fired).atom(text)


class _Compiler:
    """Checks an atom's tree and compiles it (see the module's docstring)."""

    def __init__(self, machines: dict[str, MachineInfo], where: str, fired: bool = False) -> None:
        self.machines = machines
        self.where = where
        self.fired = fired
        self.read: set[int] = set()
        self.published = False

    def fail(self, text: str, message: str) -> PropertyError:
        return PropertyError(f"{self.where}: `{' '.join(text.split())}`: {message}")

    def atom(self, text: str) -> Atom:
        src = text.strip()
        if not src:
            raise PropertyError(f"{self.where}: an empty condition")
        try:
            tree = ast.parse(src, mode="eval")
        except SyntaxError as e:
            raise self.fail(src, f"not a Python expression ({e.msg})") from None
        except (RecursionError, MemoryError, ValueError):
            raise self.fail(src[:60], "too deeply nested") from None
        if depth(tree) > MAX_DEPTH:
            raise self.fail(src[:60], f"nested more than {MAX_DEPTH} levels")
        self.read, self.published = set(), False
        body = self._rewrite(tree.body, src)
        fn_tree = ast.Expression(
            body=ast.Lambda(
                args=ast.arguments(
                    posonlyargs=[],
                    args=[ast.arg(arg="M"), ast.arg(arg="E")],
                    kwonlyargs=[],
                    kw_defaults=[],
                    defaults=[],
                ),
                body=body,
            )
        )
        ast.fix_missing_locations(fn_tree)
        code = compile(fn_tree, f"<property {src[:40]}>", "eval", dont_inherit=True)
        # the checked and rewritten tree, with only the pure builtins (and the bounded * and %) in reach
        fn = eval(code, {"__builtins__": dict(PURE), **HELPERS})
        return Atom(src, fn, self.where, frozenset(self.read), self.published, body)

    def _machine(self, node: ast.AST, text: str) -> MachineInfo:
        name = node.id if isinstance(node, ast.Name) else node.value if isinstance(node, ast.Constant) else None
        if not isinstance(name, str):
            raise self.fail(text, "name a machine here (state(p), p.count)")
        info = self.machines.get(name)
        if info is not None:
            self.read.add(info.index)
        if info is None:
            close = difflib.get_close_matches(name, list(self.machines), n=1)
            hint = f" (did you mean {close[0]}?)" if close else ""
            raise self.fail(text, f"no machine named {name}{hint}; machines: {', '.join(self.machines)}")
        return info

    @staticmethod
    def _m(index: int) -> ast.expr:
        return ast.Subscript(value=ast.Name(id="M", ctx=ast.Load()), slice=ast.Constant(index), ctx=ast.Load())

    def _rewrite(self, node: ast.AST, text: str) -> ast.expr:
        """The checked and rewritten node (raises PropertyError for anything not allowed)."""
        if isinstance(node, ast.Constant):
            if not isinstance(node.value, bool | int | float | str | type(None)):
                raise self.fail(text, f"constant {node.value!r} is not a number, string, bool or None")
            return node
        if isinstance(node, ast.BoolOp):
            return ast.BoolOp(op=node.op, values=[self._rewrite(v, text) for v in node.values])
        if isinstance(node, ast.UnaryOp):
            return ast.UnaryOp(op=node.op, operand=self._rewrite(node.operand, text))
        if isinstance(node, ast.BinOp):
            if isinstance(node.op, ast.Pow | ast.LShift | ast.MatMult):
                raise self.fail(text, "** << and @ are not allowed in a property")
            left, right = self._rewrite(node.left, text), self._rewrite(node.right, text)
            if isinstance(node.op, ast.Mult | ast.Mod):
                self._check_repeat(node, text)
                helper = "_repeat" if isinstance(node.op, ast.Mult) else "_format"
                return ast.Call(func=ast.Name(id=helper, ctx=ast.Load()), args=[left, right], keywords=[])
            return ast.BinOp(left=left, op=node.op, right=right)
        if isinstance(node, ast.IfExp):
            return ast.IfExp(
                test=self._rewrite(node.test, text),
                body=self._rewrite(node.body, text),
                orelse=self._rewrite(node.orelse, text),
            )
        if isinstance(node, ast.Compare):
            self._check_states(node, text)
            return ast.Compare(
                left=self._rewrite(node.left, text),
                ops=node.ops,
                comparators=[self._rewrite(c, text) for c in node.comparators],
            )
        if isinstance(node, ast.Tuple | ast.List | ast.Set):
            elts = [self._rewrite(e, text) for e in node.elts]
            return ast.Tuple(elts=elts, ctx=ast.Load()) if not isinstance(node, ast.Set) else ast.Set(elts=elts)
        if isinstance(node, ast.Subscript):
            if isinstance(node.slice, ast.Slice):
                parts = [node.slice.lower, node.slice.upper, node.slice.step]
                sl: ast.expr = ast.Slice(*(self._rewrite(p, text) if p is not None else None for p in parts))
            else:
                sl = self._rewrite(node.slice, text)
            return ast.Subscript(value=self._rewrite(node.value, text), slice=sl, ctx=ast.Load())
        if isinstance(node, ast.Attribute):
            if node.attr.startswith("_"):
                raise self.fail(text, f"`.{node.attr}`: names starting with _ are not allowed")
            if isinstance(node.value, ast.Name) and node.value.id not in PURE:
                info = self._machine(node.value, text)
                if node.attr not in info.variables:
                    close = difflib.get_close_matches(node.attr, list(info.variables), n=1)
                    hint = f" (did you mean {info.name}.{close[0]}?)" if close else ""
                    known = ", ".join(info.variables) or "none"
                    raise self.fail(text, f"{info.name} has no variable or input {node.attr}{hint}; it has: {known}")
                return ast.Attribute(value=self._m(info.index), attr=node.attr, ctx=ast.Load())
            return ast.Attribute(value=self._rewrite(node.value, text), attr=node.attr, ctx=ast.Load())
        if isinstance(node, ast.Call):
            return self._call(node, text)
        if isinstance(node, ast.Name):
            if node.id in self.machines:
                raise self.fail(text, f"{node.id} is a machine: ask state({node.id}), {node.id}.variable...")
            if node.id in ("true", "false"):
                return ast.Constant(node.id == "true")
            raise self.fail(text, f"unknown name {node.id} (machines: {', '.join(self.machines)})")
        raise self.fail(text, f"{type(node).__name__.lower()} is not allowed in a property")

    def _call(self, node: ast.Call, text: str) -> ast.expr:
        if not isinstance(node.func, ast.Name) or node.keywords:
            raise self.fail(text, "only state(m), suspended(m), finished(m), published(topic) and len, abs... calls")
        name = node.func.id
        if name in PURE:
            return ast.Call(func=node.func, args=[self._rewrite(a, text) for a in node.args], keywords=[])
        if name == "fired" and self.fired:
            return self._fired(node, text)
        if name not in FUNCTIONS:
            if name == "fired":
                raise self.fail(text, "fired(m, \"S\", N) is the debugger's (--break), not a property's")
            raise self.fail(text, f"unknown function {name} (the property language has {', '.join(FUNCTIONS)})")
        if len(node.args) != 1:
            raise self.fail(text, f"{name}() takes one argument")
        arg = node.args[0]
        if name == "published":
            if not isinstance(arg, ast.Constant) or not isinstance(arg.value, str) or not arg.value:
                raise self.fail(text, 'published() takes a topic name: published("/cmd_vel")')
            topic = arg.value if arg.value.startswith("/") else "/" + arg.value
            self.published = True
            return ast.Compare(left=ast.Constant(topic), ops=[ast.In()], comparators=[ast.Name(id="E", ctx=ast.Load())])
        m = self._m(self._machine(arg, text).index)
        if name == "state":
            return ast.Subscript(
                value=ast.Attribute(value=m, attr="STATES", ctx=ast.Load()),
                slice=ast.Attribute(value=self._m(self._machine(arg, text).index), attr="_state", ctx=ast.Load()),
                ctx=ast.Load(),
            )
        return ast.Attribute(value=m, attr="_suspended" if name == "suspended" else "_finished", ctx=ast.Load())

    def _fired(self, node: ast.Call, text: str) -> ast.expr:
        """`fired(m, "S", N)`: ("fired", m, S, N) among the last step's events."""
        usage = 'write fired(m, "S", N): transition N (from 0, in priority order) of state S of machine m'
        if len(node.args) != 3:
            raise self.fail(text, usage)
        info = self._machine(node.args[0], text)
        state, index = node.args[1], node.args[2]
        if not (isinstance(state, ast.Constant) and isinstance(state.value, str)):
            raise self.fail(text, usage)
        if state.value not in info.states:
            close = difflib.get_close_matches(state.value, list(info.states), n=1)
            hint = f" (did you mean {close[0]}?)" if close else ""
            raise self.fail(text, f"{info.name} has no state {state.value}{hint}; its states: {', '.join(info.states)}")
        if not (isinstance(index, ast.Constant) and type(index.value) is int):
            raise self.fail(text, usage)
        s = info.states.index(state.value)
        if info.transitions and not 0 <= index.value < info.transitions[s]:
            count = info.transitions[s]
            has = f"transitions 0 to {count - 1}" if count else "no transitions"
            raise self.fail(text, f"state {state.value} of {info.name} has {has}, not {index.value}")
        self.published = True  # an event of the last step, as published() is
        event = ast.Tuple(elts=[ast.Constant(v) for v in ("fired", info.index, s, index.value)], ctx=ast.Load())
        return ast.Compare(left=event, ops=[ast.In()], comparators=[ast.Name(id="E", ctx=ast.Load())])

    def _check_states(self, node: ast.Compare, text: str) -> None:
        """`state(p) == "CRIT"`: the strings compared with a machine's state name its states."""
        operands = [node.left, *node.comparators]
        for k, op in enumerate(operands):
            if not (isinstance(op, ast.Call) and isinstance(op.func, ast.Name) and op.func.id == "state"):
                continue
            if len(op.args) != 1:
                continue
            info = self._machine(op.args[0], text)
            if not info.known_states:
                continue
            for other in operands[:k] + operands[k + 1 :]:
                values = other.elts if isinstance(other, ast.Tuple | ast.List | ast.Set) else [other]
                for v in values:
                    if isinstance(v, ast.Constant) and isinstance(v.value, str) and v.value not in info.states:
                        close = difflib.get_close_matches(v.value, list(info.states), n=1)
                        hint = f" (did you mean {close[0]}?)" if close else ""
                        raise self.fail(
                            text, f"{info.name} has no state {v.value}{hint}; its states: {', '.join(info.states)}"
                        )

    def _check_repeat(self, node: ast.BinOp, text: str) -> None:
        """A repetition whose constants already ask for more than MAX_SEQUENCE items."""
        try:
            value = _constant_value(node)
        except RepeatError as e:
            raise self.fail(text[:80], f"{e}: refused") from None
        if isinstance(value, _SEQUENCES) and len(value) > MAX_SEQUENCE:  # pragma: no cover (caught above)
            raise self.fail(text[:80], f"a sequence of more than {MAX_SEQUENCE:,} items")


def _constant_value(node: ast.AST) -> Any:
    """The value of a constant expression of literals, `*` and `%` (bounded as at run time), or
    None when it is not one."""
    if isinstance(node, ast.Constant):
        return node.value
    if isinstance(node, ast.Tuple | ast.List):
        items = [_constant_value(e) for e in node.elts]
        return None if any(i is None for i in items) else tuple(items)
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult | ast.Mod):
        a, b = _constant_value(node.left), _constant_value(node.right)
        if a is None or b is None:
            return None
        try:
            return _repeat(a, b) if isinstance(node.op, ast.Mult) else _format(a, b)
        except (TypeError, ValueError, ZeroDivisionError, OverflowError) as e:
            if isinstance(e, RepeatError):
                raise
            return None
    return None


def depth(node: ast.AST, limit: int = MAX_DEPTH + 1) -> int:
    """How deep `node` nests (stops counting past `limit`)."""
    best = 0
    stack = [(node, 0)]
    while stack:
        n, d = stack.pop()
        if d > best:
            best = d
            if best >= limit:
                return best
        stack.extend((c, d + 1) for c in ast.iter_child_nodes(n))
    return best
