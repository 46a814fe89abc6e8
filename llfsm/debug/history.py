"""The history of a run: the last N ringlets, and the arrangement as it was at any of them
(docs/debug.md, "History").

Each ringlet boundary keeps one record: the ringlet's number, round and run time, the machine,
its state before the turn, the state its ringlet ran in and the one after, the transition that
fired, what its variables and inputs held before and after (when anything changed) and the
topics it published.  A value set from the debugger while paused is a record too.

Records are made in one of two ways, which read back the same:

- **compiled** (recording.py), where every machine's ringlets can be compiled again from their
  generated module: each ringlet appends its own record, a small tuple, with the old and new
  values of only what it can change; the scheduler's gate (`Arrangement.around_release`) adds
  what a command, parameters or inputs changed, and records a turn in which no ringlet ran;
  rounds are numbered from the live machines the scheduler tells of (`on_live`: every live
  machine has one boundary a round);
- **watched**, otherwise (a native build, a machine the monitor compiled its checks into): the
  debugger's watcher calls `record` after every ringlet, which takes all of a machine's values
  as one tuple (`Values.take`) and compares it with the take before.

Values are taken as bounded plain data (llfsm.runtime.readout: a long string or a large list is
cut, and says so), messages as their generated copies, numbers, flags and handles as they are;
what changed, name by name, is worked out when a record is read.  Records are tuples in a deque
of N, and what they refer to is bounded per record: memory is bounded by N whatever the run does.

The arrangement at record k (the page's "History" slider) is rebuilt backwards from now: every
machine's state and values as they are, then each newer record undone.
"""

from __future__ import annotations

import sys
from collections import deque
from collections.abc import Callable, Sequence
from itertools import count
from operator import attrgetter
from typing import Any

from ..msgs._message import is_message_class
from ..runtime.generated import variables_of
from ..runtime.machine import Machine
from ..runtime.readout import plain
from ..runtime.reads import ClassReads
from .recording import AFTER_AT_END, COPIED, DIRECT, FIRED_AT_END, MESSAGE, RingletRecorder, namespace_of, taken_by
from .traps import TRAP

#: One record: (number, run time ns, code, values...); a set's number is the one of the boundary
#: it follows.  (Read back without its number: `records`.)  The code says what the values are:
#: - a ringlet's own record (recording.py), a constant: (machine index, state it ran in, state
#:   after, transition fired, indices of the values taken, flags); the values are old and new
#:   pairs of those, then the state after and the transition where the flags say they are not
#:   in the code;
#: - (FULL, machine index, state before, state its ringlet ran in (None: none ran), state after,
#:   transition, round (None: from the rounds' table)); then every value before and after, or
#:   None and None when nothing changed;
#: - (SET, machine index, state, round): a value set while paused; every value before and after.
Record = tuple[Any, ...]
FULL, SET = "full", "set"


#: What `--history` keeps when the page asks for history and the command line did not say.
PAGE_DEFAULT = 1000
#: Annotations (and input types) whose values are taken as they are: immutable scalars.
_SCALARS = frozenset({"bool", "int", "float"})
#: ...and other annotations of values that cannot change in place.
_IMMUTABLE_TEXT = frozenset({"str", "bytes"})
_NONE: tuple[str, ...] = ()


def _named(annotation: str, namespace: dict[str, Any]) -> Any:
    """The class a dotted annotation names in the machine module's globals, if any."""
    first, *rest = annotation.split(".")
    if not first.isidentifier() or not all(p.isidentifier() for p in rest):
        return None  # list[int], X | None ...
    obj = namespace.get(first)
    for part in rest:
        obj = getattr(obj, part, None)
    return obj if isinstance(obj, type) else None


def shown(value: Any) -> Any:
    """A taken value as a person reads it (plain data)."""
    return plain(value)


class Values:
    """How one machine's variables and inputs are taken (see the module's docstring)."""

    __slots__ = ("fast", "kinds", "messages", "names", "replaced_only", "single", "slow")

    def __init__(self, cls: type[Machine]) -> None:
        variables = list(variables_of(cls))
        declared = {n for n, _ in variables}
        variables += [(e[0], e[1]) for e in cls.INPUTS if e[0] not in declared]
        namespace = vars(sys.modules[cls.__module__]) if cls.__module__ in sys.modules else {}
        fast, messages, slow = [], [], []
        for name, annotation in variables:
            named = None if annotation.strip() in _SCALARS else _named(annotation.strip(), namespace)
            if named is not None and is_message_class(named):
                messages.append((name, named))  # a copy (generated), compared field by field
            elif annotation.strip() in _SCALARS or (named is not None and named.__module__ != "builtins"):
                fast.append(name)  # a scalar, or a handle (a node, a publisher) shown as <Type>
            else:
                slow.append(name)
        self.messages = tuple(messages)
        self.slow = tuple(slow)
        self.names = tuple(fast) + tuple(n for n, _ in messages) + self.slow
        #: one C call for the scalars (attrgetter of one name gives the value, not a tuple)
        self.fast: Any = attrgetter(*fast) if fast else None
        self.single = len(fast) == 1
        #: how each value is taken, for a ringlet that records it (recording.py)
        self.kinds = (DIRECT,) * len(fast) + (MESSAGE,) * len(messages) + (COPIED,) * len(slow)
        #: values whose shown value changes only when the variable is assigned: immutable ones,
        #: and handles (shown by their type)
        self.replaced_only = frozenset(fast) | {n for n, a in variables if a.strip() in _IMMUTABLE_TEXT}

    def take(self, m: Machine) -> tuple[Any, ...]:
        """The machine's values now, in `names` order."""
        fast = self.fast
        out: tuple[Any, ...] = (fast(m),) if self.single else fast(m) if fast is not None else ()
        if self.messages:
            out += tuple(_encode(getattr(m, n, None), c) for n, c in self.messages)
        if self.slow:
            out += tuple(plain(getattr(m, n, None)) for n in self.slow)
        return out


def _encode(value: Any, cls: type[Any]) -> Any:
    """A message as it was (its generated copy, compared field by field); else plain data."""
    return value._copy() if type(value) is cls else plain(value)


class History:
    """The last `size` ringlet boundaries of an arrangement's machines."""

    def __init__(self, machines: Sequence[Machine], size: int) -> None:
        if size < 1:
            raise ValueError("--history must keep at least 1 ringlet")
        self.machines = list(machines)
        self.size = size
        #: The records, oldest first, the newest `size` kept: a deque, which frees the oldest
        #: record as it takes a new one (so a long run makes no work for the garbage collector).
        self.ring: deque[Record] = deque(maxlen=size)
        #: What numbers the boundaries' records (a C call in each compiled ringlet: `next`).
        self.counter = count(1)
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
        #: Whether the ringlets record themselves (set by the debugger once they are compiled).
        self.compiled = False
        #: Topics published, by the number of the boundary they belong to (the next one when
        #: published): (number, [topic, ...]), at most one entry per record.
        self.published: deque[tuple[int, list[str]]] = deque(maxlen=size)
        #: What the gate did before a ringlet (compiled): by the ringlet's record's number,
        #: (state before, values before, values after).
        self._gated: dict[int, tuple[int, tuple[Any, ...], tuple[Any, ...]]] = {}
        #: Rounds (compiled): (first number, its round, live machines a round), in order.
        self._rounds: list[tuple[int, int, int]] = [(1, 0, len(self.machines))]
        #: The page asked for the values (`snapshot`): `refresh` takes them again.
        self.wanted = False
        #: Values waiting for their machine's next turn (the arrangement's, by machine id: set by
        #: the debugger when the ringlets record themselves).
        self.waiting: dict[int, Any] = {}

    # -- made on the scheduler's thread ------------------------------------------------------------
    def _next_number(self) -> int:
        """The number the next boundary's record will have (without taking it from the counter:
        the newest record's, a boundary's or a set's, is the one before it)."""
        ring = self.ring
        return int(ring[-1][0]) + 1 if ring else 1

    @property
    def count(self) -> int:
        """Records made since the start (numbers of the dropped ones are below the first kept)."""
        return self._next_number() - 1 + self.sets

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
        number = next(self.counter)
        if published:
            self.published.append((number, list(published)))
        self.ring.append((number, now, (FULL, i, before, ran, after, fired, round_), old, new))

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
            self.ring.append(
                (next(self.counter), m._clock.now, (FULL, i, before, None, before, None, None), None, None)
            )
            return False
        take = self.values[i].take
        old = take(m)
        goes = let_go(m)
        new = take(m)
        self.cache[i][:] = new
        if goes:
            if new != old or m._state != before:
                self._gated[self._next_number()] = (before, old, new)
                self.trim()
        else:
            changed = (old, new) if new != old else (None, None)
            self.ring.append(
                (next(self.counter), m._clock.now, (FULL, i, before, None, m._state, None, None), *changed)
            )
        return goes

    def on_live(self, rounds: int, live: list[Machine]) -> None:
        """Arrangement.on_live (compiled): from the next record on, `len(live)` records a round."""
        first, n = self._next_number(), len(live)
        last = self._rounds[-1]
        if last[0] == first:
            self._rounds[-1] = (first, rounds, n)
        elif last[2] != n or self.round_of(first) != rounds:
            self._rounds.append((first, rounds, n))
        self.trim()

    def record_set(self, m: Machine, old: tuple[Any, ...], round_: int, now: int) -> dict[str, list[Any]]:
        """A value set from the debugger (paused; `old`: the values before): a record of its
        own; returns the change."""
        i = m._id
        new = self.values[i].take(m)
        self.current[i] = new
        self.cache[i][:] = new
        self.sets += 1
        self.ring.append((self._next_number() - 1, now, (SET, i, m._state, round_), old, new))
        return self._named(i, _diff(old, new))

    def refresh(self) -> None:
        """Take every machine's values again for the page (compiled; on the scheduler's thread,
        between rounds or paused), when it asked."""
        self.wanted = False
        self.current = [v.take(m) for v, m in zip(self.values, self.machines, strict=True)]

    def trim(self) -> None:
        """Forget what belongs to records no longer kept."""
        ring = self.ring
        if len(ring) < self.size:
            return
        oldest = ring[0][0]
        gated = self._gated
        while gated:
            first = next(iter(gated))
            if first >= oldest:
                break
            del gated[first]
        rounds = self._rounds
        while len(rounds) > 1 and rounds[1][0] <= oldest:
            del rounds[0]

    # -- reading (on the scheduler's thread) ------------------------------------------------------
    @property
    def records(self) -> list[tuple[int, Record]]:
        """The kept records, oldest first: (number, the record after its number)."""
        return self._newest(None)

    def _newest(self, n: int | None) -> list[tuple[int, Record]]:
        recs = list(self.ring)  # one C call: atomic for a reader on another thread
        if n is not None:
            recs = recs[-n:] if n > 0 else []
        return [(r[0], r[1:]) for r in recs]

    def round_of(self, number: int) -> int:
        rounds = self._rounds
        k = len(rounds) - 1
        while k > 0 and rounds[k][0] > number:
            k -= 1
        first, r, n = rounds[k]
        return r + (number - first) // n if n else r

    def _parts(
        self, number: int, rec: Record
    ) -> tuple[int, int, int | None, int, int | None, int | None, list[tuple[int, Any, Any]]]:
        """(machine index, state before, state it ran in, state after, transition, round (None:
        from the table), [(value index, old, new) of each value that changed])."""
        code = rec[1]
        kind = code[0]
        if kind == FULL:
            _, i, before, ran, after, fired, round_ = code
            return i, before, ran, after, fired, round_, _diff(rec[2], rec[3])
        if kind == SET:
            return code[1], code[2], None, code[2], None, code[3], _diff(rec[2], rec[3])
        i, ran, after, fired, taken, flags = code
        if flags:
            extra = list(rec[2 + 2 * len(taken) :])
            if flags & AFTER_AT_END:
                after = extra.pop(0)
            if flags & FIRED_AT_END:
                fired = extra.pop(0)
        gated = self._gated.get(number) if self._gated else None
        if gated is None:
            changed = [
                (k, rec[2 + 2 * t], rec[3 + 2 * t]) for t, k in enumerate(taken) if rec[2 + 2 * t] != rec[3 + 2 * t]
            ]
            return i, ran, ran, after, fired, None, changed
        before, old, mid = gated
        new = list(mid)
        for t, k in enumerate(taken):
            new[k] = rec[3 + 2 * t]
        return i, before, ran, after, fired, None, _diff(old, new)

    def _named(self, i: int, changed: list[tuple[int, Any, Any]]) -> dict[str, list[Any]]:
        names = self.values[i].names
        return {names[k]: [shown(a), shown(b)] for k, a, b in changed}

    def as_dict(self, number: int, rec: Record, published: dict[int, list[str]] | None = None) -> dict[str, Any]:
        i, before, ran, after, fired, round_, changed = self._parts(number, rec)
        m = self.machines[i]
        states = m.STATES
        set_ = rec[1][0] == SET
        if published is None:
            published = dict(self.published)
        return {
            "ringlet": number,
            "round": self.round_of(number) if round_ is None else round_,
            "t": round(rec[0] / 1e9, 9),
            "machine": m.NAME,
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
        recs = self._newest(n)
        published = dict(self.published)
        return [self.as_dict(number, r, published) for number, r in recs]

    def entered(self, i: int) -> int:
        """The run time machine i entered its current state, as far as the kept records tell (the
        oldest kept record's time when they do not)."""
        recs = self.records
        for number, rec in reversed(recs):
            if rec[1][0] == SET:
                continue
            j, before, _ran, after, fired, _round, _changed = self._parts(number, rec)
            if j != i:
                continue
            if after != before or fired is not None:
                return int(rec[0])
        return int(recs[0][1][0]) if recs and self.count > self.size else 0

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
        recs = self.records
        if not 0 <= back <= len(recs):
            raise IndexError(f"the history keeps {len(recs)} records; {back} back is not one of them")
        if self.compiled:  # as they are now (on the scheduler's thread)
            states = [m._state for m in self.machines]
            values = [list(v.take(m)) for v, m in zip(self.values, self.machines, strict=True)]
        else:
            states = list(self.states)
            values = [list(c) for c in self.current]
        for k in range(len(recs) - 1, len(recs) - 1 - back, -1):
            i, before, _ran, _after, _fired, _round, changed = self._parts(*recs[k])
            states[i] = before
            for j, old, _new in changed:
                values[i][j] = old
        at = recs[len(recs) - 1 - back] if back < len(recs) else None
        return {
            "record": None if at is None else self.as_dict(*at),
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
    return RingletRecorder(m._id, cls.SUSPENDED, taken, v.names, TRAP), namespace_of(
        h.ring.append, h.counter, h.cache[m._id], _encode, plain, messages
    )
