"""Properties (SPEC 11; docs/verify.md, "Properties"): their kinds, the temporal formulas of
`ltl:` and `ctl:`, and the atoms, Python boolean expressions compiled to functions of a view of
a configuration.

Atoms are parsed with `ast` and checked like a guard before anything is compiled: only the
names of the arrangement's machines (`p.count`, `state(p)`), the functions `state`,
`suspended`, `finished`, `published` and a few pure builtins (`len`, `abs`, `min`, `max`,
`round`, `int`, `float`, `bool`, `str`), constants, arithmetic, comparisons and subscripts; no
attribute that starts with `_`, no other call, no lambda, comprehension or assignment.  A
machine, state or variable that does not exist is one clear error, as is anything else.  The
checked tree is then rewritten to read the machine objects (`state(p)` becomes the name of
machine p's current state) and compiled: user text is never `eval`ed as it is written.

The temporal operators of `ltl:`/`ctl:` are read by a small parser over Python's tokens:
`!`/`not`, `&`/`and`, `|`/`or`, `->`, `X`, `F`, `G`, `U`, and `A`, `E` (also written together:
`AG`, `EF`...); what lies between them is an atom.  In those formulas the names A, E, F, G, U, X
(and AG, AF, AX, EG, EF, EX) are the operators, never machines.
"""

from __future__ import annotations

import ast
import difflib
import io
import tokenize
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

#: The kinds of property, as a verification file and `--property KIND:TEXT` name them.
KINDS = ("always", "never", "reachable", "eventually", "leads_to", "ctl", "ltl")
#: Longest property text, and deepest nesting, accepted.
MAX_TEXT = 10_000
MAX_DEPTH = 100

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
#: The functions of the property language, and what they take.
FUNCTIONS = ("state", "suspended", "finished", "published")

_TEMPORAL = {"X", "F", "G", "AX", "EX", "AF", "EF", "AG", "EG"}
_QUANTIFIERS = {"A", "E"}
_RESERVED = _TEMPORAL | _QUANTIFIERS | {"U"}

Formula = tuple[Any, ...]


class PropertyError(ValueError):
    """A property that does not parse or names what does not exist: one line for the user."""


@dataclass
class MachineInfo:
    """What an atom may name of one machine."""

    index: int
    name: str
    states: tuple[str, ...]
    variables: tuple[str, ...]  # machine variables, then inputs


@dataclass
class Atom:
    text: str
    #: the compiled atom: fn(machines, published) is true or false (the explorer reports an
    #: exception, AtomError, with the atom's text and `where`)
    fn: Callable[[Sequence[Any], frozenset[str]], Any]
    where: str = "--property"


@dataclass
class Property:
    """One property: `formula` over the atoms `atoms` (indices into the verification's atoms)."""

    kind: str
    text: str
    name: str
    formula: Formula
    where: str = "--property"
    #: the atoms' texts, in the order `("atom", k)` numbers them inside `formula`
    atoms: list[str] = field(default_factory=list)


def parse_property(kind: str, text: Any, machines: dict[str, MachineInfo], name: str | None = None,
                   where: str = "--property") -> tuple[Property, list[Atom]]:  # fmt: skip
    """The property, and its atoms compiled (local numbering: `("atom", k)` is the k-th)."""
    if kind not in KINDS:
        raise PropertyError(f"{where}: unknown kind {kind!r} (one of {', '.join(KINDS)})")
    if kind == "leads_to" and isinstance(text, list):
        if len(text) != 2 or not all(isinstance(t, str) for t in text):
            raise PropertyError(f"{where}: leads_to takes two conditions, [A, B]")
        shown = f"{text[0]} leads to {text[1]}"
        parts = [str(t) for t in text]
    elif not isinstance(text, str):
        raise PropertyError(f"{where}: the {kind} property must be text")
    else:
        shown = " ".join(text.split())
        parts = [text]
    for t in parts:
        if len(t) > MAX_TEXT:
            raise PropertyError(f"{where}: a property of more than {MAX_TEXT:,} characters")
    texts: list[str] = []

    def atom(src: str) -> Formula:
        texts.append(src)
        return ("atom", len(texts) - 1)

    if kind in ("always", "never", "reachable", "eventually"):
        a = atom(parts[0])
        formula: Formula = {
            "always": ("G", a),
            "never": ("G", ("not", a)),
            "reachable": ("E", ("F", a)),
            "eventually": ("F", a),
        }[kind]
    elif kind == "leads_to":
        if len(parts) == 1:
            parts = _split_pair(parts[0], where)
        a, b = atom(parts[0]), atom(parts[1])
        formula = ("G", ("implies", a, ("F", b)))
    else:
        formula = _FormulaParser(parts[0], kind, where, texts).parse()
    compiler = _Compiler(machines, where)
    atoms = [compiler.atom(t) for t in texts]
    prop = Property(kind, shown, name or f"{kind}: {shown}", formula, where, [a.text for a in atoms])
    return prop, atoms


def _split_pair(text: str, where: str) -> list[str]:
    """`A, B` or `[A, B]` of a leads_to given as one text: the two conditions' texts."""
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as e:
        raise PropertyError(f"{where}: leads_to: {e.msg} (write two conditions: A, B)") from None
    body = tree.body
    if not isinstance(body, ast.Tuple | ast.List) or len(body.elts) != 2:
        raise PropertyError(f"{where}: leads_to takes two conditions, written `A, B` or `[A, B]`")
    return [ast.get_source_segment(text.strip(), e) or ast.unparse(e) for e in body.elts]


class _Compiler:
    """Checks an atom's tree and compiles it (see the module's docstring)."""

    def __init__(self, machines: dict[str, MachineInfo], where: str) -> None:
        self.machines = machines
        self.where = where

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
        if _depth(tree) > MAX_DEPTH:
            raise self.fail(src[:60], f"nested more than {MAX_DEPTH} levels")
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
        # the checked and rewritten tree, with only the pure builtins in reach
        fn = eval(code, {"__builtins__": dict(PURE)})
        return Atom(src, fn, self.where)

    def _machine(self, node: ast.AST, text: str) -> MachineInfo:
        name = node.id if isinstance(node, ast.Name) else node.value if isinstance(node, ast.Constant) else None
        if not isinstance(name, str):
            raise self.fail(text, "name a machine here (state(p), p.count)")
        info = self.machines.get(name)
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
            return ast.BinOp(left=self._rewrite(node.left, text), op=node.op, right=self._rewrite(node.right, text))
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
        if name not in FUNCTIONS:
            raise self.fail(text, f"unknown function {name} (the property language has {', '.join(FUNCTIONS)})")
        if len(node.args) != 1:
            raise self.fail(text, f"{name}() takes one argument")
        arg = node.args[0]
        if name == "published":
            if not isinstance(arg, ast.Constant) or not isinstance(arg.value, str) or not arg.value:
                raise self.fail(text, 'published() takes a topic name: published("/cmd_vel")')
            topic = arg.value if arg.value.startswith("/") else "/" + arg.value
            return ast.Compare(left=ast.Constant(topic), ops=[ast.In()], comparators=[ast.Name(id="E", ctx=ast.Load())])
        m = self._m(self._machine(arg, text).index)
        if name == "state":
            return ast.Subscript(
                value=ast.Attribute(value=m, attr="STATES", ctx=ast.Load()),
                slice=ast.Attribute(value=self._m(self._machine(arg, text).index), attr="_state", ctx=ast.Load()),
                ctx=ast.Load(),
            )
        return ast.Attribute(value=m, attr="_suspended" if name == "suspended" else "_finished", ctx=ast.Load())

    def _check_states(self, node: ast.Compare, text: str) -> None:
        """`state(p) == "CRIT"`: the strings compared with a machine's state name its states."""
        operands = [node.left, *node.comparators]
        for k, op in enumerate(operands):
            if not (isinstance(op, ast.Call) and isinstance(op.func, ast.Name) and op.func.id == "state"):
                continue
            if len(op.args) != 1:
                continue
            info = self._machine(op.args[0], text)
            for other in operands[:k] + operands[k + 1 :]:
                values = other.elts if isinstance(other, ast.Tuple | ast.List | ast.Set) else [other]
                for v in values:
                    if isinstance(v, ast.Constant) and isinstance(v.value, str) and v.value not in info.states:
                        close = difflib.get_close_matches(v.value, list(info.states), n=1)
                        hint = f" (did you mean {close[0]}?)" if close else ""
                        raise self.fail(
                            text, f"{info.name} has no state {v.value}{hint}; its states: {', '.join(info.states)}"
                        )


def _depth(node: ast.AST, limit: int = MAX_DEPTH + 1) -> int:
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


# -- temporal formulas ---------------------------------------------------------------------------------


class _FormulaParser:
    """`ltl:` and `ctl:` text into a formula over atoms (see the module's docstring)."""

    def __init__(self, text: str, kind: str, where: str, atoms: list[str]) -> None:
        self.text = text
        self.kind = kind
        self.where = where
        self.atoms = atoms  # the atoms' texts; ("atom", k) is atoms[k]
        self.lines = text.splitlines(keepends=True) or [""]
        self.offsets = [0]
        for line in self.lines:
            self.offsets.append(self.offsets[-1] + len(line))
        try:
            toks = list(tokenize.generate_tokens(io.StringIO(text).readline))
        except (tokenize.TokenError, SyntaxError, IndentationError) as e:
            raise self.fail(f"cannot be read: {e}") from None
        skip = (tokenize.NEWLINE, tokenize.NL, tokenize.COMMENT, tokenize.INDENT, tokenize.DEDENT, tokenize.ENDMARKER)
        self.toks = [
            t for t in toks if t.type not in skip and not (t.type == tokenize.ERRORTOKEN and not t.string.strip())
        ]
        self.pos = 0
        self.depth = 0

    def fail(self, message: str) -> PropertyError:
        return PropertyError(f"{self.where}: {self.kind}: `{' '.join(self.text.split())}`: {message}")

    def offset(self, rc: tuple[int, int]) -> int:
        return self.offsets[rc[0] - 1] + rc[1]

    def peek(self, k: int = 0) -> tokenize.TokenInfo | None:
        i = self.pos + k
        return self.toks[i] if i < len(self.toks) else None

    def is_op(self, tok: tokenize.TokenInfo | None, *ops: str) -> bool:
        return tok is not None and tok.type in (tokenize.OP, tokenize.ERRORTOKEN, tokenize.NAME) and tok.string in ops

    def parse(self) -> Formula:
        if not self.toks:
            raise self.fail("empty")
        f = self.implies()
        if self.peek() is not None:
            raise self.fail(f"unexpected {self.peek().string!r}")  # type: ignore[union-attr]
        self.check(f, quantified=False)
        return f

    def check(self, f: Formula, quantified: bool) -> None:
        """LTL has no A/E; CTL puts each of X F G U right under an A or E."""
        op = f[0]
        if op == "atom":
            return
        if op in ("A", "E"):
            if self.kind == "ltl":
                raise self.fail(f"{op} is a CTL path quantifier: write this property as ctl:")
            if f[1][0] not in ("X", "F", "G", "U"):
                raise self.fail(f"{op} must be followed by X, F, G or U")
            for sub in f[1][1:]:
                self.check(sub, False)
            return
        if op in ("X", "F", "G", "U") and self.kind == "ctl" and not quantified:
            raise self.fail(f"in CTL, {op} needs a path quantifier before it (A{op} or E{op})")
        for sub in f[1:]:
            self.check(sub, False)

    def implies(self) -> Formula:
        left = self.or_()
        if self.is_op(self.peek(), "->"):
            self.pos += 1
            return ("implies", left, self.implies())
        return left

    def or_(self) -> Formula:
        left = self.and_()
        while self.is_op(self.peek(), "|", "or"):
            self.pos += 1
            left = ("or", left, self.and_())
        return left

    def and_(self) -> Formula:
        left = self.until()
        while self.is_op(self.peek(), "&", "and"):
            self.pos += 1
            left = ("and", left, self.until())
        return left

    def until(self) -> Formula:
        left = self.unary()
        if self.is_op(self.peek(), "U"):
            self.pos += 1
            return ("U", left, self.until())
        return left

    def unary(self) -> Formula:
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise self.fail(f"nested more than {MAX_DEPTH} levels")
        try:
            tok = self.peek()
            if tok is None:
                raise self.fail("ends where a condition was expected")
            if self.is_op(tok, "!", "not"):
                self.pos += 1
                return ("not", self.unary())
            if tok.type == tokenize.NAME and tok.string in _TEMPORAL:
                self.pos += 1
                inner = self.unary()
                if len(tok.string) == 2:
                    return (tok.string[0], (tok.string[1], inner))
                return (tok.string, inner)
            if tok.type == tokenize.NAME and tok.string in _QUANTIFIERS:
                self.pos += 1
                inner = self.unary()
                if inner[0] not in ("X", "F", "G", "U"):
                    raise self.fail(f"{tok.string} must be followed by X, F, G or [p U q]")
                return (tok.string, inner)
            return self.primary()
        finally:
            self.depth -= 1

    def primary(self) -> Formula:
        tok = self.peek()
        assert tok is not None
        if self.is_op(tok, "(", "["):
            start, known = self.pos, len(self.atoms)
            closing = ")" if tok.string == "(" else "]"
            self.pos += 1
            problem: PropertyError | None = None
            try:
                inner = self.implies()
                if self.is_op(self.peek(), closing):
                    self.pos += 1
                    nxt = self.peek()
                    if nxt is None or self.is_op(nxt, "->", "|", "or", "&", "and", "U", ")", "]"):
                        return inner
            except PropertyError as e:
                if closing == "]":
                    raise
                problem = e
            self.pos = start  # a Python expression that starts with a parenthesis: an atom
            del self.atoms[known:]
            atom = self.atom_tokens()
            if problem is not None:
                try:
                    ast.parse(self.atoms[atom[1]].strip(), mode="eval")
                except SyntaxError:
                    raise problem from None  # not Python either: the formula's own mistake
            return atom
        return self.atom_tokens()

    def atom_tokens(self) -> Formula:
        """The longest run of tokens, from here, that is one condition."""
        start = self.pos
        depth = 0
        while True:
            tok = self.peek()
            if tok is None:
                break
            if depth == 0:
                if self.is_op(tok, "->", "|", "&", ")", "]", "}", "and", "or", "U"):
                    break
                if tok.type == tokenize.NAME and tok.string in _RESERVED:
                    break
                if tok.type == tokenize.ERRORTOKEN and tok.string == "!":
                    break
            if tok.string in ("(", "[", "{"):
                depth += 1
            elif tok.string in (")", "]", "}"):
                depth -= 1
            self.pos += 1
        if self.pos == start:
            raise self.fail(f"a condition was expected at {self.peek().string!r}" if self.peek() else "ends early")  # type: ignore[union-attr]
        first, last = self.toks[start], self.toks[self.pos - 1]
        self.atoms.append(self.text[self.offset(first.start) : self.offset(last.end)])
        return ("atom", len(self.atoms) - 1)
