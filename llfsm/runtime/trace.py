"""Tracing: clfsm's `-v` lines and the `--trace FILE.jsonl` event log.

Only the instrumented scheduler loop calls a tracer, so a run without `-v`/`--trace` pays
nothing for this module.  The event log opens with a `machine` event per machine (its
description, as /llfsm/M/description carries it, and its variables' first values), so that a
trace alone can be replayed on the diagrams (`llfsm replay`, docs/debug.md); after each ringlet
that changed a variable or an input, a `variables` event gives each change as [old, new]
(plain values, bounded: llfsm.runtime.readout).
"""

from __future__ import annotations

import sys

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from collections.abc import Sequence

    from .machine import Machine
    from .protocols import TextSink
    from .readout import Changes


class Tracer:
    #: Whether the scheduler calls `values` after each ringlet (the event log records changes).
    records_values = False

    def __init__(self, verbose: TextSink | None = None, jsonl: TextSink | None = None) -> None:
        self.verbose = verbose
        self.jsonl = jsonl
        self.round = 0
        self.now = 0
        self.records_values = jsonl is not None
        self._changes: Changes | None = None

    def begin(self, machines: Sequence[Machine]) -> None:
        """The run starts: the event log names each machine, its diagram and its first values."""
        if self.jsonl is None or self._changes is not None:
            return
        from .readout import Changes, description  # deferred: start-up (only when tracing to a file)

        self._changes = Changes()
        for m in machines:
            self._event("machine", m, description=description(type(m)), variables=self._changes.first(m))

    def values(self, m: Machine) -> None:
        """After m's turn: its variables and inputs that changed, if any."""
        if self._changes is None:
            return
        changed = self._changes.changed(m)
        if changed:
            self._event("variables", m, changed=changed)

    def _event(self, kind: str, m: Machine, **fields: object) -> None:
        if self.jsonl is not None:
            import json  # only when tracing: a plain run does not import it at start-up

            rec = {"t": self.now / 1e9, "round": self.round, "event": kind, "machine": m.NAME, "id": m._id, **fields}
            self.jsonl.write(json.dumps(rec) + "\n")

    def entry(self, m: Machine, state: int) -> None:
        """Before the ringlet that enters `state` (clfsm prints here with -v)."""
        if self.verbose is not None:
            sys.stdout.flush()  # keep machine output and trace lines in order when both share a pipe
            line = "m%3d s%3d - %-20.20s - %s\n" % (m._id, state, m.NAME, m.STATES[state])  # noqa: UP031 (clfsm format)
            self.verbose.write(line)
            self.verbose.flush()
        self._event("entry", m, state=m.STATES[state])

    def transition(self, m: Machine, source: int, target: int, index: int) -> None:
        self._event("transition", m, source=m.STATES[source], target=m.STATES[target], index=index)

    def command(self, kind: str, m: Machine, state: int) -> None:
        self._event(kind, m, state=m.STATES[state])

    def finish(self, m: Machine) -> None:
        self._event("finish", m, state=m.STATES[m._state])

    def error(self, m: Machine | None, report: dict[str, object]) -> None:
        if self.jsonl is not None:
            # deferred: start-up, as in _event (only when tracing)
            import json

            fields = {("id" if k == "machine_id" else k): v for k, v in report.items()}
            rec = {"t": self.now / 1e9, "round": self.round, "event": "error", **fields}
            if m is not None:
                rec.setdefault("machine", m.NAME)
                rec.setdefault("id", m._id)
            self.jsonl.write(json.dumps(rec) + "\n")

    def close(self) -> None:
        if self.jsonl is not None:
            self.jsonl.flush()


class Tee(Tracer):
    """Several tracers seen as one by the scheduler, each told every event in turn: `-v` and
    `--trace` go on unchanged while a state feed (llfsm.ros.control) listens beside them."""

    def __init__(self, *tracers: Tracer) -> None:
        self.tracers = tracers
        self._round = self._now = 0
        self.records_values = any(t.records_values for t in tracers)

    def begin(self, machines: Sequence[Machine]) -> None:
        for t in self.tracers:
            t.begin(machines)

    def values(self, m: Machine) -> None:
        for t in self.tracers:
            t.values(m)

    @property
    def round(self) -> int:
        return self._round

    @round.setter
    def round(self, value: int) -> None:
        self._round = value
        for t in self.tracers:
            t.round = value

    @property
    def now(self) -> int:
        return self._now

    @now.setter
    def now(self, value: int) -> None:
        self._now = value
        for t in self.tracers:
            t.now = value

    def entry(self, m: Machine, state: int) -> None:
        for t in self.tracers:
            t.entry(m, state)

    def transition(self, m: Machine, source: int, target: int, index: int) -> None:
        for t in self.tracers:
            t.transition(m, source, target, index)

    def command(self, kind: str, m: Machine, state: int) -> None:
        for t in self.tracers:
            t.command(kind, m, state)

    def finish(self, m: Machine) -> None:
        for t in self.tracers:
            t.finish(m)

    def error(self, m: Machine | None, report: dict[str, object]) -> None:
        for t in self.tracers:
            t.error(m, report)

    def close(self) -> None:
        for t in self.tracers:
            t.close()
