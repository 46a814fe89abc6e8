"""The bus of a run: the graph (nodes, topics, services, remaps, parameter overrides) kept on
top of the executor (executor.py) that dispatches its work.

Delivery: publishing copies the message once per reader (so a machine may keep mutating and
re-publishing one object, as the seed machines do); a PULL reader keeps only the newest
message; a PUSH subscription queues up to its QoS depth, dropping the oldest.  A topic's taps
(`Topic.taps`) are the exception: readers that take what they need from the message during
`publish` and keep nothing (a recorder encodes it at once) are handed the message itself,
since a copy would only be thrown away.

The bus delivers within its process itself; the run's transport (transports/) carries traffic
to and from other processes.  With the in-process transport nothing else happens; with DDS the
executor also takes what arrived and waits on it instead of sleeping blindly.  See docs/bus.md.
"""

from __future__ import annotations

import os
import sys
import time
from collections import deque
from collections.abc import Callable, Sequence
from typing import IO, TYPE_CHECKING, Any, Protocol, cast

from ..runtime.context import RunContext, current
from .executor import Executor
from .lifetimes import Lifetimes
from .names import Remap
from .task import Future
from .transports.base import NodeView, ServiceView, SubscriptionView, Transport
from .transports.inproc import InProcess

if TYPE_CHECKING:
    from ..msgs._message import Message
    from .parameter_files import NodeKey


class GraphNode(NodeView, Protocol):
    """A node as the bus lists it (llfsm.ros.node.Node, which sits above the bus): what the
    graph's readers use of it (`graph()`, a transport's announcement, the recorder looking for
    a topic's publishers)."""

    @property
    def _entities(self) -> Sequence[object]: ...

    def get_fully_qualified_name(self) -> str: ...


class Topic:
    """A named channel: its type and the readers attached to it."""

    __slots__ = ("latched", "name", "on_readers", "published", "publishers", "readers", "taps", "type")

    def __init__(self, name: str, type_: type[Message]) -> None:
        self.name = name
        self.type = type_
        self.readers: list[SubscriptionView] = []
        #: Called as fn(msg) with each published message itself, not a copy, while `publish`
        #: runs: for readers that must not keep it (`--record` encodes it there and then).  They
        #: count as subscriptions.
        self.taps: list[Callable[[Message], None]] = []
        self.publishers = 0
        self.published = 0
        #: What TRANSIENT_LOCAL publishers kept for late subscribers: publisher -> last messages.
        self.latched: dict[Any, deque[Message]] = {}
        #: Called as fn(topic, joining) when a subscription is about to join (True) or has left
        #: (False): lets a publisher publish only while someone listens (llfsm.ros.control).
        self.on_readers: list[Callable[[Topic, bool], None]] = []


class _Request:
    """A service request waiting for the executor."""

    __slots__ = ("bus", "future", "request", "service")

    def __init__(self, bus: Bus, service: str, request: Message, future: Future) -> None:
        self.bus, self.service, self.request, self.future = bus, service, request, future

    def _run(self) -> None:
        server = self.bus.services.get(self.service)
        if server is None or self.future.done():
            return  # no server (any more): the future stays pending; spin_until_future_complete says TIMEOUT
        answer = server._answer(self.request)
        if isinstance(answer, Future):  # a server that answers later (an action's get_result)
            future = self.future

            def reply(done: Future) -> None:
                if not future.done():
                    future.set_result(done.result()._copy())

            answer.add_done_callback(reply)
            return
        self.future.set_result(cast("Message", answer)._copy())


class Bus(Executor):
    """The graph of one run: nodes, topics, services, remaps and parameter overrides; and, as
    its executor, its timers and pending work."""

    def __init__(self, ctx: RunContext) -> None:
        super().__init__(ctx)
        self.nodes: list[GraphNode] = []
        self.topics: dict[str, Topic] = {}
        self.services: dict[str, ServiceView] = {}  # name -> server.ServiceServer
        self.remaps: list[Remap] = []
        self.parameters: dict[tuple[str | None, str], Any] = {}  # (node or None, name) -> override
        #: Where each of `parameters` was written (`-p gain:=2`), for the message that refuses it.
        self.parameter_origins: dict[tuple[str | None, str], str] = {}
        #: --params-file entries in order: (pattern over node names, {name: (value, "FILE:LINE")}).
        self.parameter_files: list[tuple[NodeKey, dict[str, tuple[Any, str]]]] = []
        #: Called with each new topic whose name is a key here (`--echo` waits for its topic).
        self.watchers: dict[str, list[Callable[[Topic], None]]] = {}
        #: Called with every topic, those made later too (`add_tap`: `--record` puts its taps on them).
        self.taps: list[Callable[[Topic], None]] = []
        self.log_to_stdout = os.environ.get("RCUTILS_LOGGING_USE_STDOUT", "0") == "1"
        #: None: whatever sys.stderr (or sys.stdout) is when a line is logged, so that a
        #: redirection made after the bus started is honoured.
        self.log_stream: IO[str] | None = None
        #: `--log-level`: logger name ("" for every logger) -> level (logging.level_for).
        self.log_levels: dict[str, Any] = {}
        #: `--log-file`: where the log lines also go, as ROS 2's ~/.ros/log files (None: nowhere).
        self.log_file: IO[str] | None = None
        self.transport: Transport = cast("Transport | None", ctx.transport) or InProcess()
        #: The transport's poll when it can bring anything in (never for the in-process one).
        self._poll = self.transport.poll if self.transport.remote else None
        self.transport.start(self)
        self._told: set[str] = set()  # what nobody_here said already
        self._told_names: set[str] = set()  # the node names same_names said two nodes share
        if not self.transport.remote:
            ctx.at_end.append(self._unheard)
        ctx.between_rounds.append(self.spin_some)
        #: What the machines' variables hold: dropped nodes and entities are destroyed (lifetimes.py).
        self.lifetimes = Lifetimes(self)
        ctx.between_rounds.append(self.lifetimes.collect)
        if self._poll is not None:
            ctx.wake = 0  # look at the transport after the first round, then every POLL_NS

    # -- lifecycle ---------------------------------------------------------------------------
    def init(self) -> None:
        """Initialise (the first `ros.init()`, or the command line before nodes start); then
        run the run's on-init hooks once (`ctx.on_init`: the machines' state topics
        and control services join the graph with the first node, never in a run without one)."""
        if self.initialised:
            return
        self.initialised = True
        hooks, self.ctx.on_init = self.ctx.on_init, []
        for fn in hooks:
            fn(self)

    # -- topics ------------------------------------------------------------------------------
    def topic(self, name: str, type_: type[Message], role: str) -> Topic:
        t = self.topics.get(name)
        if t is None:
            t = self.topics[name] = Topic(name, type_)
            for fn in self.watchers.pop(name, []):
                fn(t)
            for fn in self.taps:
                fn(t)
        elif t.type is not type_:
            raise TypeError(f"cannot {role} {name} as {type_._TYPE}: the topic already carries {t.type._TYPE}")
        return t

    def watch(self, name: str, fn: Callable[[Topic], None]) -> None:
        """Call fn(topic) once the topic exists (now, if it already does), in this process or,
        with a remote transport, once a publisher of it appears in another process."""
        if name in self.topics:
            fn(self.topics[name])
            return
        self.watchers.setdefault(name, []).append(fn)
        if self.transport.remote:

            def found(type_: type[Message]) -> None:
                if name not in self.topics:
                    self.topic(name, type_, "subscribe to")  # calls the watchers

            self.transport.discover(name, found)

    def add_tap(self, fn: Callable[[Topic], None]) -> None:
        """Call fn(topic) for every topic: each existing one now, each new one when it is made.
        A recorder puts its tap in each topic's `Topic.taps` this way (llfsm.bag.recorder)."""
        self.taps.append(fn)
        for t in list(self.topics.values()):
            fn(t)

    def _unheard(self) -> None:
        """At the end of an in-process run: machine code's subscriptions (of nodes its variables
        hold, lifetimes.py) of a topic nothing in the run published.  Not the built-in nodes'
        (turtlesim listens to /turtle1/cmd_vel whether or not anyone drives it)."""
        held = self.lifetimes.held
        for name, t in sorted(self.topics.items()):
            if t.publishers or t.published:
                continue
            if any(id(r.node) in held for r in t.readers):
                self.nobody_here(f"nothing published {name}, which a machine subscribed to,")

    # -- services ----------------------------------------------------------------------------
    def call(self, service: str, request: Message) -> Future:
        future = Future(service)
        self.queue(_Request(self, service, request, future))
        return future

    def nobody_here(self, what: str) -> None:
        """A run on the in-process bus waits for what no node of this process provides: say once
        that this run cannot reach other processes and how to join them (a user who forgot
        `--transport dds` on one side would otherwise blame the other side)."""
        if self.transport.remote or what in self._told:
            return
        self._told.add(what)
        print(
            f"llfsm: {what} in this run, which is on the in-process bus: other processes cannot reach it. "
            "To join nodes in other processes, run every side with --transport dds (or LLFSM_TRANSPORT=dds).",
            file=self.log_output(),
        )

    def same_names(self) -> None:
        """Say once of each name that two live nodes of this run share (two machines making
        `ros.Node("x")`, a machine's node named as a `--node`): ROS 2 tools cannot tell them
        apart (`ros2 node list` warns, `ros2 param` and `node info` reach one of them), and their
        parameter services share names.  Asked between rounds, after the lifetimes look, so
        that a node a restart makes anew, whose old one is dropped, is not taken for a twin."""
        names = [n.get_fully_qualified_name() for n in self.nodes if not n._destroyed]
        if len(names) == len(set(names)):
            return
        seen: set[str] = set()
        for name in names:
            if name in seen and name not in self._told_names:
                self._told_names.add(name)
                print(
                    f"llfsm: warning: {names.count(name)} nodes of this run are named {name}: ROS 2 tools cannot tell "
                    "them apart and their parameter services clash; give one of them another name or namespace",
                    file=self.log_output(),
                )
            seen.add(name)

    # -- logging -------------------------------------------------------------------------------
    def log_output(self) -> IO[str]:
        if self.log_stream is not None:
            return self.log_stream
        return sys.stdout if self.log_to_stdout else sys.stderr

    def stamp(self) -> tuple[int, int]:
        """Seconds and nanoseconds for log lines: run time under the sim clock, else wall time."""
        ns = self.clock.now if self.clock.kind == "sim" else time.time_ns()
        return divmod(ns, 1_000_000_000)

    # -- introspection ---------------------------------------------------------------------------
    def graph(self) -> dict[str, Any]:
        """Nodes, topics (type, publishers, subscriptions, messages) and services: for the CLI."""
        return {
            "nodes": sorted(n.get_fully_qualified_name() for n in self.nodes if not n._destroyed),
            "topics": {
                name: {
                    "type": t.type._TYPE,
                    "publishers": t.publishers,
                    "subscriptions": len(t.readers) + len(t.taps),
                    "messages": t.published,
                }
                for name, t in sorted(self.topics.items())
            },
            "services": {name: s.type._TYPE for name, s in sorted(self.services.items())},
        }


def bus_of(ctx: RunContext | None = None) -> Bus:
    """The bus of the active run (made on first use)."""
    ctx = ctx if ctx is not None else current()
    bus = cast("Bus | None", ctx.bus)  # the context holds what this made, typed as the runtime sees it
    if bus is None:
        bus = ctx.bus = Bus(ctx)
    return bus
