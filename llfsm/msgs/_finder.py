"""The import hook that makes a user's interface package importable as llfsm.msgs.PKG
(docs/bus.md, "Your own interfaces").

A package in ROS layout (PKG/msg/*.msg, PKG/srv/*.srv, PKG/action/*.action) found in the interface search path
(llfsm.interface_path) is compiled by the toolchain (llfsm.idl.package) into the cache, in a
folder named after a fingerprint of its files, and imported from there.  A warm import lists
and hashes the definition files and nothing more: the toolchain (and jinja2) are imported only
when that folder does not exist yet, by the one deferred import in `compiled_package`, the
single door from run time to the toolchain.  Shipped packages never reach this hook: it sits
at the end of sys.meta_path, after the finder that imports llfsm/msgs/<pkg>/ from the package
itself.
"""

from __future__ import annotations

import os
import sys
from importlib.machinery import ModuleSpec
from importlib.util import spec_from_file_location
from typing import TYPE_CHECKING

from .. import __version__
from ..cachedir import cache_dir, fresh_private, problem, warn
from ..interface_path import is_package_name, package_dir

if TYPE_CHECKING:
    from collections.abc import Sequence
    from types import ModuleType

PREFIX = "llfsm.msgs."
_LLFSM_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
_IDL_DIR = os.path.join(_LLFSM_DIR, "idl")
_generator_id: str | None = None


def _generator_files() -> list[str]:
    """What shapes generated message code, so that a change to any of them recompiles users'
    packages: the toolchain's modules, its templates, and the message base they generate for."""
    templates = os.path.join(_IDL_DIR, "templates")
    files = sorted(os.path.join(_IDL_DIR, n) for n in os.listdir(_IDL_DIR) if n.endswith(".py"))
    files += sorted(os.path.join(templates, n) for n in os.listdir(templates) if n.endswith(".j2"))
    return [*files, os.path.join(_LLFSM_DIR, "msgs", "_message.py")]


def _cache_root() -> str:
    """Same rule as llfsm.targets.cache_root, kept here so that importing messages stays light."""
    env = os.environ.get("LLFSM_CACHE_DIR")
    if env:
        return env
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "llfsm")


def _interfaces_cache() -> str:
    """The cache's `interfaces` folder: one of ours that no one else can write (llfsm.cachedir)."""
    return cache_dir(_cache_root(), "interfaces")


def _trusted_package(out: str) -> bool:
    """A compiled package folder (and its __init__.py) that this user wrote and only it can
    change; anything else there is never imported."""
    return problem(out) is None and problem(os.path.join(out, "__init__.py"), directory=False) is None


def _fingerprint(folder: str) -> str:
    """The package's files and the generator's, hashed: the name of its folder in the cache."""
    import hashlib  # deferred: start-up (a run importing only shipped messages hashes nothing)

    global _generator_id
    if _generator_id is None:
        g = hashlib.sha256()
        g.update(__version__.encode())
        for p in _generator_files():
            with open(p, "rb") as f:
                g.update(os.path.basename(p).encode() + b"\0" + f.read())
        _generator_id = g.hexdigest()
    h = hashlib.sha256(_generator_id.encode())
    h.update(os.fsencode(folder))
    for kind in ("msg", "srv", "action"):
        kind_dir = os.path.join(folder, kind)
        if not os.path.isdir(kind_dir):
            continue
        for name in sorted(os.listdir(kind_dir)):
            path = os.path.join(kind_dir, name)
            if not name.endswith(f".{kind}") or not os.path.isfile(path):
                continue
            with open(path, "rb") as f:
                data = f.read()
            h.update(b"\0%s/%s\0%d\0" % (kind.encode(), os.fsencode(name), len(data)))
            h.update(data)
    return h.hexdigest()


def compiled_package(package: str, folder: str) -> str:
    """The cache folder holding the package's generated modules, compiled first if missing."""
    fingerprint = _fingerprint(folder)
    cache = _interfaces_cache()
    out = os.path.join(cache, f"{package}-{fingerprint[:20]}")
    if os.path.isfile(os.path.join(out, "__init__.py")):
        if _trusted_package(out):
            return out
        why = problem(out) or problem(os.path.join(out, "__init__.py"), directory=False) or "not trusted"
        warn(out, why)
        cache = fresh_private()  # compile again where only we can write
        out = os.path.join(cache, f"{package}-{fingerprint[:20]}")
        if os.path.isfile(os.path.join(out, "__init__.py")):
            return out
    import shutil  # deferred: start-up, as the toolchain below
    import tempfile
    from pathlib import Path

    # The single door from run time to the toolchain (llfsm.idl), deferred: start-up (a warm
    # import, and any import of a shipped package, never loads the compiler or jinja2).
    from ..idl.package import build_package

    tmp = tempfile.mkdtemp(prefix=f".{package}-", dir=cache)
    try:
        build_package(Path(folder), Path(tmp), fingerprint)
        try:
            os.replace(tmp, out)  # the whole package appears at once
        except OSError:
            if not _trusted_package(out):  # not a concurrent build of ours
                raise
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return out


class InterfaceFinder:
    """sys.meta_path finder for llfsm.msgs.PKG: its subpackages msg, srv and action are then found by
    Python's own finder in the cached folder, which becomes the package's __path__."""

    def find_spec(
        self, fullname: str, path: Sequence[str] | None = None, target: ModuleType | None = None
    ) -> ModuleSpec | None:
        if not fullname.startswith(PREFIX):
            return None
        package = fullname[len(PREFIX) :]
        if "." in package or not is_package_name(package):
            return None
        folder = package_dir(package)
        if folder is None:
            return None
        out = compiled_package(package, folder)
        return spec_from_file_location(fullname, os.path.join(out, "__init__.py"), submodule_search_locations=[out])

    def invalidate_caches(self) -> None:
        pass


def install() -> None:
    """Put the hook at the end of sys.meta_path (once)."""
    if not any(isinstance(f, InterfaceFinder) for f in sys.meta_path):
        sys.meta_path.append(InterfaceFinder())
