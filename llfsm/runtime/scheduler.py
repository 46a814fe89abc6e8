"""The ringlet scheduler: one thread runs an arrangement of machines round-robin (SPEC §2).

Two loops do the same thing: `_round` is the fast path (no hooks beyond what the semantics
need), `_traced_round` also reports entries and transitions for `-v` and `--trace`.  Keeping
them apart means an untraced run pays nothing for tracing.
"""

from __future__ import annotations

import signal
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from types import FrameType

from .clock import Clock, SimClock
from .context import RunContext, activate
from .errors import ErrorReport, RunStopped, is_generated, passes_through, report_for, signal_name
from .machine import RESTART, RESUME, SUSPEND, Machine, UnknownMachineError
from .trace import Tracer

FOREVER = 1 << 62

#: Exit statuses (SPEC §2): a normal end, an exception in machine code, bad input.
EXIT_OK, EXIT_ERROR, EXIT_USAGE = 0, 1, 2
#: 128 + the signal's number, as a shell reports a process the signal killed.
EXIT_SIGNAL = {signal.SIGINT: 130, signal.SIGTERM: 143, signal.SIGHUP: 129}
#: Signals that interrupt a run: Ctrl-C, `kill`, and a closed terminal (SIGHUP).
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
#: After a first interrupt, machine code that still holds the run this long (seconds of real
#: time) beyond the grace time is stopped where it is, as a second interrupt would stop it.
STUCK_SLACK_S = 0.5


@dataclass
class RunResult:
    reason: str  # finished | suspended | duration | interrupted | killed | error
    rounds: int
    time_ns: int
    status: int
    error: ErrorReport | None = None


class ArrangementError(ValueError):
    """The arrangement itself is wrong (a machine loaded twice, --suspended naming a machine that
    is not loaded): a usage error, unlike an exception raised by machine code."""


class Arrangement:
    """Machines in load order, the clock they share, and the round-robin that runs them."""

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
        self.ctx.extras["arrangement"] = self
        self.keep_accepting = keep_accepting
        self.tracer = tracer
        self.machines: list[Machine] = []
        self.by_name: dict[str, Machine] = {}
        self._attention = True  # something to look at before the next round
        self._interrupts = 0
        self._signal: int | None = None
        self._grace_end: int | None = None
        self._interrupted_at = 0.0  # time.monotonic() of the first interrupt: grace is real time too
        self._grace_ns = 1_000_000_000
        self.running = False  # inside run(): a stop may be raised into the running code
        self.rounds = 0
        #: Told once when an interrupt takes effect (the CLI prints it for the user).
        self.on_interrupt: Callable[[int], None] | None = None
        #: SPEC §2 ends a run whose machines are all suspended: nothing could resume them.  A run
        #: steered from outside (control services a page or another process calls) waits instead.
        self.end_when_suspended = True
        #: Keep running rounds with no machine left (nodes on their own, SPEC 4): the run then
        #: ends by an interrupt or --duration only.
        self.serve_forever = False
        names = [c.NAME for c in classes]
        for n in names:
            if names.count(n) > 1:
                raise ArrangementError(f"machine {n} is loaded twice; an arrangement addresses machines by name")
        for n in suspended:
            if n not in names:
                raise ArrangementError(f"--suspended {n}: no machine named {n} is loaded")
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
            m._state, m._suspended, m._entered = m.SUSPENDED, True, True
            m._resume_to = None
            m._ringlets = m._held
        self._live: list[Machine] = list(self.machines)

    # -- what machines call --------------------------------------------------------------
    def machine(self, name: str) -> Machine:
        try:
            return self.by_name[name]
        except (KeyError, TypeError):
            loaded = ", ".join(self.by_name) or "none"
            raise UnknownMachineError(f"no machine named {name!r} is loaded (loaded: {loaded})") from None

    def command(self, name: str, cmd: str) -> None:
        """Schedule a control command; it is applied at the start of the target's next ringlet."""
        m = self.machine(name)
        if m._finished and cmd != RESTART:
            return  # a finished machine can only be restarted; it stays finished until then
        m._pending = cmd  # a later command replaces an earlier pending one
        m._ringlets = m._held
        self._attention = True

    def suspend_now(self, m: Machine, remember: int | None) -> None:
        """Move `m` to its suspend state and run that state's OnEntry (no OnExit anywhere)."""
        m._resume_to = remember
        m._state = m.SUSPENDED
        m._suspended = True
        m._ringlets = m._held
        m._entered = True
        if self.tracer is not None:
            self.tracer.command("suspend", m, m.SUSPENDED)
            self.tracer.entry(m, m.SUSPENDED)
        m.RINGLETS[m.SUSPENDED](m)  # the suspend state's ringlet is its OnEntry only
        self._attention = True

    def set_tracer(self, tracer: Tracer | None) -> None:
        """Change the tracer during a run (from the scheduler's thread): the round loop picks
        it up before its next round.  How state topics get their events only while someone
        listens: the plain loop runs otherwise."""
        self.tracer = tracer
        self._attention = True

    # -- control commands -------------------------------------------------------------------
    def _apply(self, m: Machine) -> bool:
        """Apply m's pending command; True if the ringlet goes on (step 2), False if it ends."""
        cmd, m._pending = m._pending, None
        self._attention = True
        tr = self.tracer
        if cmd == SUSPEND:
            if not m._suspended:
                hook = m.ON_SUSPEND[m._state]
                if hook is not None:
                    hook(m)
                self.suspend_now(m, remember=m._state)
            return False
        if cmd == RESUME:
            if not m._suspended:
                return True  # nothing to resume: an ordinary ringlet
            hook = m.ON_RESUME[m.SUSPENDED]
            if hook is not None:
                hook(m)
            target = m.INITIAL if m._resume_to is None else m._resume_to
            m._state, m._suspended, m._resume_to = target, False, None
            _regate(m)
            hook = m.ON_RESUME[target]
            if hook is not None:
                hook(m)
            m._entered = True
            if tr is not None:
                tr.command("resume", m, target)
            return True
        # RESTART (which also brings a finished machine back)
        m._state, m._suspended, m._resume_to, m._entered = m.INITIAL, False, None, True
        m._finished = False
        _regate(m)
        if tr is not None:
            tr.command("restart", m, m.INITIAL)
        return True

    def _gate(self, m: Machine) -> int | None:
        """Stands in for the ringlet of a held machine (a command pending, or suspended): apply
        the command, then run the real ringlet if the command lets it go on."""
        if m._pending is None or not self._apply(m):
            return None  # suspended: no ringlet; or the command (suspend) ended it
        _regate(m)
        return m.RINGLETS[m._state](m)

    def _finish(self, m: Machine) -> None:
        m._finished = True
        m._suspended = False
        _regate(m)
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

    # -- rounds ----------------------------------------------------------------------------
    def _traced_round(self, live: list[Machine], tr: Tracer) -> bool:
        fired = False
        for m in live:
            if m._ringlets is m._held:
                if m._pending is None or not self._apply(m):
                    continue
                _regate(m)
            s = m._state
            if m._entered:
                tr.entry(m, s)
            r = m._ringlets[s](m)
            if r is not None:
                if r >= 0:
                    fired = True
                    tr.transition(m, s, m._state, r)
                elif not self.keep_accepting:
                    tr.finish(m)
                    self._finish(m)
        return fired

    def _attend(self, now: int, grace: int) -> RunResult | None:
        """Whatever changed since the last round: unloads, suspensions, interrupts."""
        self._attention = False
        self._live = [m for m in self.machines if not m._finished or m._pending is not None]
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
            if self._grace_end is None:
                self._grace_end = now + grace
                if self.on_interrupt is not None:
                    self.on_interrupt(grace)
            elif now >= self._grace_end or time.monotonic() - self._interrupted_at >= grace / 1e9:
                # run time or real time, whichever passes first: under `--clock sim --period 1ns`
                # a second of run time is a billion rounds
                return self._result("interrupted", status)
        return None

    def run(self, duration_ns: int | None = None, grace_ns: int = 1_000_000_000) -> RunResult:
        """Run rounds until the run ends (SPEC §2); machine exceptions become an error report."""
        prev = activate(self.ctx)
        self.ctx.deadline = duration_ns
        self._grace_ns = grace_ns
        self.running = True
        try:
            result = self._run(FOREVER if duration_ns is None else duration_ns, grace_ns)
            result.rounds = self.rounds  # the loop keeps its count in a local until it ends
            return result
        except RunStopped as exc:  # raised by signals_handled into whatever was running
            self.running = False
            status = EXIT_SIGNAL.get(exc.signum, 130)
            rep = report_for(exc) if exc.in_machine_code else None
            if rep is None:  # stopped between rounds or in the bus: nothing of the user's to show
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
            if self.tracer is not None:
                self.tracer.error(None, rep.as_dict())
            return RunResult("error", self.rounds, self.clock.now, EXIT_ERROR, rep)
        finally:
            self.running = False  # from here on a signal is only counted: at_end runs whole
            try:
                for fn in self.ctx.at_end:
                    fn()
            finally:
                if self.tracer is not None:
                    self.tracer.close()
                activate(prev)

    def _run(self, end: int, grace: int) -> RunResult:
        """The round loop.  Deliberately flat: this is the hot path of every run."""
        clock, ctx, tr = self.clock, self.ctx, self.tracer
        hooks = ctx.between_rounds
        keep = self.keep_accepting
        sim = type(clock) is SimClock
        period = clock.period if sim else 0  # type: ignore[attr-defined]
        live = self._live
        rounds = self.rounds
        try:
            while True:
                now = clock.now
                if self._attention:
                    done = self._attend(now, grace)
                    if done is not None:
                        return done
                    live = self._live
                    tr = self.tracer  # set_tracer() may have changed it
                if now >= end:
                    return self._result("duration", EXIT_OK)
                if tr is None and sim and not hooks:
                    # the common simulated case: plain rounds back to back until something
                    # needs attention (a command, an unload, a signal, the bus appearing)
                    while True:
                        for m in live:
                            r = m._ringlets[m._state](m)
                            if r is not None and r < 0 and not keep:
                                self._finish(m)
                        rounds += 1
                        now = clock.now + period
                        clock.now = now
                        if self._attention or now >= end or hooks:
                            break
                    continue
                fired = False
                if tr is None:
                    for m in live:
                        r = m._ringlets[m._state](m)
                        if r is not None:
                            if r >= 0:
                                fired = True
                            elif not keep:
                                self._finish(m)
                else:
                    tr.round, tr.now = rounds, now
                    ctx.round = rounds
                    fired = self._traced_round(live, tr)
                rounds += 1
                if sim:
                    clock.now += period  # a spin call inside machine code may have moved it on
                else:
                    clock.advance(fired)
                if hooks:
                    ctx.round = rounds
                    for h in hooks:
                        h()
        finally:
            self.rounds = rounds

    def _result(self, reason: str, status: int) -> RunResult:
        return RunResult(reason, self.rounds, self.clock.now, status)


def _regate(m: Machine) -> None:
    """Point the machine's ringlet table at the gate while it is held, at its states otherwise."""
    m._ringlets = m._held if (m._pending is not None or m._suspended) else m.RINGLETS


def _in_machine_code(frame: FrameType | None) -> bool:
    """Whether a generated module's code is on the stack (a signal handler's view of it)."""
    while frame is not None:
        if is_generated(frame.f_code.co_filename):
            return True
        frame = frame.f_back
    return False


@contextmanager
def signals_handled(arr: Arrangement) -> Iterator[None]:
    """Route SIGINT/SIGTERM/SIGHUP to the arrangement for the duration of a run.

    The first one asks the machines to finish (the scheduler sees it between rounds).  A second
    one, or the grace time passing in real time while machine code still loops or blocks (a real
    timer, SIGALRM, catches that), raises RunStopped from the handler: Python delivers it inside
    whatever code is running, machine code included, and a blocking `time.sleep` ends with it,
    so nothing a section does can keep the run from stopping."""

    def stop(frame: FrameType | None, text: str) -> None:
        if arr.running:
            # outside machine code (the scheduler sleeping between rounds, the bus) there is no
            # place of the user's to name: the run ends as the grace time's end would end it
            raise RunStopped(arr._signal or signal.SIGINT, text, in_machine_code=_in_machine_code(frame))

    def handler(signum: int, frame: FrameType | None) -> None:
        first = not arr._interrupts
        arr.interrupt(signum)
        if first:
            signal.setitimer(signal.ITIMER_REAL, arr._grace_ns / 1e9 + STUCK_SLACK_S)
        else:
            stop(frame, f"stopped by a second {signal_name(signum)}")

    def alarm(_signum: int, frame: FrameType | None) -> None:
        if arr._interrupts:
            grace = arr._grace_ns / 1e9
            sig = signal_name(arr._signal or 0)
            held = grace + STUCK_SLACK_S
            stop(frame, f"stopped by {sig}: still running {held:g} s after it (grace time {grace:g} s)")

    old = {s: signal.signal(s, handler) for s in STOP_SIGNALS}
    old[signal.SIGALRM] = signal.signal(signal.SIGALRM, alarm)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        for s, h in old.items():
            signal.signal(s, h)
