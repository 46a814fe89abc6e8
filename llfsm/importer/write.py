"""Writing an imported machine directory: all of it or none of it.

The files are written into a fresh folder beside the target (`-o DIR/.NAME.machine.XXXX`), which
is then renamed into place: a failure midway (a full disk) leaves no half-written machine, and
an existing machine is replaced (`--force`) by renaming it aside, renaming the new one in and
only then deleting the old.  Nothing is ever written outside DIR: the machine's name and its
files' names are llfsm names (identifiers), checked before any path is built.

llfsm.edit (issue 29) will write every machine directory; until it is on main this module
does, in the same all-or-nothing way.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Mapping
from pathlib import Path

from ..lang.model import is_valid_name


class WriteError(Exception):
    """The machine was not written; str(e) is one line naming the place."""


def _safe_file_name(rel: str) -> bool:
    return bool(rel) and "/" not in rel and "\\" not in rel and rel not in (".", "..") and "\0" not in rel


def write_machine(out: Path, name: str, files: Mapping[str, str], force: bool) -> Path:
    """Write `files` as the machine directory `out/NAME.machine`; its path."""
    if not is_valid_name(name) or not all(_safe_file_name(f) for f in files):
        raise WriteError(f"refusing to write {name!r}: not an llfsm name")
    target = out / f"{name}.machine"
    replacing = False
    if target.is_symlink():
        raise WriteError(f"{target} is a symlink: not replaced")
    if target.exists():
        if not target.is_dir() or not (target / "machine.yaml").is_file():
            raise WriteError(f"{target} exists and is not an llfsm machine: not replaced")
        if not force:
            raise WriteError(f"{target} exists (--force replaces it)")
        replacing = True
    try:
        tmp = Path(tempfile.mkdtemp(prefix=f".{name}.machine.", dir=out))
    except OSError as e:
        raise WriteError(f"{out}: cannot write there ({e.strerror})") from None
    try:
        for rel, text in files.items():
            fd = os.open(tmp / rel, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0), 0o644)
            with os.fdopen(fd, "w", encoding="utf-8", newline="\n") as f:
                f.write(text)
        os.chmod(tmp, 0o755)  # mkdtemp's 0700 is for the folder while it is being written
        if replacing:
            _swap(tmp, target)
        else:
            os.rename(tmp, target)
    except OSError as e:
        shutil.rmtree(tmp, ignore_errors=True)
        raise WriteError(f"{target}: not written ({e.strerror or e})") from None
    return target


def _swap(new: Path, target: Path) -> None:
    """Put `new` where `target` is, keeping `target` until `new` is in place."""
    old = Path(tempfile.mkdtemp(prefix=f".{target.name}.old.", dir=target.parent))
    os.rmdir(old)  # only its unique name is wanted: rename needs the place free
    os.rename(target, old)
    try:
        os.rename(new, target)
    except OSError:
        os.rename(old, target)
        raise
    shutil.rmtree(old, ignore_errors=True)
