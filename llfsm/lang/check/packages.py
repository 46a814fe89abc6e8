"""LF106: machine code that imports messages of a package its package.xml does not declare.

The clfsm how-to names incompletely specified dependencies as the usual reason a colcon build
of a machine fails, and only after the fact.  Here the check happens before any build: the
imports are read from the `ast` trees the reader already has, and the declarations from the
nearest package.xml above the machine directory, parsed by catkin_pkg (the parser colcon and
rosdep use, so what passes here passes there).  Like the rest of `llfsm check`, this never
imports or runs machine code, and a package.xml that cannot be read is reported, not raised.
"""

from __future__ import annotations

import ast
import functools
import os
import re
from dataclasses import dataclass
from pathlib import Path

from ..diagnostics import Diagnostic, diag

MSGS_PREFIX = "llfsm.msgs."
MANIFEST = "package.xml"
MAX_MANIFEST_BYTES = 1 << 20  # as for machine files: a real package.xml is a few KiB
# Statement fields that hold nested statements: imports are statements, so the walk never
# needs to enter an expression (the checker's hot path already pays for one full traversal).
_BODIES = ("body", "orelse", "finalbody", "handlers", "cases")


@dataclass(frozen=True)
class Manifest:
    """What LF106 needs from a package.xml, or why it could not be read."""

    path: Path
    name: str = ""
    declared: frozenset[str] = frozenset()
    error: str = ""
    line: int = 1
    column: int = 1


def undeclared_dependencies(machine_dir: Path, trees: dict[str, ast.Module]) -> list[Diagnostic]:
    """LF106 warnings for the machine at `machine_dir`, whose parsed code files are `trees`
    (file name -> module).  Empty outside a package (no package.xml above the machine)."""
    manifest_path = find_manifest(machine_dir)
    if manifest_path is None:
        return []
    manifest = read_manifest(manifest_path)
    shown = _shown(manifest_path, machine_dir)
    if manifest.error:
        return [
            diag(
                "LF106",
                shown,
                manifest.line,
                manifest.column,
                f"{MANIFEST} cannot be read, so the dependencies of the machine code are not checked: {manifest.error}",
            )
        ]
    out = []
    for fname in sorted(trees):
        for stmt, package in _message_imports(trees[fname]):
            if package == manifest.name or package in manifest.declared:
                continue
            out.append(
                diag(
                    "LF106",
                    machine_dir / fname,
                    stmt.lineno,
                    _column(machine_dir / fname, stmt),
                    f"imports messages of package {package!r}, which {shown} does not declare: "
                    f"add <depend>{package}</depend> (colcon builds and rosdep installs only what is declared)",
                )
            )
    return out


def _shown(manifest: Path, machine_dir: Path) -> Path:
    """package.xml named the way the machine was: relative paths stay relative, so that GitHub
    annotations and SARIF locations point into the repository."""
    if machine_dir.is_absolute():
        return manifest
    try:
        return Path(os.path.relpath(manifest))
    except ValueError:  # another drive (Windows)
        return manifest


def find_manifest(machine_dir: Path) -> Path | None:
    """The package.xml of the package holding the machine: the nearest one above it."""
    # the logical path, not resolve(): a package linked into src/ keeps its place in the tree
    for folder in Path(os.path.abspath(machine_dir)).parents:
        candidate = folder / MANIFEST
        if candidate.is_file():
            return candidate
    return None


def read_manifest(path: Path) -> Manifest:
    """The package's name and declared dependencies, cached while the file is unchanged (a
    package's machines are checked one after another and share one package.xml)."""
    try:
        st = path.stat()
    except OSError as e:
        return Manifest(path, error=e.strerror or str(e))
    return _read_manifest(path, st.st_mtime_ns, st.st_size)


@functools.lru_cache(maxsize=64)
def _read_manifest(path: Path, _mtime_ns: int, size: int) -> Manifest:
    if size > MAX_MANIFEST_BYTES:
        return Manifest(path, error=f"larger than {MAX_MANIFEST_BYTES // 1024} KiB; refused")
    try:
        text = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as e:
        return Manifest(path, error=f"not UTF-8 text ({e.reason} at byte {e.start})")
    except OSError as e:
        return Manifest(path, error=e.strerror or str(e))
    try:
        # deferred: start-up (only a machine inside a package has a package.xml to read)
        from catkin_pkg.package import InvalidPackage, parse_package_string
    except ImportError:  # checking still works without it; only LF106 is lost
        return Manifest(path, error="catkin_pkg, which llfsm reads it with, is not installed")
    try:
        # warnings go to the list, not to stderr: the checker reports through diagnostics only
        pkg = parse_package_string(text, filename=str(path), warnings=[])
    except InvalidPackage as e:
        return _broken(path, text, str(e.msg))
    except Exception as e:  # untrusted input: format="4" (an assert), format="x" (ValueError)...
        return _broken(path, text, f"{type(e).__name__}: {e}")
    # <depend> is expanded by catkin_pkg into build_depends and exec_depends
    declared = {d.name for d in (*pkg.build_depends, *pkg.exec_depends)}
    return Manifest(path, name=pkg.name, declared=frozenset(declared))


_EXPAT_POS = re.compile(r"line (\d+), column (\d+)")


def _broken(path: Path, text: str, message: str) -> Manifest:
    """A diagnostic's position: expat's when the XML is malformed, else the <package> tag."""
    line, col = 1, 1
    m = _EXPAT_POS.search(message)
    if m:
        line, col = int(m.group(1)), int(m.group(2)) + 1
    else:
        found = re.search(r"<package[\s>]", text)
        if found:
            line = text.count("\n", 0, found.start()) + 1
            col = found.start() - (text.rfind("\n", 0, found.start()) + 1) + 1
    # catkin_pkg writes "The manifest contains invalid XML:\n<expat>" or "Error(s):\n- a\n- b"
    parts = [s.strip().removeprefix("- ") for s in message.splitlines() if s.strip()]
    if parts and parts[0] == "The manifest contains invalid XML:":
        parts[0] = "invalid XML:"
        summary = " ".join(parts)
    else:
        summary = "; ".join(p for p in parts if p != "Error(s):") or "not a valid package manifest"
    return Manifest(path, error=summary, line=line, column=col)


def _message_imports(tree: ast.Module) -> list[tuple[ast.stmt, str]]:
    """(import statement, message package) for every llfsm.msgs.PKG import, at any depth."""
    out: list[tuple[ast.stmt, str]] = []
    stack: list[ast.AST] = [tree]
    while stack:
        node = stack.pop()
        for field in _BODIES:
            for child in getattr(node, field, ()) or ():
                if isinstance(child, ast.Import):
                    for alias in child.names:
                        pkg = _package_of(alias.name)
                        if pkg:
                            out.append((child, pkg))
                elif isinstance(child, ast.ImportFrom):
                    if child.level or not child.module:
                        continue
                    if child.module == "llfsm.msgs":  # from llfsm.msgs import geometry_msgs
                        out += [(child, a.name) for a in child.names if _is_package(a.name)]
                    else:
                        pkg = _package_of(child.module)
                        if pkg:
                            out.append((child, pkg))
                else:
                    stack.append(child)
    out.sort(key=lambda sp: (sp[0].lineno, sp[0].col_offset, sp[1]))
    return out


def _package_of(module: str) -> str | None:
    if not module.startswith(MSGS_PREFIX):
        return None
    pkg = module[len(MSGS_PREFIX) :].split(".", 1)[0]
    return pkg if _is_package(pkg) else None


def _is_package(name: str) -> bool:
    """Message packages, not llfsm's own modules beside them (llfsm.msgs._message...)."""
    return bool(name) and not name.startswith("_") and name != "*"


def _column(file: Path, node: ast.stmt) -> int:
    """1-based column in characters (ast gives UTF-8 bytes); read lazily, only for a finding."""
    try:
        with open(file, encoding="utf-8", errors="replace") as f:
            for i, text in enumerate(f, 1):
                if i == node.lineno:
                    return len(text.encode("utf-8")[: node.col_offset].decode("utf-8", "replace")) + 1
    except OSError:
        pass
    return node.col_offset + 1
