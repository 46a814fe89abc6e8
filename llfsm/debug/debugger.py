"""The debugger of one run: pause, step, continue, breakpoints, history, reading and setting
(docs/debug.md).  The terminal prompt (prompt.py), the page (llfsm.web) and the services over
the graph (services.py) all drive this one object.

**Where it pauses.**  Between two ringlets, never inside one.  With a watcher installed
(`Arrangement.watcher`: breakpoints, history, a step in progress, or the monitor's pause), at the
next ringlet boundary; otherwise at the next round boundary (`Arrangement.ask_pause`), so a run
with nothing to watch runs the scheduler's plain loops and pays nothing.  A pause is a loop on
the scheduler's thread (`_stand`) that waits for commands and keeps the bus answering the
control, parameter and debug services (`Executor.spin_control`); no ringlet runs, no timer
fires and no callback of machine code runs, so messages for machine code wait in their queues
as their QoS keeps them.  The run clock stands: the sim clock does not move, and the wall
clock leaves the paused time out of the run time (`WallClock.exclude`), so `after()` counts
only running time.  Under the sim clock a run paused, stepped and continued is the same run,
byte for byte, as one never paused (tests/test_debug_exact.py).

**Threads.**  Everything that reads or changes the run happens on the scheduler's thread.
Other threads (the prompt reading the terminal, the page's server) hand work in with `submit`,
which runs it in the pause loop, or, while the run runs, between two rounds (a between-round
hook, woken as the bus's executor is, through the run context's wake time).  `pause` alone
may be called from anywhere: it only sets flags.
"""

from __future__ import annotations

import queue
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Future
from typing import Any

from ..runtime.clock import WallClock
from ..runtime.generated import pending_of, state_of
from ..runtime.machine import Machine
from ..runtime.scheduler import GO, PAUSE, STOP, Arrangement
from .breakpoints import Breakpoint, Breakpoints
from .history import History
from .variables import SetError, assign, read

#: How often (seconds of real time) a pause looks at the bus when no command comes.
TICK = 0.01
#: What a resume asks for: run on, stop after one ringlet, stop at the end of the round.
CONTINUE, STEP, ROUND = "continue", "step", "round"


class DebugError(ValueError):
    """A command that cannot be carried out now (one line; the run goes on)."""


class Debugger:
    """Pause, step and inspect an arrangement (see the module's docstring)."""

    def __init__(
        self,
        arr: Arrangement,
        *,
        history: int | None = None,
        say: Callable[[str], None] | None = None,
    ) -> None:
        self.arr = arr
        self.say: Callable[[str], None] = say if say is not None else print
        self.breaks = Breakpoints([type(m) for m in arr.machines], self.say)
        self.history: History | None = History(arr.machines, history) if history else None
        #: The watcher the run had before (the monitor's), asked first at every boundary.
        self.inner: Callable[[Machine, int | None, int | None], int] | None = arr.watcher
        #: Paused now; the machine whose ringlet the pause follows (None: between rounds).
        self.paused = False
        #: Pauses so far (a reader of `paused` on another thread tells one pause from the next).
        self.pauses = 0
        self.at: Machine | None = None
        self.reason = ""
        #: Counted boundaries, while a watcher is installed (the history numbers its records so).
        self.boundaries = 0
        self._resume: str | None = None  # what the pause loop was asked to do when it ends
        self._stop_after: str | None = None  # STEP or ROUND while a step is under way
        self._pause_soon = False  # a pause asked for while running (from any thread)
        self._pause_reason = ""
        self.inbox: queue.SimpleQueue[Callable[[], None]] = queue.SimpleQueue()
        #: Told of every change of the debugger's state (paused or running, breakpoints): the
        #: page pushes it, the services publish it, the prompt wakes.  Called on the scheduler's thread.
        self.listeners: list[Callable[[Debugger], None]] = []
        self._notifying = self._again = False
        #: Topics published since the last boundary (a tap on the bus, when something reads them).
        self.published: list[str] = []
        self._tapped = False
        #: Serves the bus's control, parameter and debug services while paused (set by the
        #: session when the run has a bus: Executor.spin_control with services.answers).
        self.serve: Callable[[], None] | None = None
        self.bus: Any = None
        arr.on_pause = self._stand
        arr.ctx.between_rounds.append(self._drain)
        self._update_watcher()

    # -- what the session sets up -----------------------------------------------------------------
    def attach_bus(self, bus: Any, serve: Callable[[], None]) -> None:
        """The run's bus: taps for what is published (history, published() breakpoints) and the
        services to answer while paused."""
        self.bus = bus
        self.serve = serve
        self._tap()

    def _tap(self) -> None:
        if self._tapped or self.bus is None:
            return
        if self.history is None and not self.breaks.reads_published:
            return
        self._tapped = True
        published = self.published

        def tap(topic: Any) -> None:
            name = topic.name
            if not name.startswith("/llfsm/"):  # the machines' own state topics are not theirs to publish
                topic.taps.append(lambda _msg: published.append(name))

        self.bus.add_tap(tap)

    def _update_watcher(self) -> None:
        """Install the watcher while anything needs every boundary, and take it away otherwise,
        so that the scheduler runs its plain loops again.  (A monitor's watcher is always
        wrapped: its round is watched anyway, and a step must see every boundary of it.)"""
        want = bool(self.breaks.items) or self.history is not None or self._stop_after is not None
        want = want or self.inner is not None
        self.arr.watcher = self.after if want else self.inner

    # -- the watcher -------------------------------------------------------------------------------
    def after(self, m: Machine, ran: int | None, fired: int | None) -> int:
        """Arrangement.watcher: called at every ringlet boundary while installed."""
        asked = GO if self.inner is None else self.inner(m, ran, fired)
        if asked == PAUSE:
            self._pause_reason = "a monitored property was violated"
        self.boundaries += 1
        published = self.published
        if self.history is not None:
            ctx = self.arr.ctx
            self.history.record(m, ran, fired, self.boundaries, ctx.round, self.arr.clock.now, published)
        if self.breaks.items:
            events: set[Any] = set(published)
            if fired is not None:
                events.add(("fired", m._id, ran, fired))
            hit = self.breaks.hit(m._id, self.arr.machines, events)
            if hit is not None:
                asked = asked if asked == STOP else PAUSE
                self._pause_reason = f"break {hit.number}: {hit.text}"
        if published:
            published.clear()
        stop = self._stop_after
        if stop is not None and (stop == STEP or m is self.arr._live[-1]):
            asked = asked if asked == STOP else PAUSE
            self._pause_reason = self._pause_reason or ("step" if stop == STEP else "step round")
        if self._pause_soon:
            asked = asked if asked == STOP else PAUSE
        return asked

    # -- pausing -----------------------------------------------------------------------------------
    def pause(self, reason: str = "pause asked") -> None:
        """Pause at the next boundary (any thread).  Nothing happens when already paused."""
        if self.paused:
            return
        self._pause_reason = self._pause_reason or reason
        self._pause_soon = True
        self.arr.ask_pause()

    def _stand(self, m: Machine | None) -> None:
        """Arrangement.on_pause: the run stands here until a command resumes it."""
        arr = self.arr
        arr.pause_asked = False
        self._pause_soon = False
        self._stop_after = None
        self.paused, self.at = True, m
        self.pauses += 1
        self.reason, self._pause_reason = self._pause_reason or "pause asked", ""
        self._resume = None
        clock = arr.clock
        started = time.monotonic_ns()
        self._notify()
        try:
            while self._resume is None and not arr._interrupts:
                self._serve_once(TICK)
        finally:
            if isinstance(clock, WallClock):
                clock.exclude(time.monotonic_ns() - started)  # paused time is no run time
            self.paused = False
            mode, self._resume = self._resume, None
            self._stop_after = mode if mode in (STEP, ROUND) else None
            if self.breaks.items:
                self.breaks.refresh(arr.machines)  # a value set while paused starts a new edge
            self._update_watcher()
            self._notify()

    def _serve_once(self, timeout: float) -> None:
        try:
            fn = self.inbox.get(timeout=timeout)
        except queue.Empty:
            fn = None
        while fn is not None:
            fn()
            try:
                fn = self.inbox.get_nowait()
            except queue.Empty:
                fn = None
        if self.serve is not None:
            self.serve()

    def _drain(self) -> None:
        """Between rounds while running: what other threads handed in (`submit`)."""
        while True:
            try:
                fn = self.inbox.get_nowait()
            except queue.Empty:
                return
            fn()

    def submit(self, fn: Callable[[], Any]) -> Future[Any]:
        """Run fn() on the scheduler's thread (paused: in the pause loop; running: after the
        current round) and hand its result, or its exception, back through the future."""
        done: Future[Any] = Future()

        def run() -> None:
            try:
                done.set_result(fn())
            except Exception as e:  # handed back to the caller, never into the run
                done.set_exception(e)

        self.inbox.put(run)
        self.arr.ctx.wake = 0  # running: the round loop calls the between-round hooks after this round
        return done

    def _notify(self) -> None:
        """Tell the listeners; a change a listener makes is told after it, not inside it."""
        if self._notifying:
            self._again = True
            return
        self._notifying = True
        try:
            while True:
                self._again = False
                for fn in list(self.listeners):
                    try:
                        fn(self)
                    except Exception as e:  # a listener (a page gone away) never stops the run
                        self.say(f"llfsm: debugger: {type(e).__name__}: {e}")
                if not self._again:
                    return
        finally:
            self._notifying = False

    # -- commands (scheduler's thread) ----------------------------------------------------------------
    def resume(self, mode: str = CONTINUE) -> str:
        """Continue, step one ringlet or step to the end of the round (paused only)."""
        if mode not in (CONTINUE, STEP, ROUND):
            raise DebugError(f"unknown resume {mode!r}: continue, step or round")
        if not self.paused:
            raise DebugError("the run is not paused")
        self._resume = mode
        return {CONTINUE: "continuing", STEP: "stepping one ringlet", ROUND: "stepping to the end of the round"}[mode]

    def machine(self, name: str) -> Machine:
        m = self.arr.by_name.get(name)
        if m is None:
            raise DebugError(f"no machine named {name} in this run (machines: {', '.join(self.arr.by_name)})")
        return m

    def read(self, name: str | None = None) -> dict[str, Any]:
        """Each machine (or the one named) as it is now: state, pending command, time in state,
        variables, inputs."""
        now = self.arr.clock.now
        entered = self.history.entered if self.history is not None else None
        ms = [self.machine(name)] if name is not None else self.arr.machines
        return {m.NAME: read(m, now, entered[m._id] if entered is not None else None) for m in ms}

    def set_value(self, name: str, variable: str, text: str) -> str:
        """Set machine `name`'s variable or input (paused only): the line to show."""
        if not self.paused:
            raise DebugError("pause the run first: values are set between ringlets")
        m = self.machine(name)
        try:
            value = assign(m, variable, text)
        except SetError as e:
            raise DebugError(str(e)) from None
        if self.history is not None:
            self.history.record_set(m, self.boundaries, self.arr.ctx.round, self.arr.clock.now)
        self._notify()
        return f"{m.NAME}.{variable} = {value!r}"

    def add_break(self, text: str, where: str = "break") -> Breakpoint:
        try:
            bp = self.breaks.add(text, self.arr.machines, where)
        except ValueError as e:
            raise DebugError(str(e)) from None
        self._tap()
        self._update_watcher()
        self._notify()
        return bp

    def remove_break(self, number: int | None = None, text: str | None = None) -> list[Breakpoint]:
        gone = self.breaks.remove(number, text)
        if (number is not None or text is not None) and not gone:
            raise DebugError(f"no breakpoint {number if number is not None else text!r}")
        self._update_watcher()
        self._notify()
        return gone

    # -- what the run looks like ----------------------------------------------------------------------
    def where(self) -> str:
        """Where the run stands, in one line."""
        arr = self.arr
        t = f"{arr.clock.now / 1e9:.3f} s"
        if not self.paused:
            return f"running (round {arr.ctx.round}, {t})"
        m = self.at
        if m is None:
            place = f"before round {arr.rounds}" if arr.rounds else "before the first round"
        else:
            place = f"round {arr.ctx.round}, after {m.NAME}'s ringlet"
        return f"paused {place} ({t}): {self.reason}"

    def states(self) -> list[str]:
        """Every machine's state, one line each (`w`)."""
        out = []
        for m in self.arr.machines:
            status = " (finished)" if m._finished else " (suspended)" if m._suspended else ""
            command = pending_of(m)
            pending = f", {command} pending" if command else ""
            mark = "> " if m is self.at else "  "
            out.append(f"{mark}{m.NAME}: {state_of(m)}{status}{pending}")
        return out

    def status(self) -> dict[str, Any]:
        """What the page and the status topic show."""
        return {
            "paused": self.paused,
            "where": self.where(),
            "reason": self.reason if self.paused else "",
            "machine": self.at.NAME if self.paused and self.at is not None else None,
            "round": self.arr.ctx.round,
            "t": round(self.arr.clock.now / 1e9, 9),
            "breaks": [b.text for b in self.breaks.items],
            "history": self.history.size if self.history is not None else 0,
        }

    def machines(self) -> Sequence[Machine]:
        return self.arr.machines
