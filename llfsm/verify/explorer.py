"""Breadth-first exploration of an arrangement's configurations (SPEC 11; docs/verify.md).

What runs is what is explored: the arrangement is made as `llfsm run` makes it (the scheduler's
own `Arrangement`, its gate applying commands exactly as in a run), and a step calls the
scheduler's entry point of the machine whose turn it is, `m._run(m)`, on the machine objects,
after putting the configuration's values back into them (llfsm.verify.snapshot).

A configuration, as a tuple:
    (turn, live, globals, published, times, part of machine 0, ..., part of machine n-1)
- turn: the load index of the machine whose ringlet is next, or -1 once the run has ended;
- live: the machines of the current round (as the scheduler's round computes them: those not
  finished, or with a command pending), as a bit mask;
- globals: `ros.ok()`'s inputs (initialised, shut down, interrupted), with `--period` whether
  this is the first round, and the nodes machine code made on the bus (by name: a node made
  again under the same name fails as it does in a run, and a node made on one path is not there
  on another);
- published: the topics the step that reached the configuration published (`published()`);
- times: each machine's time in its current state, abstracted (see below);
- each machine's part: its ringlet, state, command, suspension, inputs as last read, variables.
Each piece is interned (a table per kind; the configuration is then a tuple of small integers),
or, with hash compaction, the configuration is kept as a 64-bit hash only.

A step is one ringlet with one choice of: the values of the machine's inputs (every valuation of
their domains), how much time has passed in its state (abstract time: any interval from the one
it is in), and with `--interrupt` whether `ros.ok()` falls before it.  Choices are numbered in a
fixed order, so a path is a list of choice numbers and is replayed exactly (`Explorer.replay`).

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
import itertools
import sys
import time
from array import array
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from ..runtime.clock import SimClock
from ..runtime.context import RunContext, activate
from ..runtime.inputs import DEFAULT, TOPIC
from ..runtime.machine import RESUME, Machine
from ..runtime.scheduler import Arrangement
from ..runtime.trace import Tracer
from .snapshot import FINISHED, PENDING, STATE, SUSPENDED, Codec, VariableValueError
from .values import Frozen, Handles

#: Positions in a configuration tuple.
TURN, LIVE, GLOBALS, PUBLISHED, TIMES = range(5)
PARTS = 5
#: Positions in the globals part.
INITIALISED, SHUT, INTERRUPTED, FIRST_ROUND, NODES = range(5)


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


class StateLimit(Exception):
    """More configurations than --max-states."""


class _Null(io.TextIOBase):
    """Where machine code's printing goes while exploring (every path prints, in any order)."""

    def write(self, s: str) -> int:
        return len(s)

    def writable(self) -> bool:
        return True


@dataclass
class Loaded:
    """An arrangement as verify loads it: the classes in load order, their machines' models,
    and per machine the cut points of each state's after* thresholds (llfsm.verify.refuse)."""

    classes: list[type[Machine]]
    models: list[Any]  # llfsm.lang.model.Machine each
    cuts: list[list[tuple[int, ...]]]
    paths: list[str] = field(default_factory=list)  # the machine directories, for messages


@dataclass
class Options:
    period: int | None = None  # ns: explore `--clock sim --period P` exactly; None: abstract time
    interrupt: bool = False
    max_states: int = 1_000_000
    hash_compact: bool = False
    #: keep every edge (liveness, CTL, exports need the graph; safety alone does not)
    graph: bool = False
    #: explore with the generic step (as replay does) rather than the specialised loop: the two
    #: must explore alike (a test compares them)
    generic: bool = False


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


class Explorer:
    """Explores one arrangement; `explore` fills the structure, `replay` rebuilds a path."""

    def __init__(
        self,
        loaded: Loaded,
        options: Options,
        atoms: Sequence[Callable[[Sequence[Machine], frozenset[str]], bool]] = (),
    ) -> None:
        self.loaded = loaded
        self.options = options
        self.atoms = list(atoms)
        if len(self.atoms) > 64:
            raise ValueError("at most 64 atoms in the properties of one verification")
        self.n = len(loaded.classes)
        self.ctx = RunContext(SimClock(options.period or 1_000_000))
        self.clock = self.ctx.clock
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
        # per machine: input names, domains, which are bound (their first round takes the default)
        self.input_names = [c.inputs for c in self.codecs]
        self.domains: list[list[tuple[Any, ...]]] = []
        self.first_round_domains: list[list[tuple[Any, ...]]] = []
        for cls in loaded.classes:
            doms = [tuple(entry[3]) for entry in cls.INPUTS]
            self.domains.append(list(itertools.product(*doms)))
            first = [(entry[DEFAULT],) if entry[TOPIC] is not None else tuple(entry[3]) for entry in cls.INPUTS]
            self.first_round_domains.append(list(itertools.product(*first)))
        self.cuts = loaded.cuts
        # abstract time: a representative time of each interval of each state
        self.reps = [[(0, *(c + 1 for c in cuts)) for cuts in per] for per in self.cuts]
        self.period = options.period
        if self.period is not None:
            p = self.period
            self.caps = [[(cuts[-1] // p + 1) * p if cuts else 0 for cuts in per] for per in self.cuts]
        # the structure: per configuration (numbered in breadth-first order, so by depth) its
        # parent in the BFS tree, the choice that reached it, its atoms' values, its fairness
        # bits, in arrays of the narrowest item that holds them; the edges if kept
        self.parent = array("i")
        self.choice = array("L")
        self.labels = array(_narrowest(len(self.atoms)))
        self.fair = array(_narrowest(self.n))
        self.edges = array("i")
        self.edge_start = array("q")
        self.steps = 0
        self.partial: str | None = None  # why the exploration stopped early, if it did
        # the tables (exact storage)
        self.parts: list[dict[tuple[Any, ...], int]] = [{} for _ in range(self.n)]
        self.part_list: list[list[tuple[Any, ...]]] = [[] for _ in range(self.n)]
        self.gtab: dict[tuple[Any, ...], int] = {}
        self.glist: list[tuple[Any, ...]] = []
        self.etab: dict[frozenset[str], int] = {}
        self.elist: list[frozenset[str]] = []
        self.ttab: dict[tuple[int, ...], int] = {}
        self.tlist: list[tuple[int, ...]] = []
        self.index: dict[Any, int] = {}
        self.configs: list[tuple[Any, ...]] = []
        # hash compaction
        self.table = array("q")
        self.table_index = array("q")
        self.frontier: deque[tuple[int, tuple[Any, ...]]] = deque()
        # what each machine object holds now (an id in its table, or -1: changed since)
        self.cur: list[Any] = [-1] * self.n
        self.cur_g: Any = -1
        #: called with (explored, queue, seconds) about once a second while exploring
        self.progress: Callable[[int, int, float], None] | None = None
        self.on_new: Callable[[int], bool] | None = None

    # -- the bus's tap: what a step publishes ----------------------------------------------------
    def _tap(self, topic: Any) -> None:
        name = topic.name
        published = self.published
        topic.taps.append(lambda _msg: published.add(name))

    # -- interning ----------------------------------------------------------------------------
    def _part_id(self, i: int, part: tuple[Any, ...]) -> int:
        tab = self.parts[i]
        pid = tab.get(part)
        if pid is None:
            pid = tab[part] = len(self.part_list[i])
            self.part_list[i].append(part)
        return pid

    def _intern(self, tab: dict[Any, int], lst: list[Any], value: Any) -> int:
        vid = tab.get(value)
        if vid is None:
            vid = tab[value] = len(lst)
            lst.append(value)
        return vid

    def part(self, config: tuple[Any, ...], i: int) -> tuple[Any, ...]:
        """Machine i's part of a configuration (a tuple)."""
        p = config[PARTS + i]
        return p if self.options.hash_compact else self.part_list[i][p]

    def globals_of(self, config: tuple[Any, ...]) -> tuple[Any, ...]:
        return self.glist[config[GLOBALS]]

    def published_of(self, config: tuple[Any, ...]) -> frozenset[str]:
        return self.elist[config[PUBLISHED]]

    def times_of(self, config: tuple[Any, ...]) -> tuple[int, ...]:
        return self.tlist[config[TIMES]]

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
    def choices(self, config: tuple[Any, ...]) -> list[tuple[tuple[Any, ...], int, bool]]:
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
        return [(v, tm, it) for it in interrupts for tm in times for v in valuations]

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

    def _add(self, config: tuple[Any, ...], parent: int, choice: int) -> tuple[int, bool]:
        """The index of `config`, and whether it is new (then its labels are taken now)."""
        if self.options.hash_compact:
            h = hash(config)
            idx = self._probe(h)
            if idx >= 0:
                return idx, False
            idx = len(self.parent)
            self._insert(h, idx)
            self.frontier.append((idx, config))
        else:
            idx = self.index.get(config, -1)
            if idx >= 0:
                return idx, False
            idx = self.index[config] = len(self.configs)
            self.configs.append(config)
        self.parent.append(parent)
        self.choice.append(max(choice, 0))  # (the initial configuration's: 0)
        self.labels.append(self.label(self.published_of(config)))
        self.fair.append(self.fairness(config))
        return idx, True

    # open addressing over two arrays: the 64-bit hashes (0: empty) and their indices
    def _probe(self, h: int) -> int:
        h = h or 1
        table = self.table
        if not table:
            return -1
        mask = len(table) - 1
        j = h & mask
        while True:
            v = table[j]
            if v == h:
                return self.table_index[j]
            if v == 0:
                return -1
            j = (j + 1) & mask

    def _insert(self, h: int, idx: int) -> None:
        h = h or 1
        if (len(self.parent) + 1) * 2 > len(self.table):
            self._grow()
        table = self.table
        mask = len(table) - 1
        j = h & mask
        while table[j] != 0:
            j = (j + 1) & mask
        table[j] = h
        self.table_index[j] = idx

    def _grow(self) -> None:
        old, old_index = self.table, self.table_index
        size = max(1024, len(old) * 2)
        self.table = array("q", bytes(8 * size))
        self.table_index = array("q", bytes(8 * size))
        mask = size - 1
        table, index = self.table, self.table_index
        for j, h in enumerate(old):
            if h:
                k = h & mask
                while table[k] != 0:
                    k = (k + 1) & mask
                table[k] = h
                index[k] = old_index[j]

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
                choice = self.choices(config)[c]
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

    def choice_between(self, a: int, b: int) -> int:
        """The number of a choice of the step from configuration a that reaches b."""
        if self.parent[b] == a:
            return self.choice[b]
        return list(self.edges_of(a)).index(b)

    def explore(self) -> None:
        """Every reachable configuration, breadth first (so each is first reached by a shortest
        path); safety is judged by `on_new` as each new one is found (it returns False to stop)."""
        prev = activate(self.ctx)
        saved = sys.stdout
        sys.stdout = self.stdout  # machine code's print: every path prints, in any order
        try:
            self._explore()
        finally:
            sys.stdout = saved
            activate(prev)

    def _explore(self) -> None:
        if not self.options.generic:
            self._explore_fast()
            return
        hc = self.options.hash_compact
        graph = self.options.graph
        start = time.monotonic()
        last = start
        c0 = self.c0 = self.initial()
        self.load(c0)
        self.published.clear()
        idx, _ = self._add(c0, -1, -1)
        if self.on_new is not None and not self.on_new(idx):
            return
        pos = 0
        limit = self.options.max_states
        while True:
            if hc:
                if not self.frontier:
                    break
                idx, config = self.frontier.popleft()
            else:
                if pos >= len(self.configs):
                    break
                idx, config = pos, self.configs[pos]
                pos += 1
            if graph:
                self.edge_start.append(len(self.edges))
            if config[TURN] < 0:  # the run has ended: it stays so, publishing nothing
                succ = (*config[:PUBLISHED], self._intern(self.etab, self.elist, frozenset()), *config[TIMES:])
                self.load(config)
                self.published.clear()
                j, new = self._add(succ, idx, 0)
                self.steps += 1
                if graph:
                    self.edges.append(j)
                if new and self.on_new is not None and not self.on_new(j):
                    return
                continue
            for c, choice in enumerate(self.choices(config)):
                try:
                    succ, _r = self.step(config, choice)
                except VariableValueError:
                    raise
                except BaseException as exc:  # machine code may raise anything
                    if isinstance(exc, KeyboardInterrupt | MemoryError):
                        raise
                    raise MachineError(exc, idx, c) from exc
                self.steps += 1
                j, new = self._add(succ, idx, c)
                if graph:
                    self.edges.append(j)
                if new:
                    if self.on_new is not None and not self.on_new(j):
                        return
                    if len(self.parent) > limit:
                        raise StateLimit()
            if self.progress is not None and self.steps & 0x3FF == 0:
                now = time.monotonic()
                if now - last >= 1.0:
                    last = now
                    queue = len(self.frontier) if hc else len(self.configs) - pos
                    self.progress(len(self.parent), queue, now - start)
        if graph:
            self.edge_start.append(len(self.edges))

    def _explore_fast(self) -> None:
        """`_explore`, with the same steps as `step`, written out in one loop with everything it
        touches in locals, and the choices and fairness of each machine's part cached (a step
        costs a few microseconds; docs/verify.md, "Performance").  Exact storage interns each
        part and keeps the configurations; hash compaction keeps each as a 64-bit hash in an
        open-addressing table, and the configurations still to expand in a queue."""
        n = self.n
        hc = self.options.hash_compact
        machines, codecs = self.machines, self.codecs
        snaps = [c.snapshot for c in codecs]
        restores = [c.restore for c in codecs]
        gates = [c.gate_index for c in codecs]
        part_tabs, part_lists = self.parts, self.part_list
        cur = self.cur
        configs, index, frontier = self.configs, self.index, self.frontier
        parent, choice_arr = self.parent, self.choice
        labels, fair_arr = self.labels, self.fair
        edges, edge_start = self.edges, self.edge_start
        graph = self.options.graph
        bus, ctx, clock = self.bus, self.ctx, self.clock
        published = self.published
        gtab, glist, etab, elist, ttab, tlist = self.gtab, self.glist, self.etab, self.elist, self.ttab, self.tlist
        period = self.period
        cuts, caps, reps = self.cuts, getattr(self, "caps", None), self.reps
        input_names = self.input_names
        atoms = self.atoms
        label = self.label
        on_new = self.on_new
        limit = self.options.max_states
        progress = self.progress
        probe, insert = self._probe, self._insert
        choice_cache: dict[tuple[Any, ...], list[tuple[tuple[Any, ...], int, bool]]] = {}
        fair_cache: dict[tuple[int, Any, int], int] = {}
        full = (1 << n) - 1
        start = last = time.monotonic()

        def fairness(config: tuple[Any, ...]) -> int:
            if period is not None:
                return full
            times = tlist[config[TIMES]]
            bits = 0
            for k in range(n):
                key = (k, config[PARTS + k], times[k])
                b = fair_cache.get(key)
                if b is None:
                    part = key[1] if hc else part_lists[k][key[1]]
                    cs = cuts[k][part[STATE]]
                    b = fair_cache[key] = int(
                        not cs or key[2] >= len(cs) or part[SUSPENDED] or part[FINISHED] or codecs[k].entered(part)
                    )
                if b:
                    bits |= 1 << k
            return bits

        def added(succ: tuple[Any, ...], idx: int, c: int, events: int) -> int:
            """The index of succ, new or not; -1 - index when new (its labels taken now)."""
            if hc:
                h = hash(succ)
                j = probe(h)
                if j >= 0:
                    return j
                j = len(parent)
                insert(h, j)
                frontier.append((j, succ))
            else:
                j = index.get(succ, -1)
                if j >= 0:
                    return j
                j = index[succ] = len(configs)
                configs.append(succ)
            parent.append(idx)
            choice_arr.append(c)
            labels.append(label(elist[events]) if atoms else 0)
            fair_arr.append(fairness(succ))
            return -1 - j

        c0 = self.c0 = self.initial()
        self.load(c0)
        published.clear()
        added(c0, -1, 0, c0[PUBLISHED])
        if on_new is not None and not on_new(0):
            return
        empty = self._intern(etab, elist, frozenset())
        pos = 0
        steps = 0
        try:
            while True:
                if hc:
                    if not frontier:
                        break
                    idx, config = frontier.popleft()
                else:
                    if pos >= len(configs):
                        break
                    idx, config = pos, configs[pos]
                    pos += 1
                if graph:
                    edge_start.append(len(edges))
                turn = config[TURN]
                if turn < 0:  # the run has ended: it stays so, publishing nothing
                    succ = (*config[:PUBLISHED], empty, *config[TIMES:])
                    steps += 1
                    self.load(succ)
                    j = added(succ, idx, 0, empty)
                    if j < 0:
                        j = -1 - j
                        if on_new is not None and not on_new(j):
                            return
                    if graph:
                        edges.append(j)
                    continue
                live = config[LIVE]
                g0 = config[GLOBALS]
                t0 = config[TIMES]
                # the choices depend on the machine's ringlet, state, command and suspension,
                # the globals and its time: not on its variables
                p0 = config[PARTS + turn] if hc else part_lists[turn][config[PARTS + turn]]
                key = (turn, p0[0], p0[1], p0[2], p0[3], p0[4], g0, tlist[t0][turn])
                choices = choice_cache.get(key)
                if choices is None:
                    choices = choice_cache[key] = self.choices(config)
                m = machines[turn]
                names = input_names[turn]
                for c, (values, tm, intr) in enumerate(choices):
                    # the configuration into the objects (what the previous choice changed)
                    for k in range(n):
                        p = config[PARTS + k]
                        if hc:
                            if cur[k] is not p:
                                restores[k](machines[k], p)
                                cur[k] = p
                        elif cur[k] != p:
                            restores[k](machines[k], part_lists[k][p])
                            cur[k] = p
                    if self.cur_g != g0:
                        self._set_globals(glist[g0])
                        self.cur_g = g0
                    if names:
                        for name, v in zip(names, values, strict=True):
                            setattr(m, name, v)
                    now = reps[turn][m._state][tm] if period is None else tm
                    m._t0 = 0
                    clock.now = now
                    if intr:
                        ctx.interrupted = True
                    # what a command changes of another machine: its pending command, the gate
                    before = [(mk._pending, mk._run) for mk in machines] if n > 1 else None
                    published.clear()
                    initialised, shut = bus.initialised, bus.shut
                    try:
                        m._run(m)
                    except BaseException as exc:  # machine code may raise anything
                        if isinstance(exc, KeyboardInterrupt | MemoryError | VariableValueError):
                            raise
                        raise MachineError(exc, idx, c) from exc
                    steps += 1
                    # the machine's new part (and those its commands touched)
                    part = snaps[turn](m)
                    if hc:
                        pid: Any = part
                    else:
                        tab = part_tabs[turn]
                        pid = tab.get(part)
                        if pid is None:
                            pid = tab[part] = len(part_lists[turn])
                            part_lists[turn].append(part)
                    cur[turn] = pid
                    if before is not None:
                        parts = list(config[PARTS:])
                        parts[turn] = pid
                        for k, (pending, run) in enumerate(before):
                            mk = machines[k]
                            if k != turn and (mk._pending != pending or mk._run is not run):
                                other = snaps[k](mk)
                                parts[k] = cur[k] = other if hc else self._part_id(k, other)
                    else:
                        parts = [pid]
                    # globals
                    gv = glist[g0]
                    if intr or bus.initialised != initialised or bus.shut != shut or len(bus.nodes) != self.nodes_count:
                        nodes = self._nodes_made() if len(bus.nodes) != self.nodes_count else gv[NODES]
                        gv = (bus.initialised, bus.shut, ctx.interrupted, gv[FIRST_ROUND], nodes)
                    # the machine's time in its state
                    if part[SUSPENDED] or part[FINISHED]:
                        e = 0
                    else:
                        run = part[1] if part[0] == gates[turn] else part[0]
                        if run == 2 * part[STATE]:
                            e = 0
                        else:
                            e = now - m._t0
                            cs = cuts[turn][part[STATE]]
                            if period is None:
                                e = bisect.bisect_left(cs, e) if cs else 0
                            else:
                                cap = caps[turn][part[STATE]]  # type: ignore[index]
                                e = e if e < cap else cap
                    times = tlist[t0]
                    if times[turn] != e:
                        times = (*times[:turn], e, *times[turn + 1 :])
                    # whose turn, or the round's end
                    nxt = -1
                    for k in range(turn + 1, n):
                        if live >> k & 1:
                            mk = machines[k]
                            if mk._pending is not None or not mk._suspended:
                                nxt = k
                                break
                    new_live = live
                    if nxt < 0:  # the round ends (as `_round_end`, written out for the usual case)
                        slow = False
                        new_live = 0
                        for k in range(n):
                            mk = machines[k]
                            commanded = mk._pending is not None
                            if mk._finished and not commanded:
                                continue  # unloaded
                            new_live |= 1 << k
                            if (commanded or mk._suspended) and mk._run is not mk._held:
                                slow = True  # the gate goes back in front: its part changes
                            if nxt < 0 and (commanded or not mk._suspended):
                                nxt = k
                        if slow or period is not None or (n > 1 and new_live != live):
                            tl = list(times)
                            nxt, new_live, gv = self._round_end(parts, tl, gv)
                            times = tuple(tl)
                    g = gtab.get(gv)
                    if g is None:
                        g = self._intern(gtab, glist, gv)
                    self.cur_g = g
                    ev = empty if not published else self._intern(etab, elist, frozenset(published))
                    t = ttab.get(times)
                    if t is None:
                        t = self._intern(ttab, tlist, times)
                    j = added((nxt, new_live, g, ev, t, *parts), idx, c, ev)
                    if j < 0:
                        j = -1 - j
                        if on_new is not None and not on_new(j):
                            return
                        if j >= limit:
                            raise StateLimit()
                    if graph:
                        edges.append(j)
                if progress is not None and not idx & 0x3FF:
                    now_s = time.monotonic()
                    if now_s - last >= 1.0:
                        last = now_s
                        self.steps = steps
                        progress(len(parent), len(frontier) if hc else len(configs) - pos, now_s - start)
            if graph:
                edge_start.append(len(edges))
        finally:
            self.steps = steps

    @property
    def count(self) -> int:
        """Configurations stored."""
        return len(self.parent)

    def memory_ok(self) -> bool:
        """Whether the process is still within the exploration's memory bound."""
        return True

    # -- paths ----------------------------------------------------------------------------------------
    def path_to(self, idx: int) -> list[int]:
        """The configurations from the initial one to `idx`, along the BFS tree (a shortest path)."""
        out = [idx]
        while self.parent[out[-1]] >= 0:
            out.append(self.parent[out[-1]])
        return out[::-1]

    def edges_of(self, idx: int) -> Sequence[int]:
        return self.edges[self.edge_start[idx] : self.edge_start[idx + 1]]


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


def _narrowest(bits: int) -> str:
    """The array type code of the narrowest unsigned item of at least `bits` bits."""
    return "B" if bits <= 8 else "H" if bits <= 16 else "L" if bits <= 32 else "Q"


def _ns(t: int) -> str:
    """A time in ns the way a person writes it: 1.5 s, 200 ms, 3 us, 7 ns."""
    for unit, scale in (("s", 1_000_000_000), ("ms", 1_000_000), ("us", 1_000)):
        if t >= scale:
            return f"{t / scale:g} {unit}"
    return f"{t} ns"
