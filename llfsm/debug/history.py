"""The history of a run: the last N ringlets, and the arrangement as it was at any of them
(docs/debug.md, "History").

Each ringlet boundary keeps one record: the ringlet's number, round and run time, the machine,
its state before the turn, the state its ringlet ran in and the one after, the transition that
fired, what its variables and inputs held before and after (when anything changed) and the
topics it published.  A value set from the debugger while paused is a record too.

Recording is on the hot path of a debugged run, so it does as little as it can: a machine's
values are taken as one tuple, `Values.take`; those annotated bool, int or float (and inputs of
those types) and handles (a node, a publisher: shown as `<Type>`, so only a new object is a
change) by one C call (operator.attrgetter), messages as their generated copies, the others as
bounded plain values (llfsm.runtime.readout: a long string or a large
list is cut, and says so).  A record
holds the tuple before and the tuple after, shared with the records around it, and nothing at
all when nothing changed; what changed, name by name, is worked out when a record is read.
Records are tuples in a deque of N: memory is bounded by N whatever the run does.

The arrangement at record k (the page's "History" slider) is rebuilt backwards from now: every
machine's state and values as they are, then each newer record undone.
"""

from __future__ import annotations

import sys
from collections import deque
from collections.abc import Sequence
from operator import attrgetter
from typing import Any

from ..msgs._message import is_message_class
from ..runtime.generated import variables_of
from ..runtime.machine import Machine
from ..runtime.readout import plain

#: One record: (number, round, run time ns, machine index, state before, state its ringlet ran in
#: (None: no ringlet), state after, transition index or None, values before, values after (None,
#: None: nothing changed), topics published, kind: "ringlet", or "set" for a set while paused).
Record = tuple[int, int, int, int, int, "int | None", int, "int | None", Any, Any, tuple[str, ...], str]

#: What `--history` keeps when the page asks for history and the command line did not say.
PAGE_DEFAULT = 1000
#: Annotations (and input types) whose values are taken as they are: immutable scalars.
_SCALARS = frozenset({"bool", "int", "float"})
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

    __slots__ = ("fast", "messages", "names", "single", "slow")

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
        self.records: deque[Record] = deque(maxlen=size)
        self.values = [Values(type(m)) for m in machines]
        self.current = [v.take(m) for v, m in zip(self.values, machines, strict=True)]
        self.first = list(self.current)
        self.states = [m._state for m in machines]
        self.entered = [0] * len(self.machines)  # run time each machine entered its state (as far as seen)
        #: Records made since the start (numbers of the dropped ones are below the first kept).
        self.count = 0

    def record(
        self, m: Machine, ran: int | None, fired: int | None, number: int, round_: int, now: int, published: list[str]
    ) -> None:
        """After m's turn (the debugger's watcher calls this at every boundary)."""
        i = m._id
        before = self.states[i]
        after = m._state
        if after != before or fired is not None:
            self.entered[i] = now
            self.states[i] = after
        old: tuple[Any, ...] | None = self.current[i]
        new: tuple[Any, ...] | None = self.values[i].take(m)
        if new == old:
            old = new = None
        else:
            self.current[i] = new  # type: ignore[assignment]  # a take, never None here
        self.count += 1
        pub = tuple(published) if published else _NONE
        self.records.append((number, round_, now, i, before, ran, after, fired, old, new, pub, "ringlet"))

    def record_set(self, m: Machine, number: int, round_: int, now: int) -> dict[str, list[Any]]:
        """A value set from the debugger (paused): a record of its own; returns the change."""
        i = m._id
        old, new = self.current[i], self.values[i].take(m)
        self.current[i] = new
        self.count += 1
        # its state as the history last saw it (a set during a pause inside a ringlet comes
        # before that ringlet's own record), so that undoing records stays consistent
        state = self.states[i]
        self.records.append((number, round_, now, i, state, None, state, None, old, new, _NONE, "set"))
        return self.changes(i, old, new)

    # -- reading -------------------------------------------------------------------------------
    def changes(self, i: int, old: Any, new: Any) -> dict[str, list[Any]]:
        """{name: [old, new]} of machine i's values that differ between two takes."""
        if old is None or new is None:
            return {}
        names = self.values[i].names
        return {names[k]: [shown(a), shown(b)] for k, (a, b) in enumerate(zip(old, new, strict=True)) if a != b}

    def as_dict(self, rec: Record) -> dict[str, Any]:
        number, round_, now, i, before, ran, after, fired, old, new, published, kind = rec
        states = self.machines[i].STATES
        return {
            "ringlet": number,
            "round": round_,
            "t": round(now / 1e9, 9),
            "machine": self.machines[i].NAME,
            "kind": kind,
            "before": states[before],
            "state": None if ran is None else states[ran],
            "after": states[after],
            "transition": fired,
            "changed": self.changes(i, old, new),
            "published": list(published),
        }

    def last(self, n: int | None = None) -> list[dict[str, Any]]:
        """The newest n records (all kept ones when n is None), oldest first."""
        recs = list(self.records)
        if n is not None:
            recs = recs[-n:] if n > 0 else []
        return [self.as_dict(r) for r in recs]

    def frame(self, back: int) -> dict[str, Any]:
        """The arrangement `back` records ago (0: now, as of the newest record): each machine's
        state and values, and the record it is seen at (None for `back` = all kept records)."""
        recs = self.records
        if not 0 <= back <= len(recs):
            raise IndexError(f"the history keeps {len(recs)} records; {back} back is not one of them")
        states = list(self.states)
        values = list(self.current)
        for k in range(len(recs) - 1, len(recs) - 1 - back, -1):
            rec = recs[k]
            i = rec[3]
            states[i] = rec[4]
            if rec[8] is not None:
                values[i] = rec[8]
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
