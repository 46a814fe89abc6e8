"""Finding machine directories.  Light (os only when imported): `llfsm build` and `llfsm run`
use it on their fast paths, before deciding whether anything needs the compiler."""

from __future__ import annotations

import os

TYPE_CHECKING = False  # not typing's own: `llfsm run` imports this module and starts fast without typing
if TYPE_CHECKING:
    from pathlib import Path  # not at run time: pathlib costs `llfsm run` a tenth of its start-up

MACHINE_SUFFIX = ".machine"
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


def machine_name_of(path: Path) -> str:
    name = path.name
    return name[: -len(MACHINE_SUFFIX)] if name.endswith(MACHINE_SUFFIX) else name


def refused_link(path: Path) -> str | None:
    """Why the machine directory `path` must not be read, or None if it may.

    The one rule of every entry point (check, build, run, graph, a path found by searching or
    named on the command line or by a shell glob): a machine directory that is a symlink is
    read only if it leads to a place inside the folder that holds the link.  A pull request
    can add `evil.machine -> /home/ci/secrets`; neither `llfsm check .` nor
    `llfsm check */*.machine` nor `llfsm build` may then read, report or compile that folder.
    """
    if not os.path.islink(path):
        return None
    from pathlib import Path

    # os.path.realpath, not Path.resolve: it never raises on a symlink loop (Python 3.11)
    real = Path(os.path.realpath(path))
    home = Path(os.path.realpath(path.parent))
    if real.is_relative_to(home):
        return None
    return f"{path.name} is a symlink leading out of {path.parent}; refused"


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
