"""The transport interface: what carries a run's traffic beyond its own process.

The bus always delivers in process itself: a publisher hands copies to the readers of its
process, a client calls a server of its process directly.  That path is deterministic and free
of serialisation, and every transport keeps it.  A transport adds links to *other* processes:
for each publisher, reader, server and client the bus asks it for a remote end (None: this
transport has none), and between rounds and inside spin calls the bus lets it bring in what
arrived (`poll`) or wait for it (`wait`).  Machine code and nodes never see which transport runs.

    inproc  no remote ends at all (today's bus; the default, deterministic under --clock sim)
    dds     Cyclone DDS: ROS 2's wire, names, QoS and graph (transports/dds.py)

A transport sees the bus and its entities only through the protocols below (`BusPort` and the
`...View`s): the few attributes and methods it reads, so that transports sit below the bus in
the layers and never import it (docs/transports.md, "How it is built").
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import IO, TYPE_CHECKING, Any, Protocol

if TYPE_CHECKING:
    from ...msgs._message import Message, Service
    from ...runtime.clock import Clock
    from ...runtime.context import RunContext


# -- what a transport reads of the bus and its entities ----------------------------------------


class Work(Protocol):
    """An item the executor runs in its turn (a PUSH subscription with messages, a request)."""

    def _run(self) -> None: ...


class LoggerView(Protocol):
    def warn(self, message: str) -> object:
        """rclpy's default QoS event handlers warn on the node's logger."""


class NodeView(Protocol):
    """A node as the graph announcement lists it (rmw's ParticipantEntitiesInfo)."""

    @property
    def _destroyed(self) -> bool: ...

    def get_name(self) -> str: ...

    def get_namespace(self) -> str: ...

    def get_logger(self) -> LoggerView: ...


class PublisherView(Protocol):
    """What a remote writer is made from: topic, type and QoS of the publisher."""

    @property
    def node(self) -> NodeView: ...
    @property
    def msg_type(self) -> type[Message]: ...
    @property
    def topic_name(self) -> str: ...
    @property
    def depth(self) -> int | None:
        """None: KEEP_ALL."""

    @property
    def transient_local(self) -> bool: ...
    @property
    def reliability(self) -> int:
        """rclpy's ReliabilityPolicy value (llfsm.ros.qos)."""


class SubscriptionView(Protocol):
    """What a remote reader is made from, and where it hands in what it takes."""

    @property
    def node(self) -> NodeView: ...
    @property
    def msg_type(self) -> type[Message]: ...
    @property
    def topic_name(self) -> str: ...
    @property
    def depth(self) -> int | None: ...
    @property
    def transient_local(self) -> bool: ...
    @property
    def reliability(self) -> int: ...
    @property
    def screen(self) -> Callable[[bytes], Any] | None:
        """Looks at a sample's CDR before it is decoded (None: decode every sample): False
        drops it unread, True decodes it, a message is delivered as it is.  What a reader
        needs of a peer's sample may be a small part of it (an action client's own goals in
        a status array of any length): this is how it never pays for the rest."""

    def _deliver(self, msg: Any) -> None:
        """A message from another process, delivered as a local publisher's copy is."""


class LaterAnswer(Protocol):
    """An answer still to come (llfsm.ros.task.Future): a server that answers when it can (an
    action's get_result, when the goal has finished) returns one of the response."""

    def add_done_callback(self, fn: Callable[[Any], None]) -> None: ...

    def result(self) -> Any: ...


class ServiceView(Protocol):
    """A server whose requests may come from other processes."""

    @property
    def node(self) -> NodeView: ...
    @property
    def type(self) -> type[Service]: ...
    @property
    def srv_name(self) -> str: ...

    def _answer(self, request: Message) -> Message | LaterAnswer:
        """The server's callback run on a request (checked), as for a local client: the
        response, or a LaterAnswer of it."""


class ClientView(Protocol):
    """A client that may reach servers of other processes."""

    @property
    def node(self) -> NodeView: ...
    @property
    def srv_type(self) -> type[Service]: ...
    @property
    def srv_name(self) -> str: ...


class PendingReply(Protocol):
    """A request's future (llfsm.ros.task.Future) as the transport that sent it completes it."""

    _remote: RemoteClient | None

    def done(self) -> bool: ...

    def set_result(self, result: Any) -> None: ...


class BusPort(Protocol):
    """What a transport uses of the bus it serves (llfsm.ros.bus.Bus)."""

    @property
    def ctx(self) -> RunContext:
        """The run: a transport closes with it (`at_end`)."""

    @property
    def clock(self) -> Clock: ...

    @property
    def nodes(self) -> Sequence[NodeView]:
        """Every node made on the bus, destroyed ones too (the graph announcement skips those)."""

    def queue(self, work: Work) -> None:
        """Run `work` in the executor's turn, as a request from this process would be."""

    def next_timer_due(self) -> int | None:
        """Run time of the next timer: an idle wait must not sleep past it."""

    def log_output(self) -> IO[str]:
        """Where the run's log lines go (a transport's warnings too)."""

    def stamp(self) -> tuple[int, int]:
        """Seconds and nanoseconds for a log line."""


# -- what the bus gets from a transport ---------------------------------------------------------


class RemoteWriter(Protocol):
    def write(self, msg: Message) -> None:
        """Send a message to the readers of other processes (the bus has served local ones)."""

    def subscription_count(self) -> int:
        """Readers in other processes matched with this writer."""

    def close(self) -> None: ...


class RemoteClient(Protocol):
    def ready(self) -> bool:
        """A server in another process is matched both ways (its request reader and reply writer)."""

    def send(self, request: Message, future: PendingReply) -> None:
        """Send the request; the future completes when `poll` brings in the reply.  Sent while
        no server is ready, it sets `future._remote = None`: nothing can answer it, and spin
        calls say TIMEOUT at once, as for a missing server in process."""

    def can_still_answer(self, future: PendingReply) -> bool:
        """False once the server the request went to is gone: spin calls then return TIMEOUT
        instead of waiting forever."""

    @property
    def in_order(self) -> bool:
        """True when replies are matched to requests by their order rather than by an id (a
        Fast DDS server): a request that waits for its answer would take a later one's."""

    def close(self) -> None: ...


class Closable(Protocol):
    def close(self) -> None: ...


class RemoteReader(Protocol):
    def publisher_count(self) -> int:
        """Writers in other processes matched with this reader."""

    def close(self) -> None: ...


class Transport:
    """The in-process transport: no remote ends; `wait` is the run clock's sleep."""

    name = "inproc"
    #: True when other processes can change what the bus sees (spin calls must wait for them).
    remote = False

    def start(self, bus: BusPort) -> None:
        self.bus = bus

    def publisher(self, pub: PublisherView) -> RemoteWriter | None:
        return None

    def subscription(self, sub: SubscriptionView) -> RemoteReader | None:
        return None

    def service(self, srv: ServiceView) -> Closable | None:
        return None

    def client(self, cli: ClientView) -> RemoteClient | None:
        return None

    def node_changed(self, node: NodeView) -> None:
        """A node was created or destroyed, or one of its endpoints was (graph announcements)."""

    def discover(self, topic: str, fn: Callable[[type[Message]], None]) -> None:
        """Call fn(message class) once a publisher of `topic` appears in another process."""

    def poll(self, force: bool = True) -> bool:
        """Bring in what arrived since the last call (messages, requests, replies, matches).
        Between rounds the bus calls it with force=False: then it must be cheap when nothing
        arrived (it runs after every round) and may skip looking if it looked very recently.
        True if anything came."""
        return False

    def wait(self, until_ns: int) -> None:
        """Block until run time `until_ns`, or earlier when something arrives."""
        self.bus.clock.sleep_until(until_ns)

    def close(self) -> None:
        pass
