"""Rules on what machine code imports: message types the message module lacks (LF042), interface
packages found nowhere (LF109), and helper modules put inside the machine folder (LF043).

Each of these passes `ast.parse` and fails only when the machine runs (`ImportError: cannot
import name 'Twists'`), often after a build or a colcon install.  The answers come from
folder listings (llfsm.interface_path): the shipped packages' definition files under
llfsm/msgs/_interfaces, the user's packages where `llfsm run` would find them.  Nothing is
imported; no definition is read.
"""

from __future__ import annotations

import ast
import functools
import os
import sys
from pathlib import Path

from ...interface_path import (
    INTERFACE_KINDS,
    SHIPPED_DIR,
    folders_around,
    interface_folder,
    interface_names,
    shipped_packages,
)
from ..model import Code
from ..positions import node_col
from .checking import Checking

MSGS = "llfsm.msgs"
WHERE = (
    "llfsm looks in the packages it ships, in the folders above the machine, in LLFSM_INTERFACE_PATH "
    "and in share/ of each AMENT_PREFIX_PATH prefix (after `source install/setup.bash`)"
)
#: Where helper modules must be, in words (docs/machine-format.md, "Helper modules").
HELPERS_DOC = "docs/machine-format.md#helper-modules"


def imports(c: Checking, code: Code, stmts: list[ast.Import | ast.ImportFrom]) -> None:
    """LF042, LF043, LF109 for the import statements of one code file."""
    for stmt in stmts:
        if isinstance(stmt, ast.ImportFrom) and stmt.level:
            continue  # LF031 (Includes.py) or Python's own error
        modules = [stmt.module or ""] if isinstance(stmt, ast.ImportFrom) else [a.name for a in stmt.names]
        for module in modules:
            if module == MSGS or module.startswith(MSGS + "."):
                _message_import(c, code, stmt, module)
            else:
                _helper_inside(c, code, stmt, module)


def _message_import(c: Checking, code: Code, stmt: ast.Import | ast.ImportFrom, module: str) -> None:
    parts = module.split(".")[2:]  # after llfsm.msgs
    col = node_col(code.text, stmt)
    if not parts:  # from llfsm.msgs import geometry_msgs, ...
        if isinstance(stmt, ast.ImportFrom):
            for a in stmt.names:
                if a.name != "*" and not a.name.startswith("_"):
                    _package(c, code, stmt, a.name)
        return
    package = parts[0]
    if package.startswith("_"):
        return  # llfsm's own modules beside the packages
    found = _package(c, code, stmt, package)
    if found is None:
        return
    folder, shipped = found
    if len(parts) == 1:
        return
    kind = parts[1]
    if kind not in INTERFACE_KINDS or not _names(folder, kind):
        kinds = [k for k in INTERFACE_KINDS if _names(folder, k)]
        wanted = [a.name for a in stmt.names] if isinstance(stmt, ast.ImportFrom) else []
        elsewhere = [f"{package}/{k}/{n}" for n in wanted for k in kinds if n in _names(folder, k)]
        has = (", ".join(kinds[:-1]) + " and " + kinds[-1] if len(kinds) > 1 else "".join(kinds)) or "no interfaces"
        what = _KIND_WORD[elsewhere[0].split("/")[1]] if elsewhere else ""
        hint = f": {elsewhere[0]} is {'an' if what == 'action' else 'a'} {what}" if elsewhere else ""
        c.add("LF042", code.file, stmt.lineno, col, f"{MSGS}.{package} has {has}, not {kind!r}{hint}")
        return
    if len(parts) > 2 or not isinstance(stmt, ast.ImportFrom):
        return
    names = _names(folder, kind)
    for a in stmt.names:
        if a.name == "*" or a.name.startswith("_") or _defines(names, a.name):
            continue
        close = c.suggest.close(a.name, names)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        where = "the interfaces llfsm ships" if shipped else _shown(Path(folder) / kind)
        c.add(
            "LF042",
            code.file,
            stmt.lineno,
            col,
            f"{MSGS}.{package}.{kind} has no {a.name!r}: there is no {package}/{kind}/{a.name}.{kind} in {where}{hint}",
        )


_KIND_WORD = {"msg": "message", "srv": "service", "action": "action"}


def _defines(names: list[str], name: str) -> bool:
    """Whether a kind module defines `name`: a type, or one of its parts (`Trigger_Request`,
    `Fibonacci_Goal`), as the generated modules do."""
    if name in names:
        return True
    base, sep, _part = name.rpartition("_")
    return bool(sep) and base in names


def _package(c: Checking, code: Code, stmt: ast.stmt, package: str) -> tuple[str, bool] | None:
    """The package's folder, or LF109 (a warning: the package may be installed where this
    check cannot see, such as a workspace not sourced in CI) and None."""
    if package in _shipped():
        return os.path.join(SHIPPED_DIR, package), True
    if c.interface_roots is None:  # once per machine: the folders `llfsm run` adds around it
        c.interface_roots = folders_around(os.fspath(c.path))
    found = interface_folder(package, c.interface_roots)
    if found is None:
        close = c.suggest.close(package, shipped_packages())
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        c.add(
            "LF109",
            code.file,
            stmt.lineno,
            node_col(code.text, stmt),
            f"no interface package {package!r}{hint}: {WHERE}",
        )
    return found


@functools.cache
def _shipped() -> frozenset[str]:
    """The packages llfsm ships: its own files, the same for as long as it runs."""
    return frozenset(shipped_packages())


def _names(folder: str, kind: str) -> list[str]:
    try:
        mtime = os.stat(os.path.join(folder, kind)).st_mtime_ns
    except OSError:
        return []
    return _names_cached(folder, kind, mtime)


@functools.lru_cache(maxsize=256)
def _names_cached(folder: str, kind: str, _mtime: int) -> list[str]:
    """Listed once per folder while it is unchanged: many machines import the same package."""
    return interface_names(folder, kind)


def _shown(path: Path) -> str:
    try:
        rel = os.path.relpath(path)
    except ValueError:
        return str(path)
    return str(path) if rel.startswith(os.pardir) else rel


def _helper_inside(c: Checking, code: Code, stmt: ast.stmt, module: str) -> None:
    """LF043: `import helpers` where helpers.py (or a helpers/ package) sits inside the machine
    folder and not beside it: the run imports from the folder that holds NAME.machine, never
    from inside it, so the import fails there (or finds another module of that name)."""
    top = module.split(".")[0]
    if not top.isidentifier() or top in sys.stdlib_module_names or top == "llfsm":
        return  # a module of Python's own wins over a file of that name anyway
    inside = _module_at(c.path, top)
    if inside is None or _module_at(c.path.parent, top) is not None:
        return
    target = os.path.join(_shown(c.path.parent), inside)
    c.add(
        "LF043",
        code.file,
        stmt.lineno,
        node_col(code.text, stmt),
        f"{top!r} is {c.path.name}/{inside}, inside the machine folder, where imports do not look: move it "
        f"beside {c.path.name}, to {target} ({HELPERS_DOC})",
    )


def _module_at(folder: Path, name: str) -> str | None:
    """`name.py` or the package `name/` in `folder`, as it is named there, or None."""
    if (folder / f"{name}.py").is_file():
        return f"{name}.py"
    d = folder / name
    if d.is_dir() and ((d / "__init__.py").is_file() or any(p.suffix == ".py" for p in d.iterdir())):
        return f"{name}/"
    return None
