"""Content fingerprints for incremental builds.

Deliberately light (hashlib and os only): `llfsm run DIR.machine` calls it to decide whether
the cached module is fresh, and must not import the compiler to find out that it is.
"""

from __future__ import annotations

import hashlib
import os
from functools import cache
from pathlib import Path

from . import __version__
from .discover import refused_link

HEADER_KEY = "# Fingerprint: "
_PKG = Path(__file__).parent


@cache
def compiler_id() -> str:
    """Changes whenever anything that shapes generated code changes: version, templates, compiler."""
    h = hashlib.sha256(__version__.encode())
    for p in sorted((_PKG / "templates").glob("machine*.j2")) + sorted((_PKG / "compiler").glob("*.py")):
        h.update(p.name.encode())
        h.update(p.read_bytes())
    return h.hexdigest()[:16]


def machine_fingerprint(path: Path, known: dict[str, bytes] | None = None) -> str:
    """Hash of every regular file of a machine directory (names and bytes) and the compiler id.
    `known`: bytes already read (by the checker), by file name: only the others are read."""
    if refused_link(path) is not None:  # never read; the build then reports it (LF037)
        raise OSError(f"{path} is a symlink leading out of its folder")
    h = hashlib.sha256(compiler_id().encode())
    h.update(os.fsencode(os.path.abspath(path)))
    with os.scandir(path) as it:  # file types from the listing: no stat per file
        entries = sorted((e for e in it if not e.name.startswith(".")), key=lambda e: e.name)
    for e in entries:
        name = e.name
        try:
            regular = e.is_file()
        except OSError:  # as Path.is_file decides (a symlink loop is no file)
            regular = (path / name).is_file()
        if not regular:
            continue
        data = known[name] if known is not None and name in known else (path / name).read_bytes()
        h.update(b"\0%s\0%d\0" % (os.fsencode(name), len(data)))
        h.update(data)
    return h.hexdigest()


def module_fingerprint(module: Path) -> str | None:
    """The fingerprint recorded in a generated module's header, if it has one."""
    try:
        with open(module, encoding="utf-8", errors="replace") as f:
            for _ in range(5):
                line = f.readline()
                if line.startswith(HEADER_KEY):
                    return line[len(HEADER_KEY) :].strip()
    except OSError:
        return None
    return None
