"""What a machine directory is on disk, for every layer that touches one: its `NAME.machine`
name, the one rule about symlinks that every entry point applies before reading it, how a
generated module names it (relative to the module's own folder: docs/machine-format.md), and
how a file of one is read safely (`read_regular`: the reader, the importer, the editor).

Stdlib only, and light (os; pathlib only when a link is found): `llfsm run` uses it on its
warm path, the fingerprints below the compiler use it, and so does the front end (llfsm.lang).
Searching folders for machines is the front end's (llfsm.lang.discover).
"""

from __future__ import annotations

import os
import stat

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


# -- reading a file that anyone may have written -------------------------------------------------
#: Never block (a FIFO or a device where a file should be would hang the reader: O_NONBLOCK, then
#: refused by its type), never become a controlling terminal, never leak into a child process.
_READ_FLAGS = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0) | getattr(os, "O_CLOEXEC", 0)
#: 0 where the system has no O_NOFOLLOW: callers then check for a symlink themselves first.
NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)


class NotRegularFile(Exception):
    """`read_regular` found no regular file there: a folder (`folder`), a FIFO, a device."""

    def __init__(self, mode: int) -> None:
        super().__init__("a folder" if stat.S_ISDIR(mode) else "not a regular file")
        self.folder = stat.S_ISDIR(mode)


class FileTooLarge(Exception):
    """`read_regular` found more than its limit: `size` bytes, or None when the file grew past the
    limit while it was being read."""

    def __init__(self, size: int | None) -> None:
        super().__init__("larger than the limit")
        self.size = size


def read_regular(path: str | os.PathLike[str], limit: int, *, follow: bool = False) -> bytes:
    """The bytes of the regular file at `path`, at most `limit` of them.  A symlink is not
    followed unless `follow` (the open fails: ELOOP); NotRegularFile or FileTooLarge, else the
    OSError the system gives (FileNotFoundError, PermissionError...).

    One open, one fstat, reads of what the file holds (a read of `limit` bytes would allocate
    that much for a three-line section), and never more than `limit` + 1 bytes from a file that
    grows while it is read."""
    fd = os.open(path, _READ_FLAGS | (0 if follow else NOFOLLOW))
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise NotRegularFile(st.st_mode)
        if st.st_size > limit:
            raise FileTooLarge(st.st_size)
        want = st.st_size + 1  # one more: a file that grew since fstat
        data = _read_fd(fd, want)
        if len(data) == want:
            data += _read_fd(fd, limit + 1 - want)
        if len(data) > limit:
            raise FileTooLarge(None)
        return data
    finally:
        os.close(fd)


def _read_fd(fd: int, n: int) -> bytes:
    """Up to `n` bytes of an open file (fewer only at its end): no buffered file object, which
    costs more than the read for a three-line section."""
    chunks: list[bytes] = []
    got = 0
    while got < n:
        more = os.read(fd, n - got)
        if not more:
            break
        chunks.append(more)
        got += len(more)
    return chunks[0] if len(chunks) == 1 else b"".join(chunks)  # b"" for none
