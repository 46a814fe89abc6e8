"""The history of a run: the last N ringlets, and the arrangement as it was at any of them
(docs/debug.md, "History").

Each ringlet boundary keeps one record: the ringlet's number, round and run time, the machine,
its state before the turn, the state its ringlet ran in and the one after, the transition that
fired, what its variables and inputs held before and after (when anything changed) and the
topics it published.  A value set from the debugger while paused is a record too.

Records are made in one of two ways, which read back the same:

- **compiled** (recording.py), where every machine's ringlets can be compiled again from their
  generated module: each ringlet appends one item to a list, one a boundary (its code, the
  old value of the one number it changes, or a tuple of its code and what it can change), and
  the gate (`Arrangement.around_release`) adds what a command, parameters or inputs changed,
  and a turn in which no ringlet ran.  A record's number is its item's place; its machine and
  round follow from the live machines the scheduler tells of (`on_live`: every live machine
  has one boundary a round, in turn), its run time from the clock (the sim clock: a period a
  round, and its jumps; any other: each time the loops read it, `note_time`).  The list is cut
  back to N between rounds once it holds 2N;
- **watched**, otherwise (a native build, a machine the monitor compiled its checks into): the
  debugger's watcher calls `record` after every ringlet, which takes all of a machine's values
  as one tuple (`Values.take`) and compares it with the take before; the records are tuples in
  a deque of N.

Values are taken as bounded plain data (llfsm.runtime.readout: a long string or a large list is
cut, and says so), messages as their generated copies, numbers, flags and handles as they are;
what changed, name by name, is worked out when a record is read.  What a record refers to is
bounded per record: memory is bounded by N whatever the run does.

The arrangement at record k (the page's "History" slider) is rebuilt backwards from now: every
machine's state and values as they are, then each newer record undone.
"""

from __future__ import annotations

from bisect import bisect_right
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from itertools import count
from operator import itemgetter
from typing import Any

from ..runtime.clock import SimClock
from ..runtime.machine import Machine
from ..runtime.readout import plain
from ..runtime.reads import ClassReads
from .recording import AFTER_AT_END, DIRECT, FIRED_AT_END, RingletRecorder, namespace_of, taken_by
from .traps import TRAP
from .values import Values, shown, taken_copy

#: A watched record: (number, run time ns, code, values before, values after); a set's number is
#: the one of the boundary it follows.  The code says what the record is:
#: - (FULL, machine index, state before, state its ringlet ran in (None: none ran), state after,
#:   transition, round); the values None and None when nothing changed;
#: - (SET, machine index, state, round): a value set while paused.
Record = tuple[Any, ...]
FULL, SET = "full", "set"


#: What `--history` keeps when the page asks for history and the command line did not say.
PAGE_DEFAULT = 1000
#: Marks a turn in which no ringlet ran (compiled; the gate's record): (TURN, machine, state
#: before, state after, values before, values after (None and None: unchanged)).  Known by
#: identity: a plain tuple, which the garbage collector stops following.
TURN = ("turn",)
_first = itemgetter(0)


#: A record as read back: (number, run time ns, a set?, machine index, state before, state its
#: ringlet ran in (None: none ran), state after, transition, round, [(value index, old, new)]).
Part = tuple[int, int, bool, int, int, "int | None", int, "int | None", int, list[tuple[int, Any, Any]]]


class History:
    """The last `size` ringlet boundaries of an arrangement's machines."""

    def __init__(self, machines: Sequence[Machine], size: int) -> None:
        if size < 1:
            raise ValueError("--history must keep at least 1 ringlet")
        self.machines = list(machines)
        self.size = size
        self.values = [Values(type(m)) for m in machines]
        #: Each machine's values as the history last took them: what the page shows (taken
        #: again on the scheduler's thread when it asks, `refresh`), and, watched, what the next
        #: take is compared with.
        self.current = [v.take(m) for v, m in zip(self.values, machines, strict=True)]
        #: The same as lists, for the compiled ringlets: what a value that can change in place
        #: (or outside its ringlets) is compared with, updated by each record that takes it.
        self.cache: list[list[Any]] = [list(c) for c in self.current]
        self.states = [m._state for m in machines]  # watched: each machine's state at its last boundary
        self.sets = 0
        #: Whether the ringlets record themselves (`attach`, once they are compiled).
        self.compiled = False
        #: Topics published, by the number of the boundary they belong to (the next one when
        #: published): (number, [topic, ...]), at most one entry per record.
        self.published: deque[tuple[int, list[str]]] = deque(maxlen=size)
        #: The page asked for the values (`snapshot`): `refresh` takes them again.
        self.wanted = False
        #: Values waiting for their machine's next turn (the arrangement's, by machine id: set by
        #: the debugger when the ringlets record themselves).
        self.waiting: dict[int, Any] = {}
        # -- watched: the records as tuples, (number, run time, code, values...), the newest N
        self._watched: deque[Record] = deque(maxlen=size)
        self._counter = count(1)
        # -- compiled (see "How it is recorded" in docs/debug.md) --
        #: One item a boundary, in order: a ringlet's code, a tuple of its code and values, the
        #: old value alone (`meanings`), or a turn of the gate's; the boundary numbered by its
        #: place (`_dropped` + index + 1).  Cut back between rounds once it holds 2N.
        self._items: list[Any] = []
        self._dropped = 0
        #: Per machine: state after -> (state it ran in, transition, value index) of its
        #: records that are the value alone (claimed as the ringlets are compiled).
        self.meanings: list[dict[int, tuple[int, int | None, int]]] = [{} for _ in machines]
        #: The ringlets' record codes (plain tuples of numbers, which the garbage collector stops
        #: following), by id: a record is a code, or a tuple that starts with one, only if it is
        #: that very object (machine code cannot reach them).
        self._codes: dict[int, tuple[Any, ...]] = {}
        self._interned: dict[tuple[Any, ...], tuple[Any, ...]] = {}
        self._still: dict[int, tuple[Any, ...]] = {}  # each suspended machine's turn that changes nothing
        #: Sets while paused: (number of the boundary before, run time, machine, state, round,
        #: values before, values after).
        self._sets: list[tuple[int, int, int, int, int, tuple[Any, ...], tuple[Any, ...]]] = []
        #: What the gate did before a ringlet: by the ringlet's record's number, (state before,
        #: values before, values after).
        self._gated: dict[int, tuple[int, tuple[Any, ...], tuple[Any, ...]]] = {}
        #: Rounds: (first number, its round, the live machines' indices in turn order), in order.
        self._rounds: list[tuple[int, int, tuple[int, ...]]] = [(1, 0, tuple(range(len(self.machines))))]
        #: Run times: (first number, its run time), in order; a later round of the sim clock is
        #: `period` later for each round since.
        self._times: list[tuple[int, int]] = [(1, 0)]
        self._period = 0
        self._every = 0  # sim clock: the run time after which the items may reach 2N
        self._arr: Any = None

    # -- made on the scheduler's thread ------------------------------------------------------------
    def attach(self, arr: Any) -> None:
        """The ringlets record themselves (compiled): number the boundaries from the scheduler's
        rounds, time them from its clock, and cut the items back between rounds."""
        self.compiled = True
        self._arr = arr
        arr.around_release = self.around_release
        arr.on_live = self.on_live
        self.waiting = arr._variables
        clock = arr.clock
        self._period = clock.period if type(clock) is SimClock else 0
        if not self._period:
            arr.note_time = self.note_time
        self._times = [(1, clock.now)]
        chained = clock.on_jump

        def jumped() -> None:  # a wait moved the time (a spin call): from the next record on
            self._time_from(self._next_number(), clock.now)
            if chained is not None:
                chained()

        clock.on_jump = jumped
        arr.ctx.between_rounds.append(self._between)

    def _time_from(self, first: int, now: int) -> None:
        """Records from number `first` on are at run time `now` (the last entry replaced when no
        record came since it; nothing added when the table already says so)."""
        times = self._times
        if times[-1][0] == first:
            times[-1] = (first, now)
        elif self._time_of(first) != now:
            times.append((first, now))

    def _between(self) -> None:
        """Between rounds (a hook of the run's context, and `on_live`): cut back; the sim clock:
        come back before the items reach 2N (a jump of its time notes itself); any other clock
        is timed as its loops read it (`note_time`)."""
        if len(self._items) >= 2 * self.size:
            self.trim()
        arr = self._arr
        if self._period:
            arr.ctx.wake_at(arr.clock.now + self._every)
        else:
            self._time_from(self._next_number(), arr.clock.now)

    def note_time(self, now: int) -> None:
        """Arrangement.note_time (any clock but the sim clock; between rounds): the next
        records are at `now`; cut back once the items reach 2N."""
        self._time_from(self._dropped + len(self._items) + 1, now)
        if len(self._items) >= 2 * self.size:
            self.trim()

    def _next_number(self) -> int:
        """The number the next boundary's record will have (watched: without taking it from the
        counter; the newest record's, a boundary's or a set's, is the one before it)."""
        if self.compiled:
            return self._dropped + len(self._items) + 1
        ring = self._watched
        return int(ring[-1][0]) + 1 if ring else 1

    @property
    def count(self) -> int:
        """Records made since the start (numbers of the dropped ones are below the first kept)."""
        return self._next_number() - 1 + self.sets

    @property
    def kept(self) -> int:
        """How many records are kept (any thread)."""
        if self.compiled:
            return min(self.size, len(self._items) + len(self._sets))
        return len(self._watched)

    def record(
        self, m: Machine, ran: int | None, fired: int | None, round_: int, now: int, published: list[str]
    ) -> None:
        """Watched: after m's turn (the debugger's watcher calls this at every boundary)."""
        i = m._id
        before = self.states[i]
        after = self.states[i] = m._state
        old: tuple[Any, ...] | None = self.current[i]
        new: tuple[Any, ...] | None = self.values[i].take(m)
        if new == old:
            old = new = None
        else:
            self.current[i] = new  # type: ignore[assignment]  # a take, never None here
        number = next(self._counter)
        if published:
            self.published.append((number, list(published)))
        self._watched.append((number, now, (FULL, i, before, ran, after, fired, round_), old, new))

    def tap(self, topic: str) -> None:
        """A topic published (compiled): it belongs to the next boundary's record."""
        n = self._next_number()
        pubs = self.published
        if pubs and pubs[-1][0] == n:
            pubs[-1][1].append(topic)
        else:
            pubs.append((n, [topic]))

    def around_release(self, m: Machine, let_go: Callable[[Machine], bool]) -> bool:
        """Arrangement.around_release (compiled): what the gate changes (a command, parameters,
        inputs) goes into the record of the ringlet it lets run, or into a record of its own
        when none runs."""
        i = m._id
        before = m._state
        inputs = m._inputs
        if m._suspended and m._pending is None and i not in self.waiting and (inputs is None or not inputs.fresh):
            let_go(m)  # nothing to apply: it stays suspended, and nothing of it changes
            still = self._still.get(i)
            if still is None or still[2] != before:
                still = self._still[i] = (TURN, i, before, before, None, None)
            self._items.append(still)
            return False
        take = self.values[i].take
        old = take(m)
        goes = let_go(m)
        new = take(m)
        self.cache[i][:] = new
        if goes:
            if new != old or m._state != before:
                self._gated[self._next_number()] = (before, old, new)
        else:
            self._items.append((TURN, i, before, m._state, *((old, new) if new != old else (None, None))))
        return goes

    def on_live(self, rounds: int, live: list[Machine]) -> None:
        """Arrangement.on_live (compiled): from the next record on, a record of each of `live`,
        in turn, a round."""
        first, ids = self._next_number(), tuple(m._id for m in live)
        last = self._rounds[-1]
        if last[0] == first:
            self._rounds[-1] = (first, rounds, ids)
        elif last[2] != ids or self.round_of(first) != rounds:
            self._rounds.append((first, rounds, ids))
        self._every = max(1, self.size // (len(ids) or 1)) * self._period
        self._time_from(first, self._arr.clock.now)
        self._between()

    def record_set(self, m: Machine, old: tuple[Any, ...], round_: int, now: int) -> dict[str, list[Any]]:
        """A value set from the debugger (paused; `old`: the values before): a record of its
        own; returns the change."""
        i = m._id
        new = self.values[i].take(m)
        self.current[i] = new
        self.cache[i][:] = new
        self.sets += 1
        number = self._next_number() - 1
        if self.compiled:
            self._sets.append((number, now, i, m._state, round_, old, new))
        else:
            self._watched.append((number, now, (SET, i, m._state, round_), old, new))
        return self._named(i, _diff(old, new))

    def refresh(self) -> None:
        """Take every machine's values again for the page (compiled; on the scheduler's thread,
        between rounds or paused), when it asked."""
        self.wanted = False
        self.current = [v.take(m) for v, m in zip(self.values, self.machines, strict=True)]

    def trim(self) -> None:
        """Compiled, between rounds: once the items reach 2N, forget all but the newest N and
        what belongs to them (the list is cut at once: one C call for N records)."""
        items = self._items
        if len(items) < 2 * self.size:
            return
        cut = len(items) - self.size
        del items[:cut]
        self._dropped += cut
        oldest = self._dropped + 1
        gated = self._gated
        while gated:
            first = next(iter(gated))
            if first >= oldest:
                break
            del gated[first]
        self._sets = [s for s in self._sets if s[0] >= oldest]
        for table in (self._rounds, self._times):
            del table[: max(0, bisect_right(table, oldest, key=_first) - 1)]  # keep the one covering `oldest`

    # -- reading (on the scheduler's thread) ------------------------------------------------------
    @property
    def records(self) -> list[Part]:
        """The kept records, oldest first (scheduler's thread; `kept` counts them anywhere)."""
        return self._view(None)

    def _view(self, n: int | None) -> list[Part]:
        """The newest n kept records (all when None), oldest first."""
        n = self.size if n is None else min(max(n, 0), self.size)
        if not self.compiled:
            recs = list(self._watched)  # one C call: atomic for a reader on another thread
            return [self._parts(r[0], r[1:]) for r in (recs[-n:] if n else [])]
        out: list[Part] = []
        for part in self._walk():
            if len(out) >= n:
                break
            out.append(part)
        out.reverse()
        return out

    def _round_entry(self, number: int) -> tuple[int, int, tuple[int, ...]]:
        rounds = self._rounds
        return rounds[max(0, bisect_right(rounds, number, key=_first) - 1)]

    def round_of(self, number: int) -> int:
        if not self.compiled:
            return 0
        first, r, ids = self._round_entry(number)
        return r + (number - first) // len(ids) if ids else r

    def _time_of(self, number: int) -> int:
        times = self._times
        first, t = times[max(0, bisect_right(times, number, key=_first) - 1)]
        return t + (self.round_of(number) - self.round_of(first)) * self._period if self._period else t

    def _walk(self) -> Iterator[Part]:
        """The compiled records, newest first, read back from each machine's state and values as
        they are now, undoing each record in turn (a record that is the old value alone takes
        its meaning from the state after it; a value's new value is the one undone last)."""
        states = [m._state for m in self.machines]
        values = [list(v.take(m)) for v, m in zip(self.values, self.machines, strict=True)]
        items, base, sets, gated, codes = self._items, self._dropped, self._sets, self._gated, self._codes
        rounds, times, period = self._rounds, self._times, self._period
        rk, tk = len(rounds) - 1, len(times) - 1  # the entries that cover `number`, moving down with it
        t_round = self.round_of(times[tk][0])
        s = len(sets) - 1
        j = len(items) - 1
        while j >= 0 or s >= 0:
            number = base + j + 1
            if s >= 0 and (j < 0 or sets[s][0] >= number):
                n_set, t, i, state, round_, old, new = sets[s]
                changed = _diff(old, new)
                yield n_set, t, True, i, state, None, state, None, round_, changed
                values[i][:] = old
                s -= 1
                continue
            item = items[j]
            j -= 1
            while rk > 0 and rounds[rk][0] > number:
                rk -= 1
            first, r0, ids = rounds[rk]
            i = ids[(number - first) % len(ids)]
            round_ = r0 + (number - first) // len(ids)
            if tk > 0 and times[tk][0] > number:
                while tk > 0 and times[tk][0] > number:
                    tk -= 1
                t_round = self.round_of(times[tk][0])
            t = times[tk][1] + (round_ - t_round) * period
            if type(item) is tuple and item and item[0] is TURN:
                _turn, _i, before, after, old, new = item
                changed = _diff(old, new)
                yield number, t, False, i, before, None, after, None, round_, changed
                states[i] = before
                for k, a, _b in changed:
                    values[i][k] = a
                continue
            now = values[i]
            code = codes.get(id(item))
            head = codes.get(id(item[0])) if code is None and type(item) is tuple and item else None
            if code is not None and code is item:  # (None is no code: a value may be None)
                ran, after, fired, taken, flags = code
                olds: list[tuple[int, Any, Any]] = []
            elif head is not None and head is item[0]:
                ran, after, fired, taken, flags = head
                olds = []
                p = 1
                for k, how in taken:
                    if how == DIRECT:
                        olds.append((k, item[p], now[k]))
                        p += 1
                    else:
                        olds.append((k, item[p], item[p + 1]))
                        p += 2
                if flags & AFTER_AT_END:
                    after = item[p]
                    p += 1
                if flags & FIRED_AT_END:
                    fired = item[p]
            else:  # the old value alone: its meaning follows from the state after
                after = states[i]
                ran, fired, k = self.meanings[i][after]
                olds = [(k, item, now[k])]
            g = gated.get(number) if gated else None
            if g is None:
                changed = [c for c in olds if c[1] != c[2]]
                yield number, t, False, i, ran, ran, after, fired, round_, changed
                states[i] = ran
                for k, a, _b in changed:
                    now[k] = a
                continue
            before, old, mid = g
            full = list(mid)
            for k, _a, b in olds:
                full[k] = b
            yield number, t, False, i, before, ran, after, fired, round_, _diff(old, full)
            states[i] = before
            now[:] = old

    def _parts(self, number: int, rec: Record) -> Part:
        """A watched record read back."""
        t, code, old, new = rec
        if code[0] == FULL:
            _, i, before, ran, after, fired, round_ = code
            return number, t, False, i, before, ran, after, fired, round_, _diff(old, new)
        _, i, state, round_ = code
        return number, t, True, i, state, None, state, None, round_, _diff(old, new)

    def _named(self, i: int, changed: list[tuple[int, Any, Any]]) -> dict[str, list[Any]]:
        names = self.values[i].names
        return {names[k]: [shown(a), shown(b)] for k, a, b in changed}

    def as_dict(self, part: Part, published: dict[int, list[str]] | None = None) -> dict[str, Any]:
        number, t, set_, i, before, ran, after, fired, round_, changed = part
        states = self.machines[i].STATES
        if published is None:
            published = dict(self.published)
        return {
            "ringlet": number,
            "round": round_,
            "t": round(t / 1e9, 9),
            "machine": self.machines[i].NAME,
            "kind": "set" if set_ else "ringlet",
            "before": states[before],
            "state": None if ran is None else states[ran],
            "after": states[after],
            "transition": fired,
            "changed": self._named(i, changed),
            "published": [] if set_ else list(published.get(number, ())),
        }

    def last(self, n: int | None = None) -> list[dict[str, Any]]:
        """The newest n records (all kept ones when n is None), oldest first."""
        published = dict(self.published)
        return [self.as_dict(p, published) for p in self._view(n)]

    def entered(self, i: int) -> int:
        """The run time machine i entered its current state, as far as the kept records tell (the
        oldest kept record's time when they do not)."""
        recs = self.records
        for _n, t, set_, j, before, _ran, after, fired, _round, _changed in reversed(recs):
            if not set_ and j == i and (after != before or fired is not None):
                return t
        return recs[0][1] if recs and self.count > self.size else 0

    def snapshot(self) -> dict[str, dict[str, Any]]:
        """Each machine's values as the history last took them, as plain data (any thread)."""
        current = self.current
        self.wanted = self.compiled
        return {
            m.NAME: {n: shown(v) for n, v in zip(self.values[m._id].names, current[m._id], strict=True)}
            for m in self.machines
        }

    def frame(self, back: int) -> dict[str, Any]:
        """The arrangement `back` records ago (0: now, as of the newest record): each machine's
        state and values, and the record it is seen at (None for `back` = all kept records)."""
        kept = self.kept
        if not 0 <= back <= kept:
            raise IndexError(f"the history keeps {kept} records; {back} back is not one of them")
        recs = self._view(back + 1)  # read back no further than the record asked for
        if self.compiled:  # as they are now (on the scheduler's thread)
            states = [m._state for m in self.machines]
            values = [list(v.take(m)) for v, m in zip(self.values, self.machines, strict=True)]
        else:
            states = list(self.states)
            values = [list(c) for c in self.current]
        for k in range(len(recs) - 1, len(recs) - 1 - back, -1):
            _n, _t, _set, i, before, _ran, _after, _fired, _round, changed = recs[k]
            states[i] = before
            for j, old, _new in changed:
                values[i][j] = old
        at = recs[len(recs) - 1 - back] if back < len(recs) else None
        return {
            "record": None if at is None else self.as_dict(at),
            "machines": [
                {
                    "machine": m.NAME,
                    "state": m.STATES[states[i]],
                    "values": {n: shown(v) for n, v in zip(self.values[i].names, values[i], strict=True)},
                }
                for i, m in enumerate(self.machines)
            ],
        }


def _diff(old: Sequence[Any] | None, new: Sequence[Any] | None) -> list[tuple[int, Any, Any]]:
    """(index, old, new) of each value that differs between two takes."""
    if old is None or new is None:
        return []
    return [(k, a, b) for k, (a, b) in enumerate(zip(old, new, strict=True)) if a != b]


def recorder(h: History, m: Machine, reads: ClassReads) -> tuple[RingletRecorder, dict[str, Any]]:
    """What compiles machine m's ringlets to record themselves into `h` (traps.Recorder): each
    ringlet takes the values `reads` says it can change."""
    cls = type(m)
    v = h.values[m._id]
    taken = taken_by(reads, v.names, v.kinds, {e[0] for e in cls.INPUTS}, v.replaced_only)
    first = len(v.names) - len(v.slow) - len(v.messages)
    messages = {first + j: c for j, (_name, c) in enumerate(v.messages)}
    namespace = namespace_of(h._items.append, h.cache[m._id], taken_copy, plain, messages)
    meanings = h.meanings[m._id]

    def claim(after: int, meaning: tuple[int, int | None, int]) -> bool:
        return meanings.setdefault(after, meaning) == meaning

    def register(code: tuple[Any, ...]) -> tuple[Any, ...]:
        code = h._interned.setdefault(code, code)  # one object for equal codes: fewer to keep warm
        h._codes[id(code)] = code
        return code

    return RingletRecorder(cls.SUSPENDED, taken, v.names, TRAP, namespace, register, claim), namespace
