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
