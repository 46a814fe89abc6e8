"""A change to a machine directory as data, and applying it to every file or to none.

A planner (llfsm.edit.structure, llfsm.edit.files) reads the directory and returns a `Change`:
the new bytes of each file it touches (None: delete it) and the bytes each had when it was read.
`apply` writes them all or none: it first makes sure the disk still holds `before` (someone else
may have written meanwhile: the editor's page, a text editor, git), writes every new file beside
its target, then renames each into place, keeping a hard link to the old one; anything that fails
on the way puts every file back, byte for byte, and removes what it made.  The undo of a change is
the change with `writes` and `before` swapped (`invert`).

Paths are checked again here, whoever made the change: relative, one or two plain names (a file
of the machine, or NAME.machine/file for a new machine), no `..`, no NUL, no symlink on the way.
"""

from __future__ import annotations

import contextlib
import os
import secrets
import stat
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from ..lang.reader import MAX_FILE_BYTES
from ..machinedir import FileTooLarge, NotRegularFile, read_regular, refused_link

#: Longest file name written (bytes; the file system's NAME_MAX, less room for a temporary name).
MAX_FILE_NAME = 230


class EditError(Exception):
    """A refused request; str(e) is the one line the user sees (the CLI exits 1 with it)."""


@dataclass(frozen=True)
class Change:
    """What a planner decided: every file it touches, before and after."""

    root: Path  # the machine directory (for new_machine: the folder that receives it)
    writes: Mapping[str, bytes | None]  # relative path -> new bytes (None: delete the file)
    before: Mapping[str, bytes | None]  # relative path -> bytes before (None: did not exist)
    summary: str  # one line: "renamed state WAIT to PAUSE (3 files)"

    @property
    def empty(self) -> bool:
        return not self.writes


def invert(change: Change) -> Change:
    """The undo of `change`: applying it puts back what `change` replaced."""
    return Change(change.root, dict(change.before), dict(change.writes), f"undo: {change.summary}")


def check_relpath(rel: str) -> tuple[str, ...]:
    """The parts of a relative path a change may write, or EditError: one file name, or a folder
    and a file name (a new machine); never `..`, `.`, an absolute path, NUL or a long name."""
    if not isinstance(rel, str) or not rel or "\0" in rel or "\\" in rel or rel.startswith("/"):
        raise EditError(f"refused path {_show(rel)}: a file name inside the machine directory")
    parts = tuple(rel.split("/"))
    if len(parts) > 2 or any(p in ("", ".", "..") or len(os.fsencode(p)) > MAX_FILE_NAME for p in parts):
        raise EditError(f"refused path {_show(rel)}: a file name inside the machine directory")
    return parts


def read_plain(root: Path, rel: str) -> bytes | None:
    """The bytes of root/rel, None when it does not exist; EditError for a symlink (never
    followed: it might lead out of the machine directory), anything not a regular file, or a
    file beyond the reader's size limit."""
    check_relpath(rel)
    path = root / rel
    for p in (path.parent, path) if path.parent != root else (path,):
        if p.is_symlink():
            raise EditError(f"{p} is a symlink; llfsm edits only plain files inside the machine directory")
    try:
        return read_regular(path, MAX_FILE_BYTES)
    except FileNotFoundError:
        return None
    except NotRegularFile:
        raise EditError(f"{path} is not a regular file") from None
    except FileTooLarge:
        raise EditError(f"{path} is larger than {MAX_FILE_BYTES // 1024} KiB; refused") from None
    except OSError as e:
        raise EditError(f"{path}: cannot read: {e.strerror or e}") from None


def check_root(root: Path, *, exists: bool = True) -> None:
    """The directory a change is applied in: a real directory (a symlink only if it stays inside
    the folder holding it, as every entry point of llfsm reads machines: llfsm.machinedir)."""
    if root.is_symlink() and refused_link(root) is not None:
        raise EditError(f"{root} is a symlink leading out of {root.parent}; refused")
    if exists and not root.is_dir():
        raise EditError(f"{root}: no such directory")


def apply(change: Change) -> None:
    """Write every file of `change`, or none (see the module's docstring).  EditError when the
    disk no longer holds `before` (naming the file) or a write fails (the directory is then as
    it was); an interrupt also leaves the directory as it was, and is raised again."""
    root = change.root
    check_root(root)
    items = list(change.writes.items())
    for rel, _ in items:
        if read_plain(root, rel) != change.before.get(rel):
            raise EditError(f"{root / rel} changed on disk since the edit was read; nothing was written")
    made_dirs: list[Path] = []
    staged: dict[str, str] = {}
    backups: dict[str, str] = {}
    done: list[str] = []
    current = root  # the file being written, named if that fails (an OSError of os.write names none)
    try:
        for rel, data in items:
            if data is None:
                continue
            current = root / rel
            folder = current.parent
            if not folder.exists():
                folder.mkdir()  # a new machine's directory (check_relpath allows one level)
                made_dirs.append(folder)
            staged[rel] = _stage(folder, data, root / rel)
        for rel, data in items:
            path = current = root / rel
            if change.before.get(rel) is not None:
                backups[rel] = _backup(path)
            if data is None:
                _remove_one(str(path))
            else:
                _commit_one(staged[rel], str(path))
                del staged[rel]
            done.append(rel)
    except BaseException as e:
        _roll_back(root, change, done, backups)
        for tmp in staged.values():
            with contextlib.suppress(OSError):
                os.unlink(tmp)
        for folder in reversed(made_dirs):
            with contextlib.suppress(OSError):
                folder.rmdir()
        if isinstance(e, OSError):
            raise EditError(f"{current}: cannot write: {e.strerror or e}; nothing was changed") from None
        raise
    finally:
        for b in backups.values():
            with contextlib.suppress(OSError):
                os.unlink(b)


def _stage(folder: Path, data: bytes, target: Path) -> str:
    """`data` in a new hidden file beside `target` (same file system: the rename is atomic),
    with the target's permissions when it exists."""
    tmp = str(folder / f".{secrets.token_hex(6)}.llfsm-edit")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0), 0o666)
    try:
        view = memoryview(data)
        while view:
            view = view[os.write(fd, view) :]
        with contextlib.suppress(OSError):
            os.fchmod(fd, stat.S_IMODE(os.lstat(target).st_mode))
    except BaseException:
        os.close(fd)
        os.unlink(tmp)
        raise
    os.close(fd)
    return tmp


def _backup(path: Path) -> str:
    """A hard link to the file about to be replaced or removed: putting it back costs no space
    (the disk may be full: that may be why we are putting it back)."""
    name = str(path.parent / f".{secrets.token_hex(6)}.llfsm-undo")
    try:
        os.link(path, name)
    except OSError:
        return ""  # no hard links here: the roll-back writes the bytes it was given instead
    return name


def _commit_one(tmp: str, path: str) -> None:
    """One file into place (a function of its own: the tests make the second one fail)."""
    os.replace(tmp, path)


def _remove_one(path: str) -> None:
    os.unlink(path)


def _roll_back(root: Path, change: Change, done: list[str], backups: dict[str, str]) -> None:
    """Every file already committed back as `before` had it."""
    for rel in reversed(done):
        path = root / rel
        old = change.before.get(rel)
        with contextlib.suppress(OSError):
            if old is None:
                os.unlink(path)
            elif backups.get(rel):
                os.replace(backups.pop(rel), path)
            else:
                tmp = _stage(path.parent, old, path)
                os.replace(tmp, path)


def _show(rel: object) -> str:
    text = repr(rel)
    return text if len(text) <= 60 else text[:59] + "…"
