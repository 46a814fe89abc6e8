"""LF050: a machine named in `suspend("M")` and its family that none of the machines checked
together is.  `suspend("WallBot")` for the machine `wall_bot` passes `ast.parse` and fails only
when the line runs (UnknownMachineError); the how-to itself misspells such names.

One machine alone cannot tell: the machine it names may be loaded beside it.  So each machine's
check notes the names its code gives as string literals (`references`), and `llfsm check` of
several machines (llfsm.lang.check.diagnose) compares them with the machines it was given and
those beside them (pre-commit gives only the machines a commit changed): a name none of them
has is a warning (an error under --strict).  Text and `ast` only, as every rule.
"""

from __future__ import annotations

import ast
import re
from collections.abc import Iterable

from ..diagnostics import Diagnostic, diag
from ..model import Code
from ..positions import node_col
from .checking import Checking, Suggester

#: The macros that take a machine's name (docs/machine-format.md, "Macros").
NAMING_MACROS = frozenset({"suspend", "resume", "restart", "is_suspended", "is_running", "state_name_of"})
_NAMING_CALL = re.compile(rf"\b(?:{'|'.join(sorted(NAMING_MACROS))})\s*\(")
#: How many machine names the warning lists before it only counts them.
LISTED = 8


def references(c: Checking, code: Code, tree: ast.AST) -> None:
    """Note each `suspend("M")` (and family) whose machine is a string literal."""
    if _NAMING_CALL.search(code.text) is None:
        return
    for node in ast.walk(tree):
        if (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Name)
            and node.func.id in NAMING_MACROS
            and node.args
            and isinstance(node.args[0], ast.Constant)
            and isinstance(node.args[0].value, str)
        ):
            arg, name = node.args[0], node.args[0].value
            assert isinstance(name, str)  # tested above; mypy does not narrow an attribute's attribute
            c.references.append((str(c.path / code.file), arg.lineno, node_col(code.text, arg), name))


def unknown_machines(names: Iterable[str], refs: Iterable[tuple[str, int, int, str]]) -> list[Diagnostic]:
    """LF050 for each reference to a machine that is none of `names` (the machines checked, and
    those in their folders)."""
    known = sorted(set(names))
    known_set = set(known)
    listed = ", ".join(known[:LISTED]) + (f" and {len(known) - LISTED} more" if len(known) > LISTED else "")
    suggest = Suggester()
    return [
        diag(
            "LF050",
            file,
            line,
            col,
            f"no machine {name!r} among the machines checked and beside them ({listed}){suggest.alike(name, known)}: "
            "naming a machine that is not loaded fails when the line runs",
        )
        for file, line, col, name in refs
        if name not in known_set
    ]
