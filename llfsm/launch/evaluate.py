"""`$(eval EXPR)`: arithmetic, comparisons and boolean logic over strings and numbers, and nothing
else: no code runs from a launch file.

launch hands the text to Python's `eval`; llfsm reads it with `ast` and evaluates only literals
(strings, integers, floats, True, False, None), `+ - * / // % **`, unary `- + not`, `and`,
`or`, comparisons (chains, `in`, `not in` on strings) and `a if c else b`.  A name, call,
attribute, subscript, comprehension, lambda, container or f-string is refused, naming what it
is.  Sizes are bounded (SPEC 18): the expression's length, an integer's bits, a string's length,
so `9**9**9` or `'x' * 10**9` is one clear refusal instead of a process that never ends.

The value is written as launch writes `str(eval(...))`: `True`, `3`, `2.5`, so a condition on
`$(eval ...)` reads it as launch's does (`if` takes `true`, `1`, `false`, `0`, any case).
"""

from __future__ import annotations

import ast
import operator
from collections.abc import Callable
from typing import Any

#: Longest expression text read, in characters.
MAX_TEXT = 4096
#: Largest integer kept, in bits, and longest string, in characters.
MAX_INT_BITS = 4096
MAX_STR = 64 * 1024

_BINARY: dict[type, Callable[[Any, Any], Any]] = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
    ast.FloorDiv: operator.floordiv,
    ast.Mod: operator.mod,
    ast.Pow: operator.pow,
}
_COMPARE: dict[type, Callable[[Any, Any], Any]] = {
    ast.Eq: operator.eq,
    ast.NotEq: operator.ne,
    ast.Lt: operator.lt,
    ast.LtE: operator.le,
    ast.Gt: operator.gt,
    ast.GtE: operator.ge,
    ast.In: lambda a, b: operator.contains(b, a),
    ast.NotIn: lambda a, b: not operator.contains(b, a),
}
#: What a refused node is called in the message.
_REFUSED = {
    ast.Name: "a name",
    ast.Call: "a call",
    ast.Attribute: "an attribute",
    ast.Subscript: "a subscript",
    ast.Lambda: "a lambda",
    ast.ListComp: "a comprehension",
    ast.SetComp: "a comprehension",
    ast.DictComp: "a comprehension",
    ast.GeneratorExp: "a comprehension",
    ast.JoinedStr: "an f-string",
    ast.NamedExpr: "an assignment",
    ast.Await: "an await",
    ast.Yield: "a yield",
    ast.YieldFrom: "a yield",
    ast.Starred: "a starred expression",
    ast.Slice: "a slice",
}


class ExpressionError(ValueError):
    """An expression that is refused or cannot be evaluated (the message says which and why)."""


def evaluate(text: str) -> str:
    """The value of `text` as launch's `$(eval)` writes it (`str()` of the result)."""
    if len(text) > MAX_TEXT:
        raise ExpressionError(f"longer than {MAX_TEXT} characters")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as e:
        raise ExpressionError(f"not an expression ({e.msg})") from None
    except (RecursionError, MemoryError, ValueError):
        raise ExpressionError("nested too deeply") from None
    try:
        return str(_value(tree.body))
    except RecursionError:
        raise ExpressionError("nested too deeply") from None


def _value(node: ast.expr) -> Any:
    if isinstance(node, ast.Constant):
        v = node.value
        if v is None or isinstance(v, (bool, int, float, str)):
            return _bounded(v)
        raise ExpressionError(f"{type(v).__name__} literals are not allowed (strings and numbers only)")
    if isinstance(node, ast.BinOp):
        return _binary(node)
    if isinstance(node, ast.UnaryOp):
        operand = _value(node.operand)
        if isinstance(node.op, ast.Not):
            return not operand
        if isinstance(node.op, ast.Invert):
            raise ExpressionError("the operator `~` is not allowed")
        _number(operand, node.op)
        return -operand if isinstance(node.op, ast.USub) else +operand
    if isinstance(node, ast.BoolOp):
        # as Python's: the first operand that decides, else the last
        stop = bool if isinstance(node.op, ast.Or) else (lambda v: not v)
        for operand in node.values[:-1]:
            result = _value(operand)
            if stop(result):
                return result
        return _value(node.values[-1])
    if isinstance(node, ast.Compare):
        left = _value(node.left)
        for op, comparator in zip(node.ops, node.comparators, strict=True):
            if type(op) not in _COMPARE:
                raise ExpressionError(f"the comparison `{_source(op)}` is not allowed (==, !=, <, <=, >, >=, in)")
            right = _value(comparator)
            if isinstance(op, (ast.In, ast.NotIn)) and not (isinstance(left, str) and isinstance(right, str)):
                raise ExpressionError("`in` compares strings only")
            try:
                if not _COMPARE[type(op)](left, right):
                    return False
            except TypeError as e:
                raise ExpressionError(str(e)) from None
            left = right
        return True
    if isinstance(node, ast.IfExp):
        return _value(node.body) if _value(node.test) else _value(node.orelse)
    what = _REFUSED.get(type(node))
    if what is None:
        what = "a container" if isinstance(node, (ast.List, ast.Tuple, ast.Set, ast.Dict)) else f"`{_source(node)}`"
    raise ExpressionError(
        f"{what} is not allowed: only arithmetic, comparisons and boolean logic on strings and numbers"
    )


def _binary(node: ast.BinOp) -> Any:
    op = type(node.op)
    if op not in _BINARY:
        raise ExpressionError(f"the operator `{_source(node.op)}` is not allowed")
    left, right = _value(node.left), _value(node.right)
    if op is ast.Mod and isinstance(left, str):
        raise ExpressionError("`%` formatting of strings is not allowed")
    if op is ast.Pow:
        _number(left, node.op)
        _number(right, node.op)
        big = isinstance(left, int) and isinstance(right, int) and right > 0 and abs(left) > 1
        if big and right * left.bit_length() > MAX_INT_BITS:
            raise ExpressionError(f"{left} ** {right} is larger than {MAX_INT_BITS} bits")
    if op is ast.Mult:
        text, count = (left, right) if isinstance(left, str) else (right, left)
        if isinstance(text, str) and isinstance(count, int) and len(text) * max(count, 0) > MAX_STR:
            raise ExpressionError(f"a string repeated {count} times is longer than {MAX_STR // 1024} KiB")
    try:
        return _bounded(_BINARY[op](left, right))
    except ZeroDivisionError:
        raise ExpressionError("division by zero") from None
    except OverflowError:
        raise ExpressionError("a number too large") from None
    except TypeError as e:
        raise ExpressionError(str(e)) from None


def _number(value: Any, op: ast.AST) -> None:
    if isinstance(value, str) or value is None:
        raise ExpressionError(f"`{_source(op)}` needs numbers, not {value!r}")


def _bounded(value: Any) -> Any:
    if isinstance(value, complex):  # (-8) ** 0.5
        raise ExpressionError("the result is a complex number")
    if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > MAX_INT_BITS:
        raise ExpressionError(f"an integer larger than {MAX_INT_BITS} bits")
    if isinstance(value, str) and len(value) > MAX_STR:
        raise ExpressionError(f"a string longer than {MAX_STR // 1024} KiB")
    return value


_OPERATOR_TEXT = {
    ast.MatMult: "@",
    ast.LShift: "<<",
    ast.RShift: ">>",
    ast.BitOr: "|",
    ast.BitXor: "^",
    ast.BitAnd: "&",
    ast.Is: "is",
    ast.IsNot: "is not",
    ast.Invert: "~",
}


def _source(node: ast.AST) -> str:
    text = _OPERATOR_TEXT.get(type(node))
    if text is not None:
        return text
    try:
        return ast.unparse(node)
    except Exception:  # an operator node alone has no source form
        return type(node).__name__
