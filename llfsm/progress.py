"""A status line for long, otherwise silent work: a native compile, a bag being recorded or
played, a verb waiting for a topic (docs/cli.md, "Progress on a terminal").

Only on a terminal: when stderr is not a TTY (a pipe, a file, a CI log) nothing is written at
all, so logs and the output tests compare stay as they were.  The line is rewritten in place
(`\\r`, then "clear to the end of the line", then the text cut to the terminal's width), at
most a few times a second, and cleared when the work ends, so what follows starts on a clean
line.  Lines the command prints meanwhile (`Status.print`) go above it.

Work that may run for minutes in CI (`llfsm verify`) asks for a log too (`log_after`,
`log_every`): off a terminal its line is written as a plain line once the work has run
`log_after` seconds, then every `log_every` seconds, so a long job shows it is alive.

Stdlib only, and light: commands import it when they start long work.
"""

from __future__ import annotations

import io
import os
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TextIO

#: At most this often is the line rewritten (seconds).
INTERVAL = 0.2
_CLEAR = "\r\x1b[K"


def on_terminal(stream: TextIO) -> bool:
    """Whether `stream` is a terminal a status line may be drawn on (not TERM=dumb)."""
    try:
        return stream.isatty() and os.environ.get("TERM") != "dumb"
    except (AttributeError, ValueError, OSError):  # closed, or not a real stream
        return False


class Status:
    """One status line on `stream` (stderr by default), drawn only on a terminal."""

    def __init__(
        self, stream: TextIO | None = None, *, log_after: float | None = None, log_every: float = 10.0
    ) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = on_terminal(self.stream)
        self._lock = threading.Lock()
        self._shown = ""  # what the line holds now ("" when cleared)
        self._last = 0.0
        #: Off a terminal, `progress` writes a plain line from this many seconds of work on (None:
        #: never), then every `log_every` seconds.
        self.log_after = log_after
        self.log_every = log_every
        self._logged: float | None = None  # the work's seconds at the last plain line

    def progress(self, text: str, elapsed: float) -> None:
        """How far long work has got after `elapsed` seconds: the status line on a terminal, a
        plain line now and then in a log (see `log_after`)."""
        if self.enabled:
            self.show(text, now=True)
            return
        if self.log_after is None or elapsed < self.log_after:
            return
        if self._logged is not None and elapsed - self._logged < self.log_every:
            return
        self._logged = elapsed
        self._write(text + "\n")

    def show(self, text: str, *, now: bool = False) -> None:
        """Put `text` on the line (at most every INTERVAL seconds, unless `now`)."""
        if not self.enabled:
            return
        t = time.monotonic()
        with self._lock:
            if not now and t - self._last < INTERVAL:
                return
            self._last = t
            width = self._width()
            line = text if len(text) < width else text[: max(1, width - 2)] + "…"
            self._write(_CLEAR + line)
            self._shown = line

    def _width(self) -> int:
        """The columns of the terminal the line is drawn on: stderr's own size (stdout may be a
        pipe, and COLUMNS may be stale), else COLUMNS, else 80."""
        try:
            columns = os.get_terminal_size(self.stream.fileno()).columns
        except (AttributeError, ValueError, OSError, io.UnsupportedOperation):
            columns = 0
        if columns > 0:
            return columns
        env = os.environ.get("COLUMNS", "")
        return int(env) if env.isdigit() and int(env) > 0 else 80

    def print(self, line: str) -> None:
        """Write a line of the command's own above the status line (which comes back after)."""
        with self._lock:
            if self.enabled and self._shown:
                self._write(_CLEAR + line.rstrip("\n") + "\n" + self._shown)
            else:
                self._write(line if line.endswith("\n") else line + "\n")

    def clear(self) -> None:
        """Take the status line away (before the command's output or its end)."""
        with self._lock:
            if self.enabled and self._shown:
                self._write(_CLEAR)
            self._shown = ""

    def _write(self, text: str) -> None:
        try:
            self.stream.write(text)
            self.stream.flush()
        except (OSError, ValueError) as e:  # the terminal or the log went away: the work goes on
            self.enabled = False
            self.log_after = None
            if isinstance(e, BrokenPipeError):
                abandon(self.stream)

    @contextmanager
    def ticking(self, text: Callable[[float], str], every: float = 0.5) -> Iterator[Status]:
        """While the block runs, show `text(seconds since it started)` every `every` seconds
        from a thread of its own (the block may be one blocking call, as a compile is); the line
        is cleared when the block ends, however it ends."""
        if not self.enabled:
            yield self
            return
        start = time.monotonic()
        done = threading.Event()

        def tick() -> None:
            while True:
                line = text(time.monotonic() - start)
                if line:
                    self.show(line, now=True)
                if done.wait(every):
                    return

        thread = threading.Thread(target=tick, name="llfsm-status", daemon=True)
        thread.start()
        try:
            yield self
        finally:
            done.set()
            thread.join()
            self.clear()

    @contextmanager
    def doing(self, prefix: str) -> Iterator[Callable[[str], None]]:
        """While the block runs, `prefix: <what it is doing>... <seconds>`, where the block
        says what it is doing by calling the function it is given (nothing shows before it
        first does: work that turns out quick, a cache hit, draws nothing)."""
        what = [""]

        def say(text: str) -> None:
            what[0] = text

        with self.ticking(lambda elapsed: f"{prefix}: {what[0]}... {seconds(elapsed)}" if what[0] else ""):
            yield say

    @contextmanager
    def waiting(self, what: str, timeout: float | None = None) -> Iterator[Status]:
        """While the block waits for `what` (a topic, a message): `waiting for WHAT... 3 s of
        5 s`, from half a second on (a wait that ends sooner draws nothing)."""
        limit = f" of {timeout:g} s" if timeout is not None else ""
        with self.ticking(lambda t: f"waiting for {what}... {seconds(t)}{limit}" if t >= 0.5 else "") as status:
            yield status


def abandon(stream: TextIO) -> None:
    """The reader of `stream` has gone (`llfsm build 2>&1 | head -1`): its file descriptor is
    pointed at /dev/null, so that later lines go nowhere and the work goes on to its end, its
    exit status still saying whether it succeeded."""
    try:
        fd = stream.fileno()
    except (AttributeError, ValueError, OSError, io.UnsupportedOperation):
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, fd)
    except (OSError, ValueError):
        pass
    finally:
        os.close(devnull)


def seconds(elapsed: float) -> str:
    """`7 s`, `2 min 05 s`: elapsed time as a status line shows it."""
    s = int(elapsed)
    return f"{s} s" if s < 60 else f"{s // 60} min {s % 60:02d} s"
