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
"""

from __future__ import annotations

import ctypes as ct
import itertools
import time
from collections import deque
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from cyclonedds._clayer import ddspy_write
from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsPublication, BuiltinTopicDcpsSubscription
from cyclonedds.core import (
    DDSStatus,
    Entity,
    Policy,
    Qos,
    ReadCondition,
    WaitSet,
)
from cyclonedds.pub import DataWriter, Publisher
from cyclonedds.sub import DataReader, Subscriber
from cyclonedds.topic import Topic

from ...msgs import _dds
from ...msgs.rmw_dds_common.msg import Gid, NodeEntitiesInfo, ParticipantEntitiesInfo
from . import dds_config
from .base import Transport
from .dds_graph import message_class, message_type, user_data_value
from .dds_read import ANY, TAKE_BATCH, Samples

if TYPE_CHECKING:
    from ...msgs._message import Message
    from .base import BusPort, ClientView, NodeView, PendingReply, PublisherView, ServiceView, SubscriptionView

U64 = (1 << 64) - 1
#: How long a server keeps an answer for a client whose reply reader it has not matched yet
#: (rmw_cyclonedds_cpp blocks 100 ms for this; we park the reply and go on running rounds).
REPLY_PATIENCE_S = 2.0
#: How long a client trusts its last look at the server's matches (spin calls ask often).
READY_CACHE_S = 0.05
#: How long a client of a Fast DDS server waits after making its bare reply reader before it
#: makes the request writer, so that the server has matched the reader before a request can
#: reach it (docs/transports.md).
PLAIN_WRITER_DELAY_S = 0.05
#: rclpy's ReliabilityPolicy values (llfsm.ros.qos): a transport imports nothing of the bus above it.
SYSTEM_DEFAULT, RELIABLE = 0, 1
#: History depth of service endpoints: rmw's default service QoS (keep last 10, reliable, volatile).
SERVICE_DEPTH = 10
#: Between rounds that run back to back (no idle sleep), look at the wait set at most this often
#: (run-clock ns): a round then costs a comparison, and a message waits at most 0.1 ms longer.
#: Spin calls and the idle sleep look at once.
POLL_INTERVAL_NS = 100_000
#: The longest single wait on the wait set (a Ctrl-C is seen when it returns).
MAX_WAIT_NS = 100_000_000


def _write(writer: DataWriter, payload: bytes) -> None:
    """Write a serialized sample (llfsm's generated CDR, several times faster than cyclonedds'
    own serialisation of an IdlStruct), padded to 4 bytes as cyclonedds pads its own."""
    if len(payload) & 3:
        payload += b"\0" * (4 - (len(payload) & 3))
    ret = ddspy_write(writer._ref, payload)
    if ret < 0:
        raise RuntimeError(f"DDS write failed on {writer.topic.name if writer.topic else '?'} ({ret})")


def _type_hash(cls: type) -> bytes:
    """`typehash=RIHS01_...;` as rmw puts it in an endpoint's USER_DATA (Iron and later)."""
    try:
        return f"typehash={_dds.type_hash(cls)};".encode()
    except TypeError:
        return b""


def _qos(
    depth: int | None,
    user_data: bytes = b"",
    *,
    reader: bool = False,
    transient_local: bool = False,
    reliability: int = RELIABLE,
) -> Qos:
    """rclpy's QoS as rmw_cyclonedds_cpp sets it: reliable (or best effort when asked; rclpy's
    SYSTEM_DEFAULT leaves Cyclone's default, best effort for a reader and reliable for a writer),
    keep last `depth` (keep all when None), volatile (transient local when asked: the machines'
    state topics), automatic liveliness, no autodispose; XCDR1; a reader ignores its own
    participant."""
    reliable = reliability == RELIABLE or (reliability == SYSTEM_DEFAULT and not reader)
    policies: list[Any] = [
        Policy.Reliability.Reliable(max_blocking_time=1_000_000_000) if reliable else Policy.Reliability.BestEffort,
        Policy.History.KeepAll if depth is None else Policy.History.KeepLast(depth),
        Policy.Durability.TransientLocal if transient_local else Policy.Durability.Volatile,
        Policy.DataRepresentation(use_cdrv0_representation=True),
    ]
    if reader:
        policies.append(Policy.IgnoreLocal.Participant)
    else:
        policies.append(Policy.WriterDataLifecycle(autodispose=False))
    if user_data:
        policies.append(Policy.Userdata(user_data))
    return Qos(*policies)


#: Cyclone's QoS policy ids, by rclpy's names for them (QoSPolicyKind), for the incompatible QoS
#: warnings (what rmw_cyclonedds_cpp maps them to).
_POLICY_NAMES = {2: "DURABILITY", 4: "DEADLINE", 8: "LIVELINESS", 11: "RELIABILITY", 13: "HISTORY"}
#: Incompatible-QoS warnings one endpoint of ours gives; then one line says the rest go unsaid
#: (a peer making and deleting endpoints in a loop would otherwise write a line per endpoint,
#: and a run whose log is a pipe nobody reads would block on them).
MAX_INCOMPATIBLE_WARNINGS = 10
# rclpy's words (its default QoS event handlers)
_OFFERING = "New publisher discovered on topic '{}', offering incompatible QoS. No messages will be received from it."
_REQUESTING = "New subscription discovered on topic '{}', requesting incompatible QoS. No messages will be sent to it."


class _Incompatible:
    """Tells, as rclpy's default QoS event handler does (a WARN on the node's logger), that an
    endpoint elsewhere was found whose QoS cannot match ours: a reliable subscription and a
    best-effort publisher, say.  Without it the subscription would just never receive."""

    def __init__(self, endpoint: Any, topic: str, node: NodeView, *, reader: bool, msg_type: str = "") -> None:
        self.endpoint, self.topic, self.node, self.reader = endpoint, topic, node, reader
        self.msg_type = msg_type  # ours, pkg/msg/Name
        self.said = 0
        self.clashes: set[str] = set()  # the other types already named

    def on_trigger(self) -> None:
        if self.reader:
            status = self.endpoint.get_requested_incompatible_qos_status()
            said = _OFFERING
        else:
            status = self.endpoint.get_offered_incompatible_qos_status()
            said = _REQUESTING
        if status.total_count_change > 0 and self.said <= MAX_INCOMPATIBLE_WARNINGS:
            self.said += 1
            logger = self.node.get_logger()
            if self.said > MAX_INCOMPATIBLE_WARNINGS:
                kind = "publishers" if self.reader else "subscriptions"
                logger.warn(
                    f"New {kind} with incompatible QoS keep being discovered on topic '{self.topic}': "
                    f"after {MAX_INCOMPATIBLE_WARNINGS} warnings, further ones are not reported."
                )
                return
            policy = _POLICY_NAMES.get(status.last_policy_id)
            if policy is None:  # Cyclone says INVALID when the types differ, not a QoS policy
                others = self.other_types() - self.clashes
                if others:
                    self.clashes |= others
                    logger.warn(self.clash(sorted(others)))
                    return
            logger.warn(f"{said.format(self.topic)} Last incompatible policy: {policy or 'INVALID'}")

    def other_types(self) -> set[str]:
        """The types other endpoints of our topic have, where they differ from ours (what the
        domain's built-in topics say; read only when Cyclone refused a match, which is rare)."""
        kind = BuiltinTopicDcpsPublication if self.reader else BuiltinTopicDcpsSubscription
        reader = BuiltinDataReader(self.endpoint.participant, kind)
        try:
            samples = reader.read(N=TAKE_BATCH)
        finally:
            _delete(reader)
        name = "rt" + self.topic
        types = {
            message_type(getattr(x, "type_name", "") or "") for x in samples if getattr(x, "topic_name", "") == name
        }
        return {t for t in types if t and t != self.msg_type}

    def clash(self, others: list[str]) -> str:
        """As the in-process bus says it ("the topic already carries ..."), naming both types."""
        theirs = " and ".join(others)
        if self.reader:
            return (
                f"cannot subscribe to {self.topic} as {self.msg_type}: a publisher elsewhere publishes {theirs} on it; "
                "the types differ, so no messages will be received from it"
            )
        return (
            f"cannot publish {self.topic} as {self.msg_type}: a subscription elsewhere takes {theirs} on it; "
            "the types differ, so no messages will be sent to it"
        )


class _WaitSet:
    """A Cyclone WaitSet whose attachments are small integers naming our handlers, so a wait
    returns just the handlers that have something (the Python wrapper does not expose this)."""

    def __init__(self, dp: Any) -> None:
        self.ws = WaitSet(dp)
        self.handlers: dict[int, Any] = {}
        self._ids = itertools.count(1)
        self._xs = (ct.c_void_p * 8)()

    def attach(self, entity: Entity, handler: Any) -> int:
        token = next(self._ids)
        ret = self.ws._waitset_attach(self.ws._ref, entity._ref, token)
        if ret < 0:
            raise RuntimeError(f"cannot attach {entity!r} to the wait set ({ret})")
        self.handlers[token] = handler
        if len(self.handlers) > len(self._xs):
            self._xs = (ct.c_void_p * (2 * len(self.handlers)))()
        return token

    def detach(self, entity: Entity, token: int) -> None:
        if self.handlers.pop(token, None) is not None:
            self.ws._waitset_detach(self.ws._ref, entity._ref)

    def wait(self, timeout_ns: int) -> list[Any]:
        xs = self._xs
        n = self.ws._waitset_wait(self.ws._ref, ct.cast(xs, ct.POINTER(ct.c_void_p)), len(xs), max(0, timeout_ns))
        if n <= 0:
            return []
        handlers = self.handlers
        # (a token is never 0, so a NULL slot, None, finds no handler either)
        return [h for h in (handlers.get(xs[i] or 0) for i in range(min(n, len(xs)))) if h is not None]


def _delete(*entities: Entity | None) -> None:
    for e in entities:
        if e is not None:
            e.__del__()  # dds_delete now; the wrapper's own __del__ later does nothing


# -- endpoints ------------------------------------------------------------------------------------


class _Endpoint:
    """One node's DDS reader or writer, as the graph announcement lists it."""

    node: NodeView
    readers: tuple[Entity, ...] = ()
    writers: tuple[Entity, ...] = ()


class _Writer(_Endpoint):
    def __init__(self, t: DdsTransport, pub: PublisherView) -> None:
        self.t, self.node = t, pub.node
        self.cdr = _dds.codec(pub.msg_type).cdr
        topic = t.topic("rt" + pub.topic_name, _dds.dds_type(pub.msg_type))
        hashed = _type_hash(pub.msg_type)
        qos = _qos(pub.depth, hashed, transient_local=pub.transient_local, reliability=pub.reliability)
        self.writer = DataWriter(t.publisher_, topic, qos=qos)
        self.writers = (self.writer,)
        self.matched = 0
        self.keeps = pub.transient_local  # the writer keeps its last samples for readers still to come
        self.incompatible = _Incompatible(
            self.writer, pub.topic_name, pub.node, reader=False, msg_type=pub.msg_type._TYPE
        )
        self.writer.set_status_mask(DDSStatus.PublicationMatched | DDSStatus.OfferedIncompatibleQos)
        self.token = t.waits.attach(self.writer, self)
        t.add_endpoint(self)

    def on_trigger(self) -> None:
        self.matched = self.writer.get_publication_matched_status().current_count
        self.incompatible.on_trigger()

    def write(self, msg: Message) -> None:
        if not (self.matched or self.keeps):
            # nobody elsewhere, nothing kept: no serialisation.  `matched` is updated when the
            # transport polls (between rounds); a reader DDS matched since (a recorder that just
            # subscribed to a publisher that just appeared) must get this message, so DDS is
            # asked (a microsecond) before a message is dropped
            self.matched = self.writer.get_publication_matched_status().current_count
            if not self.matched:
                return
        if not self.t.closed:
            _write(self.writer, self.cdr(msg))

    def subscription_count(self) -> int:
        return self.matched

    def close(self) -> None:
        self.t.waits.detach(self.writer, self.token)
        self.t.remove_endpoint(self)
        _delete(self.writer)


class _Reader(_Endpoint):
    def __init__(self, t: DdsTransport, sub: SubscriptionView) -> None:
        self.t, self.node, self.sub = t, sub.node, sub
        self.msg_type = sub.msg_type
        topic = t.topic("rt" + sub.topic_name, _dds.dds_type(sub.msg_type))
        self.reader = DataReader(
            t.subscriber_,
            topic,
            qos=_qos(
                sub.depth,
                _type_hash(sub.msg_type),
                reader=True,
                transient_local=sub.transient_local,
                reliability=sub.reliability,
            ),
        )
        self.readers = (self.reader,)
        cls = sub.msg_type
        self.samples = Samples(self.reader, self._decode, sub.topic_name, f"a {cls._TYPE}", t.warn)
        self.cond = ReadCondition(self.reader, ANY)
        self.token = t.waits.attach(self.cond, self)
        self.reader.set_status_mask(DDSStatus.RequestedIncompatibleQos)
        incompatible = _Incompatible(self.reader, sub.topic_name, sub.node, reader=True, msg_type=sub.msg_type._TYPE)
        self.status_token = t.waits.attach(self.reader, incompatible)
        t.add_endpoint(self)

    def _decode(self, data: bytes) -> Any:
        """A sample's message, or None for one the subscription's screen drops unread."""
        screen = self.sub.screen
        if screen is not None:
            seen = screen(data)
            if seen is False:
                return None
            if seen is not True:
                return seen
        return _dds.from_cdr(data, self.msg_type)

    def on_trigger(self) -> None:
        deliver = self.sub._deliver
        for msg, _info in self.samples.take():
            if msg is not None:
                deliver(msg)

    def publisher_count(self) -> int:
        return int(self.reader.get_subscription_matched_status().current_count)

    def close(self) -> None:
        self.t.waits.detach(self.cond, self.token)
        self.t.waits.detach(self.reader, self.status_token)
        self.t.remove_endpoint(self)
        _delete(self.cond, self.reader)


class _RemoteRequest:
    """A request from another process, queued in the executor like a local one."""

    __slots__ = ("guid", "request", "seq", "server", "writer_handle")

    def __init__(self, server: _Server, guid: int | None, seq: int, request: Message, writer_handle: int) -> None:
        self.server, self.guid, self.seq, self.request, self.writer_handle = server, guid, seq, request, writer_handle

    @property
    def service(self) -> str:
        """The service asked (the executor's spin_control tells control requests from others)."""
        return str(self.server.srv.srv_name)

    def _run(self) -> None:
        if self.server.closed:
            return
        response = self.server.srv._answer(self.request)
        later = getattr(response, "add_done_callback", None)  # a LaterAnswer (transports/base.py)
        if later is not None:  # answered when it is done (an action's get_result)
            later(lambda done: self._reply(done.result()))
            return
        self._reply(response)

    def _reply(self, response: Any) -> None:
        self.server.reply(self, response, time.monotonic() + REPLY_PATIENCE_S)


class _Server(_Endpoint):
    def __init__(self, t: DdsTransport, srv: ServiceView) -> None:
        self.t, self.node, self.srv = t, srv.node, srv
        self.closed = False
        name = srv.srv_name
        user = f"serviceid={t.new_csid()};".encode()
        req_type, rep_type = _dds.request_type(srv.type), _dds.response_type(srv.type)
        self.reader = DataReader(
            t.subscriber_,
            t.topic(f"rq{name}Request", req_type),
            qos=_qos(SERVICE_DEPTH, user + _type_hash(srv.type.Request), reader=True),
        )
        self.writer = DataWriter(
            t.publisher_,
            t.topic(f"rr{name}Reply", rep_type),
            qos=_qos(SERVICE_DEPTH, user + _type_hash(srv.type.Response)),
        )
        # Fast DDS clients send the bare request (no header): a reader of that form too, so their
        # calls run (their side effects happen); its reply writer only while one is matched
        # (_BareRequests says why); see docs/transports.md for why they get no answer
        self.bare_reader = DataReader(
            t.subscriber_,
            t.topic(f"rq{name}Request", _dds.dds_type(srv.type.Request)),
            qos=_qos(SERVICE_DEPTH, reader=True),
        )
        self.bare_writer: DataWriter | None = None
        self.readers, self.writers = (self.reader, self.bare_reader), (self.writer,)
        cls = srv.type.Request
        self.requests = Samples(
            self.reader, lambda data: _dds.unwrap(data, cls), name, f"a {cls._TYPE}", t.warn, kind="request"
        )
        self.cond = ReadCondition(self.reader, ANY)
        self.token = t.waits.attach(self.cond, self)
        self.bare = _BareRequests(self)
        t.add_endpoint(self)

    def on_trigger(self) -> None:
        for (guid, seq, request), info in self.requests.take():
            self.t.bus.queue(_RemoteRequest(self, guid, seq, request, info.publication_handle))

    def _client_present(self, writer_handle: int) -> str:
        """rmw_cyclonedds_cpp's check before answering: is the client's reply reader matched yet?"""
        try:
            ep = self.reader.get_matched_publication_data(writer_handle)
        except Exception:
            ep = None
        if ep is None:
            return "gone"
        clientid = user_data_value(ep.qos, "clientid")
        if clientid is None:
            return "yes"  # a client without an id (older rmw, Fast DDS): assume all is well
        for h in self.writer.get_matched_subscriptions():
            try:
                rd = self.writer.get_matched_subscription_data(h)
            except Exception:
                continue
            if rd is not None and user_data_value(rd.qos, "clientid") == clientid:
                return "yes"
        return "maybe"

    def reply(self, req: _RemoteRequest, response: Message, give_up: float) -> bool:
        """Send the answer if the client can receive it; park it (True) while it cannot yet."""
        if self.closed:
            return False
        if req.guid is None:  # a bare request (Fast DDS): a bare reply, as its server would write
            if self.bare_writer is not None:
                _write(self.bare_writer, _dds.cdr(response))
            return False
        state = self._client_present(req.writer_handle)
        if state == "maybe" and time.monotonic() < give_up:
            self.t.park(lambda: self.reply(req, response, give_up))
            return True
        if state == "yes":
            _write(self.writer, _dds.wrap(response, req.guid, req.seq))
        return False

    def close(self) -> None:
        self.closed = True
        self.t.waits.detach(self.cond, self.token)
        self.bare.close()
        self.t.remove_endpoint(self)
        _delete(self.cond, self.reader, self.writer, self.bare_reader, self.bare_writer)
        self.bare_writer = None


class _BareRequests:
    """The server's reader of requests without rmw_cyclonedds's header (from Fast DDS clients),
    and the door that keeps their requests from being lost.

    rclpy's `wait_for_service()` on rmw_fastrtps_cpp says ready once Fast DDS has matched as many
    of the service's request readers as reply writers.  That says nothing of this side: Cyclone
    may not have matched the client's request writer yet, and a volatile Cyclone reader that
    matches a writer of another vendor starts at the writer's next sample, so a request written
    in that moment is lost (its side effects never happen).  So the bare reply writer exists only
    while a Fast DDS request writer is matched here: until then the server shows Fast DDS two
    request readers and one reply writer, which its test reads as "not ready yet", and the client
    waits until this side has seen it.  (The bare reply writer is only for that count: Fast DDS
    clients drop its replies, docs/transports.md.)"""

    def __init__(self, server: _Server) -> None:
        self.server = server
        cls = server.srv.type.Request
        self.requests = Samples(
            server.bare_reader,
            lambda data: _dds.from_cdr(data, cls),
            server.srv.srv_name,
            f"a {cls._TYPE}",
            server.t.warn,
            kind="request",
        )
        self.cond = ReadCondition(server.bare_reader, ANY)
        self.token = server.t.waits.attach(self.cond, self)
        server.bare_reader.set_status_mask(DDSStatus.SubscriptionMatched)
        self.door = _Door(self)
        self.door_token = server.t.waits.attach(server.bare_reader, self.door)

    def on_trigger(self) -> None:
        srv = self.server
        for request, info in self.requests.take():
            srv.t.bus.queue(_RemoteRequest(srv, None, 0, request, info.publication_handle))

    def fast_clients(self) -> bool:
        """Whether a request writer of another vendor than Cyclone (a Fast DDS client) is matched."""
        reader = self.server.bare_reader
        for h in reader.get_matched_publications():
            try:
                ep = reader.get_matched_publication_data(h)
            except Exception:  # gone meanwhile; cyclonedds raises DDSException
                continue
            if ep is not None and not _dds.carries_request_header(ep.key):
                return True
        return False

    def open_door(self, wanted: bool) -> None:
        srv = self.server
        if srv.closed or wanted == (srv.bare_writer is not None):
            return
        t = srv.t
        if wanted:
            name, cls = srv.srv.srv_name, srv.srv.type.Response
            srv.bare_writer = DataWriter(
                t.publisher_, t.topic(f"rr{name}Reply", _dds.dds_type(cls)), qos=_qos(SERVICE_DEPTH)
            )
            srv.writers = (srv.writer, srv.bare_writer)
        else:
            _delete(srv.bare_writer)
            srv.bare_writer = None
            srv.writers = (srv.writer,)
        t._dirty = True  # ros_discovery_info lists the node's writers

    def close(self) -> None:
        waits = self.server.t.waits
        waits.detach(self.cond, self.token)
        waits.detach(self.server.bare_reader, self.door_token)
        _delete(self.cond)


class _Door:
    """The bare reader's match status on the wait set: a Fast DDS client coming or going opens or
    closes its server's door (_BareRequests)."""

    def __init__(self, bare: _BareRequests) -> None:
        self.bare = bare

    def on_trigger(self) -> None:
        self.bare.server.bare_reader.get_subscription_matched_status()  # reading a status resets its trigger
        self.bare.open_door(self.bare.fast_clients())


class _Client(_Endpoint):
    def __init__(self, t: DdsTransport, cli: ClientView) -> None:
        self.t, self.node, self.cli = t, cli.node, cli
        name = cli.srv_name
        user = f"clientid={t.new_csid()};".encode()
        srv = cli.srv_type
        self.writer = DataWriter(
            t.publisher_,
            t.topic(f"rq{name}Request", _dds.request_type(srv)),
            qos=_qos(SERVICE_DEPTH, user + _type_hash(srv.Request)),
        )
        self.reader = DataReader(
            t.subscriber_,
            t.topic(f"rr{name}Reply", _dds.response_type(srv)),
            qos=_qos(SERVICE_DEPTH, user + _type_hash(srv.Response), reader=True),
        )
        self.readers, self.writers = (self.reader,), (self.writer,)
        self.guid = self.writer.get_instance_handle() & U64  # rmw_cyclonedds: the request writer's handle
        self.seq = itertools.count(1)
        self.pending: dict[int, PendingReply] = {}
        self._ready_at = -1.0
        self._ready = False
        #: A Fast DDS server (rmw_fastrtps_cpp) was matched: it wants requests without the header.
        self.fast = False
        self.plain: _PlainClient | None = None
        cls = srv.Response
        self.replies = Samples(
            self.reader, lambda data: _dds.unwrap(data, cls), name, f"a {cls._TYPE}", t.warn, kind="reply"
        )
        self.cond = ReadCondition(self.reader, ANY)
        self.token = t.waits.attach(self.cond, self)
        self.matches = _MatchWatch(self)  # a server coming or going wakes waits at once
        t.add_endpoint(self)

    def on_trigger(self) -> None:
        for (guid, seq, response), _info in self.replies.take():
            if guid & U64 != self.guid:
                continue  # an answer to another client of the same service
            future = self.pending.pop(seq, None)
            if future is not None and not future.done():
                future.set_result(response)

    def ready(self) -> bool:
        """rmw_cyclonedds_cpp's test: a matched request reader and a matched reply writer of the
        same server (by `serviceid=`), or both matched at all when no server says its id."""
        if self.t.closed:
            return False
        now = time.monotonic()
        if now - self._ready_at < READY_CACHE_S:
            return self._ready
        self._ready_at = now
        readers = self.writer.get_matched_subscriptions()
        writers = self.reader.get_matched_publications()
        ids = set()
        fast = others = 0
        for h in readers:
            try:
                ep = self.writer.get_matched_subscription_data(h)
            except Exception:
                continue
            if ep is None:
                continue
            sid = user_data_value(ep.qos, "serviceid")
            if sid is not None:
                ids.add(sid)
            if not _dds.carries_request_header(ep.key):
                fast += 1
            else:
                others += 1
        self.fast = bool(fast) and not others and not ids
        if self.fast:
            # Fast DDS matched our (header) endpoints by name; it talks without the header
            if self.plain is None:
                if not writers:
                    # Cyclone does not know the server's reply writer yet: a reply reader made
                    # now would miss the one heartbeat Fast DDS sends it (docs/transports.md)
                    self._ready = False
                    return False
                self.plain = _PlainClient(self)
                self.t._dirty = True  # announce the new reader and writer with this client's
            self._ready = self.plain.ready()
        elif not ids:
            self._ready = bool(readers) and bool(writers)
        else:
            self._ready = False
            for h in writers:
                try:
                    ep = self.reader.get_matched_publication_data(h)
                except Exception:
                    continue
                if user_data_value(ep.qos if ep is not None else None, "serviceid") in ids:
                    self._ready = True
                    break
        return self._ready

    def send(self, request: Message, future: PendingReply) -> None:
        if self.t.closed or not self.ready():
            # sent to nobody: no process can answer it, so spin calls say TIMEOUT at once (as
            # in process); the future is left to the bus's own rule for a missing server
            future._remote = None
            if self.t.closed:
                return
        seq = next(self.seq)
        if self.fast and self.plain is not None:
            self.plain.send(request, future)
            return
        self.pending[seq] = future
        _write(self.writer, _dds.wrap(request, self.guid, seq))

    @property
    def in_order(self) -> bool:
        """Replies are matched to requests by their order (a Fast DDS server, `_PlainClient`)."""
        return self.fast

    def can_still_answer(self, future: PendingReply) -> bool:
        if self.t.closed:
            return False
        self._ready_at = -1.0 if time.monotonic() - self._ready_at > 0.2 else self._ready_at
        return self.ready()

    def close(self) -> None:
        self.t.waits.detach(self.cond, self.token)
        self.matches.close()
        self.t.remove_endpoint(self)
        if self.plain is not None:
            self.plain.close()
        _delete(self.cond, self.reader, self.writer)


class _MatchWatch:
    """A client's match statuses on the wait set: `wait_for_service` and spin calls wake as
    soon as a server is matched or lost, instead of at their next timeout."""

    def __init__(self, client: _Client) -> None:
        self.client, waits = client, client.t.waits
        client.writer.set_status_mask(DDSStatus.PublicationMatched)
        client.reader.set_status_mask(DDSStatus.SubscriptionMatched)
        self.tokens = (waits.attach(client.writer, self), waits.attach(client.reader, self))

    def on_trigger(self) -> None:
        c = self.client
        c.writer.get_publication_matched_status()  # reading a status resets its trigger
        c.reader.get_subscription_matched_status()
        c._ready_at = -1.0  # look again at the next ready()

    def close(self) -> None:
        c = self.client
        c.t.waits.detach(c.writer, self.tokens[0])
        c.t.waits.detach(c.reader, self.tokens[1])


class _PlainClient:
    """The endpoints a client uses with a Fast DDS server: the same topics and type names, the
    payload without rmw_cyclonedds's request header (rmw_fastrtps_cpp correlates replies through
    RTPS inline QoS, which Cyclone's Python binding cannot read or write).  So replies are matched
    to requests in order: right for one client per service, which is the usual case; with several
    clients of one Fast DDS service at once a reply may reach the wrong llfsm client.  Made only
    when such a server is seen."""

    def __init__(self, owner: _Client) -> None:
        t, srv, name = owner.t, owner.cli.srv_type, owner.cli.srv_name
        self.t, self.owner = t, owner
        self.reader = DataReader(
            t.subscriber_, t.topic(f"rr{name}Reply", _dds.dds_type(srv.Response)), qos=_qos(SERVICE_DEPTH, reader=True)
        )
        self.made = time.monotonic()
        self.writer: DataWriter | None = None  # made a little after the reader (ready())
        self._request_topic = t.topic(f"rq{name}Request", _dds.dds_type(srv.Request))
        owner.readers, owner.writers = (owner.reader, self.reader), (owner.writer,)
        self.waiting: deque[PendingReply] = deque()
        cls = srv.Response
        self.replies = Samples(
            self.reader, lambda data: _dds.from_cdr(data, cls), name, f"a {cls._TYPE}", t.warn, kind="reply"
        )
        self.cond = ReadCondition(self.reader, ANY)
        self.token = t.waits.attach(self.cond, self)

    def ready(self) -> bool:
        if self.writer is None:
            if time.monotonic() - self.made < PLAIN_WRITER_DELAY_S:
                return False
            self.writer = DataWriter(self.t.publisher_, self._request_topic, qos=_qos(SERVICE_DEPTH))
            self.owner.writers = (self.owner.writer, self.writer)
            self.t._dirty = True
            return False
        return bool(self.writer.get_matched_subscriptions()) and bool(self.reader.get_matched_publications())

    def send(self, request: Message, future: PendingReply) -> None:
        self.waiting.append(future)
        assert self.writer is not None  # sent only once ready()
        _write(self.writer, _dds.cdr(request))

    def on_trigger(self) -> None:
        for response, _info in self.replies.take():
            while self.waiting:
                future = self.waiting.popleft()
                if not future.done():
                    future.set_result(response)
                    break

    def close(self) -> None:
        self.t.waits.detach(self.cond, self.token)
        _delete(self.cond, self.reader, self.writer)


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
