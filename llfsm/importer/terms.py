"""What the translator's parts share: the exception that leaves code for a person, a
translated expression with its precedence and kind, the names a section sees, and helpers."""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import NamedTuple

from .kinds import Imports

# Python's precedences, lowest first
TERNARY, OR, AND, NOT, CMP, BOR, XOR, BAND, SHIFT, ADD, MUL, UNARY, POWER, ATOM = range(1, 15)


class Untranslatable(Exception):
    """Code the translator leaves for a person; the message says why (no parenthesis in it:
    it goes inside the marker's `(...)`)."""

    def __init__(self, why: str) -> None:
        super().__init__(why.replace("(", "[").replace(")", "]"))


class Expr(NamedTuple):
    text: str
    prec: int
    kind: str | None  # None: a value of a type the translator does not know


@dataclass
class Scope:
    """The names a section sees: variables (C name -> Python name and kind; a kind of None
    is a variable of a type left for a person), its locals, and the renames of the machines
    imported together (for the `suspend("...")` family) and of this machine's states."""

    imports: Imports
    variables: Mapping[str, tuple[str, str | None]]
    machines: Mapping[str, str] = field(default_factory=dict)
    states: Mapping[str, str] = field(default_factory=dict)
    locals: dict[str, tuple[str, str | None]] = field(default_factory=dict)
    #: Python names bound for the whole machine or state so far (variables, statics, modules)
    taken: set[str] = field(default_factory=set)

    def lookup(self, name: str) -> tuple[str, str | None] | None:
        return self.locals.get(name) or self.variables.get(name)


def split_template(text: str) -> tuple[str, list[str]]:
    """`std::make_shared<a::B<c>>` -> ("std::make_shared", ["a::B<c>"]): the name without
    its template arguments, and the arguments (top-level commas)."""
    text = re.sub(r"\s+", "", text)
    start = text.find("<")
    if start < 0:
        return text, []
    depth, args, cur, end = 0, [], "", len(text)
    for i in range(start, len(text)):
        ch = text[i]
        if ch == "<":
            depth += 1
            if depth == 1:
                continue
        elif ch == ">":
            depth -= 1
            if depth == 0:
                args.append(cur)
                end = i
                break
        elif ch == "," and depth == 1:
            args.append(cur)
            cur = ""
            continue
        cur += ch
    return text[:start] + text[end + 1 :], args


def wrap(e: Expr, prec: int, strict: bool = False) -> str:
    """`e`'s text, in parentheses if it binds less tightly than an operand of `prec` (or as
    tightly, when `strict`: a right operand, or any operand of a comparison, which Python
    would chain)."""
    if e.prec < prec or (e.prec == prec and (strict or prec == CMP)):
        return f"({e.text})"
    return e.text
