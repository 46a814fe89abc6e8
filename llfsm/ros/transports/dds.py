"""The DDS transport: the bus on ROS 2's wire, through Cyclone DDS (the `cyclonedds` package).

What a ROS 2 peer sees, as rmw_cyclonedds_cpp makes it (docs/transports.md, "What a ROS 2 peer sees"):
- one DomainParticipant per run (USER_DATA `enclave=/;`), configured from the ROS_* variables
  (dds_config.py);
- each `ros.Node` a ROS 2 node, announced on `ros_discovery_info` (rmw_dds_common's
  ParticipantEntitiesInfo: the participant's gid and, per node, its name, namespace and the gids
  of its readers and writers; reliable, transient local, keep last 1), so `ros2 node list` and
  rclpy's graph API list them;
- topics `rt/<name>`, services `rq/<name>Request` + `rr/<name>Reply`, type names
  `pkg::msg::dds_::Name_`; QoS as the node asked (rclpy's defaults: reliable, keep last depth,
  volatile, no autodispose; `ros.qos_profile_sensor_data` best effort), payloads XCDR1; an
  endpoint elsewhere whose QoS cannot match ours is reported as rclpy does ("New publisher
  discovered on topic ..., offering incompatible QoS");
- service endpoints carry `serviceid=` / `clientid=` in USER_DATA and requests carry
  rmw_cyclonedds's header (client id and sequence number) in the payload, so clients and
  servers on rmw_cyclonedds_cpp pair with ours exactly as with their own.

The bus delivers within the process itself; Cyclone's readers ignore this participant's own
writers (no message arrives twice).  Everything runs on the scheduler's thread: Cyclone receives
on its own threads, and `poll` takes what arrived.  One WaitSet holds a read condition per
reader and the writers' match status, so `poll` after an idle round is one `wait(0)` call,
whatever the number of readers; `wait` blocks on the same WaitSet (data wakes it).

This module is the transport itself: the participant, its graph announcement, polling and
waiting.  Its parts: dds_entities.py (QoS, USER_DATA, the write path, the wait set, incompatible
QoS warnings), dds_topics.py (publishers and subscriptions), dds_services.py (servers and
clients, with rmw_cyclonedds's header and without it for Fast DDS peers), dds_read.py (samples
from peers, validated), dds_graph.py (the domain's graph for the CLI), dds_config.py (`ROS_*`).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from typing import TYPE_CHECKING

from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsPublication
from cyclonedds.core import Policy, Qos, ReadCondition
from cyclonedds.pub import DataWriter, Publisher
from cyclonedds.sub import Subscriber
from cyclonedds.topic import Topic

from ...msgs import _dds
from ...msgs.rmw_dds_common.msg import Gid, NodeEntitiesInfo, ParticipantEntitiesInfo
from . import dds_config
from .base import Transport
from .dds_entities import (
    MAX_INCOMPATIBLE_WARNINGS,
    RELIABLE,
    SYSTEM_DEFAULT,
    _delete,
    _Endpoint,
    _WaitSet,
    _write,
)
from .dds_graph import message_class
from .dds_read import ANY, TAKE_BATCH
from .dds_services import (
    PLAIN_WRITER_DELAY_S,
    READY_CACHE_S,
    REPLY_PATIENCE_S,
    SERVICE_DEPTH,
    U64,
    _Client,
    _Server,
)
from .dds_topics import _Reader, _Writer

if TYPE_CHECKING:
    from .base import BusPort, ClientView, NodeView, PublisherView, ServiceView, SubscriptionView

__all__ = [  # what this module offered before its parts moved out, still importable from here
    "MAX_INCOMPATIBLE_WARNINGS",
    "MAX_WAIT_NS",
    "PLAIN_WRITER_DELAY_S",
    "POLL_INTERVAL_NS",
    "READY_CACHE_S",
    "RELIABLE",
    "REPLY_PATIENCE_S",
    "SERVICE_DEPTH",
    "SYSTEM_DEFAULT",
    "U64",
    "DdsTransport",
]

#: Between rounds that run back to back (no idle sleep), look at the wait set at most this often
#: (run-clock ns): a round then costs a comparison, and a message waits at most 0.1 ms longer.
#: Spin calls and the idle sleep look at once.
POLL_INTERVAL_NS = 100_000
#: The longest single wait on the wait set (a Ctrl-C is seen when it returns).
MAX_WAIT_NS = 100_000_000


class _Discovery:
    """Watches DCPSPublication for topics asked about (`--echo` of a topic published elsewhere)."""

    def __init__(self, t: DdsTransport) -> None:
        self.t = t
        self.wanted: dict[str, list[Callable[[type], None]]] = {}
        self.reader = BuiltinDataReader(t.dp, BuiltinTopicDcpsPublication)
        self.cond = ReadCondition(self.reader, ANY)
        self.token = t.waits.attach(self.cond, self)

    def on_trigger(self) -> None:
        for s in self.reader.take(N=TAKE_BATCH):
            name = getattr(s, "topic_name", None)
            if not name or not name.startswith("rt") or name[2:] not in self.wanted:
                continue
            cls = message_class(getattr(s, "type_name", ""))
            if cls is None:
                continue
            for fn in self.wanted.pop(name[2:]):
                fn(cls)

    def close(self) -> None:
        self.t.waits.detach(self.cond, self.token)
        _delete(self.cond, self.reader)


def _gid(guid: bytes) -> Gid:
    """rmw's gid of an entity: its 16-byte DDS GUID (ROS 2 Iron and later; Humble used 24)."""
    return Gid(data=list(guid[:16]))


# -- the transport ----------------------------------------------------------------------------------


class DdsTransport(Transport):
    name = "dds"
    remote = True

    def __init__(self, domain_id: int | None = None) -> None:
        self.dp = dds_config.participant(domain_id)
        self._notes = dds_config.settings().notes  # rcl's warnings (ignored peers, deprecated variable)
        self.publisher_ = Publisher(self.dp)
        self.subscriber_ = Subscriber(self.dp)
        self.waits = _WaitSet(self.dp)
        self._topics: dict[tuple[str, type], Topic] = {}
        self._endpoints: dict[int, list[_Endpoint]] = {}
        self._parked: list[Callable[[], bool]] = []
        self._discovery: _Discovery | None = None
        self._csids = itertools.count(1)
        self._gid = self.dp.get_guid().bytes
        self._dirty = True
        self._next_poll = 0
        self._warned: set[str] = set()
        self.closed = False
        graph_qos = Qos(
            Policy.Reliability.Reliable(max_blocking_time=1_000_000_000),
            Policy.History.KeepLast(1),
            Policy.Durability.TransientLocal,
            Policy.DataRepresentation(use_cdrv0_representation=True),
            Policy.WriterDataLifecycle(autodispose=False),
        )
        self._info = DataWriter(
            self.publisher_,
            self.topic("ros_discovery_info", _dds.dds_type(ParticipantEntitiesInfo)),
            qos=graph_qos,
        )

    def start(self, bus: BusPort) -> None:
        self.bus = bus
        clock = bus.clock
        if getattr(clock, "kind", "") == "wall" and hasattr(clock, "waiter"):
            clock.waiter = self._idle_wait  # the idle sleep between rounds wakes on data
        bus.ctx.at_end.append(self.close)
        for note in self._notes:
            self.warn(note)

    # -- bookkeeping --------------------------------------------------------------------------
    def topic(self, name: str, idl: type) -> Topic:
        t = self._topics.get((name, idl))
        if t is None:
            t = self._topics[(name, idl)] = Topic(self.dp, name, idl)
        return t

    def new_csid(self) -> str:
        """rmw_cyclonedds_cpp's client/service id: the participant's 12-byte prefix and a counter."""
        data = self._gid[:12] + next(self._csids).to_bytes(4, "big")
        return ".".join(f"{b:x}" for b in data)

    def add_endpoint(self, ep: _Endpoint) -> None:
        self._endpoints.setdefault(id(ep.node), []).append(ep)
        self._dirty = True

    def remove_endpoint(self, ep: _Endpoint) -> None:
        eps = self._endpoints.get(id(ep.node), [])
        if ep in eps:
            eps.remove(ep)
        self._dirty = True

    def park(self, retry: Callable[[], bool]) -> None:
        self._parked.append(retry)

    # -- the Transport interface ------------------------------------------------------------------
    def publisher(self, pub: PublisherView) -> _Writer:
        return _Writer(self, pub)

    def subscription(self, sub: SubscriptionView) -> _Reader:
        return _Reader(self, sub)

    def service(self, srv: ServiceView) -> _Server:
        return _Server(self, srv)

    def client(self, cli: ClientView) -> _Client:
        return _Client(self, cli)

    def node_changed(self, node: NodeView) -> None:
        self._dirty = True

    def discover(self, topic: str, fn: Callable[[type], None]) -> None:
        if self._discovery is None:
            self._discovery = _Discovery(self)
        self._discovery.wanted.setdefault(topic, []).append(fn)

    def poll(self, force: bool = True) -> bool:
        if self.closed:
            return False
        if not force:
            now = self.bus.clock.now
            if now < self._next_poll:
                return False  # between back-to-back rounds: looked less than POLL_INTERVAL ago
            self._next_poll = now + POLL_INTERVAL_NS
        if self._dirty:
            self._announce()
        if self._parked:
            parked, self._parked = self._parked, []
            for retry in parked:
                retry()
        handlers = self.waits.wait(0)
        for h in handlers:
            h.on_trigger()
        return bool(handlers)

    def wait(self, until_ns: int) -> None:
        if self.closed:
            super().wait(until_ns)
            return
        clock = self.bus.clock
        read = getattr(clock, "read", None)
        now = read() if read is not None else clock.now
        if until_ns > now:
            # at most 0.1 s in the C call: Python runs a Ctrl-C handler only once it returns
            self.waits.wait(min(until_ns - now, 10_000_000 if self._parked else MAX_WAIT_NS))
        clock.now = read() if read is not None else until_ns

    def _idle_wait(self, ns: int) -> None:
        """The wall clock's idle sleep: as long, unless data arrives or a timer falls due first
        (a node-only run then keeps its timers' rhythm, turtlesim's 16 ms, to the millisecond)."""
        due = self.bus.next_timer_due()
        if due is not None:
            ns = min(ns, max(0, due - self.bus.clock.read()))  # type: ignore[attr-defined]  # a WallClock (start)
        if self._parked:
            ns = min(ns, 10_000_000)
        self.waits.wait(min(ns, MAX_WAIT_NS))
        self._next_poll = 0  # whatever woke us is taken right after this round

    # -- the graph ----------------------------------------------------------------------------------
    def _announce(self) -> None:
        """Publish this participant's ParticipantEntitiesInfo (ros_discovery_info), as rmw does
        whenever a node or an endpoint comes or goes."""
        self._dirty = False
        nodes = []
        for node in self.bus.nodes:
            if node._destroyed:
                continue
            eps = self._endpoints.get(id(node), [])
            readers = [_gid(r.get_guid().bytes) for ep in eps for r in ep.readers]
            writers = [_gid(w.get_guid().bytes) for ep in eps for w in ep.writers]
            nodes.append(
                NodeEntitiesInfo(
                    node_namespace=node.get_namespace(),
                    node_name=node.get_name(),
                    reader_gid_seq=readers,
                    writer_gid_seq=writers,
                )
            )
        info = ParticipantEntitiesInfo(gid=_gid(self._gid), node_entities_info_seq=nodes)
        _write(self._info, _dds.cdr(info))

    def warn(self, text: str) -> None:
        """A problem with what another process sent: logged once per text, never fatal."""
        if text not in self._warned:
            self._warned.add(text)
            stream = self.bus.log_output()
            sec, nsec = self.bus.stamp()
            stream.write(f"[WARN] [{sec}.{nsec:09d}] [llfsm.dds]: {text}\n")
            stream.flush()

    def close(self) -> None:
        """Leave the domain: peers see this participant and its endpoints go at once."""
        if self.closed:
            return
        self.closed = True
        clock = getattr(self, "bus", None) and self.bus.clock
        if clock is not None and hasattr(clock, "waiter") and clock.waiter == self._idle_wait:
            clock.waiter = None
        _delete(self.dp)
