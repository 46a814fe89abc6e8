"""The debugger in the page (docs/debug.md, "The page"): what the page shows of it (a part of every
snapshot) and the requests its controls send (`/api/debug/...`).

Three sources answer the same requests:

- `RunDebug`: the run in this process (`llfsm run --web`, `llfsm edit`'s Run): its Debugger
  (llfsm.debug), always with a history.  Everything that reads or changes the run is handed to
  the scheduler's thread (`Debugger.submit`) and awaited here; the snapshot's part reads only
  what the scheduler's thread wrote (the history's latest values, the debugger's status).
- `GraphDebug`: `llfsm view`, runs in other processes: the debug services of each machine's node
  (llfsm.debug.services) and the `/llfsm/M/debug` topics; no history crosses the graph.
- `ReplayDebug`: `llfsm replay`: a recorded run's records and frames (llfsm.web.replay); nothing
  to pause or set.

Requests (POST, JSON): `pause`, `continue`, `step`, `step_round` ({machine} for the graph: the
run it belongs to), `set` ({machine, name, value}), `breakpoint` ({expression, enable}),
`variables` ({machine}: as `p M` reads it), `frame` ({back}: the arrangement that many records
ago; {at} in a replay), `history` ({n}).
Each answers {success, message, ...}; a refusal is one line, status 400.
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable
from typing import Any, Protocol

from ..debug.debugger import CONTINUE, ROUND, STEP, DebugError, Debugger
from .channel import state_of
from .replay import Replay
from .source import CommandError

#: The requests, and the resume each of the first ones asks for.
RESUMES = {"continue": CONTINUE, "step": STEP, "step_round": ROUND}
#: How long a request waits for the run to take it (a long ringlet keeps it waiting).
WAIT_S = 5.0


class DebugRefused(CommandError):
    """A request the debugger cannot carry out: one line for the page."""


class PageDebug(Protocol):
    """What the server asks of a debug source."""

    def state(self) -> dict[str, Any]:
        """The snapshot's part: status, breakpoints, the variables of each machine."""

    async def request(self, what: str, data: dict[str, Any]) -> dict[str, Any]:
        """Carry out request `what` (one of the module docstring's); DebugRefused if it cannot."""


def _text(data: dict[str, Any], key: str) -> str:
    value = data.get(key, "")
    if not isinstance(value, str):
        raise DebugRefused(f"{key} must be a string")
    return value


def _count(data: dict[str, Any], key: str, default: int = 0) -> int:
    value = data.get(key, default)
    if type(value) is not int or value < 0:
        raise DebugRefused(f"{key} must be a whole number >= 0")
    return value


class RunDebug:
    """The run in this process (see the module's docstring)."""

    def __init__(self, debugger: Debugger) -> None:
        self.debugger = debugger
        #: Told when the debugger pauses or goes on (the page's server pushes a snapshot at once).
        self.on_change: Callable[[], None] | None = None
        debugger.listeners.append(lambda _d: self.on_change() if self.on_change is not None else None)

    def state(self) -> dict[str, Any]:
        d = self.debugger
        status = d.status()
        h = d.history
        if h is not None:  # the values the scheduler's thread took last
            variables = h.snapshot()
            status["records"] = h.kept
        else:
            variables = {}
        return {**status, "variables": variables}

    async def _on_run(self, fn: Callable[[], Any]) -> Any:
        try:
            return await asyncio.wait_for(asyncio.wrap_future(self.debugger.submit(fn)), WAIT_S)
        except TimeoutError:
            raise DebugRefused("the run did not answer in time (is it busy in a long ringlet?)") from None
        except (DebugError, IndexError, ValueError) as e:
            raise DebugRefused(str(e)) from None

    async def request(self, what: str, data: dict[str, Any]) -> dict[str, Any]:
        d = self.debugger
        if what == "pause":
            d.pause("Pause on the page")  # flags only: safe from this thread
            return {"success": True, "message": "pausing at the next ringlet boundary"}
        if what in RESUMES:
            return {"success": True, "message": await self._on_run(lambda: d.resume(RESUMES[what]))}
        if what == "set":
            machine, name, value = _text(data, "machine"), _text(data, "name"), _text(data, "value")
            return {"success": True, "message": await self._on_run(lambda: d.set_value(machine, name, value))}
        if what == "breakpoint":
            expression, enable = _text(data, "expression"), data.get("enable", True) is not False

            def toggle() -> str:
                if enable:
                    bp = d.add_break(expression, where="breakpoint")
                    return f"breakpoint {bp.number}: {bp.text}"
                gone = d.remove_break(text=expression)
                return f"removed breakpoint {', '.join(str(b.number) for b in gone)}"

            return {"success": True, "message": await self._on_run(toggle)}
        h = d.history
        if h is None:
            raise DebugRefused("this run keeps no history")
        if what == "frame":
            back = _count(data, "back")
            return {"success": True, "message": "", **await self._on_run(lambda: h.frame(back))}
        if what == "history":
            n = _count(data, "n", 100)
            return {"success": True, "message": "", "records": await self._on_run(lambda: h.last(n))}
        if what == "variables":
            machine = _text(data, "machine")
            return {"success": True, "message": "", "machine": await self._on_run(lambda: d.read(machine)[machine])}
        raise DebugRefused(f"unknown request {what!r}")


class ReplayDebug:
    """A recorded run (`llfsm replay`): its records, and the arrangement after any of them."""

    def __init__(self, replay: Replay) -> None:
        self.replay = replay
        #: The record the page shows (the last `frame` asked for): the snapshot's states.
        self.at = len(replay.records)

    def state(self) -> dict[str, Any]:
        r = self.replay
        return {
            "paused": True,
            "replay": r.kind,
            "where": r.summary(),
            "reason": "",
            "breaks": [],
            "records": len(r.records),
            "at": self.at,
            "loop": r.loop,
            "variables": {},
        }

    async def request(self, what: str, data: dict[str, Any]) -> dict[str, Any]:
        r = self.replay
        if what == "frame":
            at = _count(data, "at", len(r.records))
            try:
                frame = r.frame(at)
            except IndexError as e:
                raise DebugRefused(str(e)) from None
            self.at = at
            return {"success": True, "message": "", **frame}
        if what == "history":
            n = _count(data, "n", 100)
            return {"success": True, "message": "", "records": r.records[-n:] if n else []}
        raise DebugRefused(f"a replay cannot {what.replace('_', ' ')}: it is a recorded run")


class ReplaySource:
    """What `llfsm replay` serves: the page's source (as llfsm.web.source's are) over a replay:
    the recorded machines' diagrams, their states and values at the record the page shows."""

    kind = "replay"
    #: The page the server serves at / (the debugger's: its History slider is the replay).
    page = "debug.html"

    def __init__(self, replay: Replay) -> None:
        self.replay = replay
        self.debug = ReplayDebug(replay)
        self.ended = False

    def machines(self) -> list[dict[str, Any]]:
        return self.replay.descriptions

    def has_machine(self, name: str) -> bool:
        return name in self.replay.names

    def state(self) -> dict[str, Any]:
        """The page's state at the record shown (llfsm.web.channel: the server sends deltas)."""
        frame = self.replay.frame(self.debug.at)
        record = frame["record"]
        rows = [
            {"name": m["machine"], "machine": m["machine"], "participant": "", "runs": 1, "ended": False,
             "state": m["state"], "status": "running", "pending": None, "since": 0, "transitions": []}
            for m in frame["machines"]
        ]  # fmt: skip
        return state_of(
            t=record["t"] if record is not None else 0,
            clock="replay",
            source=self.kind,
            ended=self.ended,
            machines=rows,
            debug={**self.debug.state(), "variables": {m["machine"]: m["values"] for m in frame["machines"]}},
        )


class GraphDebug:
    """`llfsm view`: each machine's run through its debug services and its `/llfsm/M/debug`
    topic (llfsm.debug.services).  What a peer sends is untrusted: a state is kept only as the
    strict message type carries it, a machine's YAML only as a mapping of at most MAX_YAML
    characters."""

    #: The longest YAML answer of a peer read.
    MAX_YAML = 1 << 20

    def __init__(self, source: Any) -> None:
        self.source = source
        self.runs: dict[str, dict[str, Any]] = {}  # machine -> its run's debug state, as last published
        self.variables: dict[str, Any] = {}  # machine -> its variables, as last read
        for name in sorted(getattr(source, "_followed", ())):  # the machines the view found already
            self.follow(name)

    def follow(self, name: str) -> None:
        """Read machine `name`'s /llfsm/M/debug (scheduler's thread, when the view finds it)."""
        from ..msgs.llfsm_msgs.msg import DebugState  # deferred: the view's debug part only
        from ..ros.control import LATCHED, NAMESPACE

        def on_state(msg: DebugState) -> None:
            self.runs[name] = {
                "paused": bool(msg.paused),
                "where": msg.where[:512],
                "reason": msg.reason[:512],
                "machine": msg.machine[:256],
                "breaks": [b[:512] for b in msg.breakpoints[:100]],
            }

        self.source.node.create_subscription(DebugState, f"{NAMESPACE}/{name}/debug", on_state, LATCHED)

    def state(self) -> dict[str, Any]:
        runs = dict(self.runs)
        return {
            "paused": any(r["paused"] for r in runs.values()),
            "runs": runs,
            "variables": dict(self.variables),
            "records": 0,
            "breaks": sorted({b for r in runs.values() for b in r["breaks"]}),
        }

    async def request(self, what: str, data: dict[str, Any]) -> dict[str, Any]:
        from ..msgs.llfsm_msgs.srv import GetVariables, SetBreakpoint, SetVariable  # deferred: as above
        from ..msgs.std_srvs.srv import Trigger
        from ..ros.control import NAMESPACE

        machine = _text(data, "machine")
        if not self.source.has_machine(machine):
            raise DebugRefused(f"no machine named {machine!r} on the graph")
        name = self.source.machine_name(machine)
        base = f"{NAMESPACE}/{name}"
        if what == "pause" or what in RESUMES:
            r = await self.source._request(f"{base}/{what}", Trigger, Trigger.Request())
        elif what == "set":
            setting = SetVariable.Request(name=_text(data, "name"), value=_text(data, "value"))
            r = await self.source._request(f"{base}/set_variable", SetVariable, setting)
        elif what == "breakpoint":
            enable = data.get("enable", True) is not False
            toggle = SetBreakpoint.Request(expression=_text(data, "expression"), enable=enable)
            r = await self.source._request(f"{base}/breakpoint", SetBreakpoint, toggle)
        elif what == "variables":
            r = await self.source._request(f"{base}/variables", GetVariables, GetVariables.Request())
            self.variables[machine] = _peer_yaml(r.yaml[: self.MAX_YAML])
            return {"success": True, "message": "", "paused": bool(r.paused), "machine": self.variables[machine]}
        else:
            raise DebugRefused(f"a view cannot {what.replace('_', ' ')}: no history crosses the graph")
        if not r.success:
            raise DebugRefused(r.message)
        return {"success": True, "message": r.message}


def _peer_yaml(text: str) -> Any:
    import yaml  # deferred: the view's debug part only

    try:
        data = yaml.safe_load(text)
    except (yaml.YAMLError, RecursionError):
        raise DebugRefused("the run answered with YAML that does not read") from None
    if not isinstance(data, dict):
        raise DebugRefused("the run answered with something else than a machine's mapping")
    return data


def routes(app: Any, debug: Callable[[], PageDebug | None], answer: Callable[..., Awaitable[Any]]) -> None:
    """The `/api/debug/...` routes on the page server's app; `debug()` the source's debug part
    (None: this page has no debugger), `answer` the server's JSON request wrapper."""
    names = ("pause", *RESUMES, "set", "breakpoint", "frame", "history", "variables")

    def handler(what: str) -> Callable[[Any], Awaitable[Any]]:
        async def handle(request: Any) -> Any:
            async def act(data: dict[str, Any]) -> dict[str, Any]:
                source = debug()
                if source is None:
                    raise DebugRefused("this page has no debugger")
                return await source.request(what, data)

            return await answer(request, act)

        return handle

    for what in names:
        app.router.add_post(f"/api/debug/{what}", handler(what))
