"""The run context: what one run of an arrangement shares with the bus and the nodes.

The bus (`llfsm.ros`) keeps its graph here rather than in module globals, so that every run
(and every test) starts from a clean slate, and reads the run clock and the interrupt state
from here so that `ros.ok()` turns false on Ctrl-C exactly as rclpy's does.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from .clock import Clock, WallClock


class RunContext:
    def __init__(self, clock: Clock | None = None) -> None:
        self.clock: Clock = clock if clock is not None else WallClock()
        #: Set on the first SIGINT/SIGTERM: `ros.ok()` is false from then on.
        self.interrupted = False
        #: Called after every round, in order: the bus executor dispatches callbacks and timers.
        self.between_rounds: list[Callable[[], None]] = []
        #: Called once when the run ends (nodes write their pictures, close windows).
        self.at_end: list[Callable[[], None]] = []
        #: Free slots for the bus and nodes (`bus`, `remaps`, ...).
        self.extras: dict[str, Any] = {}
        self.round = 0
        #: Run time at which the run will end (--duration), if any: blocking waits inside
        #: machine code (spin calls) never wait past it.
        self.deadline: int | None = None


_current: RunContext | None = None


def current() -> RunContext:
    """The active run's context; outside a run, a wall-clock context made on first use."""
    global _current
    if _current is None:
        _current = RunContext()
    return _current


def activate(ctx: RunContext | None) -> RunContext | None:
    """Make `ctx` the active context; returns the previous one so callers can restore it."""
    global _current
    prev, _current = _current, ctx
    return prev
