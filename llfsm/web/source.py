"""What the page shows, taken from a run in this process, and the way back into it (docs/view.md,
"How it keeps up, and what it costs").

The scheduler never waits on the page and does no work for it: the server's thread samples
the run (at most 20 times a second, and only while a page is connected) by reading plain
attributes (a machine's state index, a reader's message count), which is safe under the GIL;
nothing here ever runs machine code or changes the bus from that thread.  Every change (a
command, a publish, a service call, a new topic to watch) is handed to the scheduler's thread
through `Bus.call_soon_threadsafe`, which the bus executor drains between rounds.

Sampling coalesces by nature: a machine that changes state every ringlet shows the state it
is in when sampled, and the page's list of transitions holds the changes that sampling saw.
"""

from __future__ import annotations

import asyncio
import json
import os
import time
from collections import deque
from collections.abc import Callable
from concurrent.futures import Future as ThreadFuture
from functools import partial
from typing import TYPE_CHECKING, Any

from ..msgs import to_yaml
from ..msgs._lookup import TypeNameError, message_class, service_class
from ..msgs._yaml import ValuesError, from_yaml
from ..msgs.rcl_interfaces.msg import ParameterEvent
from ..msgs.rcl_interfaces.srv import DescribeParameters, GetParameters, ListParameters, SetParameters
from ..ros.control import NAMESPACE, description
from ..ros.names import expand
from ..ros.node import Node
from ..ros.transports.dds_graph import is_hidden
from . import parameters as params
from .channel import MAX_SERVICE_ROWS, MAX_TOPIC_ROWS, ROW_PERIOD, bounded_text, state_of
from .rosgraph import MAX_LISTED_NODES, RosGraph, from_bus, from_dds, robust_graph
from .verdicts import Verdicts

if TYPE_CHECKING:
    from ..ros.bus import Bus
    from ..runtime.scheduler import Arrangement
    from ..sim.world import TurtleWorld
    from .debugging import PageDebug

#: Transitions kept for the page, per machine.
HISTORY = 12
#: The turtle world is redrawn at most this often (it is the biggest part of a snapshot).
WORLD_PERIOD = 0.25
#: How long a service called from the page may take (waiting for its server included).
CALL_TIMEOUT = 5.0
#: How often the graph of nodes and topics is read again (wall seconds).
GRAPH_PERIOD = 0.5
#: Nodes whose parameter events are counted at most (a peer may name any number).
MAX_EVENT_NODES = 10_000


class CommandError(Exception):
    """A request from the page that cannot be carried out (shown to the user as one line)."""


def type_class(type_name: str, kind: str) -> Any:
    """The class a type typed into the page names (`pkg/msg/Name`, `pkg/srv/Name`, or `pkg/Name`),
    read as `llfsm topic pub` and `llfsm service call` read their TYPE (llfsm/msgs/_lookup.py)."""
    try:
        return message_class(type_name.strip()) if kind == "msg" else service_class(type_name.strip())
    except TypeNameError as e:
        raise CommandError(str(e)) from None


def parse_values(cls: Any, text: str) -> tuple[Any, list[Any]]:
    """The message (or request) the page's YAML values make, through the same parsing and type
    checks as `llfsm topic pub` (llfsm.msgs._yaml: PyYAML's safe loader, then field by field
    through the typed properties, never eval), and the setters of the stamps it asks for."""
    try:
        return from_yaml(cls, text)
    except ValuesError as e:
        raise CommandError(f"invalid values: {e}") from None


class _TopicStats:
    __slots__ = ("last_count", "rate", "samples", "text")

    def __init__(self) -> None:
        self.samples: deque[tuple[float, int]] = deque()
        self.rate = 0.0
        self.last_count = -1
        self.text = ""

    def update(self, now: float, count: int) -> None:
        """Messages per second over the last two seconds of wall time."""
        samples = self.samples
        samples.append((now, count))
        while len(samples) > 2 and now - samples[0][0] > 2.0:
            samples.popleft()
        t0, c0 = samples[0]
        self.rate = (count - c0) / (now - t0) if now - t0 >= 0.2 else self.rate


class Source:
    """What both sources share: the page's node, topic readers and statistics, publishing and
    service calls through the bus (on the scheduler's thread), the machines' commands through
    their control services, the nodes' parameters through their parameter services, and the
    graph of nodes and topics."""

    #: What the page's header says it watches: "run" (llfsm run --web) or "view" (llfsm view).
    kind = "run"

    def __init__(self, bus: Bus, node_name: str) -> None:
        self.bus = bus
        self.ctx = bus.ctx
        self.clock = bus.clock
        # on the scheduler's thread, before the run; each page's node its own name (as rqt's
        # rqt_gui_py_node_<pid>), so that two views on one graph are not two nodes of one name
        self.node: Node = Node(f"{node_name}_{os.getpid()}")
        self._readers: dict[str, Any] = {}
        self._asked: set[str] = set()
        self._stats: dict[str, _TopicStats] = {}
        self._rows: dict[str, tuple[float, dict[str, Any]]] = {}  # each topic row shown, and when it was read
        self._publishers: dict[str, Any] = {}
        self._clients: dict[tuple[str, str], Any] = {}
        self._warned: set[str] = set()
        self.ended = False
        #: Parameter events seen per node: the page reads an open node's parameters again when
        #: its count moves (a set from the page, `param set` or the node itself).
        self.param_events: dict[str, int] = {}
        events = self.node.create_subscription(ParameterEvent, "/parameter_events", self._on_parameter_event, 100)
        events.screen = params.event_node  # over DDS: the node's name alone is read of a peer's event
        #: What monitors said on /llfsm/monitor (this run's, or any run's on the domain).
        self.verdicts = Verdicts(self.node)
        self._graph = RosGraph()
        self._graph_at = -GRAPH_PERIOD
        #: The DDS graph beyond this process, read on the scheduler's thread (None in process).
        self.remote_graph: RosGraph | None = None
        #: The debugger's part of the page (llfsm.web.debugging), when the source has one.
        self.debug: PageDebug | None = None

    def warn(self, text: str, key: str | None = None) -> None:
        """A problem with what a peer sent or with drawing it: one line in the run's log, once
        per `key` (the text itself by default), so that a peer repeating itself, or every page
        that connects, does not repeat the line.  Never raises: it is called where something
        already went wrong."""
        key = text if key is None else key
        if key in self._warned or len(self._warned) > 10_000:
            return
        self._warned.add(key)
        try:
            sec, nsec = self.bus.stamp()
            stream = self.bus.log_output()
            stream.write(f"[WARN] [{sec}.{nsec:09d}] [llfsm.view]: {text}\n")
            stream.flush()
        except Exception:  # a closed stream at the end of a run: nothing more to say
            pass

    # -- to be provided -----------------------------------------------------------------------------
    def machines(self) -> list[dict[str, Any]]:
        """The machines' descriptions (llfsm.ros.control.description), in order."""
        raise NotImplementedError

    def machine_rows(self) -> list[dict[str, Any]]:
        """Each machine's name, state, status, pending command, since, transitions."""
        raise NotImplementedError

    def topic_types(self) -> dict[str, Any]:
        """Topic name -> message class (or None if llfsm has no class for it)."""
        raise NotImplementedError

    def service_types(self) -> dict[str, Any]:
        """Service name -> service class (or None)."""
        raise NotImplementedError

    def local_graph(self) -> RosGraph:
        """The nodes and topics of this process (none for the view, whose only node is its own)."""
        return RosGraph()

    def world(self) -> str | None:
        return None

    def has_machine(self, name: str) -> bool:
        return any(d["name"] == name for d in self.machines())

    # -- what the page is sent ---------------------------------------------------------------------
    def state(self) -> dict[str, Any]:
        """What the page shows now (server thread), each part bounded, keyed for the channel's
        deltas (llfsm.web.channel.Channel)."""
        topics, topics_total = self._topics()
        services = self.service_types()
        names = sorted(services)
        shown = set(self._graph.nodes[:MAX_LISTED_NODES])
        events = self.param_events
        return state_of(
            t=round(self.clock.now / 1e9, 3),
            clock=self.clock.kind,
            source=self.kind,
            ended=self.ended,
            machines=self.machine_rows(),
            topics=topics,
            topics_total=topics_total,
            services=[
                {"name": n, "type": t._TYPE if (t := services[n]) is not None else ""} for n in names[:MAX_SERVICE_ROWS]
            ],
            services_total=len(names),
            # only for nodes the page lists: a peer naming thousands of nodes costs the page nothing
            param_events={node: events[node] for node in shown if node in events},
            world=self.world(),
            monitor=self.verdicts.sample(),
            debug=self.debug.state() if self.debug is not None else None,
        )

    def graph(self) -> RosGraph:
        """Nodes, topics and actions (server thread): this process's read now and then, merged
        with what the scheduler's thread last read of the DDS graph."""
        now = time.monotonic()
        if now - self._graph_at >= GRAPH_PERIOD:
            self._graph_at = now
            g = self.local_graph()
            remote = self.remote_graph
            self._graph = g.merged(remote) if remote is not None else g
        return self._graph

    def _on_parameter_event(self, event: Any) -> None:
        node = event.node
        if len(node) <= params.MAX_EVENT_NAME and (
            node in self.param_events or len(self.param_events) < MAX_EVENT_NODES
        ):
            self.param_events[node] = self.param_events.get(node, 0) + 1

    # -- what the page asks for ------------------------------------------------------------------------
    async def command(self, machine: str, verb: str) -> dict[str, Any]:
        if verb not in ("suspend", "resume", "restart"):
            raise CommandError(f"unknown command {verb!r}: suspend, resume or restart")
        if not self.has_machine(machine):
            raise CommandError(f"no machine named {machine!r} in this run")
        response = await self._call(f"{NAMESPACE}/{machine}/{verb}", "std_srvs/srv/Trigger", "")
        return {"success": response.success, "message": response.message}

    async def publish(self, topic: str, type_name: str, text: str) -> dict[str, Any]:
        try:
            name = expand(topic.strip(), self.node.get_name(), "/")
        except Exception as e:  # InvalidNameError and friends: one line
            raise CommandError(str(e)) from None
        existing = self.topic_types().get(name)
        if type_name.strip():
            cls = type_class(type_name, "msg")
            if existing is not None and existing is not cls:
                raise CommandError(f"{name} carries {existing._TYPE}, not {cls._TYPE}")
        elif existing is not None:
            cls = existing
        else:
            raise CommandError(f"{name} does not exist yet: give its type, such as std_msgs/msg/String")
        msg, stamps = parse_values(cls, text)
        self._on_scheduler(lambda: self._publish(name, cls, msg, stamps))
        return {"success": True, "message": f"published on {name}", "yaml": to_yaml(msg)}

    def _publish(self, name: str, cls: Any, msg: Any, stamps: list[Any]) -> None:
        self._stamp(stamps)
        if name not in self._readers:  # so the page shows this very message as the topic's last
            self._asked.add(name)
            self._watch(name, cls)
        pub = self._publishers.get(name)
        if pub is None:
            pub = self._publishers[name] = self.node.create_publisher(cls, name, 10)
        pub.publish(msg)

    async def call(self, service: str, type_name: str, text: str) -> dict[str, Any]:
        response = await self._call(service.strip(), type_name, text)
        return {"success": True, "message": "response", "yaml": to_yaml(response)}

    async def _call(self, service: str, type_name: str, text: str) -> Any:
        try:
            name = expand(service, self.node.get_name(), "/")
        except Exception as e:
            raise CommandError(str(e)) from None
        known = self.service_types().get(name)
        if type_name.strip():
            srv = type_class(type_name, "srv")
            if known is not None and known is not srv:
                raise CommandError(f"{name} is a {known._TYPE} service, not {srv._TYPE}")
        elif known is not None:
            srv = known
        else:
            raise CommandError(f"no service {name} is known: give its type, such as std_srvs/srv/Trigger")
        req, stamps = parse_values(srv.Request, text)
        return await self._request(name, srv, req, stamps)

    async def _request(self, name: str, srv: Any, request: Any, stamps: list[Any] | None = None) -> Any:
        """The response of service `name` to `request`: the client is made and used on the
        scheduler's thread; the call waits (at most CALL_TIMEOUT in all) for a server, since a
        request sent before a server in another process is matched would reach nobody."""
        loop = asyncio.get_running_loop()
        deadline = loop.time() + CALL_TIMEOUT
        key = (name, srv._TYPE)

        def client() -> Any:
            c = self._clients.get(key)
            if c is None:
                c = self._clients[key] = self.node.create_client(srv, name)
            return c

        cli = await self._ask(client, deadline)
        while not await self._ask(cli.service_is_ready, deadline):
            if loop.time() >= deadline:
                raise CommandError(f"no server of {name} answered within {CALL_TIMEOUT:g} s: is its node running?")
            await asyncio.sleep(0.05)
        done: ThreadFuture[Any] = ThreadFuture()

        def start() -> None:
            self._stamp(stamps or [])
            fut = cli.call_async(request)
            fut.add_done_callback(lambda f: _settle(done, f))

        self._on_scheduler(start)
        try:
            return await asyncio.wait_for(asyncio.wrap_future(done), max(0.1, deadline - loop.time()))
        except TimeoutError:
            raise CommandError(f"no response from {name} within {CALL_TIMEOUT:g} s") from None

    async def _ask(self, fn: Callable[[], Any], deadline: float) -> Any:
        """fn() run on the scheduler's thread, its result here."""
        done: ThreadFuture[Any] = ThreadFuture()

        def run() -> None:
            try:
                done.set_result(fn())
            except Exception as e:  # handed to the page as one line, never into the executor
                done.set_exception(CommandError(f"{type(e).__name__}: {e}"))

        self._on_scheduler(run)
        loop = asyncio.get_running_loop()
        try:
            return await asyncio.wait_for(asyncio.wrap_future(done), max(0.1, deadline - loop.time()))
        except TimeoutError:
            raise CommandError("the run did not answer in time (is it busy in a long ringlet?)") from None

    async def parameters(self, node: str) -> dict[str, Any]:
        """A node's parameters: names, then values and descriptors, as `param list`, `get` and
        `describe` ask for them."""
        full = self._node_name(node)
        names = sorted(
            (await self._request(f"{full}/list_parameters", ListParameters, ListParameters.Request())).result.names
        )
        names = names[: params.MAX_PARAMETERS]
        values: list[Any] = []
        descriptors: list[Any] = []
        if names:
            values = list(
                (
                    await self._request(f"{full}/get_parameters", GetParameters, GetParameters.Request(names=names))
                ).values
            )
            descriptors = list(
                (
                    await self._request(
                        f"{full}/describe_parameters", DescribeParameters, DescribeParameters.Request(names=names)
                    )
                ).descriptors
            )
        return {"success": True, "node": full, "parameters": params.rows(names, values, descriptors)}

    async def set_parameter(self, node: str, name: str, text: str) -> dict[str, Any]:
        """`param set NODE NAME TEXT`: the value read as param set reads it, and the node's answer."""
        full = self._node_name(node)
        try:
            msg = params.message(name.strip(), text)
        except params.ParameterInputError as e:
            raise CommandError(str(e)) from None
        response = await self._request(f"{full}/set_parameters", SetParameters, SetParameters.Request(parameters=[msg]))
        if len(response.results) != 1:
            raise CommandError(f"node {full} answered {len(response.results)} results for one parameter")
        ok, said = params.result_text(response.results[0])
        return {"success": ok, "message": said}

    def _node_name(self, text: str) -> str:
        try:
            return params.node_name(text)
        except params.ParameterInputError as e:
            raise CommandError(str(e)) from None

    def _stamp(self, stamps: list[Any]) -> None:
        """Fill the stamps the values asked for (`header: auto`, `stamp: now`) with the run
        clock's time, on the scheduler's thread, as the message leaves."""
        if stamps:
            sec, nanosec = divmod(self.bus.clock.now, 1_000_000_000)
            for set_stamp in stamps:
                set_stamp(sec, nanosec)

    def _on_scheduler(self, fn: Any) -> None:
        if self.ended:
            raise CommandError("the run has ended")
        self.bus.call_soon_threadsafe(fn)

    def _topics(self) -> tuple[list[dict[str, Any]], int]:
        """The rows of the topics table, the first MAX_TOPIC_ROWS by name, and how many topics
        there are.  The page's own readers are made for the rows shown only, and deleted (on
        the scheduler's thread) for a topic no longer shown or no longer on the graph: a reader
        of the view's would otherwise keep a dead topic alive for every other tool."""
        wall = time.monotonic()
        types = self.topic_types()
        names = sorted(n for n in types if not is_hidden(n) and self._alive(n))  # as `ros2 topic list`
        shown = names[:MAX_TOPIC_ROWS]
        out = []
        rows = self._rows
        for name in shown:
            kept = rows.get(name)
            if kept is not None and wall - kept[0] < ROW_PERIOD:
                out.append(kept[1])  # the same row object: no change for the channel to send
                continue
            type_ = types[name]
            entry: dict[str, Any] = {"name": name, "type": type_._TYPE if type_ is not None else ""}
            machine = self._machine_topic(name)
            if machine is not None:
                count, last = machine
                stats = self._stats.setdefault(name, _TopicStats())
                stats.update(wall, count)
                entry.update(count=count, rate=round(stats.rate, 2), last=last, machine=True)
                rows[name] = (wall, entry)
                out.append(entry)
                continue
            reader = self._readers.get(name)
            if reader is None:
                if name not in self._asked and type_ is not None:
                    self._asked.add(name)
                    self.bus.call_soon_threadsafe(partial(self._watch, name, type_))
                entry.update(count=0, rate=0.0, last="")
            else:
                stats = self._stats.setdefault(name, _TopicStats())
                count = max(reader.count, self._published(name))
                stats.update(wall, count)
                if count != stats.last_count:
                    stats.last_count = count
                    latest = reader.latest
                    stats.text = bounded_text(to_yaml(latest)) if latest is not None else ""
                entry.update(count=count, rate=round(stats.rate, 2), last=stats.text)
            rows[name] = (wall, entry)
            out.append(entry)
        keep = set(shown)
        for name in [n for n in rows if n not in keep]:
            del rows[name]
        for name in [n for n in self._asked if n not in keep]:
            self._asked.discard(name)
            self._stats.pop(name, None)
            self.bus.call_soon_threadsafe(partial(self._unwatch, name))
        return out, len(names)

    def _alive(self, name: str) -> bool:
        """Whether a topic has endpoints besides the page's own (a source that knows better says)."""
        return True

    def _machine_topic(self, name: str) -> tuple[int, str] | None:
        """For a machine's /llfsm/M/state or /description: (messages, what the row says), which
        the source knows without a reader of the page's own (a reader of a state topic would
        make the run publish every state change: docs/view.md, Cost); None for another topic."""
        if not name.startswith(NAMESPACE + "/"):
            return None
        return self._published(name), "a machine's state or description: the diagrams show it"

    def _published(self, name: str) -> int:
        """Messages published on the topic in this process (also before the page's reader came)."""
        topic = self.bus.topics.get(name)
        return topic.published if topic is not None else 0

    def _watch(self, name: str, type_: Any) -> None:
        """(scheduler thread) A PULL reader for the page: counts messages, keeps the newest."""
        if name not in self._asked:
            return  # no longer shown meanwhile
        self._readers[name] = self.node.create_subscription(type_, name, None, 1)

    def _unwatch(self, name: str) -> None:
        """(scheduler thread) The page's reader of a topic it no longer shows, deleted."""
        if name in self._asked:
            return  # shown again meanwhile
        reader = self._readers.pop(name, None)
        if reader is not None:
            self.node.destroy_subscription(reader)


class RunSource(Source):
    """The machines, topics, services and turtle world of the run in this process."""

    def __init__(self, arr: Arrangement, bus: Bus, world: TurtleWorld | None = None) -> None:
        super().__init__(bus, "llfsm_web")
        self.arr = arr
        #: The turtle simulator's world (`--node turtlesim`: the run's session hands it in), drawn live.
        self.turtle_world = world
        self.descriptions = [description(type(m)) for m in arr.machines]
        self._last: list[tuple[int, int]] = [(-1, -1)] * len(arr.machines)
        self._since: list[int] = [0] * len(arr.machines)
        self._history: list[deque[dict[str, Any]]] = [deque(maxlen=HISTORY) for _ in arr.machines]
        self._world_key: object = None
        self._world_at = 0.0
        self._world_svg: str | None = None
        self._remote_topics: frozenset[str] = frozenset()  # the DDS graph's topics beyond this process
        self._dds_graph = self._read_dds_graph()

    def _read_dds_graph(self) -> Any:
        """On DDS, the graph beyond this process too, read on the scheduler's thread now and then
        (what `llfsm node list` would show); None on the in-process bus."""
        dp = getattr(self.bus.transport, "dp", None)
        if dp is None:
            return None
        graph = robust_graph(dp, self.warn)

        def read() -> None:
            try:
                graph.update()
                self.remote_graph = from_dds(graph)
                self._remote_topics = frozenset(t for t, _ in self.remote_graph.topics)
            except Exception as e:  # never into the bus executor: the page shows the last graph
                self.warn(f"the graph could not be read: {type(e).__name__}: {e}", "graph")

        self.node.create_timer(GRAPH_PERIOD, read)
        return graph

    def machines(self) -> list[dict[str, Any]]:
        return self.descriptions

    def local_graph(self) -> RosGraph:
        return from_bus(self.bus, self.node)

    def _machine_topic(self, name: str) -> tuple[int, str] | None:
        """In process, a machine's state is published on a change only while someone listens
        (docs/view.md, Cost): the count is what was published, and the row says so."""
        if not name.startswith(NAMESPACE + "/"):
            return None
        count = self._published(name)
        machine, _, part = name[len(NAMESPACE) + 1 :].rpartition("/")
        m = self.arr.by_name.get(machine)
        if part == "state" and m is not None:
            return count, (
                f"data: {m.STATES[m._state]}\n(published on a change while a subscriber listens; "
                "the diagram shows every state it samples)"
            )
        return count, "the machine's description: its diagram shows it"

    def has_machine(self, name: str) -> bool:
        return name in self.arr.by_name

    def topic_types(self) -> dict[str, Any]:
        return {name: topic.type for name, topic in list(self.bus.topics.items())}

    def _alive(self, name: str) -> bool:
        """A topic of this process with a publisher, a tap or a reader that is not the page's,
        or one the DDS graph beyond this process shows: the bus keeps every topic it ever had."""
        topic = self.bus.topics.get(name)
        if topic is None:
            return False
        if topic.publishers or topic.taps or any(r.node is not self.node for r in list(topic.readers)):
            return True
        return name in self._remote_topics

    def service_types(self) -> dict[str, Any]:
        return {name: server.type for name, server in list(self.bus.services.items())}

    def machine_rows(self) -> list[dict[str, Any]]:
        """Each machine as sampled now.  A change of state is a transition for the page's list;
        its time is the entry time the machine recorded (`_t0`) once that is newer than the
        last one seen, else the sample's run time (the target's entry is still to come, or the
        state keeps no entry time)."""
        now = self.clock.now
        machines = []
        for i, m in enumerate(self.arr.machines):
            state, t0 = m._state, m._t0
            prev, prev_t0 = self._last[i]
            if state != prev:
                since = t0 if t0 > prev_t0 else now
                if prev >= 0:
                    self._history[i].appendleft(
                        {"t": round(since / 1e9, 3), "from": m.STATES[prev], "to": m.STATES[state]}
                    )
                self._last[i] = (state, max(t0, prev_t0))
                self._since[i] = since
            elif t0 > prev_t0:  # the entry was recorded since (or the state was entered again)
                self._last[i] = (state, t0)
                self._since[i] = t0
            status = "finished" if m._finished else "suspended" if m._suspended else "running"
            machines.append(
                {
                    "name": m.NAME,
                    "machine": m.NAME,
                    "participant": "",
                    "runs": 1,
                    "ended": False,
                    "state": m.STATES[state],
                    "status": status,
                    "pending": m._pending,
                    "since": round(self._since[i] / 1e9, 3),
                    "transitions": list(self._history[i]),
                }
            )
        return machines

    def world(self) -> str | None:
        world = self.turtle_world
        if world is None:
            return None
        wall = time.monotonic()
        if self._world_svg is not None and wall - self._world_at < WORLD_PERIOD:
            return self._world_svg
        try:
            key = (world.raster_version, tuple(world.turtle_pixels()), world.background)
            if key != self._world_key or self._world_svg is None:
                # deferred: start-up (only a run with turtlesim draws a world)
                from ..sim.draw import svg_text

                text = svg_text(world)
                self._world_svg = text[text.index("<svg") :]
                self._world_key = key
        except RuntimeError:  # the scheduler changed the world while it was drawn: next time
            pass
        self._world_at = wall
        return self._world_svg


def _settle(done: ThreadFuture[Any], fut: Any) -> None:
    if done.done():
        return
    exc = fut.exception()
    if exc is not None:
        done.set_exception(CommandError(f"the service failed: {exc}"))
    elif fut.cancelled():
        done.set_exception(CommandError("the call was cancelled"))
    else:
        done.set_result(fut.result())


def dumps(data: Any) -> str:
    return json.dumps(data, separators=(",", ":"))
