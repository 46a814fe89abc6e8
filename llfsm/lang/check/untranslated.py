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
_MARKED = re.compile(r"^(?P<indent>[ \t]*)# UNTRANSLATED(?: \((?P<why>[^)\n]*)\))?:(?P<text>[^\n]*)$", re.MULTILINE)


def untranslated(c: Checking, m: Machine) -> None:
    """Every marked line of every code file of the machine."""
    files: list[Code | None] = [m.includes, m.variables_file]
    for s in m.states:
        files.append(s.variables_file)
        files.extend(s.sections.values())
        files.extend(t.guard for t in s.transitions)
    for code in files:
        if code is None or "# UNTRANSLATED" not in code.text:
            continue
        for match in _MARKED.finditer(code.text):
            line = code.text.count("\n", 0, match.start()) + code.loc.line
            text = match["text"].strip()
            why = f" ({match['why']})" if match["why"] else ""
            what = f"`{text}`" if text else "this line"
            c.add("LF080", code.file, line, len(match["indent"]) + 1,
                  f"clfsm code left untranslated{why}: write {what} in Python, then delete this line")  # fmt: skip
