"""`llfsm bag check BAG`: the monitor's properties judged over a recorded bag (SPEC 16;
docs/monitor.md, "A recorded bag").

A bag holds what was published, not the machines' variables, so its atoms are `state(m)`,
read from `/llfsm/m/state` (std_msgs/msg/String, the current state's name, as llfsm's runs
publish it and any recorder records it), and `published(topic)`.  Each message on a state topic
or on a topic a property names is one boundary, in the bag's time order: a state message sets
its machine's state there, and `published(topic)` holds at the boundary of a message on that
topic.  Before its first state message a machine's `state(m)` is None.  The machines are the
bag's `/llfsm/*/state` topics; their states are read from `/llfsm/m/description` when the bag
has it (a property naming a state the machine does not have is then one clear line), and taken
as they come otherwise.

What a bag holds is checked before it is used (SPEC 18), one clear line for each kind of problem
(said once per topic, with a count at the end), and the rest of the bag is read on: a state
topic of another type (left out: a property naming its machine is then a usage error), a state
message that does not decode (bad UTF-8, truncated) or is longer than MAX_STATE_BYTES, a
description that is not the JSON llfsm writes or is longer than MAX_DESCRIPTION bytes, more than
MAX_STATES state names for one machine.  Time is linear in the bag, memory bounded by the
largest message kept (MAX_STATE_BYTES) and the state names.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

from ..bag.reader import BagReader
from ..msgs._dds import from_cdr
from ..msgs.std_msgs.msg import String
from ..props.atoms import MachineInfo
from ..props.file import PropertySource
from .judge import HELD, NOT_SEEN, PENDING, SATISFIED, VIOLATED, Boundary, Judge, MonitorError, Verdict, atom_reads

STATE_TYPE = "std_msgs/msg/String"
#: The longest state message, description and number of state names taken from a bag.
MAX_STATE_BYTES = 4096
MAX_DESCRIPTION = 1 << 20
MAX_STATES = 10_000
#: What a bag holds of a machine: its state (suspended, finished and variables are not recorded).
READABLE = ("_state",)
#: What each verdict says in bag check's lines.
SHOWN = {
    HELD: "held at some message",
    NOT_SEEN: "not seen in the bag",
    SATISFIED: "satisfied",
}


class Recorded:
    """A machine as a bag shows it: what an atom reads (`STATES[_state]`), its state names
    numbered as they come (0: no state yet)."""

    def __init__(self, name: str, states: Sequence[str]) -> None:
        self.NAME = name
        self.STATES: list[str | None] = [None, *states]
        self.index = {s: k + 1 for k, s in enumerate(states)}
        self._state = 0
        self._suspended = False
        self._finished = False

    def enter(self, state: str) -> bool:
        """The machine is now in `state`; False when it has too many states to keep another."""
        k = self.index.get(state)
        if k is None:
            if len(self.STATES) > MAX_STATES:
                return False
            k = self.index[state] = len(self.STATES)
            self.STATES.append(state)
        self._state = k
        return True


@dataclass
class BagVerdicts:
    """What `check_bag` found: each property's verdict, and how much of the bag it read."""

    verdicts: list[Verdict]
    boundaries: int
    notes: list[str] = field(default_factory=list)

    @property
    def failed(self) -> bool:
        return any(v.verdict in (VIOLATED, NOT_SEEN) for v in self.verdicts)

    def lines(self) -> list[str]:
        out = []
        for v in self.verdicts:
            if v.verdict == VIOLATED:
                out.append(v.line().replace("llfsm: monitor: ", "", 1))
            elif v.verdict == PENDING:
                out.append(f"{v.name}: pending at the end of the bag ({v.detail})")
            elif v.verdict == "holds":
                out.append(f"{v.name}: holds ({self.boundaries:,} messages)")
            else:
                out.append(f"{v.name}: {SHOWN[v.verdict]}")
        return out


class _Notes:
    """One line per kind of problem and topic, counted."""

    def __init__(self, say: Callable[[str], None]) -> None:
        self.say = say
        self.counts: dict[tuple[str, str], int] = {}

    def __call__(self, topic: str, kind: str, text: str) -> None:
        key = (topic, kind)
        n = self.counts.get(key, 0)
        self.counts[key] = n + 1
        if n == 0:
            self.say(f"llfsm: bag check: {topic}: {text}")

    def summary(self) -> list[str]:
        return [f"{topic}: {n:,} messages left out ({kind})" for (topic, kind), n in self.counts.items() if n > 1]


def check_bag(path: str | Path, sources: Sequence[PropertySource], say: Callable[[str], None]) -> BagVerdicts:
    """Judge `sources` over the bag at `path` (BagError or MonitorError: one line, status 2)."""
    if not sources:
        raise MonitorError("bag check: give a property (--property KIND:TEXT) or a verification file")
    notes = _Notes(say)
    with BagReader(path) as reader:
        machines, state_topics = _machines(reader, notes)
        infos = {
            m.NAME: MachineInfo(k, m.NAME, tuple(s for s in m.STATES if s), (), known_states=len(m.STATES) > 1)
            for k, m in enumerate(machines)
        }
        try:
            judge = Judge(sources, infos, say)
        except MonitorError as e:
            if "has no variable or input" not in str(e):
                raise
            raise MonitorError(
                f"{e} (a bag holds each machine's state and what was published, not its variables)"
            ) from None
        for a in judge.atoms:
            for r in atom_reads(a):
                if r.what not in READABLE:
                    raise MonitorError(
                        f"{a.where}: `{a.text}`: a bag holds each machine's state and what was published, "
                        f"not {_what(r.what)}: bag check reads state(m) and published(topic)"
                    )
        topics = judge.topics_named()
        wanted = [c for c in reader.connections if c.topic in topics or c.topic in state_topics]
        start = reader.start_time
        count = 0
        published: set[str] = set()
        found: dict[int, Verdict] = {}
        for conn, t, data in reader.messages(wanted) if wanted else ():
            count += 1
            m = state_topics.get(conn.topic)
            if m is not None and conn.msgtype == STATE_TYPE:
                state = _state(conn.topic, data, notes)
                if state is not None and not m.enter(state):
                    notes(conn.topic, "too many states", f"more than {MAX_STATES:,} state names: the rest are left out")
            if conn.topic in topics:
                published.add(conn.topic)
            here = partial(Boundary, count, unit="message")
            for v in judge.boundary(machines, published, t - start, here):
                v.states = [(m.NAME, str(m.STATES[m._state])) for m in machines]
                found[v.judged.index] = v
            published.clear()
    end = Boundary(count, unit="message")
    found.update({v.judged.index: v for v in judge.at_end(0, end)})
    # a safety property never violated, an obligation always met: it holds over the bag
    verdicts = [found.get(j.index) or Verdict(j, "holds", 0, end) for j in judge.judged]
    return BagVerdicts(verdicts, count, notes.summary())


def _what(attr: str) -> str:
    return {"_suspended": "suspended(m)", "_finished": "finished(m)"}.get(attr, f"variables (`.{attr}`)")


def _machines(reader: BagReader, notes: _Notes) -> tuple[list[Recorded], dict[str, Recorded]]:
    """The machines of the bag's /llfsm/M/state topics (std_msgs/msg/String), with the states
    of their /llfsm/M/description where the bag has it."""
    names: dict[str, str] = {}
    for c in reader.connections:
        parts = c.topic.split("/")
        if len(parts) != 4 or parts[:2] != ["", "llfsm"] or parts[3] != "state":
            continue
        name = parts[2]
        if not name.isidentifier():
            notes(c.topic, "name", "not a machine name a property can use: left out")
        elif c.msgtype != STATE_TYPE:
            notes(c.topic, "type", f"of type {c.msgtype}, not {STATE_TYPE}: left out")
        else:
            names[name] = c.topic
    states = _descriptions(reader, set(names), notes)
    machines = [Recorded(n, states.get(n, ())) for n in sorted(names)]
    return machines, {names[m.NAME]: m for m in machines}


def _descriptions(reader: BagReader, names: set[str], notes: _Notes) -> dict[str, tuple[str, ...]]:
    """Each machine's states from its last /llfsm/M/description in the bag."""
    wanted = [c for c in reader.connections if c.topic in {f"/llfsm/{n}/description" for n in names}]
    out: dict[str, tuple[str, ...]] = {}
    if not wanted:
        return out  # (no connections at all would read every message)
    for conn, _t, data in reader.messages(wanted):
        if conn.msgtype != STATE_TYPE:
            notes(conn.topic, "type", f"of type {conn.msgtype}, not {STATE_TYPE}: left out")
            continue
        if len(data) > MAX_DESCRIPTION:
            notes(conn.topic, "size", f"a description of {len(data):,} bytes (at most {MAX_DESCRIPTION:,}): left out")
            continue
        try:
            desc = json.loads(from_cdr(data, String).data)  # type: ignore[attr-defined]
            found = tuple(s["name"] for s in desc["states"])
            if not all(isinstance(s, str) and s for s in found) or len(found) > MAX_STATES:
                raise ValueError("state names")
        except (ValueError, TypeError, KeyError, RecursionError) as e:
            notes(conn.topic, "description", f"not a machine's description ({type(e).__name__}): left out")
            continue
        out[conn.topic.split("/")[2]] = found
    return out


def _state(topic: str, data: bytes, notes: _Notes) -> str | None:
    """A state message's name, or None (said) for one that cannot be a state's."""
    if len(data) > MAX_STATE_BYTES:
        notes(topic, "size", f"a state message of {len(data):,} bytes (at most {MAX_STATE_BYTES:,}): left out")
        return None
    try:
        name: str = from_cdr(data, String).data  # type: ignore[attr-defined]
    except ValueError as e:
        notes(topic, "malformed", f"a message that is not a string ({e}): left out")
        return None
    if not name:
        notes(topic, "empty", "an empty state name: left out")
        return None
    return name
