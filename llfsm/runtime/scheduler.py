"""The ringlet scheduler: one thread runs an arrangement of machines round-robin (docs/semantics.md).

The untraced loops (`_sim_rounds`, `_wall_rounds`, `_rounds`) are the fast path: a round is a
plain call per live machine, `m._run(m)`, and nothing else runs between rounds unless something
asked for it: `_attention` (a command, an unload, a signal) or the run context's `wake` time
(the bus: a message queued for a callback, a timer falling due; see RunContext).
`_watched_round` also reports entries and transitions for `-v` and `--trace`, and calls the
watcher (a monitor's, a debugger's) after each ringlet while one is set.  Keeping them apart
means an untraced, unwatched run pays nothing for either.
"""

from __future__ import annotations

import _signal as signal  # the signal module without its enums: enum is a tenth of a run's start-up
import time

from .clock import Clock, SimClock, WallClock
from .context import FOREVER, RunContext, activate
from .errors import ErrorReport, RunStopped, passes_through, report_for
from .gate import Gated, _hold
from .machine import Machine
from .trace import Tracer

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from collections.abc import Callable, Sequence
    from typing import Final

    from .watchdog import Watchdog

#: Exit statuses (docs/cli.md, "Exit statuses"): a normal end, an exception in machine code, bad input,
#: a monitored property violated with --on-violation stop.
EXIT_OK, EXIT_ERROR, EXIT_USAGE, EXIT_MONITOR = 0, 1, 2, 4
#: What a watcher (Arrangement.watcher) asks for after a ringlet.
GO, STOP, PAUSE = 0, 1, 2
#: 128 + the signal's number, as a shell reports a process the signal killed.
EXIT_SIGNAL: dict[int | None, int] = {signal.SIGINT: 130, signal.SIGTERM: 143, signal.SIGHUP: 129}
#: Rounds the machines get after an interrupt before the grace time can end the run: on a host
#: with more runnable processes than cores (sixty runs stopped at once on two) a run may wait
#: for the CPU longer than its grace time, and its machines must still see `ros.ok()` turn false.
GRACE_ROUNDS = 3


#: Back-to-back firing rounds read the wall clock every BATCH rounds at most, while BATCH
#: rounds take less than FAST ns (see Arrangement._wall_rounds).
FAST: Final = 20_000
BATCH: Final = 16


class RunResult:
    """How a run ended.  (A plain class: dataclasses would cost a run's start-up.)"""

    def __init__(self, reason: str, rounds: int, time_ns: int, status: int, error: ErrorReport | None = None) -> None:
        self.reason = reason  # finished | suspended | duration | interrupted | killed | error
        self.rounds = rounds
        self.time_ns = time_ns
        self.status = status
        self.error = error

    def __repr__(self) -> str:
        return (
            f"RunResult(reason={self.reason!r}, rounds={self.rounds!r}, time_ns={self.time_ns!r}, "
            f"status={self.status!r}, error={self.error!r})"
        )


class ArrangementError(ValueError):
    """The arrangement itself is wrong (a machine loaded twice, --suspended naming a machine that
    is not loaded): a usage error, unlike an exception raised by machine code."""


def check_names(classes: Sequence[type[Machine]], suspended: Sequence[str] = ()) -> None:
    """ArrangementError for a machine loaded twice or a --suspended machine not loaded: asked
    by a run before anything beside its machines starts (a node, a transport), and again here."""
    names = [c.NAME for c in classes]
    for n in names:
        if names.count(n) > 1:
            raise ArrangementError(f"machine {n} is loaded twice; an arrangement addresses machines by name")
    for n in suspended:
        if n not in names:
            raise ArrangementError(f"--suspended {n}: no machine named {n} is loaded")


class Arrangement(Gated):
    """Machines in load order, the clock they share, and the round-robin that runs them (the gate
    in front of their ringlets: `Gated`, gate.py)."""

    def __init__(
        self,
        classes: Sequence[type[Machine]],
        *,
        clock: Clock | None = None,
        context: RunContext | None = None,
        keep_accepting: bool = False,
        tracer: Tracer | None = None,
        suspended: Sequence[str] = (),
    ) -> None:
        self.ctx = context if context is not None else RunContext(clock or SimClock())
        self.clock = self.ctx.clock
        self.ctx.arrangement = self
        self.keep_accepting = keep_accepting
        self.tracer = tracer
        self.machines: list[Machine] = []
        self.by_name: dict[str, Machine] = {}
        self._attn = True  # something to look at before the next round (see _attention)
        self._interrupts = 0
        self._signal: int | None = None
        self._grace_end: int | None = None
        self._interrupted_at = 0.0  # time.monotonic() of the first interrupt: grace is real time too
        self._grace_rounds = 0  # rounds since the interrupt was seen (GRACE_ROUNDS)
        self._cpu_wait = (0.0, 0.0)  # the main thread's CPU time and time waited for it (signals.py)
        self._grace_ns = 1_000_000_000
        self.running = False  # inside run(): a stop may be raised into the running code
        #: The between-round hooks (the bus) are running: no ringlet is, so a new input value can
        #: go straight into its machine (llfsm.runtime.inputs) without the gate.
        self.between_rounds = False
        self.rounds = 0
        #: The gate every held machine's `_run` points at (one bound method, compared with `is`).
        self._gate_fn: Callable[[Machine], int | None] = self._gate
        #: The run's watchdog (llfsm.runtime.watchdog), which ends a run stuck in a C call that
        #: holds the GIL, where no handler of signals_handled can run; None: no such help.
        self.watchdog: Watchdog | None = None
        #: Told once when an interrupt takes effect (the CLI prints it for the user).
        self.on_interrupt: Callable[[int], None] | None = None
        #: A run whose machines are all suspended ends (docs/semantics.md, "When a run ends"):
        #: nothing could resume them.  A run steered from outside (control services a page or
        #: another process calls) waits instead.
        self.end_when_suspended = True
        #: Keep running rounds with no machine left (nodes on their own, docs/turtlesim.md): the run then
        #: ends by an interrupt or --duration only.
        self.serve_forever = False
        #: Called after every ringlet (and a release that ended one) with the machine, when set
        #: (a run's monitor, llfsm.monitor; the debugger's breakpoints): it returns GO, or STOP
        #: to end the run at this ringlet boundary (status `stop_status`), or PAUSE (the
        #: debugger's, issue 30; `on_pause` is called).  It may be set or cleared at any time,
        #: from a ringlet or between rounds: a round in progress reads it after each ringlet, and
        #: a plain loop in progress stops after its round when the setter also asks for
        #: attention (`ctx.wake = 0`).  A run without one pays nothing: the plain round loops
        #: never look at it.
        self.watcher: Callable[[Machine], int] | None = None
        self.stop_status = EXIT_MONITOR
        #: What the watcher may read of the boundary it is told of: the state the machine's
        #: ringlet ran in and the transition that fired (None and None: no ringlet ran, the
        #: machine was suspended or a suspend was applied; the state and None: nothing fired).
        #: Stored by the watched round only (the debugger's history and `fired()`).
        self.ran: int | None = None
        self.fired: int | None = None
        #: Called where the run stands for the debugger (llfsm.debug): after m's ringlet (a
        #: watcher's PAUSE, or the debugger's own marks and gate), or between rounds (None, when
        #: `pause_asked`); the run goes on when it returns.
        self.on_pause: Callable[[Machine | None], None] | None = None
        #: Pause at the next round boundary (`on_pause(None)`), asked from anywhere (another
        #: thread too: `ask_pause`); the round loops see it through the attention they raise.
        self.pause_asked = False
        #: Told of each machine the gate is about to release (a command, parameters or an input
        #: to apply, before they are applied), when set: what changes a machine outside its
        #: ringlets, for a monitor.  The gate is a rare path; a run without it pays nothing.
        self.on_release: Callable[[Machine], None] | None = None
        #: Wraps each release by the gate, when set: called as `around_release(m, let_go)`, it
        #: calls `let_go(m)` and returns what that returns (whether m's ringlet runs now); the
        #: debugger's history sees there what a command, parameters or inputs changed.
        self.around_release: Callable[[Machine, Callable[[Machine], bool]], bool] | None = None
        #: Told of the live machines each time they are worked out (between rounds), with the
        #: rounds run so far: the debugger's history numbers its records' rounds by it.
        self.on_live: Callable[[int, list[Machine]], None] | None = None
        #: Told of the run time each time a round loop of any clock but the sim clock reads it
        #: (between rounds), when set: the debugger's history times its records by it.
        self.note_time: Callable[[int], None] | None = None
        self._stopped: int | None = None
        #: Ringlets run before the current round loop (its rounds times its live machines),
        #: counted once per loop, never per ringlet: with the loop's live list, what numbers a
        #: ringlet boundary for a watcher (the monitor's violation lines).
        self.ringlets = 0
        check_names(classes, suspended)
        for i, cls in enumerate(classes):
            m = cls(self, i)
            self.machines.append(m)
            self.by_name[m.NAME] = m
        prev = activate(self.ctx)
        try:
            for m in self.machines:
                m._initialise()  # the variable initialisers: user code, with every machine known
        finally:
            activate(prev)
        for n in suspended:
            m = self.by_name[n]
            m._state, m._suspended, m._resume_to = m.SUSPENDED, True, None
            m._next, m._run = m.ENTER[m.SUSPENDED], m._held
        self._live: list[Machine] = list(self.machines)
        #: New values for machines' variables (their parameters), by machine id, waiting for the
        #: machine's next ringlet (set_variables).
        self._variables: dict[int, dict[str, object]] = {}

    def set_tracer(self, tracer: Tracer | None) -> None:
        """Change the tracer during a run (from the scheduler's thread): the round loop picks
        it up before its next round.  How state topics get their events only while someone
        listens: the plain loop runs otherwise."""
        self.tracer = tracer
        self._attention = True

    def interrupt(self, signum: int = signal.SIGINT) -> None:
        """Ctrl-C / SIGTERM / SIGHUP: `ros.ok()` turns false, rounds go on for the grace time (run
        time or real time, whichever passes first); twice: stop (signals_handled raises the stop
        into running code at once).  signum 0 is a stop asked for from inside the run (teleop's
        `q`): it ends with status 0."""
        self._interrupts += 1
        if self._signal is None:
            self._signal = signum
            self._interrupted_at = time.monotonic()
        self.ctx.interrupted = True
        self._attention = True

    def stop_at_boundary(self, status: int | None = None) -> None:
        """End the run at the ringlet boundary where this is called (from a ringlet, a watcher
        or between rounds): no further ringlet runs, the rest of the round included, and the
        run ends with `status` (by default `stop_status`)."""
        self._stopped = self.stop_status if status is None else status
        for m in self.machines:
            _hold(m)  # the rest of the round meets the gate, which lets nothing through now
        self._attention = True

    def ask_pause(self) -> None:
        """Pause at the next round boundary (the debugger's; a watcher pauses sooner, at the next
        ringlet boundary).  Two plain stores: safe from any thread."""
        self.pause_asked = True
        self._attention = True

    # -- rounds ----------------------------------------------------------------------------
    def _watched_round(self, live: list[Machine], tr: Tracer | None) -> bool:
        """A round with the tracer, if any, told of entries and transitions, and the watcher,
        while one is set (read after each ringlet: set during the round, it is called at once),
        told of each ringlet boundary."""
        fired = False
        values = tr is not None and tr.records_values
        for m in live:
            s: int | None = None
            r: int | None = None
            if m._run is not m._held or self._release(m):
                s = m._state
                if tr is not None and m._entered:
                    tr.entry(m, s)
                r = m._run(m)
                if r is not None:
                    fired = True
                    if tr is not None:
                        tr.transition(m, s, m._state, r)
            # else a suspend applied, or the run stopped: for a watcher the boundary is still one
            if values:
                tr.values(m)  # type: ignore[union-attr]  # values is true only with a tracer
            watch = self.watcher
            if watch is not None:
                self.ran, self.fired = s, r
                asked = watch(m)
                if asked == STOP:
                    self.stop_at_boundary()
                    break
                if asked == PAUSE and self.on_pause is not None:
                    self.on_pause(m)
        return fired

    def _attend(self, now: int, grace: int) -> RunResult | None:
        """Whatever changed since the last round: unloads, suspensions, interrupts."""
        self._attention = False
        if self.pause_asked and self.on_pause is not None and not self._interrupts and self._stopped is None:
            self.pause_asked = False
            self.on_pause(None)  # between rounds: the run stands until it returns
            self._rehold()  # what was asked for while it stood (commands, variables)
        if self._stopped is not None:
            return self._result("stopped", self._stopped)
        self._live = [m for m in self.machines if not m._finished or m._pending is not None]
        if self.on_live is not None:
            self.on_live(self.rounds, self._live)
        if not self._live:
            if not self.serve_forever:
                return self._result("finished", EXIT_OK)
        elif self.end_when_suspended and all(m._suspended and m._pending is None for m in self._live):
            return self._result("suspended", EXIT_OK)
        if self._interrupts:
            self._attention = True  # keep checking the grace time every round
            status = EXIT_SIGNAL.get(self._signal, EXIT_OK)  # signal 0: a stop asked for from inside
            if self._interrupts > 1:
                return self._result("killed", status)
            if not self.machines:  # nodes on their own: an interrupt is how they end, as `ros2 run`'s
                return self._result("interrupted", EXIT_OK)
            if self._grace_end is None:
                self._grace_end = now + grace
                if self.on_interrupt is not None:
                    self.on_interrupt(grace)
                return None
            self._grace_rounds += 1
            if self._grace_rounds >= GRACE_ROUNDS and (
                now >= self._grace_end or time.monotonic() - self._interrupted_at >= grace / 1e9
            ):
                # run time or real time, whichever passes first (under `--clock sim --period 1ns`
                # a second of run time is a billion rounds), once the machines have had rounds
                return self._result("interrupted", status)
        return None

    def run(self, duration_ns: int | None = None, grace_ns: int = 1_000_000_000) -> RunResult:
        """Run rounds until the run ends (docs/semantics.md); machine exceptions become an error report."""
        prev = activate(self.ctx)
        self.ctx.deadline = duration_ns
        self._grace_ns = grace_ns
        self.running = True
        if self.tracer is not None:
            self.tracer.begin(self.machines)
        self.clock.start()
        try:
            result = self._run(FOREVER if duration_ns is None else duration_ns, grace_ns)
            result.rounds = self.rounds  # the loop keeps its count in a local until it ends
            return result
        except RunStopped as exc:  # raised by signals_handled into whatever was running
            self.running = False
            status = EXIT_SIGNAL.get(exc.signum, 130)
            rep = report_for(exc) if exc.in_machine_code else None
            if rep is None:  # stopped between rounds or in the bus: nothing of the user's to show
                if self._interrupts == 1 and self.machines and all(m._finished for m in self.machines):
                    # every machine left in time; only the run's own work after them (a finished
                    # machine's nodes destroyed while a hundred DDS peers leave at once, on a
                    # starved host) outlasted the stop timer: the run ends as it would have
                    return RunResult("finished", self.rounds, self.clock.now, EXIT_OK)
                reason = "killed" if self._interrupts > 1 else "interrupted"
                return RunResult(reason, self.rounds, self.clock.now, status)
            if self.tracer is not None:
                self.tracer.error(None, rep.as_dict())
            return RunResult("killed", self.rounds, self.clock.now, status, rep)
        except BaseException as exc:  # machine code may raise anything: SystemExit, CancelledError...
            self.running = False
            if passes_through(exc):
                raise
            rep = report_for(exc)
            if rep is None:
                raise
            if rep.machine_id is None and rep.machine in self.by_name:  # compiled frames hold no `self`
                rep.machine_id = self.by_name[rep.machine]._id
            if self.tracer is not None:
                self.tracer.error(None, rep.as_dict())
            return RunResult("error", self.rounds, self.clock.now, EXIT_ERROR, rep)
        finally:
            self.running = False  # from here on a signal is only counted: at_end runs whole
            # no machine code runs any more, so no section can hold the run: the timer that
            # would stop one must not fire in the middle of at_end (closing DDS can take
            # seconds while many peers leave at once), where its handler cannot answer the
            # watchdog until the call returns
            signal.setitimer(signal.ITIMER_REAL, 0)
            try:
                for fn in self.ctx.at_end:
                    fn()
            finally:
                if self.tracer is not None:
                    self.tracer.close()
                activate(prev)

    def _run(self, end: int, grace: int) -> RunResult:
        """The round loop: attend to whatever asked for it, then run rounds until something
        asks again.  Between-round hooks (the bus executor) run only when the context's `wake`
        time has come: a quiet bus costs a round nothing."""
        clock, ctx, tr = self.clock, self.ctx, self.tracer
        hooks = ctx.between_rounds
        # the clock again, as what its own loop needs (None where that loop does not run it)
        sim = clock if type(clock) is SimClock else None
        wall = clock if type(clock) is WallClock and not clock.period else None
        rounds = self.rounds
        try:
            while True:
                now = clock.now
                if self._attn:
                    self.rounds = rounds  # what on_live is told
                    self._rehold()
                    done = self._attend(now, grace)
                    if done is not None:
                        return done
                    tr = self.tracer  # set_tracer() may have changed it
                if now >= end:
                    return self._result("duration", EXIT_OK)
                if end < ctx.wake:
                    ctx.wake = end  # one test a round covers the end of the run as well
                live = self._live
                if tr is not None or self.watcher is not None:
                    if tr is not None:
                        tr.round, tr.now = rounds, now
                    ctx.round = rounds
                    fired = self._watched_round(live, tr)
                    n = 1
                    if sim is not None:
                        sim.now += sim.period
                    else:
                        clock.advance(fired)
                        if self.note_time is not None:
                            self.note_time(clock.now)
                elif sim is not None:
                    n = self._sim_rounds(live, sim)
                elif wall is not None:
                    n = self._wall_rounds(live, wall, self.note_time)
                else:
                    n = self._rounds(live, self.note_time)
                rounds += n
                self.ringlets += n * len(live)
                if clock.now >= ctx.wake:
                    ctx.wake = FOREVER  # the hooks arm it again for whatever they still hold
                    ctx.round = rounds
                    self.between_rounds = True
                    try:
                        for h in hooks:
                            h()
                    finally:
                        self.between_rounds = False
        finally:
            self.rounds = rounds

    # The three untraced loops run rounds back to back until the context's wake time comes (it
    # covers the end of the run, attention and the bus); each returns how many rounds it ran.
    # They are deliberately flat (and repeat themselves): this is the hot path of every run.

    def _sim_rounds(self, live: list[Machine], clock: SimClock) -> int:
        """The sim clock: the time is kept in a local and stored after each round.  A spin call
        inside machine code that moves the clock on also sets the wake time to 0 (SimClock
        tells the context), so the loop stops after that round without overwriting the jump,
        and the clock moves on by one period from wherever the jump left it.  The number of
        rounds follows from the time: no counter."""
        ctx = self.ctx
        period = clock.period
        start = now = clock.now
        if len(live) == 1:
            m = live[0]
            while True:
                m._run(m)
                now += period
                if now >= ctx.wake:
                    break
                clock.now = now
        else:
            while True:
                for m in live:
                    m._run(m)
                now += period
                if now >= ctx.wake:
                    break
                clock.now = now
        clock.now += period  # the last round's step (from the jump, if there was one)
        return (now - start) // period

    def _wall_rounds(self, live: list[Machine], clock: WallClock, note: Callable[[int], None] | None) -> int:
        """The wall clock without a period: sleep `idle` after a round in which no transition
        fired, then read the clock.  Rounds that each fire a transition, back to back, read it
        in batches (a clock read costs as much as a whole plain ringlet): every 2, 4, ... up to
        BATCH rounds while the rounds since the last read took less than FAST, else every
        round.  So the run clock lags only during a stretch of firing rounds, by at most
        BATCH - 1 rounds, and a round in which nothing fires always reads it.  `note`
        (`note_time`) is told of each read."""
        ctx = self.ctx
        read = time.monotonic_ns
        idle = clock.idle / 1e9
        idle_ns = clock.idle
        waiter = clock.waiter if idle_ns else None
        sleep = time.sleep
        now = clock.now
        every = left = 1
        n = 0
        single = live[0] if len(live) == 1 else None
        while True:  # not `for n in range(...)`: compiled (--native), a plain counter is cheaper
            n += 1
            if single is not None:
                fired = single._run(single) is not None
            else:
                fired = False
                for m in live:
                    if m._run(m) is not None:
                        fired = True
            if not fired:
                if waiter is not None:
                    waiter(idle_ns)  # a remote transport ends the wait early when data comes in
                elif idle:
                    sleep(idle)
                left = 1
            left -= 1
            if not left:
                t = read() - clock._start  # read each time: a pause of the debugger moves the start
                if t - now >= FAST:
                    every = 1
                elif every < BATCH:
                    every *= 2
                left = every
                now = t
                clock.now = t
                if note is not None:
                    note(t)
            if now >= ctx.wake:
                break
        return n

    def _rounds(self, live: list[Machine], note: Callable[[int], None] | None) -> int:
        """Any other clock (the wall clock with a period): the clock decides how to advance;
        `note` (`note_time`) is told of the time after each round."""
        clock, ctx = self.clock, self.ctx
        n = 0
        while True:
            n += 1
            fired = False
            for m in live:
                if m._run(m) is not None:
                    fired = True
            clock.advance(fired)
            now = clock.now
            if note is not None:
                note(now)
            if now >= ctx.wake:
                break
        return n

    def _result(self, reason: str, status: int) -> RunResult:
        return RunResult(reason, self.rounds, self.clock.now, status)
