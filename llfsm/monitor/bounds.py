"""What the constant comparisons of numbers in the checks at one return decide, so that the
test that all checks hold there (llfsm.monitor.variant, the fast path) costs one comparison per
number: `x < 5 and x < 7 and x >= 0` is tested as `0 <= x < 5`, and a term that interval already
decides is left out of the test (`x != -1`, `not x == 9`); arithmetic of numeric constants (a
machine's pinned variables, llfsm.monitor.variant) is done once, here, so that `x < limit * 10`
with `limit` pinned to 3 is the bound `x < 30`.

Everything here rests on the variable holding a number (an int, a float, a bool: ordered, so
the tightest bound implies the others, and a number inside an interval differs from one
outside it): callers make it only for variables the machine's code keeps a number
(`ClassReads.numeric`), which join the variant's NUMERIC, checked by the monitor at the start
and wherever the gate sets them.  Where the merged test fails (NaN fails every bound), the
checks one by one decide, as they did before.
"""

from __future__ import annotations

import ast
import math
import operator
from collections.abc import Callable
from typing import Any

from ..runtime.reads import number_literal

#: A comparison the other way round (`c < x` is `x > c`), and its negation for numbers (NaN
#: aside: `not x < c` holds for NaN where `x >= c` does not, which only sends the test that
#: merges bounds to the checks one by one).
_FLIP: dict[type[ast.cmpop], type[ast.cmpop]] = {ast.Lt: ast.Gt, ast.LtE: ast.GtE, ast.Gt: ast.Lt, ast.GtE: ast.LtE}
_NEGATE: dict[type[ast.cmpop], type[ast.cmpop]] = {ast.Lt: ast.GtE, ast.LtE: ast.Gt, ast.Gt: ast.LtE, ast.GtE: ast.Lt}
#: (value, strict) of the tightest bound each way; None: no bound that way
Limits = tuple[tuple[int | float, bool] | None, tuple[int | float, bool] | None]
Bound = tuple[type[ast.cmpop], int | float, int]  # OP with x on the left, c, where it was


def merge_bounds(holding: list[ast.expr], numeric: Callable[[str], bool]) -> tuple[list[ast.expr], set[str]]:
    """The terms of the test that all checks hold, with the constant bounds of each number
    merged into one comparison each way, and the terms `x == c`/`x != c` those bounds decide
    true left out; and the variables that rests on (they must hold numbers).  `numeric(x)`:
    whether the machine's code keeps `x` a number."""
    bounds: dict[str, list[Bound]] = {}
    for k, term in enumerate(holding):
        b = _bound(term)
        if b is not None and numeric(b[0]):
            bounds.setdefault(b[0], []).append((b[1], b[2], k))
    limits = {attr: _limits(found) for attr, found in bounds.items()}
    implied: dict[int, str] = {}
    for k, term in enumerate(holding):
        e = _equality(term)
        if e is not None and e[0] in limits and _decided(e[1], e[2], limits[e[0]]):
            implied[k] = e[0]
    merged = {attr: found for attr, found in bounds.items() if len(found) > 1}
    if not merged and not implied:
        return holding, set()
    out: list[ast.expr] = []
    placed = {found[0][2]: attr for attr, found in merged.items()}  # where each attr's first bound was
    dropped = {k for found in merged.values() for _op, _c, k in found} | set(implied)
    for k, term in enumerate(holding):
        attr = placed.get(k)
        if attr is not None:
            out.append(_interval(attr, limits[attr]))
        elif k not in dropped:
            out.append(term)
    return out, set(merged) | set(implied.values())


def self_attr_load(node: ast.AST) -> bool:
    """`self.x` read."""
    return (
        isinstance(node, ast.Attribute)
        and isinstance(node.ctx, ast.Load)
        and isinstance(node.value, ast.Name)
        and node.value.id == "self"
    )


def _bound(term: ast.expr) -> tuple[str, type[ast.cmpop], int | float] | None:
    """`self.x OP c` (OP one of < <= > >=, c an int or float constant, not NaN), read either way
    round and under `not`, as (x, OP with x on the left, c)."""
    negate = isinstance(term, ast.UnaryOp) and isinstance(term.op, ast.Not)
    node = term.operand if negate else term  # type: ignore[attr-defined]
    if not (isinstance(node, ast.Compare) and len(node.ops) == 1 and type(node.ops[0]) in _FLIP):
        return None
    op, left, right = type(node.ops[0]), node.left, node.comparators[0]
    if self_attr_load(right):
        op, left, right = _FLIP[op], right, left
    c = number_literal(right)
    if not self_attr_load(left) or c is None:
        return None
    return left.attr, (_NEGATE[op] if negate else op), c  # type: ignore[attr-defined]


def _equality(term: ast.expr) -> tuple[str, bool, int | float] | None:
    """`self.x == c` or `self.x != c` (c a number, not NaN), either way round and under `not`,
    as (x, whether it says "equal", c)."""
    negate = isinstance(term, ast.UnaryOp) and isinstance(term.op, ast.Not)
    node = term.operand if negate else term  # type: ignore[attr-defined]
    if not (isinstance(node, ast.Compare) and len(node.ops) == 1 and isinstance(node.ops[0], ast.Eq | ast.NotEq)):
        return None
    left, right = node.left, node.comparators[0]
    if self_attr_load(right):
        left, right = right, left
    c = number_literal(right)
    if not self_attr_load(left) or c is None:
        return None
    return left.attr, isinstance(node.ops[0], ast.Eq) != negate, c  # type: ignore[attr-defined]


def _limits(found: list[Bound]) -> Limits:
    """The tightest bound each way among `found`: the largest lower bound (strict before not at
    one value), the smallest upper bound (likewise)."""
    upper = [(c, op is ast.Lt) for op, c, _k in found if op in (ast.Lt, ast.LtE)]
    lower = [(c, op is ast.Gt) for op, c, _k in found if op in (ast.Gt, ast.GtE)]
    return (max(lower) if lower else None, min(upper, key=lambda b: (b[0], not b[1])) if upper else None)


def _decided(equal: bool, c: int | float, limits: Limits) -> bool:
    """Whether a number within `limits` makes `x == c` (`equal`) or `x != c` true whatever it is."""
    lo, hi = limits
    below = lo is not None and (c < lo[0] or (c == lo[0] and lo[1]))
    above = hi is not None and (c > hi[0] or (c == hi[0] and hi[1]))
    if not equal:
        return below or above  # c lies outside: x cannot be it
    return lo is not None and hi is not None and lo == (c, False) and hi == (c, False)  # c <= x <= c


def _interval(attr: str, limits: Limits) -> ast.expr:
    """The tightest bound each way of `self.attr`, as one comparison (`lo <= x < hi`)."""
    lo, hi = limits
    ops: list[ast.cmpop] = []
    values: list[ast.expr] = []
    if lo is not None:
        ops.append(ast.Lt() if lo[1] else ast.LtE())
        values.append(ast.Constant(lo[0]))
    values.append(ast.Attribute(value=ast.Name(id="self", ctx=ast.Load()), attr=attr, ctx=ast.Load()))
    if hi is not None:
        ops.append(ast.Lt() if hi[1] else ast.LtE())
        values.append(ast.Constant(hi[0]))
    return ast.Compare(left=values[0], ops=ops, comparators=values[1:])


#: Operators of numbers done once where both sides are constants.
_ARITHMETIC: dict[type[ast.operator], Callable[[Any, Any], Any]] = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Mod: operator.mod,
}
#: Larger operands are left to run time (an int's multiplication grows with its digits).
_MAX_BITS = 256


def fold_arithmetic(node: ast.BinOp) -> ast.expr:
    """`a OP b` of two numeric constants (+ - * %) as the constant it makes, where it is a
    finite number; anything else (a division by zero, NaN, huge ints) as it is, to run as
    written."""
    a, b = number_literal(node.left), number_literal(node.right)
    fn = _ARITHMETIC.get(type(node.op))
    if a is None or b is None or fn is None:
        return node
    if isinstance(a, int) and isinstance(b, int) and max(a.bit_length(), b.bit_length()) > _MAX_BITS:
        return node
    try:
        value = fn(a, b)
    except (ArithmeticError, ValueError):
        return node
    if isinstance(value, float) and not math.isfinite(value):
        return node
    return ast.Constant(value)
