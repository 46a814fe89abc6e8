"""Rewrite bare names in machine code into attributes of the machine: `count += 1` becomes
`self.count += 1`, `after_ms(500)` becomes `self.after_ms(500)`.

Which names to rewrite, and into what, is the front end's answer (llfsm.lang.bindings: Python's
scopes, the machine's alias where the user's own `self` hides it); this module applies those
edits to the source text at the exact positions `ast` reports.  Editing the text rather than
unparsing the tree keeps the user's comments and layout, and keeps every line where it was,
which is what lets a run-time error point back at the user's own line.
"""

from __future__ import annotations

from ..lang.bindings import MACHINE_ALIAS, Edit
from ..lang.positions import source_lines

#: The line the generated module puts before a block that reaches the machine through the alias.
ALIAS_LINE = f"{MACHINE_ALIAS} = self  # the machine, for code below whose own `self` is another object"


def apply(text: str, edits: list[Edit]) -> str:
    """Apply edits (positions in UTF-8 bytes, as ast reports them) to `text`, keeping its lines."""
    if not edits:
        return text
    lines = source_lines(text)
    by_line: dict[int, list[Edit]] = {}
    for e in edits:
        by_line.setdefault(e.line, []).append(e)
    for ln, es in by_line.items():
        raw = lines[ln - 1].encode("utf-8")
        for e in sorted(es, key=lambda e: e.start, reverse=True):
            raw = raw[: e.start] + e.text.encode("utf-8") + raw[e.end :]
        lines[ln - 1] = raw.decode("utf-8")
    return "".join(lines)
