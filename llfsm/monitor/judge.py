"""Properties judged over a sequence of ringlet boundaries (SPEC 16): the verdict logic shared by
a run's monitor (llfsm.monitor.run) and `llfsm bag check` (llfsm.monitor.bag), which differ only
in where the boundaries come from (a live arrangement, a recorded bag).

Each kind is judged as llfsm.props.kinds's table says: `always`/`never` at every boundary
(violated once, said once); `leads_to` as an obligation from the first boundary where A holds
until one where B holds, with `within:` a deadline on the run clock; `ltl` three-valued on the
run so far (LTL3: violated, satisfied, pending); `reachable` and `eventually` answered at the
end.  An atom that cannot be evaluated at a boundary (a variable still None) counts as false
there and is said once.
"""

from __future__ import annotations

import ast
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from ..props.atoms import Atom, MachineInfo, PropertyError
from ..props.automaton import Verdict3
from ..props.file import PropertySource
from ..props.formula import has
from ..props.kinds import AT_THE_END, EVERY_BOUNDARY, KINDS, OBLIGATIONS, THREE_VALUED
from ..props.parse import Property, parse_property, shared_atoms

#: The verdicts an event carries (llfsm_msgs/msg/MonitorEvent's constants).
VIOLATED, SATISFIED, PENDING, HELD, NOT_SEEN = "violated", "satisfied", "pending", "held", "not_seen"


class MonitorError(ValueError):
    """A property the monitor cannot judge (one line; a usage error, status 2)."""


def property_source(text: str, option: str = "--monitor-property") -> PropertySource:
    """`--monitor-property KIND:TEXT` (or bag check's `--property`)."""
    kind, sep, body = text.partition(":")
    if not sep or kind.strip() not in KINDS:
        raise MonitorError(f"{option} {text!r}: write KIND:TEXT, KIND one of {', '.join(KINDS)}")
    return PropertySource(kind.strip(), body.strip(), where=option)


@dataclass(frozen=True)
class Read:
    """One thing an atom reads of a machine: its state, `suspended`, `finished`, or a variable
    or input by name."""

    machine: int
    what: str  # "_state", "_suspended", "_finished", or a variable's name


def atom_reads(atom: Atom) -> set[Read]:
    """What an atom reads (from its rewritten tree: `M[k].attr`)."""
    out: set[Read] = set()
    if atom.tree is None:
        return out
    for node in ast.walk(atom.tree):
        if (
            isinstance(node, ast.Attribute)
            and isinstance(node.value, ast.Subscript)
            and isinstance(node.value.value, ast.Name)
            and node.value.value.id == "M"
            and isinstance(node.value.slice, ast.Constant)
            and node.attr != "STATES"
        ):
            index = node.value.slice.value
            assert isinstance(index, int)  # the atom compiler writes M[k] with k an int
            out.add(Read(index, node.attr))
    return out


class Judged:
    """One property as it is followed over the boundaries."""

    def __init__(self, index: int, prop: Property, atoms: list[int]) -> None:
        self.index = index
        self.prop = prop
        self.atoms = atoms  # the global number of each of its atoms
        self.mode = prop.spec.monitor
        self.decided_by = prop.spec.decided_by  # a safety atom's value that violates it
        self.done = False  # decided for good (violated, satisfied, or seen)
        self.seen = False  # reachable / eventually: its condition held at some boundary
        self.pending: tuple[int, Boundary] | None = None  # leads_to: (run time, where) of the oldest A
        self.verdict3 = Verdict3(prop.formula, f"{prop.where}: {prop.text}") if self.mode == THREE_VALUED else None
        self.state3: bool | None = None
        #: an LTL formula with X counts boundaries, so it must see every one (others are
        #: unchanged by a boundary where none of their atoms changes: stutter-invariant)
        self.counts_steps = self.mode == THREE_VALUED and has(prop.formula, "X")

    @property
    def safety(self) -> bool:
        return self.mode == EVERY_BOUNDARY


class Boundary:
    """Where a verdict was reached: a ringlet boundary, counted from 1 over the run (0: before the
    first ringlet), or a bag's message.  The count may be known only later (a plain round loop
    counts its rounds when it ends): `number` is then filled in by the caller before anything
    is said."""

    __slots__ = ("machine", "number", "offset", "unit")

    def __init__(self, number: int | None = None, machine: Any = None, offset: int = 0, unit: str = "ringlet") -> None:
        self.number = number
        self.machine = machine  # the machine whose ringlet just ended (or is about to start)
        self.offset = offset  # 1: after that machine's ringlet, 0: before it
        self.unit = unit

    def __str__(self) -> str:
        return f"{self.unit} {self.number if self.number is not None else '?'}"


@dataclass
class Verdict:
    """A property's verdict at a boundary: what a violation line, a /llfsm/monitor message and
    the page's mark say."""

    judged: Judged
    verdict: str
    time_ns: int
    where: Boundary
    #: a leads_to's A: when and where it held (a missed deadline, an obligation pending at the end)
    since: tuple[int, Boundary] | None = None
    #: filled by whoever knows the run: every machine's state, the variables the property names
    states: list[tuple[str, str]] = field(default_factory=list)
    variables: str = ""
    #: the machines the property reads, by name
    reads: list[str] = field(default_factory=list)

    @property
    def name(self) -> str:
        return self.judged.prop.name

    @property
    def detail(self) -> str:
        if self.since is None:
            return "neither violated nor satisfied so far" if self.verdict == PENDING else ""
        at = f"A held at {self.since[0] / 1e9:.3f} s"
        if self.verdict == PENDING:
            return f"{at}, B not yet"
        return f"{at}, {self.since[1]}, and B has not come within the deadline"

    def line(self) -> str:
        """The stderr line (docs/monitor.md)."""
        if self.verdict != VIOLATED:
            shown = {
                PENDING: f"pending at the end ({self.detail})",
                SATISFIED: "satisfied",
                HELD: "held at some boundary",
                NOT_SEEN: "not seen in this run",
            }[self.verdict]
            return f"llfsm: monitor: {self.name}: {shown}"
        states = ", ".join(f"{m} {s}" for m, s in self.states)
        variables = f"; {self.variables}" if self.variables else ""
        detail = f" ({self.detail})" if self.detail else ""
        at = f"{self.time_ns / 1e9:.3f} s, {self.where}{detail}"
        return f"llfsm: monitor: {self.name} violated at {at}: {states}{variables}"

    def as_dict(self) -> dict[str, Any]:
        """As the web page's snapshot and bag check's JSON carry it (docs/view.md, "violations")."""
        p = self.judged.prop
        return {
            "property": p.name,
            "kind": p.kind,
            "text": p.text,
            "verdict": self.verdict,
            "time": self.time_ns / 1e9,
            self.where.unit: self.where.number,
            "states": dict(self.states),
            "reads": self.reads,
            "variables": self.variables,
            "detail": self.detail,
        }


class Judge:
    """Parses properties over an arrangement's machines and judges them at boundaries."""

    def __init__(
        self,
        sources: Sequence[PropertySource],
        infos: dict[str, MachineInfo],
        say: Callable[[str], None],
    ) -> None:
        self.say = say
        self.atoms: list[Atom] = []
        self.judged: list[Judged] = []
        by_text: dict[str, int] = {}
        for src in sources:
            try:
                prop, local = parse_property(src.kind, src.text, infos, src.name, src.where, src.within)
            except PropertyError as e:
                raise MonitorError(str(e)) from None
            if prop.spec.monitor is None:
                raise MonitorError(f"{src.where}: {prop.kind}: not judged on a run: {prop.spec.monitor_refusal}")
            ids = shared_atoms(local, self.atoms, by_text)
            try:
                self.judged.append(Judged(len(self.judged), prop, ids))
            except PropertyError as e:
                raise MonitorError(str(e)) from None
        self._said: set[int] = set()
        #: leads_to obligations with a deadline are open (the caller judges every boundary then)
        self.deadlines_open = 0

    def topics_named(self) -> set[str]:
        """The topics the properties' `published(...)` name (`"/t" in E` in an atom's tree)."""
        out: set[str] = set()
        for a in self.atoms:
            if a.reads_published and a.tree is not None:
                for node in ast.walk(a.tree):
                    if (
                        isinstance(node, ast.Compare)
                        and isinstance(node.left, ast.Constant)
                        and isinstance(node.comparators[0], ast.Name)
                        and node.comparators[0].id == "E"
                    ):
                        out.add(str(node.left.value))
        return out

    def value(self, k: int, machines: Sequence[Any], published: Any) -> bool:
        """Atom k now; an atom that cannot be evaluated counts as false, said once."""
        a = self.atoms[k]
        try:
            return bool(a.fn(machines, published))
        except Exception as e:
            self.failed(k, e)
            return False

    def failed(self, k: int, e: BaseException) -> None:
        if k not in self._said:
            self._said.add(k)
            a = self.atoms[k]
            self.say(f"llfsm: monitor: {a.where}: `{a.text}` could not be evaluated: {type(e).__name__}: {e}")

    def boundary(
        self,
        machines: Sequence[Any],
        published: Any,
        now: int,
        where: Callable[[], Boundary],
        which: Sequence[Judged] | None = None,
    ) -> list[Verdict]:
        """Judge the properties (`which`, by default all) at one boundary; the violations found.
        `where()` says which boundary, asked only for a verdict or a leads_to's A (a monitor
        numbers boundaries only when it must)."""
        out: list[Verdict] = []
        values: dict[int, bool] = {}
        atoms = self.atoms
        for j in self.judged if which is None else which:
            if j.done:
                continue
            if j.safety:  # the common case, without the general step's lists
                k = j.atoms[0]
                try:
                    x = bool(atoms[k].fn(machines, published))
                except Exception as e:
                    self.failed(k, e)
                    x = False
                if x == j.decided_by:
                    j.done = True
                    out.append(Verdict(j, VIOLATED, now, where()))
                continue
            v = []
            for k in j.atoms:
                known = values.get(k)
                if known is None:
                    known = values[k] = self.value(k, machines, published)
                v.append(known)
            found = self.step(j, v, now, where)
            if found is not None:
                out.append(found)
        return out

    def step(self, j: Judged, v: list[bool], now: int, where: Callable[[], Boundary]) -> Verdict | None:
        """Judge one property with its atoms' values `v`; a violation, or None."""
        since = None
        if j.mode == EVERY_BOUNDARY:
            if v[0] != j.prop.spec.decided_by:
                return None
            j.done = True
        elif j.mode == OBLIGATIONS:
            held_a, held_b = v
            within = j.prop.within
            if j.pending is not None and within is not None and now - j.pending[0] > within:
                j.done = True  # the deadline passed: B came too late, or not yet
                self.deadlines_open -= 1
                since = j.pending
            elif held_b:
                if j.pending is not None and within is not None:
                    self.deadlines_open -= 1
                j.pending = None
                return None
            elif held_a and j.pending is None:
                j.pending = (now, where())
                if within is not None:
                    self.deadlines_open += 1
                return None
            else:
                return None
        elif j.mode == THREE_VALUED:
            assert j.verdict3 is not None
            j.state3 = j.verdict3.step(sum(1 << n for n, a in enumerate(j.verdict3.atoms) if v[a]))
            if j.state3 is None:
                return None
            j.done = True
            if j.state3:
                return None  # satisfied whatever follows
        else:  # AT_THE_END
            if v[0]:
                j.seen = j.done = True
            return None
        return Verdict(j, VIOLATED, now, where(), since)

    def at_end(self, now: int, where: Boundary) -> list[Verdict]:
        """What is answered at the end: pending obligations and formulas, satisfied formulas,
        reachable/eventually held or not seen."""
        out = []
        for j in self.judged:
            if j.mode == AT_THE_END:
                out.append(Verdict(j, HELD if j.seen else NOT_SEEN, now, where))
            elif j.mode == OBLIGATIONS and not j.done and j.pending is not None:
                out.append(Verdict(j, PENDING, now, where, j.pending))
            elif j.mode == THREE_VALUED and not j.done:
                out.append(Verdict(j, PENDING, now, where))
            elif j.mode == THREE_VALUED and j.state3:
                out.append(Verdict(j, SATISFIED, now, where))
        return out
