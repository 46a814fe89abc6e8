"""The ringlet scheduler: one thread runs an arrangement of machines round-robin (SPEC §2).

Two loops do the same thing: `_round` is the fast path (no hooks beyond what the semantics
need), `_traced_round` also reports entries and transitions for `-v` and `--trace`.  Keeping
them apart means an untraced run pays nothing for tracing.
"""

from __future__ import annotations

import signal
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass

from .clock import Clock, SimClock
from .context import RunContext, activate
from .errors import ErrorReport, report_for
from .machine import RESTART, RESUME, SUSPEND, Machine, UnknownMachineError
from .trace import Tracer

FOREVER = 1 << 62

#: Exit statuses (SPEC §2): a normal end, an exception in machine code, bad input.
EXIT_OK, EXIT_ERROR, EXIT_USAGE = 0, 1, 2
EXIT_SIGNAL = {signal.SIGINT: 130, signal.SIGTERM: 143}


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
        self.rounds = 0
        #: Told once when an interrupt takes effect (the CLI prints it for the user).
        self.on_interrupt: Callable[[int], None] | None = None
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
        """Ctrl-C / SIGTERM: `ros.ok()` turns false, rounds go on for the grace time; twice: stop.
        signum 0 is a stop asked for from inside the run (teleop's `q`): it ends with status 0."""
        self._interrupts += 1
        self._signal = signum if self._signal is None else self._signal
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
        elif all(m._suspended and m._pending is None for m in self._live):
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
            elif now >= self._grace_end:
                return self._result("interrupted", status)
        return None

    def run(self, duration_ns: int | None = None, grace_ns: int = 1_000_000_000) -> RunResult:
        """Run rounds until the run ends (SPEC §2); machine exceptions become an error report."""
        prev = activate(self.ctx)
        self.ctx.deadline = duration_ns
        try:
            result = self._run(FOREVER if duration_ns is None else duration_ns, grace_ns)
            result.rounds = self.rounds  # the loop keeps its count in a local until it ends
            return result
        except (BrokenPipeError, KeyboardInterrupt, SystemExit):
            raise
        except BaseException as exc:  # machine code may raise anything, e.g. asyncio.CancelledError
            rep = report_for(exc)
            if rep is None:
                raise
            if self.tracer is not None:
                self.tracer.error(None, rep.as_dict())
            return RunResult("error", self.rounds, self.clock.now, EXIT_ERROR, rep)
        finally:
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


@contextmanager
def signals_handled(arr: Arrangement) -> Iterator[None]:
    """Route SIGINT/SIGTERM to the arrangement for the duration of a run."""

    def handler(signum: int, _frame: object) -> None:
        arr.interrupt(signum)

    old = {s: signal.signal(s, handler) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)
