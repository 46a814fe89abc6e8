"""Node loggers, as `rclpy.logging` and rcutils print them: `node.get_logger().info(...)`.

The stamp is run time under the sim clock (logs are reproducible too) and the stream is the
bus's (stderr, or stdout with RCUTILS_LOGGING_USE_STDOUT=1).  See docs/bus.md (Logging).
"""

from __future__ import annotations

from enum import IntEnum
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .bus import Bus


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

    def __init__(self, bus: Bus, name: str) -> None:
        self._bus = bus
        self.name = name
        self.level = LoggingSeverity.INFO
        self._once: set[tuple[str, str]] = set()
        self._last: dict[tuple[str, str], int] = {}

    def get_name(self) -> str:
        return self.name

    def set_level(self, level: LoggingSeverity | int) -> None:
        self.level = LoggingSeverity(level)

    def get_child(self, name: str) -> Logger:
        child = Logger(self._bus, f"{self.name}.{name}")
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
