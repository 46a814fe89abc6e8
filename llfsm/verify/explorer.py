"""The exploration's loops: every reachable configuration, breadth first (SPEC 11; docs/verify.md).

`Explorer` is a `Stepper` (llfsm.verify.step: the machine objects and one step between
configurations) over a `Store` (llfsm.verify.store: the configurations and the structure).  Its
two loops explore alike: `_explore` calls the generic `step` for each choice, `_explore_fast`
writes the same step out with everything it touches in locals (a step costs a few
microseconds; docs/verify.md, "Performance"); a test compares them
(tests/test_verify.py, the specialised loop and the generic step explore alike).

Finite runs: a configuration in which the run has ended (every machine finished, or every one
left suspended) steps to itself, with nothing published, forever.
"""

from __future__ import annotations

import bisect
import gc
import sys
import time
from collections.abc import Callable, Sequence
from typing import Any

from ..runtime.context import activate
from ..runtime.machine import Machine
from .snapshot import FINISHED, STATE, SUSPENDED, VariableValueError
from .step import AtomError, MachineError, Step, Stepper, Valuations
from .store import FIRST_ROUND, GLOBALS, LIVE, NODES, PARTS, PUBLISHED, TIMES, TURN, Loaded, Options, StateLimit

__all__ = ["AtomError", "Explorer", "Loaded", "MachineError", "Options", "StateLimit", "Step"]


class Explorer(Stepper):
    """Explores one arrangement; `explore` fills the structure, `replay` rebuilds a path."""

    def __init__(
        self,
        loaded: Loaded,
        options: Options,
        atoms: Sequence[Callable[[Sequence[Machine], frozenset[str]], bool]] = (),
    ) -> None:
        super().__init__(loaded, options, atoms)
        #: called with (explored, queue, seconds) about once a second while exploring
        self.progress: Callable[[int, int, float], None] | None = None
        #: called with each new configuration's index; returns False to stop
        self.on_new: Callable[[int], bool] | None = None

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
            if self.frozen:  # the collector's again (Store.check_memory)
                gc.unfreeze()
                self.frozen = False

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
        look_at = 1  # the configurations at which to look at the memory in use next
        oracle = self.world.oracle if self.world is not None else None
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
            if self.bounds and self.beyond(config):
                continue  # past a bound of the verification file: not explored further
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
            choices = self.choices(config)
            for base, choice in enumerate(choices):
                forced: list[int] | None = []
                while forced is not None:  # each sequence of the environment's choices (one without one)
                    if oracle is not None:
                        oracle.start(forced)
                    c = base
                    try:
                        succ, _r = self.step(config, choice)
                        if oracle is not None:
                            c += len(choices) * oracle.number()
                    except VariableValueError:
                        raise
                    except BaseException as exc:  # machine code may raise anything
                        if isinstance(exc, KeyboardInterrupt | MemoryError):
                            raise
                        raise MachineError(exc, idx, c) from exc
                    forced = oracle.next_forced() if oracle is not None else None
                    self.steps += 1
                    j, new = self._add(succ, idx, c)
                    if graph:
                        self.edges.append(j)
                        if oracle is not None:
                            self.edge_choice.append(c)
                    if new:
                        if self.on_new is not None and not self.on_new(j):
                            return
                        if len(self.parent) > limit:
                            raise StateLimit()
                        if len(self.parent) >= look_at:
                            look_at = self.check_memory(len(self.parent))
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
        entries = [c.entries for c in codecs]
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
        check_memory = self.check_memory
        look_at = 1  # the configurations at which to look at the memory in use next
        bounded = bool(self.bounds)
        world = self.world
        oracle = world.oracle if world is not None else None
        topics = world if world is not None and world.topics else None  # messages before each ringlet
        if oracle is not None:
            oracle.start(())  # in the loop below, only its choices and `forced` change
        variables = [c.variables for c in codecs]
        drain = self._drain
        edge_choice = self.edge_choice
        choice_cache: dict[tuple[Any, ...], Sequence[tuple[tuple[Any, ...], int, bool]]] = {}
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
                if bounded and self.beyond(config):
                    continue  # past a bound of the verification file: not explored further
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
                    made = self.choices(config)
                    choices = choice_cache[key] = list(made) if len(made) <= Valuations.KEEP else made
                m = machines[turn]
                names = input_names[turn]
                for base, (values, tm, intr) in enumerate(choices):
                    if oracle is not None and (oracle.made or oracle.forced):  # else as start() leaves it
                        oracle.forced, oracle.made = (), []  # start(()) with no code nor description
                    while True:  # each sequence of the environment's choices (one without an environment)
                        c = base
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
                        if topics is not None:  # the environment's messages, before the ringlet
                            topics.before_ringlet(m, variables[turn])
                            if bus.ready:
                                drain()
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
                        again = -1  # the environment's next choice of the usual case (one), or -1, or -2
                        if oracle is not None:
                            if bus.ready:  # the answers and callbacks it left, as between rounds
                                drain()
                            chosen = oracle.made
                            if chosen:
                                if len(chosen) == 1:  # next_forced() of the usual case, one choice
                                    d, nd = chosen[0]
                                    c += len(choices) * d
                                    if d + 1 < nd:
                                        again = d + 1
                                else:
                                    c += len(choices) * oracle.number()
                                    again = -2
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
                        flags_moved = bus.initialised != initialised or bus.shut != shut
                        if intr or flags_moved or len(bus.nodes) != self.nodes_count:
                            nodes = self._nodes_made() if len(bus.nodes) != self.nodes_count else gv[NODES]
                            gv = (bus.initialised, bus.shut, ctx.interrupted, gv[FIRST_ROUND], nodes)
                        # the machine's time in its state
                        if part[SUSPENDED] or part[FINISHED]:
                            e = 0
                        else:
                            run = part[1] if part[0] == gates[turn] else part[0]
                            if run == entries[turn][part[STATE]]:
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
                            if j >= look_at:
                                look_at = check_memory(j)
                        if graph:
                            edges.append(j)
                            if oracle is not None:
                                edge_choice.append(c)
                        if again == -1 or oracle is None:  # (again is -1 without an environment)
                            break
                        if again >= 0:  # start() of the usual case
                            oracle.forced, oracle.made = (again,), []
                            continue
                        forced = oracle.next_forced()
                        if forced is None:
                            break
                        oracle.start(forced)
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
