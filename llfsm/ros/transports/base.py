"""The transport interface: what carries a run's traffic beyond its own process.

The bus always delivers in process itself: a publisher hands copies to the readers of its
process, a client calls a server of its process directly.  That path is deterministic and free
of serialisation, and every transport keeps it.  A transport adds links to *other* processes:
for each publisher, reader, server and client the bus asks it for a remote end (None: this
transport has none), and between rounds and inside spin calls the bus lets it bring in what
arrived (`poll`) or wait for it (`wait`).  Machine code and nodes never see which transport runs.

    inproc  no remote ends at all (today's bus; the default, deterministic under --clock sim)
    dds     Cyclone DDS: ROS 2's wire, names, QoS and graph (transports/dds.py)
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol

if TYPE_CHECKING:
    from ...msgs._message import Message
    from ..bus import Bus, Future
    from ..node import Client, Node, Publisher, ServiceServer, Subscription


class RemoteWriter(Protocol):
    def write(self, msg: Message) -> None:
        """Send a message to the readers of other processes (the bus has served local ones)."""

    def subscription_count(self) -> int:
        """Readers in other processes matched with this writer."""

    def close(self) -> None: ...


class RemoteClient(Protocol):
    def ready(self) -> bool:
        """A server in another process is matched both ways (its request reader and reply writer)."""

    def send(self, request: Message, future: Future) -> None:
        """Send the request; the future completes when `poll` brings in the reply.  Sent while
        no server is ready, it sets `future._remote = None`: nothing can answer it, and spin
        calls say TIMEOUT at once, as for a missing server in process."""

    def can_still_answer(self, future: Future) -> bool:
        """False once the server the request went to is gone: spin calls then return TIMEOUT
        instead of waiting forever."""

    def close(self) -> None: ...


class Closable(Protocol):
    def close(self) -> None: ...


class Transport:
    """The in-process transport: no remote ends; `wait` is the run clock's sleep."""

    name = "inproc"
    #: True when other processes can change what the bus sees (spin calls must wait for them).
    remote = False

    def start(self, bus: Bus) -> None:
        self.bus = bus

    def publisher(self, pub: Publisher) -> RemoteWriter | None:
        return None

    def subscription(self, sub: Subscription) -> Closable | None:
        return None

    def service(self, srv: ServiceServer) -> Closable | None:
        return None

    def client(self, cli: Client) -> RemoteClient | None:
        return None

    def node_changed(self, node: Node) -> None:
        """A node was created or destroyed, or one of its endpoints was (graph announcements)."""

    def discover(self, topic: str, fn: Any) -> None:
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
