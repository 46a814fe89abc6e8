"""Where users' interface packages are found: the folders added by `add_search_path`, then
LLFSM_INTERFACE_PATH, then `share/` of every AMENT_PREFIX_PATH prefix (docs/bus.md, "Your own
interfaces").

One list, read by the import hook of llfsm.msgs, by the package builder (llfsm.idl.package)
for the packages a package refers to, and by `ros2 interface`.  It lives at the bottom,
stdlib only, because `llfsm run` names the folders around its machines before it loads them,
and a run whose machines use no messages must not import llfsm.msgs to do so: its start-up
would pay for it.
"""

from __future__ import annotations

import os

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from collections.abc import Iterable
    from pathlib import Path

_added: list[str] = []


def add_search_path(path: str | os.PathLike[str]) -> None:
    """Search `path` (a folder holding PKG/msg, PKG/srv or PKG/action folders) for interface
    packages, before LLFSM_INTERFACE_PATH and AMENT_PREFIX_PATH."""
    p = os.path.abspath(os.fspath(path))
    if p not in _added:
        _added.append(p)


def _roots() -> list[str]:
    roots = list(_added)
    roots += [os.path.abspath(p) for p in _env_list("LLFSM_INTERFACE_PATH")]
    roots += [os.path.join(os.path.abspath(p), "share") for p in _env_list("AMENT_PREFIX_PATH")]
    return list(dict.fromkeys(roots))


def _env_list(name: str) -> list[str]:
    return [p for p in os.environ.get(name, "").split(os.pathsep) if p]


def search_path() -> list[Path]:
    """The folders searched, in order: added paths, LLFSM_INTERFACE_PATH, then `share/` of
    every AMENT_PREFIX_PATH prefix (where colcon installs PKG/msg/X.msg)."""
    from pathlib import Path  # deferred: start-up (a run that only adds folders never lists them)

    return [Path(r) for r in _roots()]


def package_dir(package: str) -> str | None:
    """The folder of the package in the search path.  Only a package name (ROS's rule) is
    looked for: a name such as `..` or `a/b`, from a file or a peer, never becomes a path."""
    if not is_package_name(package):
        return None
    for root in _roots():
        d = os.path.join(root, package)
        if any(os.path.isdir(os.path.join(d, kind)) for kind in ("msg", "srv", "action")):
            return d
    return None


def find_package(package: str) -> Path | None:
    """The folder of a user's interface package, as the import hook finds it."""
    from pathlib import Path  # deferred: start-up, as in search_path

    d = package_dir(package)
    return None if d is None else Path(d)


def is_package_name(name: str) -> bool:
    """ROS's rule for package names (lower_snake_case, as llfsm.idl.spec.PACKAGE_NAME), without
    importing re."""
    return (
        name[:1].isascii()
        and name[:1].islower()
        and all(c.isascii() and (c.islower() or c.isdigit() or c == "_") for c in name)
        and "__" not in name
        and not name.endswith("_")
    )


#: The definitions of the packages llfsm ships (llfsm/msgs/_interfaces/PKG/KIND/Name.KIND): the
#: modules of llfsm.msgs are generated from them, so their file names are the types there are.
SHIPPED_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "msgs", "_interfaces")
#: The kinds of interface a package folder holds, as ROS lays them out.
INTERFACE_KINDS = ("msg", "srv", "action")


def shipped_packages() -> list[str]:
    """The names of the packages llfsm ships, sorted."""
    try:
        names = os.listdir(SHIPPED_DIR)
    except OSError:
        return []
    return sorted(n for n in names if is_package_name(n) and os.path.isdir(os.path.join(SHIPPED_DIR, n)))


def interface_folder(package: str, extra_roots: Iterable[str] = ()) -> tuple[str, bool] | None:
    """(folder, shipped) of an interface package as an import of llfsm.msgs.PKG finds it: the
    shipped one first, then `extra_roots` (the folders `llfsm run` adds around its machines),
    then the search path.  Found by listing folders alone: no definition is read, nothing is
    imported (`llfsm check` asks this of untrusted machines)."""
    if not is_package_name(package):
        return None
    shipped = os.path.join(SHIPPED_DIR, package)
    if os.path.isdir(shipped):
        return shipped, True
    for root in [*(os.path.abspath(r) for r in extra_roots), *_roots()]:
        d = os.path.join(root, package)
        if any(os.path.isdir(os.path.join(d, k)) for k in INTERFACE_KINDS):
            return d, False
    return None


def interface_names(folder: str, kind: str) -> list[str]:
    """The types of one kind a package folder defines (`Twist` for msg/Twist.msg), sorted."""
    try:
        names = os.listdir(os.path.join(folder, kind))
    except OSError:
        return []
    suffix = "." + kind
    return sorted(n[: -len(suffix)] for n in names if n.endswith(suffix) and n[: -len(suffix)].isidentifier())


def folders_around(path: str, levels: int = 4) -> list[str]:
    """The folders above `path` (a machine folder or module) that `llfsm run` searches for
    interface packages: a machine's own `my_msgs/` beside it or a few folders up."""
    folder = os.path.realpath(path)  # realpath: no error on a loop
    out = []
    for _ in range(levels):
        parent = os.path.dirname(folder)
        if parent == folder:
            break
        folder = parent
        out.append(folder)
    return out
