"""Properties judged while a run goes on (SPEC 16; docs/monitor.md): `llfsm run --monitor
FILE.verify.yaml` and `--monitor-property KIND:TEXT`.

The property language is llfsm.props's, its atoms evaluated on the live machine objects at each
ringlet boundary through the scheduler's watcher (Arrangement.watcher: a run without a monitor
never calls it).  Each kind is judged as llfsm.props.kinds's table says: `always`/`never` at
every boundary; `leads_to` as pending obligations (with `within:`, a deadline on the run
clock); `ltl` three-valued on the run so far (violated, satisfied, pending); `reachable` and
`eventually` answered at the end; `ctl` refused with the reason.  A violation is one line on
stderr (the property, run time, ringlet, every machine's state and the variables the property
names) and, with `--on-violation stop`, the end of the run with status 4; with `pause`, the
debugger's pause (llfsm.debug: the session gives the run one, a prompt or the page continues it).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from ..props.atoms import Atom, PropertyError, infos_of
from ..props.automaton import Verdict3
from ..props.file import PropertySource
from ..props.kinds import AT_THE_END, EVERY_BOUNDARY, KINDS, OBLIGATIONS, THREE_VALUED
from ..props.parse import Property, parse_property
from ..runtime.scheduler import GO, PAUSE, STOP

#: What `--on-violation` may say.
ON_VIOLATION = ("log", "pause", "stop")


class MonitorError(ValueError):
    """A property the monitor cannot judge (one line; a usage error, status 2)."""


def property_source(text: str) -> PropertySource:
    """`--monitor-property KIND:TEXT`."""
    kind, sep, body = text.partition(":")
    if not sep or kind.strip() not in KINDS:
        raise MonitorError(f"--monitor-property {text!r}: write KIND:TEXT, KIND one of {', '.join(KINDS)}")
    return PropertySource(kind.strip(), body.strip(), where="--monitor-property")


class _Judged:
    """One property as the monitor follows it."""

    def __init__(self, prop: Property, atoms: list[int]) -> None:
        self.prop = prop
        self.atoms = atoms  # the global number of each of its atoms
        self.mode = prop.spec.monitor
        self.done = False  # decided for good (violated, satisfied)
        self.seen = False  # reachable / eventually: its condition held at some boundary
        self.pending: tuple[int, int] | None = None  # leads_to: (run time, ringlet) of the oldest A
        self.verdict3 = Verdict3(prop.formula, f"{prop.where}: {prop.text}") if self.mode == THREE_VALUED else None
        self.state3: bool | None = None


class Monitor:
    """Judges properties at each ringlet boundary of an arrangement (see the module's docstring)."""

    def __init__(
        self,
        sources: Sequence[PropertySource],
        classes: Sequence[type[Any]],
        on_violation: str = "log",
        say: Callable[[str], None] | None = None,
    ) -> None:
        if on_violation not in ON_VIOLATION:
            raise MonitorError(f"--on-violation {on_violation}: one of {', '.join(ON_VIOLATION)}")
        self.on_violation = on_violation
        self.say = say if say is not None else print
        infos = infos_of(classes)
        self.atoms: list[Atom] = []
        by_text: dict[str, int] = {}
        self.judged: list[_Judged] = []
        for src in sources:
            try:
                prop, local = parse_property(src.kind, src.text, infos, src.name, src.where, src.within)
            except PropertyError as e:
                raise MonitorError(str(e)) from None
            if prop.spec.monitor is None:
                raise MonitorError(f"{src.where}: {prop.kind}: not judged on a run: {prop.spec.monitor_refusal}")
            ids = []
            for a in local:
                k = by_text.setdefault(a.text, len(self.atoms))
                if k == len(self.atoms):
                    self.atoms.append(a)
                ids.append(k)
            try:
                self.judged.append(_Judged(prop, ids))
            except PropertyError as e:
                raise MonitorError(str(e)) from None
        self.published: set[str] = set()
        self.reads_published = any(a.reads_published for a in self.atoms)
        self.machines: list[Any] = []
        self.clock: Any = None
        self.ringlets = 0
        self.violations = 0

    # -- the run ----------------------------------------------------------------------------
    def attach(self, arr: Any, bus: Any = None) -> None:
        """Watch `arr` (its machines between ringlets); with `bus`, what is published too."""
        self.machines = arr.machines
        self.clock = arr.clock
        if self.reads_published and bus is not None:
            published = self.published

            def tap(topic: Any) -> None:
                name = topic.name
                topic.taps.append(lambda _msg: published.add(name))

            bus.add_tap(tap)
        arr.watcher = self.after
        self._judge(None)  # the boundary before the first ringlet

    def after(self, m: Any, state: int | None = None, fired: int | None = None) -> int:
        """The watcher: judge at the boundary after m's ringlet."""
        self.ringlets += 1
        violated = self._judge(m)
        self.published.clear()
        if not violated or self.on_violation == "log":
            return GO
        return STOP if self.on_violation == "stop" else PAUSE

    def _judge(self, m: Any) -> bool:
        machines, published = self.machines, self.published
        values = []
        for a in self.atoms:
            try:
                values.append(bool(a.fn(machines, published)))
            except Exception as e:  # an atom that cannot be evaluated now counts as false, said once
                values.append(False)
                if not getattr(a, "_said", False):
                    a._said = True  # type: ignore[attr-defined]
                    self.say(f"llfsm: monitor: {a.where}: `{a.text}` could not be evaluated: {type(e).__name__}: {e}")
        now = self.clock.now if self.clock is not None else 0
        violated = False
        for j in self.judged:
            if j.done:
                continue
            v = [values[k] for k in j.atoms]
            if j.mode == EVERY_BOUNDARY:
                if v[0] != j.prop.spec.decided_by:
                    continue
                j.done = True
            elif j.mode == OBLIGATIONS:
                held_a, held_b = v
                if j.pending is not None and j.prop.within is not None and now - j.pending[0] > j.prop.within:
                    j.done = True  # the deadline passed: B came too late, or not yet
                elif held_b:
                    j.pending = None
                    continue
                elif held_a and j.pending is None:
                    j.pending = (now, self.ringlets)
                    continue
                else:
                    continue
            elif j.mode == THREE_VALUED:
                assert j.verdict3 is not None
                j.state3 = j.verdict3.step(sum(1 << n for n, a in enumerate(j.verdict3.atoms) if v[a]))
                if j.state3 is None:
                    continue
                j.done = True
                if j.state3:
                    continue  # satisfied whatever follows
            else:  # AT_THE_END
                if v[0]:
                    j.seen = j.done = True
                continue
            violated = True
            self.violations += 1
            self.say(self._line(j, now))
        return violated

    def _line(self, j: _Judged, now: int) -> str:
        states = ", ".join(f"{m.NAME} {m.STATES[m._state]}" for m in self.machines)
        names = []
        for k in j.atoms:
            for i in sorted(self.atoms[k].machines):
                m = self.machines[i]
                for var in getattr(type(m), "__slots__", ()) or ():
                    if var in self.atoms[k].text and not var.startswith("_"):
                        names.append(f"{m.NAME}.{var}={getattr(m, var, None)!r}")
        variables = f"; {', '.join(dict.fromkeys(names))}" if names else ""
        extra = ""
        if j.mode == OBLIGATIONS and j.pending is not None:
            since = j.pending[0] / 1e9
            extra = f" (A held at {since:.3f} s, ringlet {j.pending[1]}, and B has not come within the deadline)"
        return (
            f"llfsm: monitor: {j.prop.name} violated at {now / 1e9:.3f} s, ringlet {self.ringlets}{extra}: "
            f"{states}{variables}"
        )

    def at_end(self) -> list[str]:
        """What is left at the end of the run: the lines to print (pending, not seen, held)."""
        out = []
        for j in self.judged:
            name = j.prop.name
            if j.mode == AT_THE_END:
                out.append(f"llfsm: monitor: {name}: {'held at some boundary' if j.seen else 'not seen in this run'}")
            elif j.mode == OBLIGATIONS and not j.done and j.pending is not None:
                out.append(
                    f"llfsm: monitor: {name}: pending at the end (A held at {j.pending[0] / 1e9:.3f} s, B not yet)"
                )
            elif j.mode == THREE_VALUED and not j.done:
                out.append(f"llfsm: monitor: {name}: pending at the end (neither violated nor satisfied so far)")
            elif j.mode == THREE_VALUED and j.state3:
                out.append(f"llfsm: monitor: {name}: satisfied")
        return out
