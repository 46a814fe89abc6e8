"""One verification: the arrangement explored once, every property judged on it.

Safety (`always`, `never`) and `reachable` are judged as each new configuration is found, so a
failing `always` has a shortest counterexample and the exploration stops early when nothing is
left to judge; liveness (`eventually`, `leads_to`, `ltl:`) and `ctl:` are judged on the explored
structure afterwards (llfsm.verify.ltl, llfsm.verify.ctl).
"""

from __future__ import annotations

import itertools
import math
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from ..props.atoms import Atom, PropertyError
from ..props.automaton import Automaton
from ..props.formula import core, neg
from ..props.kinds import CTL as BY_CTL
from ..props.kinds import ON_THE_FLY
from ..props.parse import Property, duration_text, parse_property, shared_atoms
from ..runtime.errors import report_for
from .ctl import CTL
from .environment import EnvironmentError_
from .explorer import AtomError, Explorer, Loaded, MachineError, Options, StateLimit, Step
from .load import PropertySource, VerifyError, machine_infos
from .ltl import ProductLimit, Structure, check_ltl
from .snapshot import VariableValueError
from .step import VerifyError_, input_product_refusal
from .store import TURN, MemoryLimit


@dataclass
class Trace:
    """A counterexample (or a witness): the steps from the initial configuration, and for a
    lasso the step at which the loop starts (the last configuration steps back to it)."""

    configs: list[int]
    steps: list[tuple[tuple[Any, ...], Step | None]]
    loop: int | None = None


@dataclass
class Outcome:
    prop: Property
    verdict: str  # holds | fails | unknown
    seconds: float = 0.0
    trace: Trace | None = None
    why: str | None = None  # for unknown: why it was not decided; for a CTL failure without a trace


@dataclass
class Verification:
    """Everything `llfsm verify` reports."""

    loaded: Loaded
    explorer: Explorer | None
    outcomes: list[Outcome] = field(default_factory=list)
    configurations: int = 0
    steps: int = 0
    seconds: float = 0.0
    partial: str | None = None  # interrupted | state limit | memory bound
    #: at the memory bound: (bytes in use when it was seen, the bound)
    memory: tuple[int, int] | None = None
    growing: list[str] = field(default_factory=list)
    error: str | None = None  # machine code raised: the report, with the path to it
    error_trace: Trace | None = None
    #: what the user should know about the result (a replay that did not give the same path)
    warnings: list[str] = field(default_factory=list)
    #: configurations past a bound of the verification file, not explored further
    cut: int = 0
    #: at a limit in exact time: what grew and the coarsest --period that keeps every threshold exact
    hint: str | None = None

    @property
    def status(self) -> int:
        if self.error is not None or any(o.verdict == "fails" for o in self.outcomes):
            return 1
        if self.partial in ("state limit", "memory bound"):
            return 3
        if self.partial == "interrupted":
            return 130
        return 0


def verify(
    loaded: Loaded,
    sources: list[PropertySource],
    options: Options,
    progress: Callable[[int, int, float], None] | None = None,
    keep_graph: bool = False,
    judging: Callable[[str, int, int, float], None] | None = None,
) -> Verification:
    """Explore `loaded` and judge each property; bad properties raise VerifyError (status 2).
    `progress` is told how the exploration goes, `judging(property, product states, automaton
    states, seconds)` how an `ltl:` judgement on the structure goes, about once a second."""
    infos = machine_infos(loaded)
    props: list[Property] = []
    atoms: list[Atom] = []
    atom_ids: list[list[int]] = []  # per property, the global number of each of its atoms
    by_text: dict[str, int] = {}
    for src in sources:
        try:
            prop, local = parse_property(src.kind, src.text, infos, src.name, src.where, src.within)
        except PropertyError as e:
            raise VerifyError(str(e)) from None
        props.append(prop)
        atom_ids.append(shared_atoms(local, atoms, by_text))
    if len(atoms) > 64:
        raise VerifyError(f"the properties name {len(atoms)} different conditions; at most 64 in one verification")
    automata: dict[int, Automaton] = {}
    for n, p in enumerate(props):  # built (and bounded) before anything is explored
        if p.within is not None:
            if options.period is None:
                raise VerifyError(
                    f"{p.where}: {p.kind} within {p.within / 1e9:g} s: a deadline needs exact time (--period P, or "
                    "`period:` in the verification file): abstract time lets any time pass between two ringlets, "
                    "so no deadline can hold there"
                )
            if options.hash_compact:
                raise VerifyError(
                    f"{p.where}: a deadline (within) is judged on the configurations kept: not with --hash-compact"
                )
            continue
        if p.spec.verify not in (ON_THE_FLY, BY_CTL):
            try:
                automata[n] = Automaton(core(neg(p.formula)), text=f"{p.where}: {p.kind}: `{p.text}`")
            except PropertyError as e:
                raise VerifyError(str(e)) from None
    refusal = input_product_refusal(loaded, options.max_states)
    if refusal is not None:
        raise VerifyError(refusal)
    needs_graph = keep_graph or any(p.spec.verify != ON_THE_FLY for p in props)
    options.graph = needs_graph
    try:
        explorer = Explorer(loaded, options, [a.fn for a in atoms])
    except (VariableValueError, EnvironmentError_, VerifyError_) as e:
        raise VerifyError(str(e)) from None
    except VerifyError:
        raise
    except BaseException as exc:  # a variable's initial value raised: machine code may raise anything
        if isinstance(exc, KeyboardInterrupt | MemoryError):
            raise
        rep = report_for(exc)
        if rep is None:
            raise
        err = VerifyError("a machine's variables raised while they were set", status=1)
        err.details = rep.format()
        raise err from None
    explorer.progress = progress
    result = Verification(loaded, explorer)

    # safety, judged on each new configuration
    first_bad: dict[int, int] = {}  # property -> the first configuration that decides it
    pending = {  # the property -> (the atom's value that decides it, its bit)
        n: (int(p.spec.decided_by), atom_ids[n][0]) for n, p in enumerate(props) if p.spec.verify == ON_THE_FLY
    }

    def on_new(idx: int) -> bool:
        if not pending:
            return True
        lab = explorer.labels[idx]
        for n, (deciding, bit) in list(pending.items()):
            if lab >> bit & 1 == deciding:
                first_bad[n] = idx
                del pending[n]
        return bool(pending) or needs_graph

    explorer.on_new = on_new if pending else None
    start = time.monotonic()
    try:
        explorer.explore()
    except MemoryLimit as e:
        result.partial = "memory bound"
        result.memory = (e.used, explorer.meter.bound)
        result.growing = growing_variables(explorer)
    except StateLimit:
        result.partial = "state limit"
        result.growing = growing_variables(explorer)
    except MemoryError:  # past the bound between two looks: what is left is enough to say so
        result.partial = "memory bound"
        result.memory = (explorer.meter.bound, explorer.meter.bound)
        result.growing = growing_variables(explorer)
    except KeyboardInterrupt:
        result.partial = "interrupted"
    except VariableValueError as e:
        raise VerifyError(str(e)) from None
    except AtomError as e:
        a = atoms[e.atom]
        raise VerifyError(f"{a.where}: `{a.text}` could not be evaluated: {e}") from None
    except MachineError as e:
        rep = report_for(e.exc)
        result.error = rep.format() if rep is not None else f"{type(e.exc).__name__}: {e.exc}"
        path = explorer.path_to(e.config)
        choices = [explorer.choice[c] for c in path[1:]] + [e.choice]
        try:
            steps = explorer.replay(choices[:-1])
        except Exception:  # the path cannot be rebuilt: the report alone
            steps = []
        result.error_trace = Trace(path, steps)
    result.seconds = time.monotonic() - start
    for cls in loaded.classes:  # SPEC 12: set from outside at run time, which nothing here does
        names = [name for name, _kind in cls.PARAMETERS]
        if names:
            result.warnings.append(
                f"{cls.NAME}: its parameters ({', '.join(names)}) kept their initial values in the exploration; "
                "a run may set them from outside (llfsm param set): make what may change an input to explore it"
            )
    result.configurations = explorer.count
    result.steps = explorer.steps
    result.cut = explorer.cut
    if result.partial in ("state limit", "memory bound") and options.period is not None:
        result.hint = waiting_hint(loaded, options.period)
    explored = time.monotonic()

    structure: Structure | None = None
    ctl: CTL | None = None
    for n, prop in enumerate(props):
        t0 = time.monotonic()
        out = Outcome(prop, "unknown")
        if prop.spec.verify == ON_THE_FLY:
            idx = first_bad.get(n)
            if prop.spec.witness:
                out.verdict = "holds" if idx is not None else "fails"
                if idx is not None:
                    out.trace = _trace(explorer, explorer.path_to(idx))
            elif idx is not None:
                out.verdict = "fails"
                out.trace = _trace(explorer, explorer.path_to(idx))
            else:
                out.verdict = "holds"
            if (result.partial or result.error) and idx is None:
                out.verdict = "unknown"
        elif result.partial is None and result.error is None:
            if structure is None:
                structure = _structure(explorer)
            if prop.within is not None:
                missed = _deadline_missed(explorer, atom_ids[n], prop.within // (options.period or 1))
                out.verdict = "holds" if missed is None else "fails"
                if missed is not None:
                    out.trace = _trace(explorer, missed)
            elif prop.spec.verify == BY_CTL:
                if ctl is None:
                    ctl = CTL(structure, list(range(len(atoms))))
                out.verdict, out.trace, out.why = _judge_ctl(explorer, ctl, prop, atom_ids[n])
            else:
                told = None
                if judging is not None:
                    t_start = time.monotonic()

                    def told(nodes: int, states: int, name: str = prop.name, t_start: float = t_start) -> None:
                        judging(name, nodes, states, time.monotonic() - t_start)

                try:
                    lasso = check_ltl(
                        structure, automata[n], atom_ids[n], told, max_nodes=options.max_states * 4,
                        memory_ok=explorer.memory_ok,
                    )  # fmt: skip
                except PropertyError as e:  # the automaton passed its bound while the product grew
                    raise VerifyError(str(e)) from None
                except ProductLimit as e:
                    lasso = None
                    out.verdict, out.why = "unknown", str(e)
                else:
                    out.verdict = "holds" if lasso is None else "fails"
                if lasso is not None:
                    out.trace = _trace(explorer, lasso.path, lasso.loop)
        if out.trace is not None and not _replays(explorer, out.trace):
            result.warnings.append(
                f"{prop.name}: its path, run again, did not give the configurations explored: the machines "
                "read something verify does not keep (a global of a helper module?), so the result may be wrong"
            )
        out.seconds = (explored - start) + (time.monotonic() - t0)
        if out.verdict == "unknown" and out.why is None:
            out.why = result.partial or "machine code raised before it was decided"
        result.outcomes.append(out)
    result.seconds = time.monotonic() - start  # exploring and judging: the whole check
    return result


def _structure(explorer: Explorer) -> Structure:
    return Structure(explorer.count, explorer.edges_of, explorer.labels, explorer.fair, explorer.n)


def _trace(explorer: Explorer, path: list[int], loop: int | None = None) -> Trace:
    choices = [explorer.choice_between(a, b) for a, b in itertools.pairwise(path)]
    if loop is not None:  # the step back to the loop's start
        choices.append(explorer.choice_between(path[-1], path[loop]))
    return Trace(path, explorer.replay(choices), loop)


def _replays(explorer: Explorer, trace: Trace) -> bool:
    """Whether running the path again gave the configurations the exploration stored (exact
    storage only: with hash compaction nothing is kept to compare)."""
    if explorer.options.hash_compact:
        return True
    got = [config for config, _step in trace.steps]
    return got == [explorer.configs[c] for c in trace.configs] + (
        [explorer.configs[trace.configs[trace.loop]]] if trace.loop is not None else []
    )


def _judge_ctl(explorer: Explorer, ctl: CTL, prop: Property, ids: list[int]) -> tuple[str, Trace | None, str | None]:
    """(verdict, trace, why) of a CTL property: a trace for AG f (a shortest path to where f
    fails) and EF f (to where it holds); other forms say only where they fail."""
    ctl.atom_ids = ids
    sat = ctl.sat(prop.formula)
    if sat[0]:
        if prop.formula[0] == "E" and prop.formula[1][0] == "F":
            inner = ctl.sat(prop.formula[1][1])
            target = _nearest(explorer, inner)
            return "holds", (_trace(explorer, explorer.path_to(target)) if target is not None else None), None
        return "holds", None, None
    if prop.formula[0] == "A" and prop.formula[1][0] == "G":
        inner = ctl.sat(prop.formula[1][1])
        target = _nearest(explorer, bytearray(1 - x for x in inner))
        if target is not None:
            return "fails", _trace(explorer, explorer.path_to(target)), None
    return "fails", None, "it does not hold in the initial configuration"


def _nearest(explorer: Explorer, where: bytearray) -> int | None:
    """The configuration of `where` nearest the initial one: the first in breadth-first order."""
    found = where.find(1)
    return found if found >= 0 else None


def growing_variables(explorer: Explorer) -> list[str]:
    """The variables whose values kept growing: those with the most distinct values among the
    configurations stored (each with its range, for numbers), most first."""
    out: list[tuple[int, str]] = []
    for i, codec in enumerate(explorer.codecs):
        if explorer.options.hash_compact:
            parts = [explorer.part(c, i) for _idx, c in explorer.frontier]
        else:
            parts = explorer.part_list[i]
        if not parts:
            continue
        for k, name in enumerate(codec.shown_names):
            values = {p[codec.first_variable + k] for p in parts}
            if len(values) < 16:
                continue
            nums = [v for v in values if isinstance(v, int | float) and not isinstance(v, bool)]
            span = f", from {min(nums)} to {max(nums)}" if len(nums) == len(values) else ""
            unit, sizes = _sizes(values)
            grew = max(sizes) - min(sizes)
            if grew > 4:  # in size as well as in value: a list that keeps growing
                span += f", in size from {min(sizes):,} to {max(sizes):,} {unit}"
            out.append((len(values), f"{explorer.machines[i].NAME}.{name} ({len(values):,} values{span})"))
    out.sort(key=lambda x: -x[0])
    return [text for _n, text in out[:5]]


def _sizes(values: set[Any]) -> tuple[str, list[int]]:
    """The sizes of a variable's values and what they count: the characters of text, the bytes
    of bytes (a 12 MB blob is 12,000,000 bytes), else the items of what it holds (None aside)."""
    kinds = {type(v) for v in values if v is not None}
    if kinds == {str}:
        return "characters", [len(v) for v in values if v is not None]
    if kinds == {bytes}:
        return "bytes", [len(v) for v in values if v is not None]
    return "items", [_items(v) for v in values]


def _items(value: Any) -> int:
    """How many items a frozen value holds, all the way down (a scalar, a text, bytes: 1)."""
    if isinstance(value, tuple):  # tuples and Frozen (lists, dicts, messages: their kind first)
        return sum(_items(v) for v in value[1:]) if type(value) is not tuple else sum(_items(v) for v in value)
    return 1


def _deadline_missed(explorer: Explorer, ids: list[int], rounds: int) -> list[int] | None:
    """`leads_to: [A, B]` within a deadline of `rounds` periods, in exact time: a shortest path to
    where B has not come `rounds` periods after A, or None.  Breadth first over the
    configurations paired with the age (in periods) of the oldest A not yet answered by B, and
    whether the next ringlet starts a new round (the turn wrapped, or the run has ended: time
    goes on), which is when the clock moves on by a period.  A configuration's time is that of
    the round whose ringlet reached it."""
    a, b = ids
    labels, configs = explorer.labels, explorer.configs

    def after(c: int, age: int | None) -> int | None:
        if labels[c] >> b & 1:
            return None
        return 0 if age is None and labels[c] >> a & 1 else age

    Node = tuple[int, int | None, bool]
    start: Node = (0, after(0, None), False)  # the first ringlet is round 0's: time 0
    parent: dict[Node, Node | None] = {start: None}
    queue = deque([start])
    while queue:
        node = queue.popleft()
        c, age, new_round = node
        tc = configs[c][TURN]
        for d in set(explorer.edges_of(c)):
            td = configs[d][TURN]
            aged = None if age is None else age + new_round
            if aged is not None and aged > rounds:  # B came too late, or not at all
                path = [d]
                back: Node | None = node
                while back is not None:
                    path.append(back[0])
                    back = parent[back]
                return path[::-1]
            nxt: Node = (d, after(d, aged), td < 0 or td <= tc)
            if nxt not in parent:
                parent[nxt] = node
                queue.append(nxt)
    return None


def waiting_hint(loaded: Loaded, period: int) -> str | None:
    """In exact time each period waited in a state is a configuration of its own: what waits
    longest (its largest threshold / the period), and the coarsest period that keeps every
    threshold exact (their greatest common divisor), when it is coarser than this one."""
    waits = []
    thresholds = []
    for cls, per in zip(loaded.classes, loaded.cuts, strict=True):
        for state, cuts in enumerate(per):
            thresholds += [c for c in cuts if c > 0]
            if cuts and cuts[-1] // period >= 10:
                waits.append((cuts[-1] // period, f"{cls.NAME} {cls.STATES[state]} {cuts[-1] // period:,}"))
    if not waits:
        return None
    waits.sort(reverse=True)
    coarsest = math.gcd(*thresholds)
    said = "; ".join(text for _n, text in waits[:4])
    out = f"waiting is what grew: in exact time each period waited is a configuration (threshold / period: {said})"
    if coarsest > period:
        out += f"; --period {duration_text(coarsest)} keeps every after* threshold exact"
    return out
