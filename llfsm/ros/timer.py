"""Timers, as `rclpy.timer`: `node.create_timer(period_s, callback)`, on the run clock.

The executor (executor.py) keeps them in one heap and fires them in due order, before queued
work, so a run under the sim clock is reproducible.  See docs/bus.md (Timers).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .executor import Executor


class Timer:
    """Calls back every period of run time; the first call is one period after creation."""

    __slots__ = ("_bus", "_cancelled", "_due", "callback", "period_ns")

    def __init__(self, bus: Executor, period_sec: float, callback: Callable[[], Any]) -> None:
        if isinstance(period_sec, bool) or not isinstance(period_sec, int | float) or not period_sec > 0:
            raise ValueError(f"create_timer(): the period must be a number of seconds > 0, not {period_sec!r}")
        self._bus = bus
        self.period_ns = max(1, round(period_sec * 1e9))
        self.callback = callback
        self._cancelled = False
        self._due = bus.clock.now + self.period_ns
        bus.add_timer(self, self._due)

    def _call(self) -> None:
        self.callback()

    @property
    def timer_period_ns(self) -> int:
        return self.period_ns

    def cancel(self) -> None:
        self._cancelled = True

    def is_canceled(self) -> bool:
        return self._cancelled

    def reset(self) -> None:
        self._cancelled = False
        self._due = self._bus.clock.now + self.period_ns
        self._bus.add_timer(self, self._due)

    def time_until_next_call(self) -> int:
        return max(0, self._due - self._bus.clock.now)

    def destroy(self) -> None:
        self.cancel()
