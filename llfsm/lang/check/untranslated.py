"""LF080: lines of clfsm C++ that `llfsm import` kept for a person (docs/import.md).

`llfsm import` writes each statement it cannot translate as comment lines

    # UNTRANSLATED (unlink is not a function llfsm knows): unlink(testfile);

so that the machine is valid Python everywhere else, and `llfsm check` lists exactly what is
left: each marked line is an error, at its file and line, until a person has written the
Python and deleted the line.  Text only, like every rule.
"""

from __future__ import annotations

import re

from ..model import Code, Machine
from .checking import Checking

#: The marker `llfsm import` writes (llfsm.importer.statements.MARKER), with its reason.
_MARKED = re.compile(r"(?P<indent>[ \t]*)# UNTRANSLATED(?: \((?P<why>[^)]*)\))?:(?P<text>.*)")


def untranslated(c: Checking, m: Machine) -> None:
    """Every marked line of every code file of the machine (one pass over each file's lines)."""
    files: list[Code | None] = [m.includes, m.variables_file]
    for s in m.states:
        files.append(s.variables_file)
        files.extend(s.sections.values())
        files.extend(t.guard for t in s.transitions)
    for code in files:
        if code is None or "# UNTRANSLATED" not in code.text:
            continue
        for i, line in enumerate(code.text.split("\n")):
            match = _MARKED.fullmatch(line) if "# UNTRANSLATED" in line else None
            if match is None:
                continue
            text = match["text"].strip()
            why = f" ({match['why']})" if match["why"] else ""
            what = f"`{text}`" if text else "this line"
            message = f"clfsm code left untranslated{why}: write {what} in Python, then delete this line"
            c.add("LF080", code.file, code.loc.line + i, len(match["indent"]) + 1, message)
