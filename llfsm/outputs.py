"""Every file a user names for output (`check -o`, `graph -o`, `run --image`, `run --trace`)
is written through here, so that each failure is one clear line and nothing is left half-written.

- A whole file (a report, a picture) is written to a temporary file beside the target and
  renamed over it: readers see the old file or the new one, and a full disk leaves the old one.
  A target that exists but is not a regular file (/dev/stdout, a FIFO, /dev/null) is written in
  place: renaming over it would replace a device or a pipe with a plain file.  A symbolic link
  is written through (its target is replaced), not replaced itself.
- A streamed file (the `--trace` log) remembers its first write error instead of raising it
  into the scheduler, and is removed at the end if it could not be written whole.

OutputError carries the message; the command line prints it and exits 1.  Leaf module: it
imports nothing from llfsm, so the simulator and the run time may use it.
"""

from __future__ import annotations

import contextlib
import os
import secrets
import stat
from collections.abc import Callable
from typing import IO


class OutputError(OSError):
    """A named output that could not be written; str() is the whole message for the user,
    `strerror` the reason alone (so callers that catch OSError keep their own wording)."""

    def __init__(self, message: str, reason: str) -> None:
        super().__init__(message)
        self.strerror = reason


def _why(e: OSError) -> str:
    return e.strerror or str(e)


def _error(shown: str, reason: str) -> OutputError:
    return OutputError(f"{shown}: cannot write: {reason}", reason)


def write_file(
    path: str | os.PathLike[str], data: bytes | Callable[[IO[bytes]], object], *, what: str = "", mkdirs: bool = False
) -> None:
    """Write `data` (bytes, or a function that writes to a binary file) to `path`, atomically
    when `path` is (or will be) a regular file.  Raises OutputError with `what PATH: ...`."""
    shown = f"{what} {os.fspath(path)}".strip()
    write = data if callable(data) else (lambda f: f.write(data))
    try:
        st: os.stat_result | None = os.stat(path)
    except FileNotFoundError:
        st = None
    except OSError as e:
        raise _error(shown, _why(e)) from None
    try:
        if st is not None and stat.S_ISDIR(st.st_mode):
            raise _error(shown, "it is a directory")
        if st is not None and not stat.S_ISREG(st.st_mode):
            with open(path, "wb") as f:  # a device or a pipe: there is nothing to replace
                write(f)
            return
        target = os.path.realpath(path)  # through a symbolic link, not over it
        folder = os.path.dirname(target) or "."
        if mkdirs:
            os.makedirs(folder, exist_ok=True)
        tmp = os.path.join(folder, f".{os.path.basename(target)}.{os.getpid()}.{secrets.token_hex(4)}.tmp")
        flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0)
        try:
            fd = os.open(tmp, flags, 0o666)  # the umask applies, as for any file the user writes
        except OSError as e:
            raise _error(shown, f"{_why(e)} (creating a temporary file in {folder})") from None
        try:
            with os.fdopen(fd, "wb") as f:
                write(f)
                f.flush()
                os.fsync(f.fileno())
            os.replace(tmp, target)
        except BaseException:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
            raise
    except OSError as e:
        raise _error(shown, _why(e)) from None


class StreamedOutput:
    """A text file written while a run goes on (`--trace`).  Write errors (a full disk) do not
    reach the scheduler: the first is kept, later writes are dropped, and `finish()` removes the
    incomplete file and returns the message."""

    def __init__(self, path: str | os.PathLike[str], *, what: str = "") -> None:
        self.shown = f"{what} {os.fspath(path)}".strip()
        self.path = os.fspath(path)
        try:
            st = os.stat(path)
            if stat.S_ISDIR(st.st_mode):
                raise _error(self.shown, "it is a directory")
            self._regular = stat.S_ISREG(st.st_mode)
        except FileNotFoundError:
            self._regular = True
        except OSError as e:
            raise _error(self.shown, _why(e)) from None
        try:
            self._f: IO[str] | None = open(path, "w", encoding="utf-8")  # noqa: SIM115 (closed by finish)
        except OSError as e:
            raise _error(self.shown, _why(e)) from None
        self.error: str | None = None

    def _failed(self, e: OSError) -> None:
        if self.error is None:
            self.error = f"{self.shown}: cannot write: {_why(e)}"

    def write(self, text: str) -> int:
        if self.error is None and self._f is not None:
            try:
                return self._f.write(text)
            except OSError as e:
                self._failed(e)
        return 0

    def flush(self) -> None:
        if self.error is None and self._f is not None:
            try:
                self._f.flush()
            except OSError as e:
                self._failed(e)

    def close(self) -> None:
        self.flush()

    def finish(self) -> str | None:
        """Close the file; the error message if it could not be written whole (it is removed)."""
        f, self._f = self._f, None
        if f is not None:
            try:
                f.close()
            except OSError as e:
                self._failed(e)
        if self.error is not None and self._regular:
            with contextlib.suppress(OSError):
                os.unlink(self.path)
        return self.error
