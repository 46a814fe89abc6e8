"""Lines and columns of source text as `ast` counts them.

`ast` numbers lines by \\n, \\r\\n and \\r only, and reports columns as UTF-8 byte offsets;
diagnostics give character columns, and the compiler edits the text at `ast`'s positions.
Both go through this one module, so that a position means the same thing everywhere.
"""

from __future__ import annotations

import bisect
import re
from functools import lru_cache
from typing import Protocol

_EOL = re.compile(r"\r\n|\r|\n")


class Located(Protocol):
    """A node `ast` gives a place in the text (an expression, a statement, an argument, a
    keyword, an alias, a handler, a pattern): `ast.AST` itself declares no position."""

    @property
    def lineno(self) -> int: ...
    @property
    def col_offset(self) -> int: ...
    @property
    def end_lineno(self) -> int | None: ...
    @property
    def end_col_offset(self) -> int | None: ...


def source_lines(text: str) -> list[str]:
    """The lines of `text` as `ast` numbers them, with their line ends.

    Only \\n, \\r\\n and \\r end a line of Python source.  `str.splitlines` also splits on form
    feeds, U+2028 and other characters that may sit in a comment or a string, and would then
    apply an edit to the wrong line.
    """
    out = []
    pos = 0
    for m in _EOL.finditer(text):
        out.append(text[pos : m.end()])
        pos = m.end()
    out.append(text[pos:])
    return out


class LineIndex:
    """The lines of one text, split once, and byte -> character columns on them.

    `ast` reports columns as UTF-8 byte offsets; diagnostics give character columns.  Finding
    the line anew for each diagnostic re-splits the whole file each time: a file with N
    problems then costs N times its size (20,000 lines took minutes).  One index per text
    makes every conversion O(1) on ASCII lines, O(log n) on others."""

    def __init__(self, text: str) -> None:
        self.lines = source_lines(text)
        self._offsets: dict[int, list[int] | None] = {}

    def char_col(self, line: int, byte_offset: int) -> int:
        """1-based character column of a 0-based UTF-8 byte offset on a 1-based line."""
        if not 1 <= line <= len(self.lines):
            return byte_offset + 1
        offsets = self._offsets.get(line, ())
        if offsets == ():
            src = self.lines[line - 1]
            offsets = None
            if not src.isascii():
                offsets, pos = [], 0
                for ch in src:
                    pos += len(ch.encode("utf-8", "surrogatepass"))
                    offsets.append(pos)
            self._offsets[line] = offsets
        if offsets is None:
            return byte_offset + 1
        return bisect.bisect_right(offsets, byte_offset) + 1


@lru_cache(maxsize=16)
def line_index(text: str) -> LineIndex:
    """The `LineIndex` of `text`, made once however many diagnostics point into it (a str
    caches its hash, so a lookup costs nothing like the text's length)."""
    return LineIndex(text)


def source_segment(text: str, node: Located) -> str | None:
    """`ast.get_source_segment`, on the file's `LineIndex`: the standard one splits the whole
    source anew for every node, so a Variables.py of N lines cost N squared."""
    try:
        l0 = node.lineno - 1
        end_line = node.end_lineno
        c0 = node.col_offset
        c1 = node.end_col_offset
    except AttributeError:
        return None
    l1 = end_line - 1 if end_line is not None else None
    if l1 is None or c1 is None:
        return None
    lines = line_index(text).lines
    if l0 == l1:
        return lines[l0].encode("utf-8")[c0:c1].decode("utf-8")
    first = lines[l0].encode("utf-8")[c0:].decode("utf-8")
    last = lines[l1].encode("utf-8")[:c1].decode("utf-8")
    return first + "".join(lines[l0 + 1 : l1]) + last


def char_col(text: str, line: int, byte_offset: int) -> int:
    """1-based character column of a 0-based UTF-8 byte offset (as `ast` gives) on a 1-based line."""
    return line_index(text).char_col(line, byte_offset)


def node_col(text: str, node: Located) -> int:
    """1-based character column where `node` starts in `text`."""
    return char_col(text, node.lineno, node.col_offset)
