"""Node loggers, as `rclpy.logging` and rcutils print them: `node.get_logger().info(...)`.

The stamp is run time under the sim clock (logs are reproducible too) and the stream is the
bus's (stderr, or stdout with RCUTILS_LOGGING_USE_STDOUT=1).  Each line is also published on
/rosout as an rcl_interfaces/msg/Log by the node's rosout publisher, as rcl's rosout output
handler does, so `ros2 topic echo /rosout` (and a bag of /rosout) shows machine logs; the
message names the user's file and line where the call was made (a machine's section, not the
generated module).  See docs/bus.md (Logging).
"""

from __future__ import annotations

import sys
from enum import IntEnum
from typing import TYPE_CHECKING, Any

from ..msgs.builtin_interfaces.msg import Time
from ..msgs.rcl_interfaces.msg import Log
from ..runtime.generated import FUNCTION_PREFIX, map_line, source_map_of

if TYPE_CHECKING:
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


class Logger:
    """rclpy's logger: `[INFO] [seconds.nanoseconds] [name]: message`, on stderr as ROS 2 Humble
    does (RCUTILS_LOGGING_USE_STDOUT=1 sends it to stdout).  Under the sim clock the stamp is run
    time, so logs are reproducible too."""

    def __init__(self, bus: Bus, name: str, rosout: Publisher | None = None) -> None:
        self._bus = bus
        self.name = name
        self.level = LoggingSeverity.INFO
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
