"""A monitored variant of a compiled machine class: the same ringlets, with a property's check
compiled in before each `return` of the ringlets that can change what the property reads
(llfsm.runtime.reads), and nothing added anywhere else (docs/monitor.md, "Cost").

The variant is made from the generated module's own text and compiled under its file name, so
tracebacks, the source map and the watchdog read it as the original.  Its ringlets run in a
copy of the module's namespace, where each ringlet's name is bound to its variant, so that
`self._run = _llfsm_enter_B` in any of them reaches the variant: the module and its class stay
as they are for every other run of the process.  The variant class is a subclass with the
variant ringlets in ENTER and STEADY and no slot of its own, so a live machine becomes one by
having its class changed (`m.__class__ = variant`), keeping its variables.

A safety property's check is its atom inlined, `self` for its own machine, `_llfsm_mon_M[k]` for
another's; at a `return` where the ringlet's target state is written just before it (every
`return` the compiler writes: `self._state = K ... return i`, or no transition at all), the
machine's own `state(m)` is that state's name as a constant, and the comparisons it takes part
in are folded: a check that cannot fail there is left out.  So is a check that held at the
boundary before the ringlet and that the ringlet cannot make fail (`_cannot_fail`): everything it
reads is as it was, but for numbers the ringlet steps one way (llfsm.runtime.reads,
`ClassReads.step`) that it bounds on the other side (`always: m.count >= 0` in a ringlet whose
only change is `count += 1`).  That rests on the variable holding a number (an int, a float or a
bool), which its machine's code keeps (`ClassReads.numeric`) and the monitor checks where
anything else could set it (llfsm.monitor.run): the variant names those variables in
`NUMERIC`; likewise for numbers read only modulo what the ringlet steps them by (`count % 2`
where `count += 2`), which must hold ints (`INTEGRAL`).  A number of the machine's own that
nothing in it changes is compiled in as its value when the run starts (`PINS`, which the
monitor checks wherever the gate sets it), so `count < limit * 10` is a constant bound, and the
bounds at one return are one comparison per number, leaving out the terms they decide
(llfsm.monitor.bounds).  Other kinds call the monitor with the properties to judge.  Names
start with `_llfsm_mon_`, which machine code cannot use (LF013).
"""

from __future__ import annotations

import ast
import copy
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..props.atoms import HELPERS, PURE
from ..runtime.generated import variant_class
from ..runtime.reads import ClassReads, is_self_attr
from .bounds import fold_arithmetic, merge_bounds, self_attr_load

PREFIX = "_llfsm_mon_"
#: The names a variant's namespace gets from the monitor.
VIOLATED, FAILED, JUDGE = PREFIX + "v", PREFIX + "x", PREFIX + "j"
#: ...and the arrangement's machines and the topics published since the last boundary.
MACHINES, PUBLISHED = PREFIX + "M", PREFIX + "E"
#: The class attribute of a variant naming the variables whose checks it left out because the
#: ringlets step them as numbers (they must hold numbers for that to stand).
NUMERIC = PREFIX + "numeric"
#: ...and the variables whose values it compiled in as constants (`pins` of make_variant), with
#: those values: a variant stands only while each still has its value.
PINS = PREFIX + "pins"
#: ...and the variables whose checks it left out because the ringlets step them by multiples of
#: what the property takes them modulo (they must hold ints for that to stand).
INTEGRAL = PREFIX + "integral"
#: The types a variable keeps `(x + k * m) % m == x % m` under.
INTEGERS = (int, bool)
#: The types a stepped variable keeps its order under (`x + 1 >= x`, NaN staying NaN).
NUMBERS = (int, float, bool)


@dataclass
class Check:
    """What to judge at a ringlet's boundary: a safety property inline (`index`, its atom's
    rewritten tree, whether the atom true means violated), or properties through the monitor."""

    index: int
    tree: ast.expr | None = None  # None: judged by a call (JUDGE)
    violated_when: bool = False


@dataclass
class _Ringlet:
    """What a rewrite knows of the ringlet it rewrites: the machine, the state it runs in
    (None: more than one), and what it may change (None: no fold by what it steps)."""

    own: int
    cls: type[Any]
    checks: list[Check]
    entered_in: int | None = None
    reads: ClassReads | None = None
    name: str = ""
    #: the variables the checks left out rely on being numbers (filled in as they are left out)
    numeric: set[str] | None = None
    #: variables of its own machine compiled in as constants (make_variant's `pins`)...
    pins: dict[str, Any] | None = None
    #: ...and those the checks read (filled in as they are inlined)
    pinned: set[str] | None = None
    #: the variables the checks left out rely on being ints (filled in as they are left out)
    integral: set[str] | None = None


def make_variant(
    cls: type[Any],
    reads: ClassReads,
    own: int,
    checks: dict[str, list[Check]],
    helpers: dict[str, Callable[..., Any]],
    steps: bool = True,
    pins: dict[str, Any] | None = None,
) -> type[Any]:
    """The monitored variant of `cls` (the machine at load index `own`): `checks` by ringlet
    function name; with `steps`, a check a ringlet cannot make fail by stepping numbers is
    left out (the variables this relies on are the variant's NUMERIC), and the variables of
    `pins` (numbers that no ringlet of the machine changes, with their values now) are read as
    those constants, folded into the bounds (`count < limit * 10` is `count < 30`); the
    variant's PINS names those the checks read, with their values."""
    namespace = dict(reads.namespace)
    namespace.update(helpers)
    namespace.update({PREFIX + k: v for k, v in PURE.items()})
    namespace.update({PREFIX + k: v for k, v in HELPERS.items()})
    made: dict[str, Any] = {}
    numeric: set[str] = set()
    pinned: set[str] = set()
    integral: set[str] = set()
    for fn in (*cls.ENTER, *cls.STEADY):
        name = fn.__name__
        wanted = checks.get(name)
        if wanted and name not in made:
            state = _state_of(cls, fn)
            ctx = _Ringlet(own, cls, wanted, state, name=name, numeric=numeric, pinned=pinned, integral=integral)
            if steps:  # what the folds rest on
                ctx.reads, ctx.pins = reads, pins
            tree = copy.deepcopy(reads.trees[name])
            tree.body = _rewrite_block(tree.body, state, ctx)[0]
            module = ast.Module(body=[tree], type_ignores=[])
            ast.fix_missing_locations(module)
            exec(compile(module, reads.filename, "exec", dont_inherit=True), namespace)
            made[name] = namespace[name]
    variant = variant_class(cls, namespace, made)
    setattr(variant, NUMERIC, frozenset(numeric))
    setattr(variant, PINS, {k: pins[k] for k in pinned} if pins else {})
    setattr(variant, INTEGRAL, frozenset(integral))
    return variant


def _state_of(cls: type[Any], fn: Any) -> int | None:
    """The state whose ringlet `fn` is (None: it is the ringlet of more than one)."""
    states = {s for s, (e, st) in enumerate(zip(cls.ENTER, cls.STEADY, strict=True)) if fn is e or fn is st}
    return states.pop() if len(states) == 1 else None


def _sets_state(node: ast.stmt) -> int | bool | None:
    """`self._state = K` (K), `self._enter_suspend_state()` (True), or False."""
    if isinstance(node, ast.Assign) and len(node.targets) == 1:
        t = node.targets[0]
        if is_self_attr(t, "_state"):
            v = node.value
            return v.value if isinstance(v, ast.Constant) and isinstance(v.value, int) else None
    return (
        isinstance(node, ast.Expr)
        and isinstance(node.value, ast.Call)
        and is_self_attr(node.value.func, "_enter_suspend_state")
    )


def _changes_state(stmts: list[ast.stmt]) -> bool:
    for st in stmts:
        for node in ast.walk(st):
            if isinstance(node, ast.stmt) and _sets_state(node) is not False:
                return True
    return False


def _rewrite_block(stmts: list[ast.stmt], known: int | None, ctx: _Ringlet) -> tuple[list[ast.stmt], int | None]:
    """The block with the checks before each of its returns (nested blocks too, never inside a
    nested function), and the state known after it (None: unknown)."""
    out: list[ast.stmt] = []
    for st in stmts:
        if isinstance(st, ast.Return):
            out.extend(_returning(st, known, ctx))
            return out, known
        sets = _sets_state(st)
        if sets is True:
            known = ctx.cls.SUSPENDED
        elif sets is not False:
            known = sets
        elif isinstance(st, ast.If | ast.For | ast.AsyncFor | ast.While | ast.With | ast.AsyncWith | ast.Try):
            st = copy.copy(st)
            changed = False
            for attr in ("body", "orelse", "finalbody"):
                block = getattr(st, attr, None)
                if block:
                    setattr(st, attr, _rewrite_block(block, known, ctx)[0])
                    changed = changed or _changes_state(block)
            if isinstance(st, ast.Try):
                handlers = []
                for h in st.handlers:
                    h = copy.copy(h)
                    changed = changed or _changes_state(h.body)
                    h.body = _rewrite_block(h.body, known, ctx)[0]
                    handlers.append(h)
                st.handlers = handlers
            if changed:
                known = None
        out.append(st)
    # a block that ends without a return: the function's end is one more boundary
    return out, known


def _returning(ret: ast.Return, known: int | None, ctx: _Ringlet) -> list[ast.stmt]:
    """The checks, then the return (its value kept first when it is not a constant).  A
    constant return after a last inline check returns from inside it when the property holds
    (`if holds: return 0`): the common case then costs the test alone."""
    cls = ctx.cls
    state = cls.STATES[known] if known is not None else None
    body: list[ast.stmt] = []
    ids: list[int] = []
    last: tuple[ast.Try, ast.expr, int] | None = None
    holding: list[ast.expr] = []  # what each inline check's holding is, for the fast path below
    for c in ctx.checks:
        if c.tree is None:
            ids.append(c.index)
            continue
        cond = _violated(c, ctx, state)
        if not isinstance(cond, ast.Constant) and _cannot_fail(cond, c, ctx):
            continue
        if not isinstance(cond, ast.Constant):
            cond = _fold(_Arithmetic(ctx).visit(cond))
        if isinstance(cond, ast.Constant):
            if cond.value:
                body.append(_call(VIOLATED, c.index))  # violated whenever it returns here
                last = None
            continue
        test = ast.If(test=cond, body=[_call(VIOLATED, c.index)], orelse=[])
        handler = ast.ExceptHandler(
            type=ast.Name(id="Exception", ctx=ast.Load()),
            name=PREFIX + "e",
            body=[_call(FAILED, c.index, ast.Name(id=PREFIX + "e", ctx=ast.Load()))],
        )
        guarded = ast.Try(body=[test], handlers=[handler], orelse=[], finalbody=[])
        body.append(guarded)
        last = guarded, cond, c.index
        holding.append(_fold(ast.UnaryOp(op=ast.Not(), operand=copy.deepcopy(cond))))
    if ids:
        body.append(_call(JUDGE, ast.Tuple(elts=[ast.Constant(i) for i in ids], ctx=ast.Load())))
        last = None
    if not body:
        return [ret]
    constant = ret.value is None or isinstance(ret.value, ast.Constant)
    if last is not None and constant and len(holding) > 1 and not ids and len(body) == len(holding):
        # several checks: one test of them all returns at once when all hold (atoms are pure, so
        # the checks one by one below, which say which failed, may evaluate them again)
        terms = holding
        if ctx.reads is not None and ctx.numeric is not None:
            terms, used = merge_bounds(holding, ctx.reads.numeric)
            ctx.numeric |= used
        all_hold = _Shared().share(terms[0] if len(terms) == 1 else ast.BoolOp(op=ast.And(), values=terms))
        fast = ast.If(test=all_hold, body=[copy.deepcopy(ret)], orelse=[])
        quiet = ast.ExceptHandler(type=ast.Name(id="Exception", ctx=ast.Load()), name=None, body=[ast.Pass()])
        body.insert(0, ast.Try(body=[fast], handlers=[quiet], orelse=[], finalbody=[]))
    elif last is not None and constant:
        guarded, cond, index = last
        holds = _fold(ast.UnaryOp(op=ast.Not(), operand=cond))
        guarded.body = [ast.If(test=holds, body=[copy.deepcopy(ret)], orelse=[]), _call(VIOLATED, index)]
    for node in body:
        _locate(node, ret)
    if ret.value is None or isinstance(ret.value, ast.Constant):
        return [*body, ret]
    keep = ast.Assign(targets=[ast.Name(id=PREFIX + "r", ctx=ast.Store())], value=ret.value)
    new_ret = ast.Return(value=ast.Name(id=PREFIX + "r", ctx=ast.Load()))
    return [_locate(keep, ret), *body, _locate(new_ret, ret)]


def _violated(c: Check, ctx: _Ringlet, state: str | None) -> ast.expr:
    """When check `c` is violated, as code of a ringlet of machine `ctx.own` whose own state
    is `state` (None: unknown), its pinned variables read as constants, folded."""
    assert c.tree is not None  # an inline check's
    cond = _fold(_Inline(ctx.own, state, ctx.pins, ctx.pinned).visit(copy.deepcopy(c.tree)))
    if not c.violated_when:
        cond = _fold(ast.UnaryOp(op=ast.Not(), operand=cond))
    return cond


def _cannot_fail(cond: ast.expr, c: Check, ctx: _Ringlet) -> bool:
    """Whether a safety property's check (`cond`: when it is violated here) cannot fail at this
    return, given that it held at the boundary before the ringlet: what it reads is as it was,
    or a number the ringlet only steps one way (`ClassReads.step`) that the property bounds on the
    other side.  A property violated before is said already; one that raised then counted as
    violated.  What the gate changes at the start of a ringlet (a command, a parameter, an input)
    makes the monitor judge the boundary after it in full (llfsm.monitor.run)."""
    cr = ctx.reads
    if cr is None or ctx.entered_in is None or ctx.numeric is None or ctx.integral is None:
        return False
    before = _violated(c, ctx, ctx.cls.STATES[ctx.entered_in])
    if ast.dump(before) != ast.dump(cond):  # the state it reads moves in this ringlet
        return False
    ringlet = cr.ringlets[ctx.name]
    moved = {"_state", "_suspended"} if ringlet.moves else set()
    if ringlet.finishes:
        moved.add("_finished")
    changed = {cr.group.get(t, t) for t in ringlet.touches}
    holds = _fold(ast.UnaryOp(op=ast.Not(), operand=cond))
    stepped: set[str] = set()
    integral: set[str] = set()
    for attr in {n.attr for n in ast.walk(holds) if self_attr_load(n)}:  # type: ignore[attr-defined]
        if attr in moved:
            return False
        if cr.group.get(attr, attr) not in changed or attr not in cr.variables:
            continue  # as it was before the ringlet
        step = cr.step(ctx.name, attr)
        if step and _polarity(holds, attr) in (0, step):
            stepped.add(attr)
        elif _residue_kept(holds, attr, cr, ctx.name):
            integral.add(attr)
        else:
            return False
    ctx.numeric |= stepped
    ctx.integral |= integral
    return True


def _residue_kept(holds: ast.expr, attr: str, cr: ClassReads, ringlet: str) -> bool:
    """Whether the ringlet keeps what `holds` reads of `self.attr`: it reads it only as `attr % m`
    (m a nonzero int constant), the ringlet only steps it by multiples of m (`count += 2` keeps
    `count % 2`), and the machine's code keeps it an int (for an int, `(x + k * m) % m == x % m`;
    a float's sum can round)."""
    kinds = cr.ringlets[ringlet].changes.get(attr)
    if not kinds or not kinds <= {"up", "down"} or not cr.integral(attr):
        return False
    moduli: list[int] = []
    for n in ast.walk(holds):
        if isinstance(n, ast.Call) and isinstance(n.func, ast.Name) and n.func.id == PREFIX + "_format":
            args = n.args
        elif isinstance(n, ast.BinOp) and isinstance(n.op, ast.Mod):
            args = [n.left, n.right]
        else:
            continue
        if len(args) == 2 and _is_attr(args[0], attr) and isinstance(args[1], ast.Constant):
            m = args[1].value
            if type(m) is int and m != 0:
                moduli.append(m)
    reads = sum(1 for n in ast.walk(holds) if _is_attr(n, attr))
    if not moduli or len(moduli) != reads:
        return False  # read otherwise as well
    return all(type(d) is int and d % m == 0 for d in cr.ringlets[ringlet].literals[attr] for m in moduli)


class _Arithmetic(ast.NodeTransformer):
    """`*` and `%` of numbers as Python's own operators: an atom calls the bounded `_repeat` and
    `_format` (llfsm.props.atoms, SPEC 18) since either side may be a sequence or text there, a
    call per ringlet; where both sides of `*` (the left of `%`) are numeric constants or
    variables the machine's code keeps numbers (`ClassReads.numeric`, which join NUMERIC as in
    `_merge_bounds`), the helper would only do the operation itself."""

    HELPERS = {PREFIX + "_repeat": 2, PREFIX + "_format": 1}  # how many operands must be numbers

    def __init__(self, ctx: _Ringlet) -> None:
        self.ctx = ctx

    def visit_Call(self, node: ast.Call) -> ast.AST:
        node = self.generic_visit(node)  # type: ignore[assignment]
        cr, numeric = self.ctx.reads, self.ctx.numeric
        f = node.func
        need = self.HELPERS.get(f.id) if isinstance(f, ast.Name) else None
        if need is None or cr is None or numeric is None or len(node.args) != 2 or node.keywords:
            return node
        attrs: set[str] = set()
        for arg in node.args[:need]:
            if isinstance(arg, ast.Constant) and type(arg.value) in (int, float):
                continue
            if self_attr_load(arg) and cr.numeric(arg.attr):  # type: ignore[attr-defined]
                attrs.add(arg.attr)  # type: ignore[attr-defined]
                continue
            return node
        numeric |= attrs
        op = ast.Mult() if f.id == PREFIX + "_repeat" else ast.Mod()  # type: ignore[attr-defined]
        return fold_arithmetic(ast.BinOp(left=node.args[0], op=op, right=node.args[1]))

    def visit_BinOp(self, node: ast.BinOp) -> ast.AST:
        """`+` and `-` of constants (pinned variables) done once."""
        return fold_arithmetic(self.generic_visit(node))  # type: ignore[arg-type]


#: How a comparison `x OP c` changes as x grows: +1 (false to true at most), -1 (true to false at most).
_GROWS: dict[type[ast.cmpop], int] = {ast.Gt: 1, ast.GtE: 1, ast.Lt: -1, ast.LtE: -1}


def _polarity(e: ast.expr, attr: str) -> int | None:
    """How the truth of `e` moves as `self.attr` grows, the rest kept: 0 (it does not read it),
    +1 (it can only turn true), -1 (only false), None (either, or not known): comparisons of
    `self.attr` itself with what does not read it, under `not`, `and`, `or`."""
    if not _reads(e, attr):
        return 0
    if isinstance(e, ast.UnaryOp) and isinstance(e.op, ast.Not):
        p = _polarity(e.operand, attr)
        return None if p is None else -p
    if isinstance(e, ast.BoolOp):
        ps = {_polarity(v, attr) for v in e.values} - {0}
        return ps.pop() if len(ps) == 1 else None
    if isinstance(e, ast.Compare) and len(e.ops) == 1:
        grows = _GROWS.get(type(e.ops[0]))
        left, right = e.left, e.comparators[0]
        if grows is None:
            return None
        if _is_attr(left, attr) and not _reads(right, attr):
            return grows
        if _is_attr(right, attr) and not _reads(left, attr):
            return -grows
    return None


def _is_attr(node: ast.AST, attr: str) -> bool:
    return self_attr_load(node) and node.attr == attr  # type: ignore[attr-defined]


def _reads(e: ast.AST, attr: str) -> bool:
    return any(_is_attr(n, attr) for n in ast.walk(e))


class _Shared(ast.NodeTransformer):
    """`self.x` read more than once in a test: read once into a local (`(_llfsm_mon_x := self.x)`
    where it is first evaluated, the local after).  Used in the fast path only, under a `try`
    that falls back to the checks one by one, so a first read a branch skipped costs nothing
    but the fallback."""

    def share(self, node: ast.expr) -> ast.expr:
        counts: dict[str, int] = {}
        for n in ast.walk(node):
            if self_attr_load(n):
                counts[n.attr] = counts.get(n.attr, 0) + 1  # type: ignore[attr-defined]
        self.shared = {a for a, c in counts.items() if c > 1}
        self.seen: set[str] = set()
        out = self.visit(node)
        assert isinstance(out, ast.expr)
        return out

    def visit_Attribute(self, node: ast.Attribute) -> ast.AST:
        if not self_attr_load(node) or node.attr not in self.shared:
            return self.generic_visit(node)
        local = PREFIX + "a_" + node.attr
        if node.attr in self.seen:
            return ast.Name(id=local, ctx=ast.Load())
        self.seen.add(node.attr)
        return ast.NamedExpr(target=ast.Name(id=local, ctx=ast.Store()), value=node)


def _locate(node: ast.AST, at: ast.AST) -> Any:
    """`node` and everything in it at the line of `at` (a check reads as the return it precedes)."""
    for n in ast.walk(node):
        for attr in ("lineno", "col_offset", "end_lineno", "end_col_offset"):
            if attr in n._attributes:
                setattr(n, attr, getattr(at, attr, 0))
    return node


def _call(fn: str, *args: Any) -> ast.stmt:
    call = ast.Call(
        func=ast.Name(id=fn, ctx=ast.Load()),
        args=[ast.Name(id="self", ctx=ast.Load()), *(a if isinstance(a, ast.expr) else ast.Constant(a) for a in args)],
        keywords=[],
    )
    return ast.Expr(value=call)


class _Inline(ast.NodeTransformer):
    """An atom's tree (over `M` and `E`) as code of a ringlet of machine `own`."""

    def __init__(
        self, own: int, state: str | None, pins: dict[str, Any] | None = None, pinned: set[str] | None = None
    ) -> None:
        self.own = own
        self.state = state
        self.pins = pins or {}
        self.pinned = pinned if pinned is not None else set()

    def visit_Attribute(self, node: ast.Attribute) -> ast.AST:
        if node.attr in self.pins and _is_own(node, node.attr, self.own):
            self.pinned.add(node.attr)
            return ast.Constant(self.pins[node.attr])
        return self.generic_visit(node)

    def visit_Subscript(self, node: ast.Subscript) -> ast.AST:
        if self.state is not None and node.value is not None and _is_own(node.value, "STATES", self.own):
            sl = node.slice
            if _is_own(sl, "_state", self.own):
                return ast.Constant(self.state)
        if isinstance(node.value, ast.Name) and node.value.id == "M" and isinstance(node.slice, ast.Constant):
            if node.slice.value == self.own:
                return ast.Name(id="self", ctx=ast.Load())
            return ast.Subscript(value=ast.Name(id=MACHINES, ctx=ast.Load()), slice=node.slice, ctx=ast.Load())
        return self.generic_visit(node)

    def visit_Name(self, node: ast.Name) -> ast.AST:
        if node.id in PURE or node.id in HELPERS:
            return ast.Name(id=PREFIX + node.id, ctx=ast.Load())
        if node.id == "E":
            return ast.Name(id=PUBLISHED, ctx=ast.Load())
        return node


def _is_own(node: ast.AST, attr: str, own: int) -> bool:
    """`M[own].attr`."""
    return (
        isinstance(node, ast.Attribute)
        and node.attr == attr
        and isinstance(node.value, ast.Subscript)
        and isinstance(node.value.value, ast.Name)
        and node.value.value.id == "M"
        and isinstance(node.value.slice, ast.Constant)
        and node.value.slice.value == own
    )


_COMPARE: dict[type[ast.cmpop], Callable[[Any, Any], bool]] = {
    ast.Eq: lambda a, b: a == b,
    ast.NotEq: lambda a, b: a != b,
    ast.In: lambda a, b: a in b,
    ast.NotIn: lambda a, b: a not in b,
    ast.Lt: lambda a, b: a < b,
    ast.LtE: lambda a, b: a <= b,
    ast.Gt: lambda a, b: a > b,
    ast.GtE: lambda a, b: a >= b,
}


def _fold(node: ast.expr) -> ast.expr:
    """Comparisons of constants (a state's name with the names it is compared with, a pinned
    number with a bound), `not` and `and`/`or` over them, folded to constants; anything else as
    it is."""
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.Not):
        inner = _fold(node.operand)
        if isinstance(inner, ast.Constant):
            return ast.Constant(not inner.value)
        if isinstance(inner, ast.UnaryOp) and isinstance(inner.op, ast.Not):
            return inner.operand  # in a test, `not not x` is x
        return ast.UnaryOp(op=node.op, operand=inner)
    if isinstance(node, ast.BoolOp):
        is_and = isinstance(node.op, ast.And)
        kept = []
        for v in (_fold(x) for x in node.values):
            if isinstance(v, ast.Constant):
                if bool(v.value) != is_and:
                    return ast.Constant(not is_and)  # a false term of `and`, a true one of `or`
                continue  # a true term of `and` (a false one of `or`) says nothing
            kept.append(v)
        if not kept:
            return ast.Constant(is_and)
        # a lone term keeps its truth, not its value: the check only tests it
        return kept[0] if len(kept) == 1 else ast.BoolOp(op=node.op, values=kept)
    if isinstance(node, ast.Compare) and len(node.ops) == 1 and type(node.ops[0]) in _COMPARE:
        left, right = node.left, node.comparators[0]
        values = _literal(left), _literal(right)
        if values[0] is not _NO and values[1] is not _NO:
            try:
                return ast.Constant(bool(_COMPARE[type(node.ops[0])](*values)))
            except TypeError:
                return node
    return node


_NO = object()


def _literal(node: ast.expr) -> Any:
    """A constant's value, or a tuple/set of constants, else _NO."""
    if isinstance(node, ast.Constant):
        return node.value
    if isinstance(node, ast.Tuple | ast.Set) and all(isinstance(e, ast.Constant) for e in node.elts):
        return tuple(e.value for e in node.elts)  # type: ignore[attr-defined]
    return _NO
