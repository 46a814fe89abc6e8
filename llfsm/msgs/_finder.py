"""The import hook that makes a user's interface package importable as llfsm.msgs.PKG.

A package in ROS layout (PKG/msg/*.msg, PKG/srv/*.srv) found in the search path is compiled by
llfsm.idl.package into the cache, in a folder named after a fingerprint of its files,
and imported from there.  A warm import lists and hashes the definition files and nothing more:
the compiler (and jinja2) are imported only when that folder does not exist yet.  Built-in
packages never reach this hook: the hook sits at the end of sys.meta_path, after the finder that
imports llfsm/msgs/<pkg>/ from the package itself.
"""

from __future__ import annotations

import os
import sys
from importlib.machinery import ModuleSpec
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Sequence
    from pathlib import Path
    from types import ModuleType

PREFIX = "llfsm.msgs."
_LLFSM_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# What shapes generated message code: a change to any of these recompiles users' packages.
_GENERATOR_FILES = (
    os.path.join(_LLFSM_DIR, "idl", "package.py"),
    os.path.join(_LLFSM_DIR, "idl", "ddsgen.py"),
    os.path.join(_LLFSM_DIR, "msgs", "_message.py"),
)
_added: list[str] = []
_generator_id: str | None = None


def add_search_path(path: str | os.PathLike[str]) -> None:
    """Search `path` (a folder holding PKG/msg or PKG/srv folders) for interface packages,
    before LLFSM_INTERFACE_PATH and AMENT_PREFIX_PATH."""
    p = os.path.abspath(os.fspath(path))
    if p not in _added:
        _added.append(p)


def _take_pending() -> None:
    """The folders named before this module was imported (llfsm.idl.paths)."""
    from ..idl import paths as interface_paths

    for p in interface_paths.pending:
        add_search_path(p)
    interface_paths.pending.clear()


_take_pending()


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
    from pathlib import Path

    return [Path(r) for r in _roots()]


def _package_dir(package: str) -> str | None:
    """The folder of the package in the search path.  Only a package name (ROS's rule) is
    looked for: a name such as `..` or `a/b`, from a file or a peer, never becomes a path."""
    if not _is_package_name(package):
        return None
    for root in _roots():
        d = os.path.join(root, package)
        if os.path.isdir(os.path.join(d, "msg")) or os.path.isdir(os.path.join(d, "srv")):
            return d
    return None


def find_package(package: str) -> Path | None:
    """The folder of a user's interface package, as the import hook finds it."""
    from pathlib import Path

    d = _package_dir(package)
    return None if d is None else Path(d)


def _is_package_name(name: str) -> bool:
    """ROS's rule for package names (lower_snake_case), without importing re."""
    return (
        name[:1].isascii()
        and name[:1].islower()
        and all(c.isascii() and (c.islower() or c.isdigit() or c == "_") for c in name)
        and "__" not in name
        and not name.endswith("_")
    )


def _cache_root() -> str:
    """Same rule as llfsm.targets.cache_root, kept here so that importing messages stays light."""
    env = os.environ.get("LLFSM_CACHE_DIR")
    if env:
        return env
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "llfsm")


def _interfaces_cache() -> str:
    """The cache's `interfaces` folder: one of ours that no one else can write (llfsm.cachedir)."""
    from ..cachedir import cache_dir

    return cache_dir(_cache_root(), "interfaces")


def _trusted_package(out: str) -> bool:
    """A compiled package folder (and its __init__.py) that this user wrote and only it can
    change; anything else there is never imported."""
    from ..cachedir import problem

    return problem(out) is None and problem(os.path.join(out, "__init__.py"), directory=False) is None


def _fingerprint(package_dir: str) -> str:
    import hashlib

    global _generator_id
    if _generator_id is None:
        g = hashlib.sha256()
        from .. import __version__

        g.update(__version__.encode())
        templates = os.path.join(_LLFSM_DIR, "idl", "templates")
        names = sorted(n for n in os.listdir(templates) if n.startswith("msgs") and n.endswith(".j2"))
        for p in (*_GENERATOR_FILES, *(os.path.join(templates, n) for n in names)):
            with open(p, "rb") as f:
                g.update(os.path.basename(p).encode() + b"\0" + f.read())
        _generator_id = g.hexdigest()
    h = hashlib.sha256(_generator_id.encode())
    h.update(os.fsencode(package_dir))
    for kind in ("msg", "srv"):
        folder = os.path.join(package_dir, kind)
        if not os.path.isdir(folder):
            continue
        for name in sorted(os.listdir(folder)):
            path = os.path.join(folder, name)
            if not name.endswith(f".{kind}") or not os.path.isfile(path):
                continue
            with open(path, "rb") as f:
                data = f.read()
            h.update(b"\0%s/%s\0%d\0" % (kind.encode(), os.fsencode(name), len(data)))
            h.update(data)
    return h.hexdigest()


def compiled_package(package: str, package_dir: str) -> str:
    """The cache folder holding the package's generated modules, compiled first if missing."""
    fingerprint = _fingerprint(package_dir)
    cache = _interfaces_cache()
    out = os.path.join(cache, f"{package}-{fingerprint[:20]}")
    if os.path.isfile(os.path.join(out, "__init__.py")):
        if _trusted_package(out):
            return out
        from ..cachedir import fresh_private, problem, warn

        why = problem(out) or problem(os.path.join(out, "__init__.py"), directory=False) or "not trusted"
        warn(out, why)
        cache = fresh_private()  # compile again where only we can write
        out = os.path.join(cache, f"{package}-{fingerprint[:20]}")
        if os.path.isfile(os.path.join(out, "__init__.py")):
            return out
    import shutil
    import tempfile
    from pathlib import Path

    from ..idl.package import build_package

    tmp = tempfile.mkdtemp(prefix=f".{package}-", dir=cache)
    try:
        build_package(Path(package_dir), Path(tmp), fingerprint)
        try:
            os.replace(tmp, out)  # the whole package appears at once
        except OSError:
            if not _trusted_package(out):  # not a concurrent build of ours
                raise
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return out


class InterfaceFinder:
    """sys.meta_path finder for llfsm.msgs.PKG: its subpackages msg and srv are then found by
    Python's own finder in the cached folder, which becomes the package's __path__."""

    def find_spec(
        self, fullname: str, path: Sequence[str] | None = None, target: ModuleType | None = None
    ) -> ModuleSpec | None:
        if not fullname.startswith(PREFIX):
            return None
        package = fullname[len(PREFIX) :]
        if "." in package or not _is_package_name(package):
            return None
        package_dir = _package_dir(package)
        if package_dir is None:
            return None
        out = compiled_package(package, package_dir)
        from importlib.util import spec_from_file_location

        return spec_from_file_location(fullname, os.path.join(out, "__init__.py"), submodule_search_locations=[out])

    def invalidate_caches(self) -> None:
        pass


def install() -> None:
    if not any(isinstance(f, InterfaceFinder) for f in sys.meta_path):
        sys.meta_path.append(InterfaceFinder())
