"""Where a launch's lines go: the screen, and a log folder of its own, as `ros2 launch` keeps them.

The folder is `<log dir>/<date-time>-<host>-<pid>`, the log dir being ROS_LOG_DIR, else
ROS_HOME/log, else ~/.ros/log (launch.logging's rule); `latest` beside it points at the newest.
It holds `launch.log` (the launcher's own messages and, for `output="log"`, every line of the
processes, each with its time) and, for `output="own_log"` or `"full"`, each process's
`NAME-N-stdout.log`, `NAME-N-stderr.log` and `NAME-N.log`.

Where a process's lines go, by its `output` (launch.logging.get_output_loggers' aliases):
`screen` both streams to the screen; `log` (launch's default) both to launch.log and stderr also
to the screen; `both` both to both; `own_log` to its own files only; `full` everywhere.  On the
screen, a process's stdout goes to the launcher's stdout and its stderr to the launcher's stderr,
each line `[NAME-N] text`, written whole (one write per line), so lines never mix.
"""

from __future__ import annotations

import datetime
import os
import socket
import time
from collections.abc import Mapping

from .plan import ProcessSpec

STDOUT, STDERR = 1, 2


def log_base(environ: Mapping[str, str]) -> str:
    """launch.logging's logging directory: ROS_LOG_DIR, else ROS_HOME/log, else ~/.ros/log."""
    base = environ.get("ROS_LOG_DIR") or os.path.join(environ.get("ROS_HOME") or os.path.join("~", ".ros"), "log")
    return os.path.normpath(os.path.expanduser(base))


class _Sink:
    """A file descriptor lines are written to, whole; one that fails (a closed pipe, a full
    disk) is given up, once, and the launch goes on."""

    def __init__(self, fd: int, stamped: bool = False) -> None:
        self.fd: int | None = fd
        self.stamped = stamped

    def write(self, data: bytes) -> None:
        if self.fd is None:
            return
        if self.stamped:
            data = f"{time.time():.7f} ".encode() + data
        try:
            view = memoryview(data)
            while view:
                view = view[os.write(self.fd, view) :]
        except OSError:
            self.fd = None


class LaunchLog:
    """The screen and the launch's log folder (None when it could not be made: said once)."""

    def __init__(self, environ: Mapping[str, str], *, screen_out: int = STDOUT, screen_err: int = STDERR) -> None:
        self.out = _Sink(screen_out)
        self.err = _Sink(screen_err)
        self.files: list[int] = []
        self.folder: str | None = None
        self.launch_file: _Sink | None = None
        problem = None
        base = log_base(environ)
        try:
            self.folder = _unique_folder(base)
            fd = self._open("launch.log")
            self.launch_file = _Sink(fd, stamped=True)
            _renew_latest(self.folder)
        except OSError as e:
            problem = f"cannot write a log folder under {base}: {e.strerror or e}; output meant for it is shown instead"
            self.folder = None
        if self.folder is not None:
            self.message("INFO", "launch", f"All log files can be found below {self.folder}")
        else:
            self.message("WARNING", "launch", str(problem))
        self.message("INFO", "launch", "Default logging verbosity is set to INFO")

    def _open(self, name: str) -> int:
        assert self.folder is not None
        fd = os.open(os.path.join(self.folder, name), os.O_WRONLY | os.O_CREAT | os.O_APPEND | os.O_CLOEXEC, 0o644)
        self.files.append(fd)
        return fd

    def message(self, level: str, who: str, text: str) -> None:
        """A line of the launcher's own, as launch prints it: `[LEVEL] [who]: text`."""
        data = f"[{level}] [{who}]: {text}\n".encode()
        self.err.write(data)
        if self.launch_file is not None:
            self.launch_file.write(data)

    def routes(self, spec: ProcessSpec) -> tuple[list[_Sink], list[_Sink]]:
        """Where the process's stdout lines and stderr lines go."""
        mode = spec.output
        out: list[_Sink] = []
        err: list[_Sink] = []
        if mode in ("screen", "both", "full") or (self.folder is None and mode != "screen"):
            out.append(self.out)
            err.append(self.err)
        elif mode == "log":
            err.append(self.err)
        if self.launch_file is not None and mode in ("log", "both", "full"):
            out.append(self.launch_file)
            err.append(self.launch_file)
        if self.folder is not None and mode in ("own_log", "full"):
            name = spec.label.replace(os.sep, "_")  # a label is a file name here, never a path
            try:
                both = _Sink(self._open(f"{name}.log"))
                out += [_Sink(self._open(f"{name}-stdout.log")), both]
                err += [_Sink(self._open(f"{name}-stderr.log")), both]
            except OSError as e:
                self.message("WARNING", spec.label, f"cannot write its log files: {e.strerror or e}")
        return out, err

    def close(self) -> None:
        for fd in self.files:
            try:
                os.close(fd)
            except OSError:
                pass
        self.files.clear()


def _unique_folder(base: str) -> str:
    """`<base>/<date-time>-<host>-<pid>`, made (launch's _make_unique_log_dir)."""
    os.makedirs(base, exist_ok=True)
    while True:
        stamp = datetime.datetime.now().strftime("%Y-%m-%d-%H-%M-%S-%f")
        folder = os.path.join(base, f"{stamp}-{socket.gethostname()}-{os.getpid()}")
        try:
            os.mkdir(folder)
            return folder
        except FileExistsError:
            continue


def _renew_latest(folder: str) -> None:
    """`latest` beside the folder points at it, unless `latest` is something other than a link."""
    latest = os.path.join(os.path.dirname(folder), "latest")
    try:
        if os.path.lexists(latest):
            if not os.path.islink(latest):
                return
            os.unlink(latest)
        os.symlink(folder, latest, target_is_directory=True)
    except OSError:
        pass  # another launch renewed it at the same moment: theirs is as good
