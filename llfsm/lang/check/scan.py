"""One traversal of a code file for everything the code rules need, and the bytecode compile
that proves a piece compiles where the generated module puts it.

The scan is the checker's hot path (every file of every machine, in CI): one explicit-stack
walk notes the names read and bound, the reserved names, `global`/`return` and the like, and
whether the file is "plain" (made only of nodes no compile step can refuse), which spares the
compile for almost every section and guard.  Nothing here runs user code: `compile` only
turns the tree into bytecode.
"""

from __future__ import annotations

import ast
import io
import itertools
import tokenize
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TypeVar

from ...runtime.machine import MACROS
from ..reader import MAX_CODE_DEPTH
from ..scopes import child_nodes

_Node = TypeVar("_Node", bound=ast.stmt | ast.arg)  # what compile_error makes, to be given a place

_BINDERS = (
    ast.NamedExpr,
    ast.Import,
    ast.ImportFrom,
    ast.FunctionDef,
    ast.AsyncFunctionDef,
    ast.ClassDef,
    ast.ExceptHandler,
    ast.MatchAs,
    ast.MatchStar,
    ast.MatchMapping,
)
_NESTS = (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)
_ESCAPES = (ast.Return, ast.Yield, ast.YieldFrom, ast.Await)

#: Node types that no compiler check can refuse inside a method body, whatever surrounds them
#: (the parser has already accepted them).  A file made only of these, shallow enough that 20
#: nested blocks are impossible, skips the bytecode compile: the compile is a third of check's
#: time, and almost every section and guard is this simple.  The rest (break, starred targets,
#: lambdas, async comprehensions, import *, ...) is compiled as before.
_PLAIN: frozenset[type[ast.AST]] = frozenset(
    {
        ast.Expr, ast.Assign, ast.AugAssign, ast.AnnAssign, ast.If, ast.For, ast.While, ast.Pass,
        ast.Import, ast.ImportFrom, ast.alias, ast.Assert, ast.Raise, ast.Delete, ast.With, ast.withitem,
        ast.Try, ast.ExceptHandler, ast.BoolOp, ast.BinOp, ast.UnaryOp, ast.Compare, ast.Call,
        ast.keyword, ast.IfExp, ast.Attribute, ast.Subscript, ast.Slice, ast.Name, ast.Constant,
        ast.List, ast.Tuple, ast.Dict, ast.Set, ast.JoinedStr, ast.FormattedValue,
        ast.ListComp, ast.SetComp, ast.DictComp, ast.GeneratorExp, ast.comprehension,
        ast.Load, ast.Store, ast.Del,
        ast.And, ast.Or, ast.Add, ast.Sub, ast.Mult, ast.MatMult, ast.Div, ast.Mod, ast.Pow, ast.LShift,
        ast.RShift, ast.BitOr, ast.BitXor, ast.BitAnd, ast.FloorDiv, ast.Invert, ast.Not, ast.UAdd,
        ast.USub, ast.Eq, ast.NotEq, ast.Lt, ast.LtE, ast.Gt, ast.GtE, ast.Is, ast.IsNot, ast.In,
        ast.NotIn,
    }
)  # fmt: skip
_PLAIN_DEPTH = 20  # CPython refuses more than 20 statically nested blocks


_PLAIN_IF_CHECKED = (ast.ImportFrom, ast.Call, ast.Try, ast.comprehension)
_PLAIN_IF_CHECKED_T: frozenset[type[ast.AST]] = frozenset(_PLAIN_IF_CHECKED)
_NESTS_T: frozenset[type[ast.AST]] = frozenset(_NESTS)
#: The node types `scan_code` notes something about (besides `Name`): every other node is only
#: walked through.  (`ast.parse` makes nodes of these exact classes, never of subclasses.)
_SPECIAL: frozenset[type[ast.AST]] = frozenset(
    {ast.Import, ast.ImportFrom, ast.Attribute, ast.arg, ast.alias, ast.Global, ast.Nonlocal}
    | {ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef, ast.ExceptHandler, ast.MatchAs, ast.MatchStar}
    | {ast.MatchMapping, *_BINDERS, *_ESCAPES}
)


def _plain_as_used(node: ast.AST) -> bool:
    """For a `_PLAIN_IF_CHECKED` node: whether none of its compile-time-only errors applies."""
    if isinstance(node, ast.ImportFrom):
        return node.module != "__future__" and all(a.name != "*" for a in node.names)
    if isinstance(node, ast.Call):
        given = [k.arg for k in node.keywords if k.arg is not None]
        return len(given) == len(set(given))  # `keyword argument repeated` is the compiler's
    if isinstance(node, ast.Try):
        return all(h.type is not None for h in node.handlers[:-1])
    return not node.is_async  # type: ignore[attr-defined]  # a comprehension


@dataclass
class Scanned:
    """What `scan_code` found in one code file."""

    loads: dict[str, ast.Name] = field(default_factory=dict)  # first use of each name read
    bound: set[str] = field(default_factory=set)  # every name the code binds, in any scope
    reserved: list[ast.Name] = field(default_factory=list)  # `_llfsm*`, or a macro assigned
    escapes: list[tuple[ast.stmt | ast.expr, str]] = field(default_factory=list)  # global/nonlocal; top-level return...
    may_bind_variable: bool = False  # a :=, import, def... binds a name of the mapping, or `self` is used
    too_deep: ast.AST | None = None  # the first node nested deeper than MAX_CODE_DEPTH: stop there
    plain: bool = True  # only `_PLAIN` nodes, used as it allows: compiling to bytecode cannot fail
    imports: list[ast.Import | ast.ImportFrom] = field(default_factory=list)  # for LF041
    to_msg: list[ast.Attribute] = field(default_factory=list)  # `x.to_msg`, for LF041


def scan_code(tree: ast.AST, mapping: Mapping[str, str]) -> Scanned:
    """Everything the checker needs from a code file, in one traversal (checks run on every
    file of every machine in CI, so this is the checker's hot path)."""
    out = Scanned()
    bound = out.bound
    stack: list[tuple[ast.AST, bool, int]] = [(tree, False, 0)]
    name_t, plain_t, checked_t, special_t, nests_t = ast.Name, _PLAIN, _PLAIN_IF_CHECKED_T, _SPECIAL, _NESTS_T
    while stack:
        node, nested, depth = stack.pop()
        if depth > MAX_CODE_DEPTH:
            # the compiler's walks recurse: a deeper tree would exhaust Python's stack in them
            out.too_deep = node
            return out
        for child in child_nodes(node):
            t = type(child)
            if out.plain and (
                t not in plain_t or depth >= _PLAIN_DEPTH or (t in checked_t and not _plain_as_used(child))
            ):
                out.plain = False
            if t is not name_t and t not in special_t:  # most nodes: nothing to note, only to walk
                stack.append((child, nested or t in nests_t, depth + 1))
                continue
            if t is name_t:
                name: ast.Name = child  # type: ignore[assignment]  # its type is ast.Name, exactly
                if name.id == "self":
                    # the user's own in a method, lambda or comprehension that binds it, else
                    # the machine's: the scoped walk decides (LF013 there)
                    out.may_bind_variable = True
                elif name.id.startswith("_llfsm"):
                    out.reserved.append(name)
                elif isinstance(name.ctx, ast.Load | ast.Del):  # `del x` reads x as well
                    out.loads.setdefault(name.id, name)
                else:
                    bound.add(name.id)
                    if name.id in MACROS:
                        out.reserved.append(name)
                continue
            if isinstance(child, ast.Import | ast.ImportFrom):
                out.imports.append(child)
            elif isinstance(child, ast.Attribute) and child.attr == "to_msg":
                out.to_msg.append(child)
            if isinstance(child, ast.arg):
                bound.add(child.arg)
                if child.arg == "self":  # the scoped walk looks for machine names it would hide
                    out.may_bind_variable = True
                elif child.arg.startswith("_llfsm"):
                    out.reserved.append(
                        ast.Name(id=child.arg, ctx=ast.Store(), lineno=child.lineno, col_offset=child.col_offset)
                    )
            elif isinstance(child, ast.alias):
                bound.add((child.asname or child.name).split(".")[0])
            elif (
                isinstance(
                    child,
                    ast.FunctionDef
                    | ast.AsyncFunctionDef
                    | ast.ClassDef
                    | ast.ExceptHandler
                    | ast.MatchAs
                    | ast.MatchStar,
                )
                and child.name
            ):
                bound.add(child.name)
            elif isinstance(child, ast.MatchMapping) and child.rest:
                bound.add(child.rest)
            elif isinstance(child, ast.Global | ast.Nonlocal):
                bound.update(child.names)
            if isinstance(child, ast.Global | ast.Nonlocal):
                out.escapes.append((child, "global"))
            elif not nested and isinstance(child, _ESCAPES):
                out.escapes.append((child, "return"))
            if isinstance(child, _BINDERS):
                names = (
                    [a.asname or a.name.split(".")[0] for a in child.names]
                    if isinstance(child, ast.Import | ast.ImportFrom)
                    else [
                        getattr(child, "name", None)
                        or getattr(getattr(child, "target", None), "id", None)
                        or getattr(child, "rest", None)
                    ]
                )
                if any(n in mapping for n in names if n):
                    out.may_bind_variable = True
            stack.append((child, nested or isinstance(child, _NESTS), depth + 1))
    return out


def _located(node: _Node) -> _Node:
    node.lineno = node.end_lineno = 1
    node.col_offset = node.end_col_offset = 0
    return node


def compile_error(tree: ast.Module, guard: bool) -> SyntaxError | None:
    """The error `compile` gives for code placed in a method body as the generated module
    places it (a guard as the condition of an `if`); None if it compiles."""
    body: list[ast.stmt] = tree.body
    if guard:
        test: ast.expr = tree.body[0].value  # type: ignore[attr-defined]  # check: one expression
        body = [_located(ast.If(test=test, body=[_located(ast.Pass())], orelse=[]))]
    args = ast.arguments(
        posonlyargs=[], args=[_located(ast.arg(arg="self"))], kwonlyargs=[], kw_defaults=[], defaults=[]
    )
    method = ast.FunctionDef(name="_llfsm_check", args=args, body=body or [_located(ast.Pass())], decorator_list=[])
    try:
        with warnings.catch_warnings():  # `x is 1` and the like: not check's business, nor stderr's
            warnings.simplefilter("ignore")
            compile(ast.Module(body=[_located(method)], type_ignores=[]), "<check>", "exec", dont_inherit=True)
    except SyntaxError as e:
        return e
    except (RecursionError, MemoryError, ValueError, TypeError) as e:
        return SyntaxError(f"{type(e).__name__}")
    return None


def guard_semicolon(text: str) -> tuple[int, int] | None:
    """(line, column) of a `;` token in a guard, if any: `x;` parses as one statement, but the
    guard becomes the condition of an `if`, where a `;` is a syntax error."""
    if ";" not in text:
        return None
    try:
        for tok in tokenize.generate_tokens(io.StringIO(text).readline):
            if tok.type == tokenize.OP and tok.string == ";":
                return tok.start[0], tok.start[1] + 1
    except (tokenize.TokenError, SyntaxError):
        return None
    return None


def trailing_semicolons(text: str) -> list[tuple[int, int]]:
    """(line, column) of each `;` that ends a line's code (C++'s habit); `a = 1; b = 2` is left
    alone.  At most a few: one per line is enough to make the point."""
    out: list[tuple[int, int]] = []
    try:
        toks = list(tokenize.generate_tokens(io.StringIO(text).readline))
    except (tokenize.TokenError, SyntaxError):
        return out
    for tok, nxt in itertools.pairwise(toks):
        if tok.type == tokenize.OP and tok.string == ";" and nxt.type in (tokenize.NEWLINE, tokenize.COMMENT):
            out.append((tok.start[0], tok.start[1] + 1))
            if len(out) >= 20:
                break
    return out


def single_expression(tree: ast.Module) -> bool:
    return len(tree.body) == 1 and isinstance(tree.body[0], ast.Expr)
