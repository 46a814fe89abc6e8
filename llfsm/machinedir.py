"""What a machine directory is on disk, for every layer that touches one: its `NAME.machine`
name, the one rule about symlinks that every entry point applies before reading it, and how a
generated module names it (relative to the module's own folder: docs/machine-format.md).

Stdlib only, and light (os; pathlib only when a link is found): `llfsm run` uses it on its
warm path, the fingerprints below the compiler use it, and so does the front end (llfsm.lang).
Searching folders for machines is the front end's (llfsm.lang.discover).
"""

from __future__ import annotations

import os

TYPE_CHECKING = False  # not typing's own: `llfsm run` imports this module and starts fast without typing
if TYPE_CHECKING:
    from pathlib import Path  # not at run time: pathlib costs `llfsm run` a tenth of its start-up

MACHINE_SUFFIX = ".machine"
#: Where the editor placed the states (llfsm.lang.layout_file): no part of what a machine does,
#: so no part of its fingerprint (a machine builds to the same bytes whatever its layout).
LAYOUT_FILE = "layout.yaml"


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
    from pathlib import Path  # deferred: start-up (only a linked machine directory needs it)

    # os.path.realpath, not Path.resolve: it never raises on a symlink loop (Python 3.11)
    real = Path(os.path.realpath(path))
    home = Path(os.path.realpath(path.parent))
    if real.is_relative_to(home):
        return None
    return f"{path.name} is a symlink leading out of {path.parent}; refused"


def source_ref(machine_dir: str | os.PathLike[str], module_dir: str | os.PathLike[str]) -> str:
    """The machine folder as a module built into `module_dir` names it: relative to that folder,
    so that a module holds no absolute path and the same machine gives the same bytes wherever
    the two folders are (copied, checked out elsewhere) as long as they move together."""
    try:
        return os.path.relpath(os.path.abspath(machine_dir), os.path.abspath(module_dir))
    except ValueError:  # another drive (Windows): no relative path exists
        return os.path.abspath(machine_dir)


def machine_dir_of(ref: str, module_file: str) -> str:
    """The machine folder a module names with `ref` (`source_ref`), from the module's own path.
    Lexical, as `source_ref` is: the module found by the path it was built under."""
    return os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(module_file)), ref))
