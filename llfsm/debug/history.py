"""The history of a run: the last N ringlets, and the arrangement as it was at any of them
(docs/debug.md, "History").

Each ringlet boundary keeps one record: the ringlet's number, round and run time, the machine,
its state before the turn, the state its ringlet ran in and the one after, the transition that
fired, the variables and inputs that changed (old and new, as bounded plain values:
llfsm.runtime.readout) and the topics it published.  A value set from the debugger while paused
is a record too.  Records are tuples in a deque of N, so memory is bounded by N whatever the run
does (a value too large to keep whole is cut, and says so).

The arrangement at record k (the page's "History" slider) is rebuilt backwards from now: every
machine's state and values as they are, then each newer record undone (state back to its
`before`, each changed value back to its old value).  So nothing is kept per record but what
changed.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from typing import Any

from ..runtime.machine import Machine
from ..runtime.readout import Changes

#: One record: (number, round, run time ns, machine index, state before, state its ringlet ran in
#: (None: no ringlet), state after, transition index or None, changes {name: [old, new]},
#: topics published, what kind ("ringlet", or "set" for a value set while paused)).
Record = tuple[int, int, int, int, int, int | None, int, int | None, dict[str, list[Any]], tuple[str, ...], str]

#: What `--history` keeps when the page asks for history and the command line did not say.
PAGE_DEFAULT = 1000


class History:
    """The last `size` ringlet boundaries of an arrangement's machines."""

    def __init__(self, machines: Sequence[Machine], size: int) -> None:
        if size < 1:
            raise ValueError("--history must keep at least 1 ringlet")
        self.machines = list(machines)
        self.size = size
        self.records: deque[Record] = deque(maxlen=size)
        self.changes = Changes()
        self.states = [m._state for m in machines]
        self.entered = [0] * len(self.machines)  # run time each machine entered its state (as far as seen)
        self.first_values = [self.changes.first(m) for m in machines]
        #: Records made since the start (numbers of the dropped ones are below the first kept).
        self.count = 0

    def record(
        self,
        m: Machine,
        ran: int | None,
        fired: int | None,
        number: int,
        round_: int,
        now: int,
        published: Sequence[str],
    ) -> None:
        """After m's turn (the debugger's watcher calls this at every boundary)."""
        i = m._id
        before = self.states[i]
        after = m._state
        if after != before or fired is not None:
            self.entered[i] = now
        self.states[i] = after
        self.count += 1
        self.records.append(
            (number, round_, now, i, before, ran, after, fired, self.changes.changed(m), tuple(published), "ringlet")
        )

    def record_set(self, m: Machine, number: int, round_: int, now: int) -> dict[str, list[Any]]:
        """A value set from the debugger (paused): a record of its own; returns the change."""
        changed = self.changes.changed(m)
        i = m._id
        self.count += 1
        self.records.append((number, round_, now, i, m._state, None, m._state, None, changed, (), "set"))
        return changed

    # -- reading -------------------------------------------------------------------------------
    def as_dict(self, rec: Record) -> dict[str, Any]:
        number, round_, now, i, before, ran, after, fired, changed, published, kind = rec
        m = self.machines[i]
        states = m.STATES
        out: dict[str, Any] = {
            "ringlet": number,
            "round": round_,
            "t": round(now / 1e9, 9),
            "machine": m.NAME,
            "kind": kind,
            "before": states[before],
            "state": None if ran is None else states[ran],
            "after": states[after],
            "transition": fired,
            "changed": changed,
            "published": list(published),
        }
        return out

    def last(self, n: int | None = None) -> list[dict[str, Any]]:
        """The newest n records (all kept ones when n is None), oldest first."""
        recs = list(self.records)
        if n is not None:
            recs = recs[-n:] if n > 0 else []
        return [self.as_dict(r) for r in recs]

    def frame(self, back: int) -> dict[str, Any]:
        """The arrangement `back` records ago (0: now, as of the newest record): each machine's
        state and values, and the record it is seen at (None for `back` beyond what is kept)."""
        recs = self.records
        if not 0 <= back <= len(recs):
            raise IndexError(f"the history keeps {len(recs)} records; {back} back is not one of them")
        states = list(self.states)
        values = [dict(self.changes.last.get(m._id, {})) for m in self.machines]
        for k in range(len(recs) - 1, len(recs) - 1 - back, -1):
            _number, _r, _t, i, before, _ran, _after, _fired, changed, _pub, _kind = recs[k]
            states[i] = before
            for name, (old, _new) in changed.items():
                values[i][name] = old
        at = recs[len(recs) - 1 - back] if back < len(recs) else None
        return {
            "record": None if at is None else self.as_dict(at),
            "machines": [
                {"machine": m.NAME, "state": m.STATES[states[i]], "values": values[i]}
                for i, m in enumerate(self.machines)
            ],
        }
