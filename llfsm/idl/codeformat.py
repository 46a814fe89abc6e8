"""Generated Python laid out as `ruff format` lays it out, so the committed message modules pass
the project's lint like hand-written code (and a diff after `make msgs` shows only what changed).

Both generators (llfsm.idl.pygen, llfsm.idl.ddsgen) build statements from these: literals as
ruff quotes them, a statement on one line while it fits in LINE_LIMIT, else split where ruff
splits it.  Only the shapes the generators produce are handled.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from .spec import Value

LINE_LIMIT = 120  # the project's ruff line-length


def str_literal(s: str) -> str:
    """A string literal quoted as ruff would: double quotes unless the text holds some."""
    r = repr(s)
    if r.startswith("'") and '"' not in s:
        r = '"' + r[1:-1].replace("\\'", "'") + '"'
    return r


def literal(value: Value) -> str:
    """A default or constant value of a definition as Python source."""
    if isinstance(value, str):
        return str_literal(value)
    if isinstance(value, float) and not math.isfinite(value):
        return f'float("{value}")'
    if isinstance(value, list):
        return "[" + ", ".join(literal(v) for v in value) + "]"
    return repr(value)


def fits(text: str, indent: int) -> bool:
    return all(indent + len(line) <= LINE_LIMIT for line in text.split("\n"))


def bracketed(head: str, items: list[str], tail: str, indent: int, *, is_tuple: bool = False) -> str:
    """`head(a, b)tail` on one line if it fits, else one item a line with a trailing comma:
    the two layouts ruff keeps as they are."""
    one = f"{head}{', '.join(items)}{',' if is_tuple and len(items) == 1 else ''}{tail}"
    if fits(one, indent) or not items:
        return one
    return head + "\n" + "".join(f"    {item},\n" for item in items) + tail


def assign(target: str, value: str | Call, indent: int, parts: tuple[str, str, str | Call] | None = None) -> str:
    """`target = value`, wrapped in parentheses as ruff does when too long; `parts` are the
    (body, condition, alternative) of a conditional value, split one a line if still too long.
    A value (or an alternative) that is a `Call` and still too long is split inside its own
    parentheses, as ruff prefers to splitting around it."""
    one = f"{target} = {value}"
    if fits(one, indent):
        return one
    if parts is None and isinstance(value, Call):
        return layout(f"{target} = ", value, "", indent)
    if fits(str(value), indent + 4) or parts is None:
        return f"{target} = (\n    {value}\n)"
    body, cond, alt = parts
    lines = [f"    {body}", f"    if {cond}", indented(layout("else ", alt, "", indent + 4))]
    return f"{target} = (\n" + "\n".join(lines) + "\n)"


def conditional(body: str, cond: str, alt: str | Call) -> tuple[str, tuple[str, str, str | Call]]:
    """`body if cond else alt`, and its parts for `assign` to split."""
    return f"{body} if {cond} else {alt}", (body, cond, alt)


@dataclass
class Call:
    """A call expression kept as a tree, so that a long one is laid out as ruff lays it out."""

    fn: str
    args: Sequence[str | Call]

    def __str__(self) -> str:
        return f"{self.fn}({', '.join(map(str, self.args))})"


def layout(prefix: str, expr: str | Call, suffix: str = "", indent: int = 4, *, atom: bool = False) -> str:
    """`prefix + expr + suffix` as a statement at `indent`, split as ruff format splits it: on
    one line if it fits; else the arguments on one line of their own if they fit (calls only:
    a bracketed collection, `atom`, is always exploded); else one argument a line, each laid
    out likewise, with a trailing comma."""
    one = f"{prefix}{expr}{suffix}"
    if indent + len(one) <= LINE_LIMIT or not isinstance(expr, Call) or not expr.args:
        return one
    body = ", ".join(map(str, expr.args))
    if not atom and indent + 4 + len(body) <= LINE_LIMIT:
        return f"{prefix}{expr.fn}(\n    {body}\n){suffix}"
    items = [layout("", a, ",", indent + 4) for a in expr.args]
    return f"{prefix}{expr.fn}(\n" + "".join(indented(i) + "\n" for i in items) + f"){suffix}"


def indented(text: str, by: str = "    ") -> str:
    return "\n".join(by + line for line in text.split("\n"))
