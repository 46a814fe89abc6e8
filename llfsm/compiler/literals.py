"""What the generated module writes of its own (not user code): Python literals and docstrings
made from the machine's names and text, safe and within the line length people read.

Safe: every string goes through `repr`, every docstring through `doc_lines`, so no name or
description can end a string and start code (tests/test_security.py tries).  Readable: no line
the template writes is longer than `WIDTH`; a literal that does not fit is spread over lines as
a formatter would, a long string cut into pieces Python joins again, and a docstring continued
with a backslash, which keeps its value on one line (what `__doc__` says is unchanged).
"""

from __future__ import annotations

import re

#: The longest line the template writes (user code keeps its own lines).
WIDTH = 120
_WORDS = re.compile(r"\S*\s*")


def py(value: object) -> str:
    """A Python literal for a value, on one line: strings through repr."""
    if isinstance(value, list | tuple):
        inner = ", ".join(py(v) for v in value)
        return f"({inner},)" if len(value) == 1 else f"({inner})"
    if isinstance(value, frozenset | set):
        return "{" + ", ".join(py(v) for v in sorted(value)) + "}" if value else "()"
    return repr(value)


def py_block(value: object, indent: int, start: int, end: int = 0) -> str:
    """`py(value)` when it fits between column `start` and `end` characters before `WIDTH`; else
    spread over lines below a line at `indent`: a tuple an item per line, a string in pieces."""
    return _block(value, _py_tree(value), indent, start, end)


_Tree = tuple[str, list["_Tree"]]


def _py_tree(value: object) -> _Tree:
    """`py(value)`, with the same for each item of a tuple or list: each literal made once."""
    if isinstance(value, list | tuple):
        items = [_py_tree(v) for v in value]
        inner = ", ".join(text for text, _ in items)
        return (f"({inner},)" if len(value) == 1 else f"({inner})"), items
    return py(value), []


def _block(value: object, tree: _Tree, indent: int, start: int, end: int) -> str:
    text, items = tree
    if start + len(text) + end <= WIDTH:
        return text
    inner = indent + 4
    pad = " " * inner
    if isinstance(value, list | tuple) and value:
        lines = [_block(v, t, inner, inner, 1) for v, t in zip(value, items, strict=True)]
        return "(\n" + "".join(f"{pad}{line},\n" for line in lines) + " " * indent + ")"
    if isinstance(value, str) and value:
        pieces = _string_pieces(value, WIDTH - inner)
        return "(\n" + "".join(f"{pad}{piece}\n" for piece in pieces) + " " * indent + ")"
    return text


def names_block(names: list[str], indent: int, start: int) -> str:
    """A tuple of names (functions of the module, None), spread an item per line if need be."""
    one = f"({', '.join(names)},)"
    if start + len(one) <= WIDTH:
        return one
    pad = " " * (indent + 4)
    return "(\n" + "".join(f"{pad}{n},\n" for n in names) + " " * indent + ")"


def _string_pieces(value: str, width: int) -> list[str]:
    """`value` as string literals of at most `width` characters each (where a word allows),
    cut after spaces: Python joins adjacent literals into the same string."""
    pieces: list[str] = []
    current = ""
    for word in _WORDS.findall(value):
        if current and len(repr(current + word)) > width:
            pieces.append(repr(current))
            current = ""
        while len(repr(word)) > width:  # a word longer than a line: cut it where it must be
            cut = _longest_prefix(word, width)
            pieces.append(repr(word[:cut]))
            word = word[cut:]
        current += word
    if current or not pieces:
        pieces.append(repr(current))
    return pieces


def _longest_prefix(word: str, width: int) -> int:
    """How many characters of `word` fit in a literal of `width` (at least one)."""
    n = 1
    while n < len(word) and len(repr(word[: n + 1])) <= width:
        n += 1
    return n


def doc_units(text: str) -> list[str]:
    """`text` on one line (runs of white space become one space; none at all, "A machine."), as
    the pieces of a docstring body: each character, escaped so that no description can end the string (quotes and
    backslashes escaped, non-printable characters spelled out)."""
    out = []
    for ch in " ".join(text.split()) or "A machine.":
        if ch in '\\"':
            out.append("\\" + ch)
        elif not ch.isprintable():
            out.append(ch.encode("unicode_escape").decode("ascii"))
        else:
            out.append(ch)
    return out


def doc_lines(text: str, indent: int) -> str:
    """A docstring at `indent` whose value is `text` on one line: lines end with a backslash
    (which Python drops with the line end, so the value has no line break), cut after a space,
    and the lines after the first start at column 0 (an indent would be part of the value)."""
    units = doc_units(text)
    one = "".join(units)
    if indent + len(one) + 6 <= WIDTH:  # the usual case: on one line with its quotes
        return " " * indent + '"""' + one + '"""'
    lines: list[str] = []
    line: list[str] = []
    room = WIDTH - indent - 3 - 1  # the opening quotes and the backslash
    used = 0
    word: list[str] = []

    def flush_word() -> None:
        nonlocal used, room, line
        size = sum(len(u) for u in word)
        if used and used + size > room:
            lines.append("".join(line))
            line, used, room = [], 0, WIDTH - 1
        for u in word:
            if used + len(u) > room:  # one word longer than a line
                lines.append("".join(line))
                line, used, room = [], 0, WIDTH - 1
            line.append(u)
            used += len(u)
        word.clear()

    for u in units:
        word.append(u)
        if u == " ":
            flush_word()
    flush_word()
    if used + 3 > room + 1:  # the closing quotes do not fit after the last piece
        lines.append("".join(line))
        line = []
    lines.append("".join(line))
    return " " * indent + '"""' + "\\\n".join(lines) + '"""'
