"""The temporal formulas of `ltl:` and `ctl:` (SPEC 11): read from text into tuples over atoms,
and the rewriting the automata and the checks use.

The text is read by a small parser over Python's tokens: `!`/`not`, `&`/`and`, `|`/`or`, `->`,
`X`, `F`, `G`, `U`, and `A`, `E` (also written together: `AG`, `EF`...); what lies between them
is an atom.  In those formulas the names A, E, F, G, U, X (and AG, AF, AX, EG, EF, EX) are the
operators, never machines.  A formula is a tuple: `("atom", k)` (the k-th atom's text in the
list the parser fills), `("not", f)`, `("and", f, g)`, `("or", f, g)`, `("implies", f, g)`,
`("X", f)`, `("F", f)`, `("G", f)`, `("U", f, g)`, `("A", path)`, `("E", path)`, `("true",)`.

Bounds (SPEC 18): a chain of one operator (`a & b & ...`, `a U b U ...`) and any nesting stop at
MAX_DEPTH levels, read without recursion on a chain, so a thousand terms are one clear line, not
a RecursionError; atoms with the same text are one atom.
"""

from __future__ import annotations

import ast
import io
import tokenize
from collections.abc import Callable
from typing import Any

from .atoms import MAX_DEPTH, PropertyError

Formula = tuple[Any, ...]
TRUE: Formula = ("true",)

_TEMPORAL = {"X", "F", "G", "AX", "EX", "AF", "EF", "AG", "EG"}
_QUANTIFIERS = {"A", "E"}
_RESERVED = _TEMPORAL | _QUANTIFIERS | {"U"}


def formula_depth(f: Formula) -> int:
    """How deep a formula nests (without recursion)."""
    best = 0
    stack = [(f, 1)]
    while stack:
        g, d = stack.pop()
        best = max(best, d)
        if g[0] != "atom":
            stack.extend((x, d + 1) for x in g[1:] if isinstance(x, tuple))
    return best


def core(f: Formula) -> Formula:
    """`f` with only true, atoms, not, and, X, U (F, G, or, implies rewritten)."""
    op = f[0]
    if op in ("atom", "true"):
        return f
    if op == "not":
        return neg(core(f[1]))
    if op == "and":
        return ("and", core(f[1]), core(f[2]))
    if op == "or":
        return neg(("and", neg(core(f[1])), neg(core(f[2]))))
    if op == "implies":
        return neg(("and", core(f[1]), neg(core(f[2]))))
    if op == "X":
        return ("X", core(f[1]))
    if op == "U":
        return ("U", core(f[1]), core(f[2]))
    if op == "F":
        return ("U", TRUE, core(f[1]))
    if op == "G":
        return neg(("U", TRUE, neg(core(f[1]))))
    raise ValueError(f"not an LTL operator: {op}")


def neg(f: Formula) -> Formula:
    return f[1] if f[0] == "not" else ("not", f)


def has(f: Formula, op: str) -> bool:
    """Whether `op` occurs in `f`."""
    return f[0] == op or any(isinstance(x, tuple) and has(x, op) for x in f[1:])


class FormulaParser:
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
        if formula_depth(f) > MAX_DEPTH:
            raise self.fail(f"nested more than {MAX_DEPTH} levels")
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

    def chain(self, ops: tuple[str, ...], name: str, operand: Callable[[], Formula], right: bool) -> Formula:
        """Operands joined by one of `ops`, read in a loop (never one call per operand) and
        refused past MAX_DEPTH of them: `->` and `U` group to the right, `&` and `|` to the left."""
        parts = [operand()]
        while self.is_op(self.peek(), *ops):
            self.pos += 1
            parts.append(operand())
            if len(parts) > MAX_DEPTH:
                raise self.fail(
                    f"a chain of more than {MAX_DEPTH} `{ops[0]}` nests too deep (at most {MAX_DEPTH} levels)"
                )
        if right:
            f = parts[-1]
            for p in reversed(parts[:-1]):
                f = (name, p, f)
            return f
        f = parts[0]
        for p in parts[1:]:
            f = (name, f, p)
        return f

    def implies(self) -> Formula:
        return self.chain(("->",), "implies", self.or_, right=True)

    def or_(self) -> Formula:
        return self.chain(("|", "or"), "or", self.and_, right=False)

    def and_(self) -> Formula:
        return self.chain(("&", "and"), "and", self.until, right=False)

    def until(self) -> Formula:
        return self.chain(("U",), "U", self.unary, right=True)

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
        text = self.text[self.offset(first.start) : self.offset(last.end)]
        norm = " ".join(text.split())
        for k, known in enumerate(self.atoms):  # the same condition twice is one atom
            if " ".join(known.split()) == norm:
                return ("atom", k)
        self.atoms.append(text)
        return ("atom", len(self.atoms) - 1)
