"""Properties judged while a run goes on (SPEC 16; docs/monitor.md): `llfsm run --monitor
FILE.verify.yaml` and `--monitor-property KIND:TEXT`.

**Where it judges.**  A property's value can change only where what it reads changes, so the
monitor judges it only there, and the semantics stay "judged at every ringlet boundary":

- in the ringlets that can change what it reads (llfsm.runtime.reads), by a check compiled
  into a monitored variant of the machine's ringlets (llfsm.monitor.variant); every other
  ringlet runs as compiled, in the scheduler's plain loops;
- at the boundaries after something the ringlets' code does not show: a command, a parameter or
  an input applied by the scheduler's gate (`Arrangement.on_release`), an input
  set between rounds, a publish on a topic a property names (a tap): then the monitor
  *watches*, judging every property at each boundary until nothing calls for it any more (the
  next boundary; the boundary after a publish, where `published` turns false again; while a
  `leads_to` with `within:` waits for B, since its deadline passes with time).  Watching is
  the scheduler's watcher (`Arrangement.watcher`, called after each ringlet of a round that
  has one) and, for the rest of a plain round in progress, its gate (`Arrangement.hold_all`:
  every machine's next ringlet meets the gate, which the monitor wraps);
- always, for a property whose value can change where the monitor cannot see it (a variable
  handed to a function of the machine's own, or touched by a callback; a machine built native,
  whose ringlets cannot be rewritten), and for an `ltl` formula with `X`, which counts
  boundaries; such a run pays for a call after every ringlet.

**Where a verdict is said.**  A plain loop counts its rounds only when it ends, so a verdict
reached in a round asks the loop to end after that round (`ctx.wake = 0`); the monitor's first
between-round hook then numbers the boundary (`Arrangement.ringlets`) and says it: the stderr
line, a message on `/llfsm/monitor` (llfsm_msgs/msg/MonitorEvent, llfsm.monitor.topic), and the
listeners (the web page).  `--on-violation stop` ends the run at that boundary
(`Arrangement.stop_at_boundary`, exit status 4); `pause` pauses it there (the debugger's pause,
llfsm.debug, through `Monitor.pause`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from ..props.atoms import infos_of
from ..props.file import PropertySource
from ..runtime.generated import become
from ..runtime.reads import ClassReads, class_reads
from ..runtime.scheduler import GO, Arrangement
from .judge import VIOLATED, Boundary, Judge, Judged, MonitorError, Verdict, atom_reads
from .topic import MonitorTopic
from .variant import FAILED, INTEGERS, INTEGRAL, JUDGE, MACHINES, NUMBERS, NUMERIC, PINS, PUBLISHED, Check, make_variant
from .variant import VIOLATED as VIOLATED_FN

#: What `--on-violation` may say.
ON_VIOLATION = ("log", "pause", "stop")


class Monitor:
    """Judges properties on a running arrangement (see the module's docstring)."""

    def __init__(
        self,
        sources: Sequence[PropertySource],
        classes: Sequence[type[Any]],
        on_violation: str = "log",
        say: Callable[[str], None] | None = None,
        targeted: bool = True,
    ) -> None:
        if on_violation not in ON_VIOLATION:
            raise MonitorError(f"--on-violation {on_violation}: one of {', '.join(ON_VIOLATION)}")
        self.on_violation = on_violation
        self.say = say if say is not None else print
        self.judge = Judge(sources, infos_of(classes), self.say)
        #: False: judge every boundary (the plain watcher; what the targeted judging is tested against)
        self.targeted = targeted
        #: Every verdict said so far, in order (the page's marks, the end of the run).
        self.verdicts: list[Verdict] = []
        #: Told of each verdict once it is said (the /llfsm/monitor publisher, the web page).
        self.listeners: list[Callable[[Verdict], None]] = []
        self.published: set[str] = set()
        self.topics = self.judge.topics_named()
        self.arr: Arrangement | None = None
        self.machines: list[Any] = []
        self._unsaid: list[Verdict] = []
        self._unnumbered: list[Boundary] = []
        #: the latest boundary is to be judged in full (a publish during the ringlet before it)
        self._pending = False
        #: the next boundary is to be judged in full (something the gate applied)
        self._once = False
        #: the last boundary judged in full had something published: the next one has not
        self._fall = False
        #: every boundary is judged (see the module's docstring)...
        self.always = False
        #: ...for these properties alone (None: all of them), the others where they can change
        self._everywhere: list[Judged] | None = None
        self._before: Callable[[Any], int] | None = None  # a watcher that was there first
        #: `--on-violation pause`: pauses the run where a violation is reached (the debugger's,
        #: llfsm.debug, which the session sets; called at that boundary with the verdict).
        self.pause: Callable[[Verdict], None] | None = None
        self._watcher = self._watch  # one bound method, compared with `is`
        self._inputs: dict[int, list[object]] = {}
        self._reads_inputs = not targeted  # an input a property reads (found by _instrument)
        #: by machine: what its variant relies on the variables holding (llfsm.monitor.variant:
        #: NUMERIC, INTEGRAL, PINS), and the variant that relies on none of it, made if one is
        #: set to anything else
        self._numeric: dict[int, tuple[_Relies, Callable[[], type]]] = {}
        self.ended = False

    # -- attaching ------------------------------------------------------------------------------
    def attach(self, arr: Arrangement, bus: Any = None, publish: bool = True) -> None:
        """Watch `arr` from its next ringlet on (called before it runs); with `publish`, the
        verdicts go to /llfsm/monitor too once the run has a bus (llfsm.monitor.topic)."""
        self.arr = arr
        self.machines = arr.machines
        if self.targeted:
            everywhere = self._instrument(arr)
            self.always = bool(everywhere)
            self._everywhere = everywhere if len(everywhere) < len(self.judge.judged) else None
        else:
            self.always = True
        orig_gate = arr._gate_fn

        def gate(m: Any) -> int | None:
            if self._pending:
                self._full(m, 0)
            r = orig_gate(m)
            if self._once or arr.watcher is self._watcher:
                self._full(m, 1)
                if arr.watcher is self._watcher:
                    arr.hold_all()  # the rest of this round meets the gate too
            return r

        def released(m: Any) -> None:
            inputs = m._inputs
            if m._pending is not None or m._id in arr._variables or (inputs is not None and inputs.fresh):
                self._once = True  # a command, a parameter, an input: judge the boundary after it
                self._watch_on()
                if m._id in self._numeric and m._id in arr._variables:
                    relies, unstepped = self._numeric[m._id]
                    if not all(relies.kept(k, v) for k, v in arr._variables[m._id].items()):
                        del self._numeric[m._id]
                        become(m, unstepped())  # its checks in full from this ringlet on

        arr._gate_fn = gate
        arr.on_release = released
        for m in arr.machines:
            if m._run is m._held:
                m._run = gate
            m._held = gate
        ctx = arr.ctx
        ctx.between_rounds.insert(0, self._between)
        if self._reads_inputs:
            ctx.between_rounds.append(self._inputs_changed)
        ctx.at_end.insert(0, self._end)
        if self.topics:
            if bus is not None:
                bus.add_tap(self._tap)
            else:
                ctx.on_init.append(lambda b: b.add_tap(self._tap))
        if publish:
            MonitorTopic(self, ctx)
        self._full(None, 0)  # the boundary before the first ringlet
        if self.always:
            self._watch_on()

    def _instrument(self, arr: Arrangement) -> list[Judged]:
        """Compile each property's checks into the ringlets that can change what it reads; the
        properties that must be judged at every boundary instead (none compiled in)."""
        judge = self.judge
        reads: dict[int, ClassReads | None] = {}
        checks: dict[int, dict[str, list[Check]]] = {}
        everywhere: list[Judged] = []
        self._reads_inputs = False
        for j in judge.judged:
            every = False
            places: set[tuple[int, str]] = set()
            for k in j.atoms:
                for r in atom_reads(judge.atoms[k]):
                    m = arr.machines[r.machine]
                    if r.machine not in reads:
                        reads[r.machine] = class_reads(type(m))
                    cr = reads[r.machine]
                    if cr is None:
                        every = True
                        continue
                    if r.what in ("_state", "_suspended"):
                        places |= {(r.machine, n) for n, x in cr.ringlets.items() if x.moves}
                    elif r.what == "_finished":
                        places |= {(r.machine, n) for n, x in cr.ringlets.items() if x.finishes}
                    elif r.what in cr.variables:
                        if cr.is_escaped(r.what):
                            every = True
                        places |= {(r.machine, n) for n in cr.changers(r.what)}
                    else:  # an input: the gate takes its snapshot, or it is set between rounds
                        self._reads_inputs = True
            if j.counts_steps:
                every = True
            if every:
                everywhere.append(j)
                continue
            check = _check(judge, j)
            for machine, name in places:
                checks.setdefault(machine, {}).setdefault(name, []).append(check)
        helpers: dict[str, Any] = {
            VIOLATED_FN: self._violated,
            FAILED: self._failed,
            JUDGE: self._judge_some,
            MACHINES: arr.machines,
            PUBLISHED: self.published,
        }
        for index, by_ringlet in checks.items():
            m = arr.machines[index]
            cr = reads[index]
            assert cr is not None
            cls = type(m)

            def unstepped(cls: type = cls, cr: ClassReads = cr, index: int = index, by: Any = by_ringlet) -> type:
                return make_variant(cls, cr, index, by, helpers, steps=False)

            variant = make_variant(cls, cr, index, by_ringlet, helpers, pins=_pinnable(m, cr))
            relies = _Relies(getattr(variant, NUMERIC), getattr(variant, INTEGRAL), getattr(variant, PINS))
            if not all(relies.kept(v, getattr(m, v, None)) for v in relies.names()):
                variant = unstepped()  # a stepped variable holds something else already
            elif relies.names():
                self._numeric[index] = (relies, unstepped)
            become(m, variant)
        return everywhere

    # -- judging ---------------------------------------------------------------------------------
    def _where(self, m: Any, offset: int) -> Boundary:
        """The boundary after (offset 1) or before (0) m's ringlet, numbered now if the count is
        known, else when the round loop ends (which it is asked to do after this round)."""
        arr = self.arr
        assert arr is not None
        if not arr.running or arr.between_rounds or m is None:
            return Boundary(arr.ringlets)
        b = Boundary(None, m, offset)
        self._unnumbered.append(b)
        arr.ctx.wake = 0
        return b

    def _now(self) -> int:
        return self.arr.clock.now if self.arr is not None else 0

    def _full(self, m: Any, offset: int) -> None:
        """Judge every property at a boundary, then what it calls for."""
        self._pending = self._once = False
        arr = self.arr
        if arr is None or arr._stopped is not None:
            return
        published = self.published
        had = bool(published)
        found = self.judge.boundary(self.machines, published, arr.clock.now, lambda: self._where(m, offset))
        if had:
            published.clear()
        self._fall = had
        for v in found:
            self._record(v)
        if not self.always:
            self._update()

    def _watch(self, m: Any) -> int:
        """The watcher: the boundary after m's ringlet."""
        every = self._everywhere
        if self.always and (every is None or not self._called_for()):  # watching for good: the judging alone
            self._pending = self._once = False
            arr = self.arr
            assert arr is not None
            if arr._stopped is None:
                now = arr.clock.now
                found = self.judge.boundary(self.machines, self.published, now, lambda: self._where(m, 1), every)
                if self.published and every is None:
                    self.published.clear()
                for v in found:
                    self._record(v)
        else:
            self._full(m, 1)
        before = self._before
        return before(m) if before is not None else GO

    def _called_for(self) -> bool:
        """Whether the next boundary is to be judged in full (see the module's docstring)."""
        return self._fall or self._once or self._pending or bool(self.judge.deadlines_open)

    def _update(self) -> None:
        """Keep watching while something calls for it."""
        if self.always or self._called_for():
            self._watch_on()
        else:
            self._watch_off()

    def _watch_on(self) -> None:
        arr = self.arr
        if arr is None or arr.watcher is self._watcher:
            return
        self._before = arr.watcher
        arr.watcher = self._watcher
        arr.ctx.wake = 0  # a plain loop ends after this round; the watched round reads the watcher
        if arr.running and not arr.between_rounds:
            arr.hold_all()  # the rest of this round: the gate judges

    def _watch_off(self) -> None:
        arr = self.arr
        if arr is not None and arr.watcher is self._watcher:
            arr.watcher, self._before = self._before, None

    def _violated(self, m: Any, index: int) -> None:
        """A compiled-in check: safety property `index` is violated at the boundary after m's ringlet."""
        j = self.judge.judged[index]
        arr = self.arr
        if j.done or (arr is not None and arr._stopped is not None):
            return
        j.done = True
        self._record(Verdict(j, VIOLATED, self._now(), self._where(m, 1)))

    def _failed(self, m: Any, index: int, e: BaseException) -> None:
        """A compiled-in check raised: its atom counts as false (an `always` is then violated)."""
        j = self.judge.judged[index]
        self.judge.failed(j.atoms[0], e)
        if not j.prop.spec.decided_by:
            self._violated(m, index)

    def _judge_some(self, m: Any, indices: tuple[int, ...]) -> None:
        """A compiled-in check of properties other than safety: judge them after m's ringlet."""
        arr = self.arr
        if arr is not None and arr._stopped is not None:
            return
        which = [self.judge.judged[i] for i in indices]
        found = self.judge.boundary(self.machines, self.published, self._now(), lambda: self._where(m, 1), which)
        for v in found:
            self._record(v)
        if self.judge.deadlines_open:
            self._watch_on()

    def _record(self, v: Verdict) -> None:
        """A verdict reached at a boundary: the states and variables as they are now; said when
        its boundary is numbered."""
        v.states = [(m.NAME, m.STATES[m._state]) for m in self.machines]
        v.variables = self._variables(v.judged)
        v.reads = self._reads(v.judged)
        self._unsaid.append(v)
        arr = self.arr
        if arr is None:
            return
        arr.ctx.wake = 0
        if v.verdict == VIOLATED and self.on_violation == "stop":
            arr.stop_at_boundary()
        elif v.verdict == VIOLATED and self.on_violation == "pause" and self.pause is not None:
            self.pause(v)

    def _reads(self, j: Judged) -> list[str]:
        """The machines a property reads, in load order."""
        read = {r.machine for k in j.atoms for r in atom_reads(self.judge.atoms[k])}
        return [m.NAME for m in self.machines if m._id in read]

    def _variables(self, j: Judged) -> str:
        names = []
        for k in j.atoms:
            for r in sorted(atom_reads(self.judge.atoms[k]), key=lambda r: (r.machine, r.what)):
                if r.what.startswith("_"):
                    continue
                m = self.machines[r.machine]
                names.append(f"{m.NAME}.{r.what}={getattr(m, r.what, None)!r}")
        return ", ".join(dict.fromkeys(names))

    # -- between rounds and at the end -------------------------------------------------------------
    def _between(self) -> None:
        """First between-round hook: the boundary after the round, if it is to be judged, then
        what was reached in the round said (its boundaries are numbered now)."""
        if self._pending:
            self._full(None, 0)
        self._say()

    def _say(self) -> None:
        arr = self.arr
        if self._unnumbered and arr is not None:
            live = arr._live
            base = arr.ringlets - len(live)
            for b in self._unnumbered:
                try:
                    b.number = base + live.index(b.machine) + b.offset
                except ValueError:  # pragma: no cover (a machine left the live list mid-round)
                    b.number = arr.ringlets
            self._unnumbered.clear()
        unsaid, self._unsaid = self._unsaid, []
        for v in unsaid:
            self.verdicts.append(v)
            self.say(v.line())
            for fn in self.listeners:
                fn(v)

    def _inputs_changed(self) -> None:
        """Last between-round hook: an input set between rounds (the bus took a message in)
        changes the machine at once, so the next boundary is judged."""
        for m in self.machines:
            inputs = m._inputs
            if inputs is None:
                continue
            if self._inputs.get(m._id) != inputs.values:
                self._inputs[m._id] = list(inputs.values)
                self._once = True
                self._watch_on()

    def _tap(self, topic: Any) -> None:
        """A tap on each topic a property names: a publish there calls for the boundary after it."""
        if topic.name not in self.topics:
            return
        name = topic.name
        arr = self.arr

        def published(_msg: object) -> None:
            self.published.add(name)
            if arr is not None and arr.running and not arr.between_rounds:
                self._pending = True  # the boundary after the ringlet that published
            else:
                self._once = True  # published between rounds: the next boundary
            self._watch_on()

        topic.taps.append(published)

    def _end(self) -> None:
        """The run's end (before its nodes close): the last verdicts, then what is answered at
        the end."""
        if self.ended:
            return
        self.ended = True
        if self._pending:
            self._full(None, 0)
        self._say()
        where = Boundary(self.arr.ringlets if self.arr is not None else 0)
        self._unsaid = self.judge.at_end(self._now(), where)
        self._say()


def _pinnable(m: Any, cr: ClassReads) -> dict[str, Any]:
    """The variables of machine `m` a variant may compile in as constants, with their values:
    numbers (immutable: an int, a float, a bool, not NaN) that no ringlet, OnSuspend/OnResume hook
    or anything the machine hands them to can change.  What else sets one goes through the
    scheduler's gate (a parameter, the debugger's set), where the monitor checks it kept its value."""
    inputs = {entry[0] for entry in getattr(type(m), "INPUTS", ())}
    out = {}
    for v in cr.variables:
        value = getattr(m, v, None)
        if type(value) not in NUMBERS or value != value or v in inputs or v in cr.hooked:
            continue
        if not cr.is_escaped(v) and not cr.changers(v):
            out[v] = value
    return out


class _Relies:
    """What a variant relies on its machine's variables holding (llfsm.monitor.variant): numbers
    (NUMERIC), ints (INTEGRAL), the values it compiled in (PINS)."""

    def __init__(self, numeric: frozenset[str], integral: frozenset[str], pins: dict[str, Any]) -> None:
        self.numeric, self.integral, self.pins = numeric, integral, pins

    def names(self) -> set[str]:
        return set(self.numeric) | set(self.integral) | set(self.pins)

    def kept(self, name: str, value: Any) -> bool:
        """Whether `name` holding `value` keeps the variant right (`1 == 1.0 == True`: a pin's
        type too)."""
        if name in self.numeric and type(value) not in NUMBERS:
            return False
        if name in self.integral and type(value) not in INTEGERS:
            return False
        pinned = self.pins.get(name, _NONE)
        return pinned is _NONE or (type(value) is type(pinned) and value == pinned)


_NONE = object()


def _check(judge: Judge, j: Judged) -> Check:
    """How a property is checked where it can change: a safety property's atom inline, anything
    else through the monitor."""
    if j.safety:
        return Check(j.index, judge.atoms[j.atoms[0]].tree, j.prop.spec.decided_by)
    return Check(j.index)
