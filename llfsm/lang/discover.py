"""Finding machine directories below a folder, for `llfsm check`, `llfsm build` and the package
builds.  Light (os only when imported); what a machine directory is (its name, the symlink
rule) is llfsm.machinedir's, below the front end."""

from __future__ import annotations

import os

from ..machinedir import MACHINE_SUFFIX

TYPE_CHECKING = False  # not typing's own: a warm `llfsm build` imports this module, and typing costs it
if TYPE_CHECKING:
    from pathlib import Path

#: Folders never searched for machines: VCS data, caches, virtual environments.
SKIP_DIRS = frozenset(
    {
        ".git",
        ".hg",
        ".svn",
        "__pycache__",
        "node_modules",
        ".venv",
        "venv",
        ".tox",
        ".mypy_cache",
        ".ruff_cache",
        ".pytest_cache",
    }
)
#: colcon's output folders, skipped when they sit beside a `src/` (they hold copies).
COLCON_OUTPUT = frozenset({"build", "install", "log"})


def is_machine_dir(path: Path) -> bool:
    return path.name.endswith(MACHINE_SUFFIX) and path.is_dir()


def find_machines(path: Path) -> list[Path]:
    """`path` itself if it is a machine directory, else every NAME.machine folder below it, in
    sorted order.  An explicit stack, not os.walk (which recurses once per level in Python 3.11):
    a pull request with thousands of nested folders must not crash `llfsm check .`."""
    if is_machine_dir(path) or (path / "machine.yaml").exists():
        return [path]
    found: list[Path] = []
    stack = [path]
    while stack:
        here = stack.pop()
        try:
            with os.scandir(here) as it:
                # links to folders are listed (check refuses machines linked from outside) but
                # never descended into, as os.walk(followlinks=False) does
                dirs = sorted((e.name, e.is_symlink()) for e in it if _is_dir(e))
        except OSError:
            continue  # unreadable folders are skipped, as os.walk skips them
        below = []
        for d, link in dirs:
            if d in SKIP_DIRS or d.startswith("."):
                continue
            if d in COLCON_OUTPUT and (here / "src").is_dir():
                continue
            if d.endswith(MACHINE_SUFFIX):
                found.append(here / d)
            elif not link:
                below.append(here / d)
        stack.extend(reversed(below))  # depth first, in name order
    return sorted(found, key=lambda p: p.parts)


def _is_dir(entry: os.DirEntry[str]) -> bool:
    try:
        return entry.is_dir()
    except OSError:  # a symlink loop
        return False
