"""Node loggers, as `rclpy.logging` and rcutils print them: `node.get_logger().info(...)`.

The stamp is run time under the sim clock (logs are reproducible too) and the stream is the
bus's (stderr, or stdout with RCUTILS_LOGGING_USE_STDOUT=1).  Each line is also published on
/rosout as an rcl_interfaces/msg/Log by the node's rosout publisher, as rcl's rosout output
handler does, so `ros2 topic echo /rosout` (and a bag of /rosout) shows machine logs; the
message names the user's file and line where the call was made (a machine's section, not the
generated module).  See docs/bus.md (Logging).
"""

from __future__ import annotations

import os
import sys
import time
from enum import IntEnum
from typing import IO, TYPE_CHECKING, Any

from ..msgs.builtin_interfaces.msg import Time
from ..msgs.rcl_interfaces.msg import Log
from ..runtime.generated import FUNCTION_PREFIX, map_line, source_map_of

if TYPE_CHECKING:
    from collections.abc import Callable
    from types import FrameType

    from .bus import Bus
    from .publisher import Publisher


class LoggingSeverity(IntEnum):
    UNSET = 0
    DEBUG = 10
    INFO = 20
    WARN = 30
    ERROR = 40
    FATAL = 50


#: `--log-level` spellings, as rcutils reads them (any case).
LEVELS = {"debug": 10, "info": 20, "warn": 30, "warning": 30, "error": 40, "fatal": 50, "unset": 0}


def parse_log_level(text: str) -> tuple[str, LoggingSeverity]:
    """`--log-level [NAME:=]LEVEL` as ros2's `--ros-args --log-level` takes it: ("", level) for
    every logger, (NAME, level) for one; ValueError with the line to print for a bad one."""
    name, sep, level = text.rpartition(":=")
    if sep and not name:
        raise ValueError(f"--log-level {text}: give a logger name before ':='")
    value = LEVELS.get(level.strip().lower())
    if value is None:
        raise ValueError(f"--log-level {text}: {level!r} is not a level (debug, info, warn, error, fatal, unset)")
    return name.strip(), LoggingSeverity(value)


def level_for(name: str, levels: dict[str, LoggingSeverity]) -> LoggingSeverity:
    """The level of logger `name`: its own `--log-level NAME:=`, else its nearest parent's
    (`robot.talker` takes `robot`'s, as rcutils' loggers do), else the default, else INFO."""
    while True:
        level = levels.get(name)
        if level is not None and level is not LoggingSeverity.UNSET:
            return level
        if not name:
            return LoggingSeverity.INFO
        name = name.rpartition(".")[0]


def log_directory(environ: Any = os.environ) -> str:
    """Where ROS 2 keeps its log files: ROS_LOG_DIR, else ROS_HOME/log, else ~/.ros/log."""
    if environ.get("ROS_LOG_DIR"):
        return os.path.expanduser(environ["ROS_LOG_DIR"])
    if environ.get("ROS_HOME"):
        return os.path.join(os.path.expanduser(environ["ROS_HOME"]), "log")
    return os.path.join(os.path.expanduser("~"), ".ros", "log")


def open_log_file(executable: str = "llfsm") -> tuple[str, IO[str]]:
    """A log file of this process as rcl's logging opens one: `<dir>/<executable>_<pid>_<ms
    since the epoch>.log`.  OSError when it cannot be made."""
    folder = log_directory()
    os.makedirs(folder, exist_ok=True)
    path = os.path.join(folder, f"{executable}_{os.getpid()}_{time.time_ns() // 1_000_000}.log")
    return path, open(path, "a", encoding="utf-8", buffering=1)  # closed at the run's end


class LogSettings:
    """`--log-level` and `--log-file` of a run, read before it starts (ValueError for a bad
    level) and given to its bus when the bus is initialised, before any node logs."""

    def __init__(self, levels: tuple[str, ...], to_file: bool) -> None:
        self.levels = dict(parse_log_level(text) for text in levels)
        self.to_file = to_file

    def apply(self, bus: Bus, say: Callable[[str], None], verbose: bool) -> None:
        bus.log_levels = self.levels
        if not self.to_file:
            return
        try:
            path, bus.log_file = open_log_file()
        except OSError as e:  # the run goes on: a log file is a convenience
            say(f"llfsm: warning: --log-file: cannot write in {log_directory()}: {e.strerror or e}")
            return
        bus.ctx.at_end.append(bus.log_file.close)
        if verbose:
            say(f"llfsm: log file {path}")


class Logger:
    """rclpy's logger: `[INFO] [seconds.nanoseconds] [name]: message`, on stderr as ROS 2 Humble
    does (RCUTILS_LOGGING_USE_STDOUT=1 sends it to stdout).  Under the sim clock the stamp is run
    time, so logs are reproducible too."""

    def __init__(self, bus: Bus, name: str, rosout: Publisher | None = None) -> None:
        self._bus = bus
        self.name = name
        self.level = level_for(name, bus.log_levels) if bus.log_levels else LoggingSeverity.INFO
        self._once: set[tuple[str, str]] = set()
        self._last: dict[tuple[str, str], int] = {}
        self._rosout = rosout  # the node's /rosout publisher (None: enable_rosout=False)

    def get_name(self) -> str:
        return self.name

    def set_level(self, level: LoggingSeverity | int) -> None:
        self.level = LoggingSeverity(level)

    def get_child(self, name: str) -> Logger:
        child = Logger(self._bus, f"{self.name}.{name}", self._rosout)  # rosout of the node, as since Iron
        child.level = self.level
        return child

    def log(
        self,
        message: object,
        severity: LoggingSeverity,
        *,
        once: bool = False,
        throttle_duration_sec: float | None = None,
        skip_first: bool = False,
    ) -> bool:
        if severity < self.level:
            return False
        text = str(message)
        key = (severity.name, text)
        if once:
            if key in self._once:
                return False
            self._once.add(key)
        if skip_first and key not in self._last:
            self._last[key] = self._bus.clock.now
            return False
        if throttle_duration_sec is not None:
            last = self._last.get(key)
            if last is not None and self._bus.clock.now - last < throttle_duration_sec * 1e9:
                return False
            self._last[key] = self._bus.clock.now
        sec, nsec = self._bus.stamp()
        stream = self._bus.log_output()
        stream.write(f"[{severity.name}] [{sec}.{nsec:09d}] [{self.name}]: {text}\n")
        stream.flush()
        if self._bus.log_file is not None:  # as rcl's file: the stamp first
            self._bus.log_file.write(f"{sec}.{nsec:09d} [{severity.name}] [{self.name}]: {text}\n")
        rosout = self._rosout
        if rosout is not None and not rosout._destroyed:
            file, function, line = _caller(sys._getframe(1))
            rosout.publish(
                Log(
                    stamp=Time(sec=sec, nanosec=nsec),
                    level=int(severity),
                    name=self.name,
                    msg=text,
                    file=file,
                    function=function,
                    line=line,
                )
            )
        return True

    def debug(self, message: object, **kw: Any) -> bool:
        return self.log(message, LoggingSeverity.DEBUG, **kw)

    def info(self, message: object, **kw: Any) -> bool:
        return self.log(message, LoggingSeverity.INFO, **kw)

    def warning(self, message: object, **kw: Any) -> bool:
        return self.log(message, LoggingSeverity.WARN, **kw)

    warn = warning

    def error(self, message: object, **kw: Any) -> bool:
        return self.log(message, LoggingSeverity.ERROR, **kw)

    def fatal(self, message: object, **kw: Any) -> bool:
        return self.log(message, LoggingSeverity.FATAL, **kw)


def _caller(frame: FrameType | None) -> tuple[str, str, int]:
    """(file, function, line) of the code that logged, as rcutils names them: the first frame
    outside this module (info() calls log()); in a machine's generated module, the user's file
    and line by the module's source map, so a log names State_MOVE_OnEntry.py:3."""
    while frame is not None and frame.f_code.co_filename == __file__:
        frame = frame.f_back
    if frame is None:
        return "", "", 0
    code = frame.f_code
    source_map = source_map_of(frame.f_globals)
    if source_map:
        mapped = map_line(code.co_filename, frame.f_lineno, source_map)
        if mapped is not None:
            # a ringlet's own function (_llfsm_enter_S) means nothing to the user: the section does
            function = code.co_name
            if function.startswith(FUNCTION_PREFIX) and mapped[0].startswith("State_"):
                function = mapped[0].removeprefix("State_").rsplit(".", 1)[0]
            return mapped[0], function, mapped[1]
    return code.co_filename, code.co_name, frame.f_lineno
