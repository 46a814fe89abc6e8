"""Rules on Includes.py, the machine's imports (LF031, LF013, LF041 for rclpy imports, and
LF042/LF043/LF109 for what the imports name: llfsm.lang.check.imports), and the names it gives
every section and guard.
"""

from __future__ import annotations

import ast

from ..model import Machine
from ..positions import node_col
from .checking import Checking
from .imports import imports
from .ros_habits import ros_habits
from .scan import Scanned

#: Module-level names the compiled module itself uses (templates/machine.py.j2): an import in
#: Includes.py that rebinds one would break the class the module defines.
MODULE_NAMES = frozenset({"Machine", "super", "frozenset"})


def includes(c: Checking, m: Machine) -> None:
    """LF041 for its rclpy imports; LF031: only absolute imports; LF013: no name the module uses."""
    tree = c.read.trees.get("Includes.py")
    if tree is None or m.includes is None:
        return
    stmts = [s for s in tree.body if isinstance(s, ast.Import | ast.ImportFrom)]
    ros_habits(c, m.includes, Scanned(imports=stmts))
    imports(c, m.includes, stmts)
    for stmt in tree.body:
        col = node_col(m.includes.text, stmt)
        if not isinstance(stmt, ast.Import | ast.ImportFrom):
            c.add(
                "LF031",
                "Includes.py",
                stmt.lineno,
                col,
                f"Includes.py may hold only imports, not a `{type(stmt).__name__.lower()}` statement",
            )
        elif isinstance(stmt, ast.ImportFrom) and stmt.module == "__future__":
            c.add("LF031", "Includes.py", stmt.lineno, col, "`from __future__` imports are added by llfsm itself")
        elif isinstance(stmt, ast.ImportFrom) and stmt.level:
            c.add(
                "LF031",
                "Includes.py",
                stmt.lineno,
                col,
                "relative imports cannot work in a compiled machine; import by absolute name",
            )
        else:
            for a in stmt.names:
                bound = (a.asname or a.name).split(".")[0]
                if bound in MODULE_NAMES or bound.startswith("_llfsm"):
                    c.add(
                        "LF013",
                        "Includes.py",
                        stmt.lineno,
                        col,
                        f"Includes.py binds `{bound}`, which the compiled module uses itself; "
                        "import it under another name (`import x as y`)",
                    )


def imported_names(c: Checking) -> set[str] | None:
    """Names Includes.py binds; None if it star-imports (then any name may exist)."""
    tree = c.read.trees.get("Includes.py")
    if tree is None:
        return set()
    out = set()
    for stmt in tree.body:
        if isinstance(stmt, ast.Import | ast.ImportFrom):
            for a in stmt.names:
                if a.name == "*":
                    return None
                out.add((a.asname or a.name).split(".")[0])
    return out
