"""Publishers, as `rclpy.publisher`: `node.create_publisher(T, topic, qos)` makes one.

Publishing copies the message once per reader of this process, hands the message itself to the
topic's taps, and gives it to the transport's writer for other processes.  See docs/bus.md
(Publishers).
"""

from __future__ import annotations

from collections import deque
from typing import TYPE_CHECKING

from .names import type_name
from .qos import ReliabilityPolicy

if TYPE_CHECKING:
    from ..msgs._message import Message
    from .bus import Bus
    from .transports.base import NodeView


class Publisher:
    __slots__ = (
        "_bus",
        "_destroyed",
        "_remote",
        "_topic",
        "_type",
        "depth",
        "msg_type",
        "node",
        "reliability",
        "topic_name",
    )

    #: TRANSIENT_LOCAL (see LatchingPublisher): a transport gives its writer that durability.
    transient_local = False

    def __init__(
        self,
        bus: Bus,
        node: NodeView,
        msg_type: type[Message],
        topic_name: str,
        depth: int | None = 10,
        reliability: ReliabilityPolicy = ReliabilityPolicy.RELIABLE,
    ) -> None:
        """`topic_name` is resolved (the node expanded and remapped it)."""
        self._bus = bus
        self.node = node
        self.topic_name = topic_name
        self._topic = bus.topic(topic_name, msg_type, "publish on")
        self._topic.publishers += 1
        self._type = self.msg_type = msg_type
        self.depth = depth  # None: KEEP_ALL
        self.reliability = reliability  # the transport's writer offers it; in process nothing is lost
        self._destroyed = False
        self._remote = bus.transport.publisher(self)  # None unless the transport has one

    def publish(self, msg: Message) -> None:
        if type(msg) is not self._type:
            raise TypeError(
                f"publish() on {self.topic_name}: expected a {self._type._TYPE} message, got {type_name(msg)}"
            )
        topic = self._topic
        topic.published += 1
        for reader in topic.readers:
            reader._deliver(msg._copy())
        if topic.taps:
            for tap in topic.taps:
                tap(msg)
        if self._remote is not None:
            self._remote.write(msg)

    def get_subscription_count(self) -> int:
        remote = self._remote.subscription_count() if self._remote is not None else 0
        return len(self._topic.readers) + len(self._topic.taps) + remote

    def destroy(self) -> None:
        if not self._destroyed:
            self._destroyed = True
            self._topic.publishers -= 1
            self._topic.latched.pop(self, None)
            if self._remote is not None:
                self._remote.close()


class LatchingPublisher(Publisher):
    """A TRANSIENT_LOCAL publisher: also keeps its last `depth` messages on the topic, for
    subscriptions that join later (a DDS transport gives its writer the same durability).
    A subclass, so volatile publishers pay nothing for it."""

    __slots__ = ()
    transient_local = True

    def __init__(
        self,
        bus: Bus,
        node: NodeView,
        msg_type: type[Message],
        topic_name: str,
        depth: int | None,
        reliability: ReliabilityPolicy = ReliabilityPolicy.RELIABLE,
    ) -> None:
        super().__init__(bus, node, msg_type, topic_name, depth, reliability)
        self._topic.latched[self] = deque(maxlen=depth)

    def publish(self, msg: Message) -> None:
        super().publish(msg)
        kept = self._topic.latched.get(self)
        if kept is not None:
            kept.append(msg._copy())
