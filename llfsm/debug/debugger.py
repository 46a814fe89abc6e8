"""The debugger of one run: pause, step, continue, breakpoints, history, reading and setting
(docs/debug.md).  The terminal prompt (prompt.py), the page (llfsm.web) and the services over
the graph (services.py) all drive this one object.

**Where it pauses.**  Between two ringlets, never inside one: after a ringlet of a watched round
(`Arrangement.watcher`: breakpoints, a step in progress, the history where the ringlets cannot
record themselves: history.py), at the end of a ringlet that
took a marked transition (a breakpoint on a state: traps.py), before a held machine's turn
(`Arrangement.on_release`: a step inside a plain round, a command reaching a breakpoint's
state), where the monitor reached a violation (`--on-violation pause`), or between rounds
(`Arrangement.ask_pause`); a run with nothing to watch runs the scheduler's plain loops and pays
nothing.  A pause is a loop on
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
import sys
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Future
from typing import Any

from ..runtime.clock import WallClock
from ..runtime.generated import pending_of, state_of
from ..runtime.machine import RESTART, RESUME, Machine
from ..runtime.reads import ClassReads, class_reads
from ..runtime.scheduler import GO, PAUSE, STOP, Arrangement
from .breakpoints import Breakpoint, Breakpoints
from .history import History, recorder
from .traps import Traps, true_states
from .variables import SetError, assign, read

#: How often (seconds of real time) a pause looks at the bus when no command comes.
TICK = 0.01
#: What a resume asks for: run on, stop after one ringlet, stop at the end of the round.
CONTINUE, STEP, ROUND = "continue", "step", "round"
#: Where a pause stands: after a ringlet in a watched round, between rounds, at a marked
#: transition (the end of a ringlet in a plain round), as a command took effect (a turn has
#: begun, its ringlet is next), before a turn (after the previous machine's ringlet).
RINGLET, ROUND_END, TRAP, TURN, GATE = "ringlet", "round", "trap", "turn", "gate"


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
        #: The watcher that was there when the debugger set its own (the monitor's), asked first
        #: at every boundary, and put back when the debugger needs none; the same for on_release.
        self.inner: Callable[[Machine], int] | None = None
        self._inner_release: Callable[[Machine], None] | None = None
        #: bound once, so that they can be compared with `is`: what the debugger puts into the
        #: arrangement's watcher and on_release
        self._after, self._recorder, self._on_release = self.after, self._record, self._released
        self._watchers = (self._after, self._recorder)
        #: Paused now; the machine whose ringlet the pause follows (None: between rounds).
        self.paused = False
        #: Pauses so far (a reader of `paused` on another thread tells one pause from the next).
        self.pauses = 0
        self.at: Machine | None = None
        self.reason = ""
        #: Counted boundaries, while a watcher is installed.
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
        self._tapped = self._history_tapped = False
        #: Serves the bus's control, parameter and debug services while paused (set by the
        #: session when the run has a bus: Executor.spin_control with services.answers).
        self.serve: Callable[[], None] | None = None
        self.bus: Any = None
        #: Breakpoints on states, marked on the machines' transitions (traps.py): no watcher.
        self.traps = Traps(self._trapped)
        if self.history is not None:
            reads = [class_reads(type(m)) if _own_class(m) else None for m in arr.machines]
            if all(r is not None for r in reads):
                self._compile_history(self.history, reads)  # type: ignore[arg-type]  # none is None
        self._trapped_breaks: dict[int, tuple[int, frozenset[int]]] = {}  # breakpoint -> (machine, states)
        #: A pause before this machine's next turn (a step where the round is not watched),
        #: which follows the ringlet of `_gate_after`.
        self._gate_for: Machine | None = None
        self._gate_after: Machine | None = None
        self._origin = ROUND_END  # where the current pause stands: RINGLET, ROUND_END, TRAP, TURN, GATE
        #: A pause inside a ringlet of a watched round: the watcher is still to be told of that
        #: same boundary once the ringlet returns (no step may end there).
        self._same_boundary = False
        self._marked_for: tuple[str, ...] | None = None  # the breakpoints the marks were made for
        arr.on_pause = self._on_pause
        arr.ctx.between_rounds.append(self._drain)
        self._update_watcher()

    def _compile_history(self, h: History, reads: list[ClassReads]) -> None:
        """The history recorded by the machines' own ringlets (recording.py), compiled with the
        marks (traps.py) from each machine's module (`reads`: what each ringlet can change): no
        watcher for it.  Otherwise (a native build, a machine the monitor compiled its checks
        into) the watcher records."""
        self.traps.recorder = lambda m: recorder(h, m, reads[m._id])
        h.attach(self.arr)

    # -- what the session sets up -----------------------------------------------------------------
    def attach_bus(self, bus: Any, serve: Callable[[], None]) -> None:
        """The run's bus: taps for what is published (history, published() breakpoints) and the
        services to answer while paused."""
        self.bus = bus
        self.serve = serve
        self._tap()

    def _tap(self) -> None:
        if self.bus is None:
            return
        h = self.history
        if h is not None and h.compiled and not self._history_tapped:
            self._history_tapped = True
            self._add_tap(h.tap)
        if self._tapped or not (self.breaks.reads_published or (h is not None and not h.compiled)):
            return
        self._tapped = True
        self._add_tap(self.published.append)

    def _add_tap(self, told: Callable[[str], None]) -> None:
        """`told(name)` of each publish on a topic (the machines' own state topics left out)."""

        def tap(topic: Any) -> None:
            name = topic.name
            if not name.startswith("/llfsm/"):  # the machines' own state topics are not theirs to publish
                topic.taps.append(lambda _msg: told(name))

        assert self.bus is not None
        self.bus.add_tap(tap)

    def _update_watcher(self) -> None:
        """Install the watcher while anything needs every boundary (`after`; `_record` when only
        the history does), and take it away otherwise, so that the scheduler runs its plain
        loops again.  A watcher found there (the monitor's) is called first by `after`, and put
        back when the debugger needs none.  Breakpoints on states are marked on transitions
        instead (traps.py), and the scheduler's rare path tells of commands and of the turn a
        step waits for (`on_release`)."""
        texts = tuple(b.text for b in self.breaks.items)
        if texts != self._marked_for:  # marking compiles ringlets again: only when breakpoints change
            self._marked_for = texts
            self._mark_states()
        arr = self.arr
        judged = any(b.number not in self._trapped_breaks for b in self.breaks.items)
        want = judged or self._stop_after is not None
        watched = self.history is not None and not self.history.compiled
        mine = self._after if want else self._recorder if watched else None
        if not any(arr.watcher is w for w in self._watchers):
            self.inner = arr.watcher  # another's (the monitor's): called first by ours, or left as it is
        if mine is not None:
            arr.watcher = mine if self.inner is None else self._after  # only `after` calls the other's
        elif any(arr.watcher is w for w in self._watchers):
            arr.watcher, self.inner = self.inner, None
        rare = bool(self._trapped_breaks) or self._gate_for is not None
        if arr.on_release is not self._on_release:
            self._inner_release = arr.on_release
        if rare:
            arr.on_release = self._on_release
        elif arr.on_release is self._on_release:
            arr.on_release, self._inner_release = self._inner_release, None
        if mine is not None or rare:
            arr.ctx.wake = 0  # a plain loop in progress ends with its round: the next one is watched

    def _mark_states(self) -> None:
        """Which breakpoints read one machine's state alone, and the transitions that make each
        become true, marked on the machines (those whose module can be marked)."""
        classes = [self.traps.own.get(m._id, type(m)) for m in self.arr.machines]
        markable = [m._id in self.traps.own or _own_class(m) for m in self.arr.machines]
        found: dict[int, tuple[int, frozenset[int]]] = {}
        edges: dict[int, set[tuple[int, int]]] = {}
        for b in self.breaks.items:
            states = true_states(b.atom, classes)
            if states is None:
                continue
            i, holds = states
            found[b.number] = states
            for x, transitions in enumerate(classes[i].TRANSITIONS):
                if x not in holds:
                    edges.setdefault(i, set()).update((x, t) for t, _guard in transitions if t in holds)
        for m in self.arr.machines:
            # a machine another has given ringlets of its own (the monitor's checks), or one built
            # native, cannot be marked: the watcher judges its breakpoints
            if not markable[m._id] or not self.traps.mark(m, edges.get(m._id, set())):
                found = {n: s for n, s in found.items() if s[0] != m._id}
        self._trapped_breaks = found

    def _trapped(self, m: Machine, source: int, target: int) -> None:
        """A marked transition of `m` (from `source` into `target`) has just been taken: the
        breakpoints it makes true pause the run here, at the end of m's ringlet."""
        if self.arr.watcher is self._after:
            return  # the watcher judges every breakpoint at this boundary anyway
        hit = self._state_break(m, source, target)
        if hit is not None:
            self._pause_reason = hit
            self._stand(m, TRAP)

    def monitor_paused(self, verdict: Any) -> None:
        """`--on-violation pause`: the monitor (llfsm.monitor) reached a violation at a boundary:
        after a machine's ringlet (inside it, or in the scheduler's gate or watcher), before one
        (in the gate), or between rounds; the run stands there."""
        self._pause_reason = f"monitor: {verdict.judged.prop.name} violated"
        where = verdict.where
        if not self.arr.running:
            self.pause(self._pause_reason)  # the boundary before the first ringlet: at the run's start
        elif where.machine is None:
            self._stand(None, ROUND_END)
        elif where.offset:
            self._stand(where.machine, TRAP)
        else:  # before where.machine's ringlet: after the ringlet of the one before it, if any
            live = self.arr._live
            j = live.index(where.machine) if where.machine in live else 0
            self._stand(live[j - 1] if j > 0 else None, GATE)

    def _state_break(self, m: Machine, source: int, target: int) -> str | None:
        for b in self.breaks.items:
            found = self._trapped_breaks.get(b.number)
            if found is not None and found[0] == m._id and source not in found[1] and target in found[1]:
                return f"break {b.number}: {b.text}"
        return None

    def _released(self, m: Machine) -> None:
        """Arrangement.on_release: a held machine's turn begins.  A step may wait for it; a
        command about to take it into a state a breakpoint wants pauses first."""
        if self._inner_release is not None:
            self._inner_release(m)
        if m is self._gate_for:
            self._gate_for = None
            self._pause_reason = self._pause_reason or "step"
            self._stand(self._gate_after, GATE)
            return
        command = pending_of(m)
        if command not in (RESUME, RESTART) or self.arr.watcher is self._after:
            return  # nothing moves it, or the watcher judges the boundary after this turn
        if command == RESUME and not m._suspended:
            return
        target = m.INITIAL if command == RESTART or m._resume_to is None else m._resume_to
        hit = self._state_break(m, m._state, target)
        if hit is not None:
            self._pause_reason = f"{hit} (the {command} of {m.NAME} takes it to {m.STATES[target]})"
            self._stand(m, TURN)

    # -- the watcher -------------------------------------------------------------------------------
    def _record(self, m: Machine) -> int:
        """The watcher when only the history needs every boundary: `after`, without the rest."""
        arr = self.arr
        self.boundaries += 1
        published = self.published
        self.history.record(m, arr.ran, arr.fired, arr.ctx.round, arr.clock.now, published)  # type: ignore[union-attr]
        if published:
            published.clear()
        if self._same_boundary:
            self._same_boundary = False
            return GO
        return PAUSE if self._pause_soon else GO

    def after(self, m: Machine) -> int:
        """Arrangement.watcher: called at every ringlet boundary while installed."""
        ran, fired = self.arr.ran, self.arr.fired
        asked = GO if self.inner is None else self.inner(m)
        if asked == PAUSE:
            self._pause_reason = "a monitored property was violated"
        self.boundaries += 1
        published = self.published
        h = self.history
        if h is not None and not h.compiled:
            h.record(m, ran, fired, self.arr.ctx.round, self.arr.clock.now, published)
        if self.breaks.items:
            events: Any = ()
            if self.breaks.reads_published:
                events = set(published)
                if fired is not None:
                    events.add(("fired", m._id, ran, fired))
            hit = self.breaks.hit(m._id, self.arr.machines, events)
            if hit is not None:
                asked = asked if asked == STOP else PAUSE
                self._pause_reason = f"break {hit.number}: {hit.text}"
        if published:
            published.clear()
        if self._same_boundary:  # the boundary the run paused at, from inside its ringlet
            self._same_boundary = False
            return asked
        stop = self._stop_after
        if stop == STEP:
            asked = asked if asked == STOP else PAUSE
            self._pause_reason = self._pause_reason or "step"
        elif stop == ROUND and m is self.arr._live[-1]:
            self._round_end("step round")
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

    def _round_end(self, reason: str) -> None:
        """Pause between this round and the next (after the bus's work between them)."""
        self._stop_after = None
        self._pause_reason = self._pause_reason or reason
        self.arr.ask_pause()

    def _on_pause(self, m: Machine | None) -> None:
        """Arrangement.on_pause: after m's ringlet in a watched round, or between rounds (None)."""
        self._stand(m, RINGLET if m is not None else ROUND_END)

    def _stand(self, m: Machine | None, origin: str) -> None:
        """The run stands here until a command resumes it.  `origin`: where (RINGLET, ROUND_END,
        TRAP, TURN, GATE)."""
        arr = self.arr
        arr.pause_asked = False
        self._pause_soon = False
        self._stop_after = None
        self._gate_for = None
        self._origin = origin
        self._same_boundary = origin == TRAP and arr.watcher is not None
        self.paused, self.at = True, m
        self.pauses += 1
        self.reason, self._pause_reason = self._pause_reason or "pause asked", ""
        self._resume = None
        if self.history is not None and self.history.compiled:
            self.history.refresh()  # the values the page shows while paused
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
            if mode is not None and mode != CONTINUE and not arr._interrupts:
                self._step_from(origin, m, mode)
            if self.breaks.items:
                self.breaks.refresh(arr.machines)  # a value set while paused starts a new edge
            self._update_watcher()
            self._notify()

    def _step_from(self, origin: str, m: Machine | None, mode: str) -> None:
        """Where the step just asked for ends.  In a watched round, or between rounds (the next
        round is watched), the watcher counts the boundaries.  Inside a plain round (a pause at a
        marked transition, at a command, before a turn), the scheduler's rare path does: the
        machine whose turn follows the next ringlet is held, and its turn pauses before it
        begins; a step to the end of the round, or past the round's last ringlet, pauses
        between rounds."""
        if origin in (RINGLET, ROUND_END):
            self._stop_after = mode
            return
        if mode == ROUND:
            self._round_end("step round")
            return
        live = self.arr._live
        j = live.index(m) if m in live else -1
        following = j if origin == TURN else j + 1  # the machine whose ringlet the step runs
        if following + 1 < len(live):
            self._gate_after, self._gate_for = live[following], live[following + 1]
            self.arr.hold(self._gate_for)
        elif following + 1 == len(live):
            self._round_end("step")  # the round's last ringlet, then between rounds
        else:
            self._stop_after = STEP  # the next round's first ringlet: watched
            self.arr.ctx.wake = 0  # the plain loop ends with this round

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
        """Between rounds while running: what other threads handed in (`submit`), and the values
        the page asked for."""
        h = self.history
        if h is not None and h.wanted:
            h.refresh()
        if self.inbox.empty():
            return  # the common case, without raising queue.Empty
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
        h = self.history
        ms = [self.machine(name)] if name is not None else self.arr.machines
        return {m.NAME: read(m, now, h.entered(m._id) if h is not None else None) for m in ms}

    def set_value(self, name: str, variable: str, text: str) -> str:
        """Set machine `name`'s variable or input (paused only): the line to show."""
        if not self.paused:
            raise DebugError("pause the run first: values are set between ringlets")
        m = self.machine(name)
        h = self.history
        old = h.values[m._id].take(m) if h is not None else ()
        try:
            value = assign(m, variable, text)
        except SetError as e:
            raise DebugError(str(e)) from None
        if variable not in {entry[0] for entry in type(m).INPUTS}:
            # set now, and again by the scheduler's gate before the machine's next ringlet, where
            # the monitor sees what is set from outside (its checks may have compiled the old
            # value in: llfsm.monitor.variant, PINS)
            self.arr.set_variables(m.NAME, {variable: value})
        if h is not None:
            h.record_set(m, old, self._set_round(h), self.arr.clock.now)
        self._notify()
        return f"{m.NAME}.{variable} = {value!r}"

    def _set_round(self, h: History) -> int:
        """The round a set while paused belongs to: where the pause stands."""
        if not h.compiled:
            return self.arr.ctx.round  # watched rounds keep it
        if self._origin == ROUND_END or not h.kept:
            return self.arr.rounds  # between rounds: before the next one
        return h.round_of(h.count - h.sets)  # after a ringlet: its round

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
        m, origin = self.at, self._origin
        if m is None:
            place = f"before round {arr.ctx.round}" if arr.ctx.round or arr.clock.now else "before the first round"
        elif origin == TURN:
            place = f"at {m.NAME}'s turn, before its command"
        elif origin == RINGLET:
            place = f"round {arr.ctx.round}, after {m.NAME}'s ringlet"
        else:  # inside a plain round, which counts no rounds: the time says when
            place = f"after {m.NAME}'s ringlet"
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


def _own_class(m: Machine) -> bool:
    """Whether `m` is of the class its generated module made (not a variant another gave it)."""
    cls = type(m)
    return getattr(sys.modules.get(cls.__module__), cls.__name__, None) is cls
