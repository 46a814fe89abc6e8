"""The run clock as rclpy shows it (`rclpy.clock`, `rclpy.time`): `node.get_clock().now()`.

Run time in integer nanoseconds (llfsm.runtime.clock), virtual under `--clock sim`.  See
docs/bus.md (Timers).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .executor import Executor


@dataclass(frozen=True)
class Time:
    nanoseconds: int

    def seconds_nanoseconds(self) -> tuple[int, int]:
        return divmod(self.nanoseconds, 1_000_000_000)


class RunClock:
    """`node.get_clock()`: the run clock (virtual under --clock sim)."""

    def __init__(self, bus: Executor) -> None:
        self._bus = bus

    def now(self) -> Time:
        return Time(self._bus.clock.now)
