"""Subscriptions, as `rclpy.subscription`: `node.create_subscription(T, topic, callback, qos)`.

PUSH (a callback) or PULL (callback None, clfsm's preferred style); see docs/bus.md
(Subscriptions: PUSH and PULL).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from .qos import ReliabilityPolicy

if TYPE_CHECKING:
    from ..msgs._message import Message
    from .bus import Bus
    from .transports.base import NodeView


class Subscription:
    """A reader of a topic.  PUSH (with a callback): messages queue up to the QoS depth and the
    callback runs when the executor spins.  PULL (callback None, clfsm's preferred style):
    `latest` is the newest message, `take()` the newest one not taken yet, `count` how many came."""

    __slots__ = (
        "_bus",
        "_destroyed",
        "_fresh",
        "_queue",
        "_remote",
        "_scheduled",
        "_topic",
        "callback",
        "count",
        "depth",
        "latest",
        "msg_type",
        "node",
        "reliability",
        "screen",
        "topic_name",
        "transient_local",
    )

    def __init__(
        self,
        bus: Bus,
        node: NodeView,
        msg_type: type[Message],
        topic_name: str,
        callback: Callable[[Any], Any] | None,
        depth: int | None,
        transient_local: bool = False,
        reliability: ReliabilityPolicy = ReliabilityPolicy.RELIABLE,
    ) -> None:
        """`topic_name` is resolved (the node expanded and remapped it)."""
        self._bus = bus
        self.topic_name = topic_name
        self._topic = bus.topic(topic_name, msg_type, "subscribe to")
        self.msg_type = msg_type
        self.callback = callback
        self.count = 0
        self.latest: Any = None
        self._fresh = False
        self._queue: deque[Any] = deque(maxlen=depth)
        self._scheduled = False
        self._destroyed = False
        #: For a reader of other processes' samples: `screen(payload)` looks at a sample's CDR
        #: before it is decoded: False drops it unread, True decodes it as usual, a message is
        #: delivered instead (an action client reads only its own goals out of a peer's status
        #: array, transports/base.py SubscriptionView).  None: every sample is decoded.
        self.screen: Callable[[bytes], Any] | None = None
        topic = self._topic
        for fn in topic.on_readers:  # before joining: a latched value can still be brought up to date
            fn(topic, True)
        topic.readers.append(self)
        if transient_local:  # a late joiner gets what TRANSIENT_LOCAL publishers kept, oldest first
            for kept in list(topic.latched.values()):
                for msg in kept:
                    self._deliver(msg._copy())
        self.node = node
        self.depth = depth  # None: KEEP_ALL
        self.transient_local = transient_local
        self.reliability = reliability  # what the transport's reader asks for
        self._remote = bus.transport.subscription(self)  # brings in other processes' messages

    def _deliver(self, msg: Any) -> None:
        self.latest = msg
        self.count += 1
        if self.callback is None:
            self._fresh = True
            return
        self._queue.append(msg)  # a full queue drops its oldest message
        if not self._scheduled:
            self._scheduled = True
            self._bus.queue(self)

    def _run(self) -> None:
        """Executor work: hand the messages queued so far to the callback, oldest first.  What
        callbacks publish meanwhile waits for the next spin, so a callback that publishes on
        its own topic cannot loop forever."""
        queue = self._queue
        self._scheduled = False
        for _ in range(len(queue)):
            if self._destroyed:
                return
            self.callback(queue.popleft())  # type: ignore[misc]  # not None: only PUSH subscriptions queue

    def get_publisher_count(self) -> int:
        """Publishers of the topic: of this process, and (DDS) those of other processes matched
        with this subscription, as rclpy's counts the matched ones."""
        remote = self._remote.publisher_count() if self._remote is not None else 0
        return self._topic.publishers + remote

    def take(self) -> Any:
        """The newest message not taken yet, or None (PULL readers)."""
        if self._fresh:
            self._fresh = False
            return self.latest
        return None

    def destroy(self) -> None:
        if not self._destroyed:
            self._destroyed = True
            topic = self._topic
            topic.readers.remove(self)
            for fn in topic.on_readers:
                fn(topic, False)
            if self._remote is not None:
                self._remote.close()
