"""One step of an exploration: a ringlet of the machine whose turn it is, run on the machine
objects with one choice of inputs, time and interrupt (SPEC 11; docs/verify.md).

What runs is what is explored: the arrangement is made as `llfsm run` makes it (the scheduler's
own `Arrangement`, its gate applying commands exactly as in a run), and a step calls the
scheduler's entry point of the machine whose turn it is, `m._run(m)`, on the machine objects,
after putting the configuration's values back into them (llfsm.verify.snapshot).

A step is one ringlet with one choice of: the values of the machine's inputs (every valuation of
their domains), how much time has passed in its state (abstract time: any interval from the one
it is in), and with `--interrupt` whether `ros.ok()` falls before it.  Choices are numbered in a
fixed order, so a path is a list of choice numbers and is replayed exactly (`Explorer.replay`);
choices.py makes them.

Time.  Abstract (the default): a state's `after*` thresholds (constants: llfsm.verify.refuse)
cut the time since it was entered into intervals; at each ringlet not entering the state the
machine may be in its interval or any later one; entering resets it.  A representative time of
the interval is put on the clock (`after*` then answers as in any run with that timing), so the
run-time `after` is untouched.  `--period P`: each round advances the clock by P; a machine's
time in its state is kept exactly, capped just past its state's largest threshold.

Finite runs: a configuration in which the run has ended (every machine finished, or every one
left suspended) steps to itself, with nothing published, forever.
"""

from __future__ import annotations

import bisect
import io
import sys
from array import array
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from ..runtime.clock import SimClock
from ..runtime.context import RunContext, activate
from ..runtime.inputs import DEFAULT, TOPIC
from ..runtime.machine import RESUME, Machine
from ..runtime.scheduler import Arrangement
from ..runtime.trace import Tracer
from .choices import Choices, Valuations
from .choices import input_product_refusal as input_product_refusal  # named here as before
from .environment import Declaring, World
from .snapshot import FINISHED, PENDING, STATE, SUSPENDED, Codec
from .store import (
    FIRST_ROUND,
    GLOBALS,
    INITIALISED,
    INTERRUPTED,
    LIVE,
    NODES,
    PARTS,
    PUBLISHED,
    SHUT,
    TIMES,
    TURN,
    Loaded,
    Options,
    Store,
)
from .values import Frozen, Handles


class _Recorder(Tracer):
    """What the scheduler reports of one step being described: entries and commands."""

    def __init__(self) -> None:
        super().__init__()
        self.entered: list[tuple[int, int]] = []
        self.commands: list[tuple[str, int, int]] = []

    def entry(self, m: Machine, state: int) -> None:
        self.entered.append((m._id, state))

    def command(self, kind: str, m: Machine, state: int) -> None:
        self.commands.append((kind, m._id, state))


class MachineError(Exception):
    """Machine code raised during a step (the report is llfsm.runtime.errors's)."""

    def __init__(self, exc: BaseException, config: int, choice: int) -> None:
        super().__init__(str(exc))
        self.exc = exc
        self.config = config
        self.choice = choice


class AtomError(Exception):
    """An atom of a property raised while it was evaluated (which one, and the exception)."""

    def __init__(self, atom: int, exc: Exception) -> None:
        super().__init__(f"{type(exc).__name__}: {exc}")
        self.atom = atom
        self.exc = exc


class _Null(io.TextIOBase):
    """Where machine code's printing goes while exploring (every path prints, in any order)."""

    def write(self, s: str) -> int:
        return len(s)

    def writable(self) -> bool:
        return True


@dataclass
class Step:
    """What one step did, for a counterexample (made only when a path is replayed)."""

    machine: int
    choice: int
    state: int  # the machine's state before the ringlet
    inputs: dict[str, Any]
    interval: str | None  # the time choice, as a person reads it
    interrupted: bool  # ros.ok() fell before this ringlet
    entered: list[tuple[int, int]]  # (machine, state) whose OnEntry ran, in order
    transition: int | None  # the index of the transition that fired, or None
    commands: list[tuple[str, int, int]]  # (command, machine, state) applied
    published: frozenset[str]
    changed: dict[str, tuple[Any, Any]]  # variable -> (before, after), of any machine
    round: int  # the round the ringlet ran in (counted from 0 along the path)
    finished: bool  # the machine finished in this ringlet
    environment: list[str] = field(default_factory=list)  # what the environment chose, in order


class VerifyError_(ValueError):
    """A verification file's bound that names no variable (one line)."""


class Stepper(Store):
    """The machine objects of one arrangement, on the bus verify makes, and the steps between
    configurations (`step`, and `replay` of a path)."""

    def __init__(
        self,
        loaded: Loaded,
        options: Options,
        atoms: Sequence[Callable[[Sequence[Machine], frozenset[str]], bool]] = (),
    ) -> None:
        self.loaded = loaded
        self.atoms = list(atoms)
        if len(self.atoms) > 64:
            raise ValueError("at most 64 atoms in the properties of one verification")
        Store.__init__(self, options, len(loaded.classes), len(atoms))
        self.ctx = RunContext(SimClock(options.period or 1_000_000))
        self.clock = self.ctx.clock
        if loaded.environment and loaded.environment.services and not options.generic:
            self.ctx.transport = Declaring(set(loaded.environment.services))  # clients of declared services
        self.stdout = _Null()
        prev = activate(self.ctx)
        try:
            from ..ros.bus import bus_of  # deferred: start-up (verify imports the bus when it explores)

            self.bus = bus_of(self.ctx)
            self.bus.log_stream = self.stdout  # type: ignore[assignment]  # a text stream that keeps nothing
            self.published: set[str] = set()
            self.bus.add_tap(self._tap)
            arr = Arrangement(loaded.classes, context=self.ctx)
        finally:
            activate(prev)
        self.arr = arr
        self.machines: list[Machine] = arr.machines
        #: the environment a verification file declares (llfsm.verify.environment), on the bus
        self.world = World(loaded.environment, self.bus, direct=not options.generic) if loaded.environment else None
        self.edge_choice = array("L")  # with an environment: each edge's choice number
        # the bus as the machines found it (nodes their initialisers made stay, as in a run)
        self.base_nodes = list(self.bus.nodes)
        self.base_services = dict(self.bus.services)
        self.node_objects: dict[str, Any] = {}
        self.node_services: dict[str, dict[str, Any]] = {}
        self.nodes_on_bus: frozenset[str] = frozenset()
        self.nodes_count = len(self.bus.nodes)
        self.handles = Handles()
        self.codecs = [
            Codec(cls, model, arr._gate_fn, self.handles)
            for cls, model in zip(loaded.classes, loaded.models, strict=True)
        ]
        #: a verification file's bounds: (machine, position in its part, the largest value explored on)
        self.bounds: list[tuple[int, int, float]] = []
        for key, bound in loaded.bounds.items():
            name, _, var = key.partition(".")
            k = next((k for k, c in enumerate(loaded.classes) if name == c.NAME), None)
            codec = self.codecs[k] if k is not None else None
            if codec is None or var not in codec.shown_names:
                raise VerifyError_(f"bounds: {key}: no machine {name} with a variable {var}")
            self.bounds.append((k, codec.first_variable + codec.shown_names.index(var), bound))  # type: ignore[arg-type]
        #: configurations past a bound, not explored further
        self.cut = 0
        # per machine: input names, domains, which are bound (their first round takes the default)
        self.input_names = [c.inputs for c in self.codecs]
        self.domains: list[Valuations] = []
        self.first_round_domains: list[Valuations] = []
        for cls in loaded.classes:
            self.domains.append(Valuations([tuple(entry[3]) for entry in cls.INPUTS]))
            first = [(entry[DEFAULT],) if entry[TOPIC] is not None else tuple(entry[3]) for entry in cls.INPUTS]
            self.first_round_domains.append(Valuations(first))
        self.cuts = loaded.cuts
        # abstract time: a representative time of each interval of each state
        self.reps = [[(0, *(c + 1 for c in cuts)) for cuts in per] for per in self.cuts]
        self.period = options.period
        if self.period is not None:
            p = self.period
            self.caps = [[(cuts[-1] // p + 1) * p if cuts else 0 for cuts in per] for per in self.cuts]
        # what each machine object holds now (an id in its table, or -1: changed since)
        self.cur: list[Any] = [-1] * self.n
        self.cur_g: Any = -1
        self.c0: tuple[Any, ...] = ()  # the initial configuration, once explored

    # -- the bus's tap: what a step publishes ----------------------------------------------------
    def _tap(self, topic: Any) -> None:
        name = topic.name
        published = self.published
        topic.taps.append(lambda _msg: published.add(name))

    # -- putting a configuration into the machine objects ---------------------------------------
    def load(self, config: tuple[Any, ...]) -> None:
        hc = self.options.hash_compact
        for i in range(self.n):
            p = config[PARTS + i]
            if self.cur[i] is not p if hc else self.cur[i] != p:
                self.codecs[i].restore(self.machines[i], p if hc else self.part_list[i][p])
                self.cur[i] = p
        g = config[GLOBALS]
        if self.cur_g != g:
            self._set_globals(self.glist[g])
            self.cur_g = g

    def _set_globals(self, gv: tuple[Any, ...]) -> None:
        self.bus.initialised, self.bus.shut, self.ctx.interrupted = gv[INITIALISED], gv[SHUT], gv[INTERRUPTED]
        if gv[NODES] != self.nodes_on_bus:
            self._put_nodes(gv[NODES])

    # -- the nodes machine code made: part of the globals, put back on the bus -----------------
    def _put_nodes(self, names: frozenset[str]) -> None:
        """The bus as a run that made the nodes `names` has it: those nodes and their services
        (their parameter services), no other made by machine code."""
        bus = self.bus
        bus.nodes[:] = self.base_nodes + [self.node_objects[n] for n in sorted(names)]
        bus.services.clear()
        bus.services.update(self.base_services)
        for n in names:
            bus.services.update(self.node_services[n])
        self.nodes_on_bus = names
        self.nodes_count = len(bus.nodes)

    def _nodes_made(self) -> frozenset[str]:
        """After a step that made nodes: the names of the nodes on the bus now (the first node
        made under each name, with its services, is the one put back for it later)."""
        bus = self.bus
        names = set(self.nodes_on_bus)
        for node in bus.nodes[self.nodes_count :]:
            name = node.get_fully_qualified_name()
            if name not in self.node_objects:
                self.node_objects[name] = node
                self.node_services[name] = {k: v for k, v in bus.services.items() if getattr(v, "node", None) is node}
            names.add(name)
        made = frozenset(names)
        self.nodes_on_bus = made
        self.nodes_count = len(bus.nodes)
        return made

    # -- the choices of a step ------------------------------------------------------------------
    def choices(self, config: tuple[Any, ...]) -> Choices:
        """(input values, time, interrupt now) for each choice of the step from `config`, in
        order; time: the abstract interval chosen, or the exact time in the state."""
        i = config[TURN]
        part = self.part(config, i)
        g = self.globals_of(config)
        first_round = self.period is not None and g[FIRST_ROUND]
        valuations = self.first_round_domains[i] if first_round else self.domains[i]
        t = self.times_of(config)[i]
        if self.period is None:
            state = part[STATE]
            cuts = self.cuts[i][state]
            # an ordinary ringlet follows: no command, or a resume of a machine not suspended
            ordinary = part[PENDING] is None or part[PENDING] == RESUME
            if cuts and ordinary and not part[SUSPENDED] and not self.codecs[i].entered(part):
                times: Sequence[int] = range(t, len(cuts) + 1)
            else:
                times = (t,)
        else:
            times = (t,)
        interrupts = (False, True) if self.options.interrupt and not g[INTERRUPTED] else (False,)
        return Choices(valuations, times, interrupts)

    # -- one step --------------------------------------------------------------------------------
    def step(
        self, config: tuple[Any, ...], choice: tuple[tuple[Any, ...], int, bool], record: _Recorder | None = None
    ) -> tuple[tuple[Any, ...], int | None]:
        """The configuration one step from `config` with `choice`, and the transition fired.
        With `record`, the scheduler's own traced path runs the ringlet (as `-v` does) and
        tells it the entries and commands."""
        hc = self.options.hash_compact
        self.load(config)
        i = config[TURN]
        m = self.machines[i]
        values, tm, intr = choice
        for name, v in zip(self.input_names[i], values, strict=True):
            setattr(m, name, v)
        self.cur[i] = -1
        if self.world is not None:  # the environment's messages, before the ringlet (as between rounds)
            self.world.before_ringlet(m, self.codecs[i].variables)
            self._drain()
        # abstract time: a time of the interval chosen; exact: the time itself
        now = self.reps[i][m._state][tm] if self.period is None else tm
        m._t0 = 0
        self.clock.now = now
        if intr:
            self.ctx.interrupted = True
            self.cur_g = -1
        arr = self.arr
        # what a command changes of another machine: its pending command, the gate in front
        others = [(mk._pending, mk._run) for mk in self.machines] if self.n > 1 else []
        self.published.clear()
        was = self.bus.initialised, self.bus.shut
        if record is None:
            r = m._run(m)
        else:
            arr.tracer = record
            try:
                r = None
                if m._run is not m._held or arr._release(m):  # as the traced round does
                    if self._entered(m):
                        record.entry(m, m._state)
                    r = m._run(m)
            finally:
                arr.tracer = None
        if self.bus.ready:  # requests and callbacks the ringlet left: the executor's, between rounds
            self._drain()
        # the machine's new part, and those its commands touched
        parts = list(config[PARTS:])
        codecs = self.codecs
        changed = {i} | {
            k
            for k, (pending, run) in enumerate(others)
            if self.machines[k]._pending != pending or self.machines[k]._run is not run
        }
        for k in changed:
            part = codecs[k].snapshot(self.machines[k])
            pid = part if hc else self._part_id(k, part)
            parts[k] = pid
            self.cur[k] = pid
        gv = self.globals_of(config)
        if (self.bus.initialised, self.bus.shut) != was or intr or len(self.bus.nodes) != self.nodes_count:
            nodes = self._nodes_made() if len(self.bus.nodes) != self.nodes_count else gv[NODES]
            gv = (self.bus.initialised, self.bus.shut, self.ctx.interrupted, gv[FIRST_ROUND], nodes)
            self.cur_g = -1
        times = list(self.times_of(config))
        times[i] = self._time_after(i, m, now)
        published = frozenset(self.published) if self.published else frozenset()
        live = config[LIVE]
        turn = self._next_turn(i, live)
        if turn < 0:  # the round ends
            turn, live, gv = self._round_end(parts, times, gv)
        g = self.cur_g = self._intern(self.gtab, self.glist, gv)  # the bus's flags are gv's now
        e = self._intern(self.etab, self.elist, published)
        t = self._intern(self.ttab, self.tlist, tuple(times))
        return (turn, live, g, e, t, *parts), r

    def beyond(self, config: tuple[Any, ...]) -> bool:
        """Whether a variable of `config` is past its bound (then it is counted in `cut`)."""
        for k, pos, bound in self.bounds:
            v = self.part(config, k)[pos]
            if isinstance(v, int | float) and v > bound:
                self.cut += 1
                return True
        return False

    def _drain(self) -> None:
        """Run what waits for the executor (the environment's answers, PUSH callbacks) now."""
        ready = self.bus.ready
        while ready:
            ready.popleft()._run()

    def _time_after(self, i: int, m: Machine, now: int) -> int:
        """Machine i's time in its state after its ringlet ran with the clock at `now`."""
        if m._suspended or m._finished or self._entered(m):
            return 0
        e = now - m._t0
        cuts = self.cuts[i][m._state]
        if self.period is None:
            return bisect.bisect_left(cuts, e)  # the interval e falls in: e <= cuts[0] is 0
        cap = self.caps[i][m._state]
        return e if e < cap else cap

    @staticmethod
    def _entered(m: Machine) -> bool:
        run = m._next if m._run is m._held else m._run
        return run is m.ENTER[m._state]

    def _would_run(self, k: int) -> bool:
        m = self.machines[k]
        return m._pending is not None or not m._suspended

    def _next_turn(self, i: int, live: int) -> int:
        for k in range(i + 1, self.n):
            if live >> k & 1 and self._would_run(k):
                return k
        return -1

    def _round_end(self, parts: list[Any], times: list[int], gv: tuple[Any, ...]) -> tuple[int, int, tuple[Any, ...]]:
        """Between rounds, as the scheduler: the gate back in front of machines that commanded
        themselves and then fired, the clock on by a period, the next round's machines; the run
        ends when none is left or all left are suspended.  Returns (turn, live, globals)."""
        hc = self.options.hash_compact
        arr = self.arr
        rehold = [
            k for k, m in enumerate(self.machines) if (m._pending is not None or m._suspended) and m._run is not m._held
        ]
        if rehold:
            arr._rehold()
            for k in rehold:
                part = self.codecs[k].snapshot(self.machines[k])
                pid = part if hc else self._part_id(k, part)
                parts[k] = pid
                self.cur[k] = pid
        if self.period is not None:
            p = self.period
            for k, m in enumerate(self.machines):
                if m._suspended or m._finished or self._entered(m):
                    times[k] = 0
                else:
                    cap = self.caps[k][m._state]
                    e = times[k] + p
                    times[k] = e if e < cap else cap
            if gv[FIRST_ROUND]:
                gv = (*gv[:FIRST_ROUND], False, *gv[FIRST_ROUND + 1 :])
        live = 0
        for k, m in enumerate(self.machines):
            if not m._finished or m._pending is not None:
                live |= 1 << k
        for k in range(self.n):
            if live >> k & 1 and self._would_run(k):
                return k, live, gv
        return -1, live, gv  # ended: nothing left to run

    # -- labels -------------------------------------------------------------------------------------
    def label(self, published: frozenset[str]) -> int:
        """The atoms' values (a bit each) on the machine objects as they are now."""
        bits = 0
        machines = self.machines
        k = 0
        try:
            for k, atom in enumerate(self.atoms):
                if atom(machines, published):
                    bits |= 1 << k
        except Exception as e:  # a variable of another type than the atom expects
            raise AtomError(k, e) from None
        return bits

    def fairness(self, config: tuple[Any, ...]) -> int:
        """A bit per machine whose time passes in this configuration (SPEC 11's fairness): in
        its state's last interval (every after* of the state holds), or its next ringlet enters
        its state, or it is suspended or finished.  With --period time always passes."""
        if self.period is not None:
            return (1 << self.n) - 1
        bits = 0
        times = self.times_of(config)
        for k in range(self.n):
            part = self.part(config, k)
            cuts = self.cuts[k][part[STATE]]
            if not cuts or times[k] >= len(cuts) or part[SUSPENDED] or part[FINISHED] or self.codecs[k].entered(part):
                bits |= 1 << k
        return bits

    # -- the exploration ------------------------------------------------------------------------------
    def initial(self) -> tuple[Any, ...]:
        hc = self.options.hash_compact
        parts = []
        for k, m in enumerate(self.machines):
            part = self.codecs[k].snapshot(m)
            pid = part if hc else self._part_id(k, part)
            parts.append(pid)
            self.cur[k] = pid
        gv: tuple[Any, ...] = (self.bus.initialised, self.bus.shut, False, self.period is not None, frozenset())
        g = self.cur_g = self._intern(self.gtab, self.glist, gv)
        e = self._intern(self.etab, self.elist, frozenset())
        t = self._intern(self.ttab, self.tlist, (0,) * self.n)
        live = (1 << self.n) - 1
        turn = next((k for k in range(self.n) if self._would_run(k)), -1)
        return (turn, live, g, e, t, *parts)

    def replay(self, choices: Sequence[int]) -> list[tuple[tuple[Any, ...], Step | None]]:
        """The configurations from the initial one along `choices` (a choice number per step),
        each with the step that reached it (None for the initial one): a path rebuilt by
        running it again, with what each ringlet did."""
        prev = activate(self.ctx)
        saved = sys.stdout
        sys.stdout = self.stdout
        try:
            config = self.c0
            out: list[tuple[tuple[Any, ...], Step | None]] = [(config, None)]
            rnd = 0
            for c in choices:
                if config[TURN] < 0:
                    config = (*config[:PUBLISHED], self._intern(self.etab, self.elist, frozenset()), *config[TIMES:])
                    out.append((config, None))
                    continue
                i = config[TURN]
                mine = self.choices(config)
                choice = mine[c % len(mine)]
                if self.world is not None:  # the environment makes the choices it made then
                    self.world.oracle.start(code=c // len(mine), describe=True)
                before = [self.part(config, k) for k in range(self.n)]
                state_before = before[i][STATE]
                rec = _Recorder()
                succ, r = self.step(config, choice, rec)
                after = [self.part(succ, k) for k in range(self.n)]
                changed: dict[str, tuple[Any, Any]] = {}
                for k in range(self.n):
                    old, new = self.codecs[k].variables_of(before[k]), self.codecs[k].variables_of(after[k])
                    for name, v in new.items():
                        changed.update(_diff(f"{self.machines[k].NAME}.{name}", old[name], v))
                values, tm, intr = choice
                step = Step(
                    machine=i,
                    choice=c,
                    state=state_before,
                    inputs=dict(zip(self.input_names[i], values, strict=True)),
                    interval=self._time_text(i, state_before, tm, before[i]),
                    interrupted=intr,
                    entered=rec.entered,
                    transition=r,
                    commands=rec.commands,
                    published=self.published_of(succ),
                    changed=changed,
                    round=rnd,
                    finished=bool(after[i][FINISHED]) and not before[i][FINISHED],
                    environment=list(self.world.oracle.said) if self.world is not None else [],
                )
                out.append((succ, step))
                if succ[TURN] < 0 or succ[TURN] <= i:
                    rnd += 1
                config = succ
            return out
        finally:
            sys.stdout = saved
            activate(prev)

    def _time_text(self, i: int, state: int, tm: int, part: tuple[Any, ...]) -> str | None:
        """The time a step chose, as a person reads it (None when it did not matter)."""
        cuts = self.cuts[i][state]
        if not cuts or self.codecs[i].entered(part) or part[SUSPENDED]:
            return None
        name = self.machines[i].STATES[state]
        if self.period is not None:
            cap = self.caps[i][state]
            return f"{_ns(tm)} in {name}" + (" or more" if tm >= cap else "")
        lo = f"more than {_ns(cuts[tm - 1])}" if tm > 0 else ""
        hi = f"at most {_ns(cuts[tm])}" if tm < len(cuts) else ""
        return f"{lo}{' and ' if lo and hi else ''}{hi} in {name}"


def _diff(name: str, old: Any, new: Any) -> dict[str, tuple[Any, Any]]:
    """What changed of a variable, as `name: (old, new)`; a message's fields one by one."""
    if old == new and type(old) is type(new):
        return {}
    if type(old) is Frozen and type(new) is Frozen and old[0] == new[0] == "message" and old[1] is new[1]:
        out: dict[str, tuple[Any, Any]] = {}
        for (field_name, _), a, b in zip(old[1]._FIELDS, old[2:], new[2:], strict=True):
            out.update(_diff(f"{name}.{field_name}", a, b))
        return out
    return {name: (old, new)}


def _ns(t: int) -> str:
    """A time in ns the way a person writes it: 1.5 s, 200 ms, 3 us, 7 ns."""
    for unit, scale in (("s", 1_000_000_000), ("ms", 1_000_000), ("us", 1_000)):
        if t >= scale:
            return f"{t / scale:g} {unit}"
    return f"{t} ns"
