"""Cyclone's entities as rmw_cyclonedds_cpp makes them, shared by every endpoint of the DDS
transport (dds.py): the QoS and USER_DATA of a reader or writer, the one write path (llfsm's own
CDR, not cyclonedds' serialisation), deleting an entity at once, the wait set that names our
handlers, and rclpy's warnings when an endpoint elsewhere cannot match ours.

Topics use these in dds_topics.py, services in dds_services.py; the transport that owns them
all is dds.py.
"""

from __future__ import annotations

import ctypes as ct
import itertools
from typing import TYPE_CHECKING, Any

from cyclonedds._clayer import ddspy_write
from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsPublication, BuiltinTopicDcpsSubscription
from cyclonedds.core import Entity, Policy, Qos, WaitSet
from cyclonedds.pub import DataWriter

from ...msgs import _dds
from .dds_graph import message_type
from .dds_read import TAKE_BATCH

if TYPE_CHECKING:
    from .base import NodeView

#: rclpy's ReliabilityPolicy values (llfsm.ros.qos): a transport imports nothing of the bus above it.
SYSTEM_DEFAULT, RELIABLE = 0, 1


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
