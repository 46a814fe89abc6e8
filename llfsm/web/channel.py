"""The channel from the view's server to a page: protocol 1 (docs/view.md, "The page's channel").

A page is sent the whole of what it shows once, then only what changed:

- `hello`: the first message of a connection, and again whenever the machines' diagrams
  change: `{"type": "hello", "protocol": 1, "machines": [diagrams], "graph": graph or null,
  "snapshot": state}`, where `state` has the form of a delta from nothing (every row upserted);
- `delta`: `{"type": "delta", "seq": n, ...}` holding only the parts that changed since the
  message before: `header` (run time, clock, source, ended), each collection (`machines`,
  `topics`, `services`) as `{"upsert": [rows], "remove": [keys], "total": n}`, `param_events`
  (node -> count, the changed ones), `world` (the turtle world's SVG), `monitor` (verdicts),
  `debug` (the debugger's status, and the variables of the machines whose values changed);
- `graph`: the drawing of nodes and topics and the lists beside it, when they change.

Every collection is bounded before it is sent (the source bounds its rows; `total` counts what
it left out), so what a page receives per second is bounded by what it can draw, whatever a peer
does.  The deltas are computed once and sent to every page: they share one baseline, and a page
that connects is sent that baseline, so that the next delta applies to it exactly.

`Mirror` is the receiving side in Python (the tests' clients use it; the page's script does the
same in JavaScript): it keeps the state the messages describe.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

#: The protocol's version, in every hello: a page that does not know it must not guess.
PROTOCOL = 1
#: The keyed collections of a state, and the field that keys their rows.
COLLECTIONS = {"machines": "name", "topics": "name", "services": "name"}
#: The parts of a state sent whole when they change: the turtle world's SVG, the monitor's
#: verdicts (llfsm.web.verdicts: a count and the newest 20), the debugger's part
#: (llfsm.web.debugging: status, breakpoints, the variables of each machine; None without one).
WHOLE = ("world", "monitor", "debug")
#: What a page is sent at most (docs/view.md, "The page's channel"): rows of the topics table,
#: services named in the call form, characters of a topic's last message.  The rest is counted.
#: (Machines are bounded by their sources, the graph's lists by llfsm.web.rosgraph.)
MAX_TOPIC_ROWS = 200
MAX_SERVICE_ROWS = 500
MAX_LAST_CHARS = 2000
#: A topic's row (count, rate, last message) is read again at most this often (wall seconds): a
#: busy topic's count changes at every sample, and the table need not be redrawn 20 times a second.
ROW_PERIOD = 0.5


def bounded_text(text: str) -> str:
    """A topic's last message as the page shows it: at most MAX_LAST_CHARS, the rest said."""
    if len(text) <= MAX_LAST_CHARS:
        return text
    return f"{text[:MAX_LAST_CHARS]}\n... ({len(text) - MAX_LAST_CHARS:,} more characters not shown)"


class Channel:
    """The deltas of a sequence of states (one per sample of the source), computed once for
    every page.  A state is `{"header": {...}, "machines": {key: row}, "topics": {key: row},
    "topics_total": n, "services": {key: row}, "services_total": n, "param_events": {node: n},
    "world": svg or None}` (llfsm.web.source.Source.state)."""

    def __init__(self) -> None:
        self.seq = 0
        self._last: dict[str, Any] | None = None

    @property
    def baseline(self) -> dict[str, Any] | None:
        """The state the last message described: what a page that connects now is sent."""
        return self._last

    def reset(self, state: dict[str, Any]) -> dict[str, Any]:
        """A hello's `snapshot`: `state` as a delta from nothing; it becomes the baseline."""
        self._last = state
        return full(state, self.seq)

    def delta(self, state: dict[str, Any]) -> dict[str, Any] | None:
        """The delta from the baseline to `state` (which becomes the baseline), or None when
        nothing changed."""
        last = self._last
        if last is None:
            self.reset(state)
            return full(state, self.seq)
        out: dict[str, Any] = {}
        if state["header"] != last["header"]:
            out["header"] = state["header"]
        for name in COLLECTIONS:
            now, before = state[name], last[name]
            upsert = [row for key, row in now.items() if before.get(key) != row]
            remove = [key for key in before if key not in now]
            total = state.get(f"{name}_total", len(now))
            if upsert or remove or total != last.get(f"{name}_total", len(before)):
                out[name] = {"upsert": upsert, "remove": remove, "total": total}
        events = {node: n for node, n in state["param_events"].items() if last["param_events"].get(node) != n}
        if events:
            out["param_events"] = events
        for part in WHOLE:
            if state.get(part) != last.get(part):
                out[part] = state.get(part)
        if "debug" in out:
            out["debug"] = _debug_delta(state.get("debug"), last.get("debug"))
        self._last = state
        if not out:
            return None
        self.seq += 1
        return {"type": "delta", "seq": self.seq, **out}


def _debug_delta(now: dict[str, Any] | None, before: dict[str, Any] | None) -> dict[str, Any] | None:
    """The debugger's part as a delta sends it: whole, but for `variables`, which holds only the
    machines whose values changed (None for a machine no longer there): a step of one machine
    among two hundred sends one machine's values."""
    if now is None or before is None:
        return now
    was, values = before.get("variables") or {}, now.get("variables") or {}
    changed: dict[str, Any] = {m: v for m, v in values.items() if was.get(m) != v}
    changed.update((m, None) for m in was if m not in values)
    return {**now, "variables": changed}


def state_of(
    *,
    t: float = 0.0,
    clock: str = "wall",
    source: str = "run",
    ended: bool = False,
    machines: Iterable[dict[str, Any]] = (),
    topics: Iterable[dict[str, Any]] = (),
    topics_total: int | None = None,
    services: Iterable[dict[str, Any]] = (),
    services_total: int | None = None,
    param_events: dict[str, int] | None = None,
    world: str | None = None,
    monitor: dict[str, Any] | None = None,
    debug: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """A state as a source hands it to the channel: rows keyed by name (machines keep their
    order in `order`), totals counting what the rows leave out."""
    rows = {name: {r["name"]: r for r in kind} for name, kind in (("topics", topics), ("services", services))}
    return {
        "header": {"t": t, "clock": clock, "source": source, "ended": ended},
        "machines": {r["name"]: {**r, "order": i} for i, r in enumerate(machines)},
        "topics": rows["topics"],
        "topics_total": len(rows["topics"]) if topics_total is None else topics_total,
        "services": rows["services"],
        "services_total": len(rows["services"]) if services_total is None else services_total,
        "param_events": dict(param_events or {}),
        "world": world,
        "monitor": monitor,
        "debug": debug,
    }


def full(state: dict[str, Any], seq: int) -> dict[str, Any]:
    """A state as a delta from nothing (a hello's snapshot)."""
    out: dict[str, Any] = {"type": "delta", "seq": seq, "header": state["header"]}
    for name in COLLECTIONS:
        rows = state[name]
        out[name] = {"upsert": list(rows.values()), "remove": [], "total": state.get(f"{name}_total", len(rows))}
    out["param_events"] = dict(state["param_events"])
    for part in WHOLE:
        out[part] = state.get(part)
    return out


class Mirror:
    """What a page holds after the messages it received (protocol 1): `apply(message)` returns
    the state as one dict, `{"t", "clock", "source", "ended", "machines": [rows], "topics":
    [rows], "topics_total", "services": [rows], "services_total", "param_events", "world",
    "monitor", "debug"}`,
    after a hello or a delta, and None after any other message."""

    def __init__(self) -> None:
        self.header: dict[str, Any] = {}
        self.rows: dict[str, dict[str, Any]] = {name: {} for name in COLLECTIONS}
        self.totals: dict[str, int] = {name: 0 for name in COLLECTIONS}
        self.param_events: dict[str, int] = {}
        self.whole: dict[str, Any] = dict.fromkeys(WHOLE)
        self.seq = -1

    def apply(self, message: dict[str, Any]) -> dict[str, Any] | None:
        kind = message.get("type")
        if kind == "hello":
            if message.get("protocol") != PROTOCOL:
                raise ValueError(f"protocol {message.get('protocol')!r} is not {PROTOCOL}")
            self.__init__()  # type: ignore[misc]  # a hello replaces everything
            self._delta(message["snapshot"])
        elif kind == "delta":
            self._delta(message)
        else:
            return None
        return self.state()

    def _delta(self, d: dict[str, Any]) -> None:
        self.seq = d.get("seq", self.seq)
        self.header.update(d.get("header") or {})
        for name, key in COLLECTIONS.items():
            change = d.get(name)
            if change is None:
                continue
            rows = self.rows[name]
            for gone in change.get("remove", ()):
                rows.pop(gone, None)
            for row in change.get("upsert", ()):
                rows[row[key]] = row
            self.totals[name] = change.get("total", len(rows))
        self.param_events.update(d.get("param_events") or {})
        debug_before = self.whole["debug"]
        for part in WHOLE:
            if part in d:
                self.whole[part] = d[part]
        debug = self.whole["debug"]
        if "debug" in d and debug is not None and debug_before is not None:  # the machines that changed
            variables = {**(debug_before.get("variables") or {}), **(debug.get("variables") or {})}
            self.whole["debug"] = {**debug, "variables": {m: v for m, v in variables.items() if v is not None}}

    def state(self) -> dict[str, Any]:
        out = dict(self.header)
        for name in COLLECTIONS:
            out[name] = (
                sorted(self.rows[name].values(), key=lambda r: r.get("order", 0))
                if name == "machines"
                else [self.rows[name][k] for k in sorted(self.rows[name])]
            )
            out[f"{name}_total"] = self.totals[name]
        out["param_events"] = dict(self.param_events)
        out.update(self.whole)
        return out
