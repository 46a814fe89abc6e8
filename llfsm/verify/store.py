"""The store of configurations an exploration found (SPEC 11; docs/verify.md, "Performance").

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

The structure, per configuration numbered in breadth-first order (so by depth): its parent in
the BFS tree, the choice that reached it, its atoms' values and its fairness bits, in arrays of
the narrowest item that holds them; and the edges when they are kept (liveness, CTL, exports).
"""

from __future__ import annotations

import gc
from array import array
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from ..runtime.machine import Machine
from .memory import Meter, default_bound

#: Positions in a configuration tuple.
TURN, LIVE, GLOBALS, PUBLISHED, TIMES = range(5)
PARTS = 5
#: Positions in the globals part.
INITIALISED, SHUT, INTERRUPTED, FIRST_ROUND, NODES = range(5)


#: How many new configurations between two settlings of what the exploration keeps
#: (`Store.check_memory`).
SETTLE = 16_384


class StateLimit(Exception):
    """More configurations than --max-states."""


class MemoryLimit(StateLimit):
    """More memory in use than --max-memory (`used` bytes when it was seen)."""

    def __init__(self, used: int) -> None:
        super().__init__(used)
        self.used = used


@dataclass
class Loaded:
    """An arrangement as verify loads it: the classes in load order, their machines' models,
    and per machine the cut points of each state's after* thresholds (llfsm.verify.refuse)."""

    classes: list[type[Machine]]
    models: list[Any]  # llfsm.lang.model.Machine each
    cuts: list[list[tuple[int, ...]]]
    paths: list[str] = field(default_factory=list)  # the machine directories, for messages
    #: what a verification file declares of the world (llfsm.props.file.Environment), or None
    environment: Any = None
    #: `machine.variable` -> the largest value explored on (a verification file's `bounds:`)
    bounds: dict[str, float] = field(default_factory=dict)


@dataclass
class Options:
    period: int | None = None  # ns: explore `--clock sim --period P` exactly; None: abstract time
    interrupt: bool = False
    max_states: int = 1_000_000
    #: bytes the process may hold in memory while exploring (None: half of what it may use)
    max_memory: int | None = None
    hash_compact: bool = False
    #: keep every edge (liveness, CTL, exports need the graph; safety alone does not)
    graph: bool = False
    #: explore with the generic step rather than the specialised loop, and an environment's
    #: services answered by the bus's own executor rather than directly (llfsm.verify.environment,
    #: World): each pair must explore alike (tests compare them)
    generic: bool = False


class Store:
    """The configurations, interned or hashed, and the structure between them."""

    def __init__(self, options: Options, n: int, atoms: int) -> None:
        self.options = options
        self.n = n
        self.meter = Meter(options.max_memory if options.max_memory is not None else default_bound())
        self.settle_at = SETTLE
        self.frozen = False  # what is kept was set aside from the cycle collector (check_memory)
        # the structure: per configuration (numbered in breadth-first order, so by depth) its
        # parent in the BFS tree, the choice that reached it, its atoms' values, its fairness
        # bits, in arrays of the narrowest item that holds them; the edges if kept
        self.parent = array("i")
        self.choice = array("L")
        self.labels = array(_narrowest(atoms))
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

    def choice_between(self, a: int, b: int) -> int:
        """The number of a choice of the step from configuration a that reaches b."""
        if self.parent[b] == a:
            return self.choice[b]
        k = list(self.edges_of(a)).index(b)
        edge_choice = getattr(self, "edge_choice", None)  # an environment's choices number edges apart
        return edge_choice[self.edge_start[a] + k] if edge_choice else k

    @property
    def count(self) -> int:
        """Configurations stored."""
        return len(self.parent)

    def memory_ok(self) -> bool:
        """Whether the process is still within the exploration's memory bound (--max-memory)."""
        return self.meter.ok()

    def check_memory(self, count: int) -> int:
        """MemoryLimit past the bound; else the number of configurations at which to look again
        (llfsm.verify.memory.Meter.next_look: sooner as the configurations grow).

        Every SETTLE configurations, what the exploration keeps is set aside from Python's cycle
        collector (`gc.freeze`, after a collection of the young generations, so little garbage
        is kept until the end; a full collection would walk the whole process, modules and all):
        the configurations and their parts are kept to the end, and a part that holds a bus
        handle or a frozen list stays tracked, so each of the collector's full passes would walk
        every one found so far again.  `explore` gives them back."""
        if not self.meter.ok():
            raise MemoryLimit(self.meter.used)
        if count >= self.settle_at:
            self.settle_at = count + SETTLE
            gc.collect(1)
            gc.freeze()
            self.frozen = True
        return self.meter.next_look(count)

    # -- paths ----------------------------------------------------------------------------------------
    def path_to(self, idx: int) -> list[int]:
        """The configurations from the initial one to `idx`, along the BFS tree (a shortest path)."""
        out = [idx]
        while self.parent[out[-1]] >= 0:
            out.append(self.parent[out[-1]])
        return out[::-1]

    def edges_of(self, idx: int) -> Sequence[int]:
        return self.edges[self.edge_start[idx] : self.edge_start[idx + 1]]


def _narrowest(bits: int) -> str:
    """The array type code of the narrowest unsigned item of at least `bits` bits."""
    return "B" if bits <= 8 else "H" if bits <= 16 else "L" if bits <= 32 else "Q"
