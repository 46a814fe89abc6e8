"""Services on the DDS wire, as rmw_cyclonedds_cpp carries them: `rq/<name>Request` and
`rr/<name>Reply`, `serviceid=` / `clientid=` in USER_DATA, and rmw_cyclonedds's header (client
id and sequence number) in each payload, so clients and servers of rmw_cyclonedds_cpp pair with
ours exactly as with their own.

Fast DDS (rmw_fastrtps_cpp) peers send and expect payloads without that header: a server also
reads bare requests (`_BareRequests`, and the door that keeps them from being lost), a client of
a Fast DDS server talks through `_PlainClient` (docs/transports.md says what this costs).
Actions are five such services and topics, made by llfsm.ros.action over the same transport.
"""

from __future__ import annotations

import itertools
import time
from collections import deque
from typing import TYPE_CHECKING, Any

from cyclonedds.core import DDSStatus, ReadCondition
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader

from ...msgs import _dds
from .dds_entities import _delete, _Endpoint, _qos, _type_hash, _write
from .dds_graph import user_data_value
from .dds_read import ANY, Samples

if TYPE_CHECKING:
    from ...msgs._message import Message
    from .base import ClientView, PendingReply, ServiceView
    from .dds import DdsTransport


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
#: History depth of service endpoints: rmw's default service QoS (keep last 10, reliable, volatile).
SERVICE_DEPTH = 10


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
