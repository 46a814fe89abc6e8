"""Quality of service as rclpy spells it (`rclpy.qos`): the policies, `QoSProfile`, rclpy's preset
profiles, and what an endpoint makes of a profile or a bare depth.

Depth and durability matter in process too; reliability only over DDS.  See docs/bus.md
(Publishers, Subscriptions) and docs/transports.md (QoS on the wire).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum
from typing import Any


class ReliabilityPolicy(IntEnum):
    """rclpy's reliability policies (same names and values).  Over DDS a RELIABLE writer
    resends what a reader missed; a BEST_EFFORT one never does (sensor drivers publish so).  A
    RELIABLE reader never matches a BEST_EFFORT writer, as in ROS 2; in process nothing is ever
    lost, so the policy changes nothing there.  SYSTEM_DEFAULT leaves Cyclone's default, as
    rmw_cyclonedds_cpp does: a writer is reliable, a reader best effort."""

    SYSTEM_DEFAULT = 0
    RELIABLE = 1
    BEST_EFFORT = 2


class HistoryPolicy(IntEnum):
    """rclpy's history policies.  KEEP_LAST keeps the newest `depth` messages per queue;
    KEEP_ALL keeps every message not yet handed on (depth is then ignored); SYSTEM_DEFAULT is
    KEEP_LAST (of 1 when the depth is 0, Cyclone's default)."""

    SYSTEM_DEFAULT = 0
    KEEP_LAST = 1
    KEEP_ALL = 2


class DurabilityPolicy(IntEnum):
    """rclpy's durability policies.  TRANSIENT_LOCAL: a publisher keeps its last `depth`
    messages and hands them to subscriptions that join later (and ask for TRANSIENT_LOCAL too),
    as a latched topic does; VOLATILE (the default): a late subscription gets only new messages.
    SYSTEM_DEFAULT is VOLATILE (DDS's default)."""

    SYSTEM_DEFAULT = 0
    TRANSIENT_LOCAL = 1
    VOLATILE = 2


# rclpy's older names
QoSReliabilityPolicy = ReliabilityPolicy
QoSHistoryPolicy = HistoryPolicy
QoSDurabilityPolicy = DurabilityPolicy


def _policy(enum: type[IntEnum], value: Any, keyword: str) -> Any:
    """`value` as a member of `enum`, or a ValueError naming the keyword and the choices."""
    try:
        return enum(value)
    except (ValueError, TypeError):
        choices = ", ".join(f"{enum.__name__}.{m.name}" for m in enum)
        raise ValueError(f"QoSProfile(): {keyword} must be one of {choices}, not {value!r}") from None


class QoSProfile:
    """rclpy's QoSProfile: history and depth, reliability and durability.  Depth and durability
    matter in process too; reliability matters only over DDS (see ReliabilityPolicy).  Other
    policies (deadline, lifespan, liveliness...) are accepted where rclpy takes them and ignored.
    Unlike rclpy, `depth` defaults to 10 (rclpy demands history or depth)."""

    _FIELDS = ("history", "depth", "reliability", "durability")

    def __init__(
        self,
        depth: int = 10,
        *,
        reliability: ReliabilityPolicy = ReliabilityPolicy.RELIABLE,
        durability: DurabilityPolicy = DurabilityPolicy.VOLATILE,
        history: HistoryPolicy = HistoryPolicy.KEEP_LAST,
        **_ignored: Any,
    ) -> None:
        self.depth = depth
        self.reliability: ReliabilityPolicy = _policy(ReliabilityPolicy, reliability, "reliability")
        self.durability: DurabilityPolicy = _policy(DurabilityPolicy, durability, "durability")
        self.history: HistoryPolicy = _policy(HistoryPolicy, history, "history")

    def _key(self) -> tuple[Any, ...]:
        return tuple(getattr(self, k) for k in self._FIELDS)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, QoSProfile):
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())

    def __repr__(self) -> str:
        return (
            f"QoSProfile(history={self.history.name}, depth={self.depth}, "
            f"reliability={self.reliability.name}, durability={self.durability.name})"
        )


# rclpy's preset profiles (rmw's qos_profiles.h)
qos_profile_sensor_data = QoSProfile(5, reliability=ReliabilityPolicy.BEST_EFFORT)
qos_profile_system_default = QoSProfile(
    0,
    reliability=ReliabilityPolicy.SYSTEM_DEFAULT,
    durability=DurabilityPolicy.SYSTEM_DEFAULT,
    history=HistoryPolicy.SYSTEM_DEFAULT,
)
qos_profile_services_default = QoSProfile(10)
qos_profile_parameters = QoSProfile(1000)
qos_profile_parameter_events = QoSProfile(1000)
#: What each node's /rosout publisher offers (rcl's: reliable, transient local, the last 1000;
#: its 10 s lifespan is one of the policies llfsm ignores)
qos_profile_rosout_default = QoSProfile(1000, durability=DurabilityPolicy.TRANSIENT_LOCAL)


@dataclass(frozen=True, slots=True)
class EndpointQos:
    """A profile (or a bare depth) as an endpoint uses it: `depth` None keeps all."""

    depth: int | None
    reliability: ReliabilityPolicy
    transient_local: bool


def resolve(qos: int | QoSProfile, where: str) -> EndpointQos:
    """What an endpoint keeps and offers: rclpy takes a bare depth or a profile wherever it takes
    QoS, and KEEP_ALL / SYSTEM_DEFAULT change what the depth means.  `where` names the call in
    the error a bad depth gets."""
    if not isinstance(qos, QoSProfile):
        return EndpointQos(_depth(qos, where), ReliabilityPolicy.RELIABLE, False)
    transient_local = qos.durability == DurabilityPolicy.TRANSIENT_LOCAL
    if qos.history == HistoryPolicy.KEEP_ALL:
        return EndpointQos(None, qos.reliability, transient_local)
    depth = qos.depth
    if qos.history == HistoryPolicy.SYSTEM_DEFAULT and depth == 0:
        depth = 1
    return EndpointQos(_depth(depth, where), qos.reliability, transient_local)


def _depth(depth: Any, where: str) -> int:
    if isinstance(depth, bool) or not isinstance(depth, int) or depth < 1:
        raise ValueError(f"{where}: the QoS depth must be an integer >= 1, not {depth!r}")
    return depth
