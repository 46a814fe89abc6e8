"""A node's publishers and subscriptions on the DDS wire: topics `rt/<name>`, one DataWriter
or DataReader each, with the QoS the node asked for (dds_entities.py).

A writer serialises only when a reader elsewhere is matched (the bus already delivered within
the process); a reader hands what it takes, decoded through dds_read.Samples, to its
subscription.  Both are made and polled by the transport (dds.py).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from cyclonedds.core import DDSStatus, ReadCondition
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader

from ...msgs import _dds
from .dds_entities import _delete, _Endpoint, _Incompatible, _qos, _type_hash, _write
from .dds_read import ANY, Samples

if TYPE_CHECKING:
    from ...msgs._message import Message
    from .base import PublisherView, SubscriptionView
    from .dds import DdsTransport


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
