"""Run clocks.  Time is integer nanoseconds since the start of the run, so that timer
comparisons are exact and a simulated run is reproducible byte for byte.

The bottom of the runtime: it imports nothing of it (docs/architecture.md, "runtime/").
"""

from __future__ import annotations

import time

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from collections.abc import Callable


def parse_duration(text: str) -> int:
    """`0.5`, `500ms`, `2s`, `250us`, `1min` -> nanoseconds.  Bare numbers are seconds."""
    t = text.strip().lower()
    units = (("ns", 1), ("us", 1_000), ("µs", 1_000), ("ms", 1_000_000), ("min", 60_000_000_000), ("s", 1_000_000_000))
    scale = 1_000_000_000
    for suffix, mult in units:
        if t.endswith(suffix):
            t, scale = t[: -len(suffix)].strip(), mult
            break
    try:
        value = float(t)
    except ValueError:
        raise ValueError(f"not a duration: {text!r} (use seconds such as 0.5, or 500ms, 2s)") from None
    if not value >= 0 or value == float("inf"):
        raise ValueError(f"not a duration: {text!r} (must be a finite value >= 0)")
    return round(value * scale)


class Clock:
    """`now` is read by machines (after_ms) and the bus; the scheduler moves it between rounds."""

    kind = "abstract"
    now: int = 0
    #: Called when a wait moves the time on (`sleep_until`, inside a spin call): the sim clock's
    #: run context raises the scheduler's attention; the debugger's history notes the time.
    on_jump: Callable[[], None] | None = None

    def start(self) -> None:
        """The rounds begin (Arrangement.run): a clock of real time counts from here."""

    def advance(self, fired: bool) -> None:
        raise NotImplementedError

    def sleep_until(self, t: int) -> None:
        """Block until run time t (the bus waits this way inside spin calls)."""
        raise NotImplementedError


class SimClock(Clock):
    """Virtual time from 0, advanced by `period` after each round, never sleeping."""

    kind = "sim"

    def __init__(self, period_ns: int = 1_000_000) -> None:
        if period_ns <= 0:
            raise ValueError("the sim clock needs a period > 0")
        self.now = 0
        self.period = period_ns
        #: Called when a wait moves the time forward (`sleep_until`): the run context using this
        #: clock sets it, to raise the scheduler's attention (the scheduler keeps the time in a
        #: local during rounds).
        self.on_jump: Callable[[], None] | None = None

    def advance(self, fired: bool) -> None:
        self.now += self.period

    def sleep_until(self, t: int) -> None:
        if t > self.now:
            self.now = t
            if self.on_jump is not None:
                self.on_jump()


class WallClock(Clock):
    """Real time.  Rounds run back to back, sleeping `idle` after a round in which no transition
    fired (applying a control command is not a transition);
    with a `period`, a round starts every period instead (time-triggered)."""

    kind = "wall"

    def __init__(self, idle_ns: int = 10_000_000, period_ns: int | None = None) -> None:
        self._start = time.monotonic_ns()
        self.now = 0
        self.idle = idle_ns
        self.period = period_ns
        self._next = period_ns or 0
        #: Waits out the idle sleep instead of time.sleep; a transport that receives from other
        #: processes sets it so that arriving data ends the sleep early (the DDS transport).
        self.waiter: Callable[[int], None] | None = None

    def read(self) -> int:
        return time.monotonic_ns() - self._start

    def start(self) -> None:
        """Run time goes on from `now` when the rounds begin: the start-up before them (the
        transport, the nodes, the page: seconds on a loaded machine) is not run time.  Counted
        from the clock's making, it was: the first ringlet saw 0 and its first wait jumped by the
        whole start-up (`wait_for_service(timeout_sec=8.0)` in INITIAL said False at once after
        a start-up of 20 s), and `--duration` ended a run that had barely begun."""
        self._start = time.monotonic_ns() - self.now

    def exclude(self, ns: int) -> None:
        """Leave `ns` of real time out of the run time (a pause of the debugger: `after()`
        counts only the time the run ran), as if the run had started that much later."""
        self._start += ns
        if self.period:
            self._next += ns

    def advance(self, fired: bool) -> None:
        if self.period:
            now = self.read()
            if now < self._next:
                time.sleep((self._next - now) / 1e9)
            self._next += self.period
            # a round that overran does not make the next ones run back to back forever
            if self._next < self.read():
                self._next = self.read() + self.period
        elif not fired and self.idle:
            if self.waiter is not None:
                self.waiter(self.idle)
            else:
                time.sleep(self.idle / 1e9)
        self.now = self.read()

    def sleep_until(self, t: int) -> None:
        now = self.read()
        if t > now:
            time.sleep((t - now) / 1e9)
        self.now = self.read()
        if self.on_jump is not None:
            self.on_jump()
