"""`llfsm replay FILE`: a recorded run read back as a history the page steps through on the
diagrams (docs/debug.md, "Replay").

FILE is a `--trace FILE.jsonl` of `llfsm run` (its `machine` events carry each machine's
description and first values; later events say what each ringlet did, `variables` events what
it changed), or a folder that `llfsm verify --counterexample DIR` wrote (its `steps.jsonl`, the
same format, with a `step` event closing each step: the inputs, the topics published).  Both
become the page's records, the shape of the live history's (llfsm.debug.history), and frames:
every machine's state and values after any record.

A file is untrusted (SPEC 18): read line by line (a line of more than MAX_LINE characters, more
than MAX_EVENTS events, a nesting too deep are refused), every event checked by a strict model
and every description by the view's (llfsm.diagram.description), each machine and state named
checked against the descriptions; what does not fit is one ReplayError naming the file and
line.  Frames are rebuilt from checkpoints kept every CHECKPOINT records, so moving the slider
anywhere costs at most CHECKPOINT records' work.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, JsonValue, ValidationError

from ..diagram.description import DescriptionError, validate

#: Longest line read, events read at most, records between two kept frames.
MAX_LINE = 1 << 20
MAX_EVENTS = 2_000_000
CHECKPOINT = 256
#: What `llfsm verify --counterexample DIR` writes the path's steps into.
STEPS = "steps.jsonl"

_KINDS = ("machine", "entry", "transition", "suspend", "resume", "restart", "finish", "variables", "error")
_NAME = Field(min_length=1, max_length=256)


class ReplayError(ValueError):
    """A file that is not a run's trace nor a counterexample: one line, naming it."""


class _Event(BaseModel):
    model_config = ConfigDict(strict=True, extra="ignore", frozen=True)

    event: str = Field(max_length=64)
    t: float | None = Field(default=None, allow_inf_nan=False)
    round: int | None = Field(default=None, ge=0)
    machine: str | None = Field(default=None, min_length=1, max_length=256)
    id: int | None = Field(default=None, ge=0)
    state: str | None = Field(default=None, max_length=256)
    source: str | None = Field(default=None, max_length=256)
    target: str | None = Field(default=None, max_length=256)
    index: int | None = Field(default=None, ge=0)
    changed: dict[str, Annotated[list[JsonValue], Field(min_length=2, max_length=2)]] | None = None
    variables: dict[str, JsonValue] | None = None
    description: dict[str, Any] | None = None
    published: list[str] | None = None
    inputs: dict[str, JsonValue] | None = None


class Replay:
    """The machines of a recorded run and what each of its ringlets did."""

    def __init__(self, source: str, kind: Literal["trace", "counterexample"]) -> None:
        self.source = source
        self.kind = kind
        self.descriptions: list[dict[str, Any]] = []
        self.names: list[str] = []
        self.first: list[dict[str, Any]] = []
        self.records: list[dict[str, Any]] = []
        #: The record where a lasso's loop starts (a liveness counterexample), if any.
        self.loop: int | None = None
        self._checkpoints: list[tuple[list[str], list[dict[str, Any]]]] = []

    # -- frames -----------------------------------------------------------------------------------
    def _initial(self) -> tuple[list[str], list[dict[str, Any]]]:
        return [d["initial"] for d in self.descriptions], [dict(v) for v in self.first]

    def _apply(self, states: list[str], values: list[dict[str, Any]], rec: dict[str, Any]) -> None:
        i = self.names.index(rec["machine"])
        states[i] = rec["after"]
        for name, (_old, new) in rec["changed"].items():
            values[i][name] = new
        for machine, changed in rec.get("others", {}).items():  # a step that changed another machine's
            for name, (_old, new) in changed.items():
                values[self.names.index(machine)][name] = new

    def _index(self) -> None:
        """Checkpoints every CHECKPOINT records (the state after record k*CHECKPOINT - 1)."""
        states, values = self._initial()
        self._checkpoints = [(list(states), [dict(v) for v in values])]
        for k, rec in enumerate(self.records, start=1):
            self._apply(states, values, rec)
            if k % CHECKPOINT == 0:
                self._checkpoints.append((list(states), [dict(v) for v in values]))

    def frame(self, k: int) -> dict[str, Any]:
        """Every machine's state and values after record k (0: before the first), and the record."""
        if not 0 <= k <= len(self.records):
            raise IndexError(f"the replay has {len(self.records)} records; {k} is not one of them")
        base = k // CHECKPOINT
        kept_states, kept_values = self._checkpoints[base]
        states, values = list(kept_states), [dict(v) for v in kept_values]
        for rec in self.records[base * CHECKPOINT : k]:
            self._apply(states, values, rec)
        return {
            "record": self.records[k - 1] if k else None,
            "machines": [
                {"machine": name, "state": states[i], "values": values[i]} for i, name in enumerate(self.names)
            ],
        }

    def summary(self) -> str:
        n = len(self.records)
        what = "trace" if self.kind == "trace" else "counterexample"
        k = len(self.names)
        return f"{what} {self.source}: {k} machine{'s' if k != 1 else ''}, {n:,} ringlet{'s' if n != 1 else ''}"


def read(path: str | Path) -> Replay:
    """The replay of FILE (a `--trace` file, or a counterexample's folder); ReplayError if not one."""
    p = Path(path)
    if p.is_dir():
        steps = p / STEPS
        if not steps.is_file():
            raise ReplayError(
                f"{p}: a folder, but not a counterexample (no {STEPS}: `llfsm verify --counterexample DIR` writes one)"
            )
        return _read(steps, Replay(str(p), "counterexample"))
    if not p.exists():
        raise ReplayError(f"{p}: no such file or folder")
    return _read(p, Replay(str(p), "trace"))


def _read(path: Path, replay: Replay) -> Replay:
    try:
        with path.open("r", encoding="utf-8", errors="strict") as f:
            events = list(_events(f, path))
    except UnicodeDecodeError:
        raise ReplayError(f"{path}: not text (a --trace file is JSON lines)") from None
    except OSError as e:
        raise ReplayError(f"{path}: cannot be read: {e.strerror}") from None
    _Builder(replay, path).build(events)
    return replay


def _events(f: Any, path: Path) -> Any:
    for n, line in enumerate(iter(lambda: f.readline(MAX_LINE + 1), ""), start=1):
        if n > MAX_EVENTS:
            raise ReplayError(f"{path}: more than {MAX_EVENTS:,} events: too long to replay")
        if len(line) > MAX_LINE:
            raise ReplayError(f"{path}:{n}: a line of more than {MAX_LINE:,} characters")
        if not line.strip():
            continue
        try:
            data = json.loads(line)
        except RecursionError:
            raise ReplayError(f"{path}:{n}: nested too deeply") from None
        except json.JSONDecodeError as e:
            raise ReplayError(f"{path}:{n}: not JSON ({e.msg}): a --trace file has one JSON object a line") from None
        if not isinstance(data, dict) or "event" not in data:
            raise ReplayError(f'{path}:{n}: not an event of a --trace file (a JSON object with an "event")')
        try:
            yield n, _Event.model_validate(data)
        except ValidationError as e:
            err = e.errors(include_url=False, include_input=False)[0]
            where = ".".join(str(x) for x in err.get("loc", ()))
            raise ReplayError(f"{path}:{n}: {where}: {err.get('msg', 'invalid')}") from None


class _Builder:
    """Events into records: one per ringlet of a machine (grouped by round and machine, or
    closed by a counterexample's `step` event)."""

    def __init__(self, replay: Replay, path: Path) -> None:
        self.r = replay
        self.path = path
        self.states: list[str] = []
        self.current: dict[str, Any] | None = None
        self.key: tuple[int, int] | None = None

    def fail(self, n: int, text: str) -> ReplayError:
        return ReplayError(f"{self.path}:{n}: {text}")

    def build(self, events: list[tuple[int, _Event]]) -> None:
        r = self.r
        stepped = any(ev.event == "step" for _, ev in events)
        for n, ev in events:
            if ev.event == "machine":
                self._machine(n, ev)
                continue
            if not r.names:
                raise self.fail(n, "no `machine` event before it: a trace of an older llfsm cannot be replayed")
            if ev.event == "loop":
                self._flush()
                r.loop = len(r.records)
                continue
            if ev.event == "ended":
                self._flush()
                continue
            if ev.event not in (*_KINDS, "step"):
                continue  # a newer llfsm's event: nothing the page shows
            i = self._machine_index(n, ev)
            key = (ev.round or 0, i)
            if self.current is not None and (key != self.key and not stepped):
                self._flush()
            if self.current is None:
                self.key = key
                self.current = {
                    "ringlet": len(r.records) + 1,
                    "round": ev.round or 0,
                    "t": ev.t or 0.0,
                    "machine": r.names[i],
                    "kind": "ringlet",
                    "before": self.states[i],
                    "state": None,
                    "after": self.states[i],
                    "transition": None,
                    "changed": {},
                    "published": [],
                }
            self._event(n, ev, i)
            if ev.event == "step":
                self._flush()
        self._flush()
        if not r.names:
            raise ReplayError(f"{self.path}: no machine in it: not a --trace file of llfsm run")
        r._index()

    def _machine(self, n: int, ev: _Event) -> None:
        r = self.r
        if r.records or self.current is not None:
            raise self.fail(n, "a `machine` event after the run began")
        try:
            desc = validate(ev.description, ev.machine)
        except DescriptionError as e:
            raise self.fail(n, f"the machine's description: {e}") from None
        if desc["name"] in r.names:
            raise self.fail(n, f"machine {desc['name']} twice")
        r.descriptions.append(desc)
        r.names.append(desc["name"])
        r.first.append(dict(ev.variables or {}))
        self.states.append(desc["initial"])

    def _machine_index(self, n: int, ev: _Event) -> int:
        if ev.machine not in self.r.names:
            raise self.fail(n, f"machine {ev.machine!r} is not one of the run's ({', '.join(self.r.names)})")
        return self.r.names.index(ev.machine)

    def _state(self, n: int, i: int, name: str | None) -> str:
        states = [s["name"] for s in self.r.descriptions[i]["states"]]
        if name is None or name not in states:
            raise self.fail(n, f"{self.r.names[i]} has no state {name!r}")
        return name

    def _event(self, n: int, ev: _Event, i: int) -> None:
        cur = self.current
        assert cur is not None
        kind = ev.event
        if kind == "entry":
            cur["after"] = self._state(n, i, ev.state)
            cur["state"] = cur["state"] or cur["after"]
        elif kind == "transition":
            cur["state"] = self._state(n, i, ev.source)
            cur["after"] = self._state(n, i, ev.target)
            cur["transition"] = ev.index
        elif kind in ("suspend", "resume", "restart", "finish", "step"):
            if ev.state is not None:
                cur["after"] = self._state(n, i, ev.state)
            if kind == "step":
                cur["published"] = list(ev.published or [])
                cur["inputs"] = dict(ev.inputs or {})
            elif kind != "finish":
                cur.setdefault("commands", []).append(kind)
        elif kind == "variables":
            changed = {k: list(v) for k, v in (ev.changed or {}).items()}
            if self.r.names[i] == cur["machine"]:
                cur["changed"].update(changed)
            else:
                cur.setdefault("others", {}).setdefault(self.r.names[i], {}).update(changed)
            return
        elif kind == "error":
            cur["error"] = True
        self.states[self.r.names.index(cur["machine"])] = cur["after"]

    def _flush(self) -> None:
        if self.current is not None:
            self.r.records.append(self.current)
            self.current = None
            self.key = None
