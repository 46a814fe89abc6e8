"""The monitor's verdicts as messages on `/llfsm/monitor` (SPEC 16; docs/monitor.md): one
llfsm_msgs/msg/MonitorEvent per violation, as it is said, and one per property answered at the
end of the run.

The topic joins the graph with the run's bus (now if it is up, else at the first `ros.init()`),
as the machines' own topics do (llfsm.ros.control), from a node `/llfsm/_monitor` (hidden, as a
tool's node is); a run that never has a bus publishes nothing.  It is reliable and
TRANSIENT_LOCAL with a depth of KEEP: a reader that joins late (a page, `llfsm topic echo`, `ros2
topic echo` with llfsm_msgs built) is handed the verdicts so far; each property has at most two
(its violation, its answer at the end), so KEEP covers any monitor of fewer than KEEP / 2
properties.
"""

from __future__ import annotations

from typing import Any

from ..msgs.builtin_interfaces.msg import Time
from ..msgs.llfsm_msgs.msg import MonitorEvent
from ..ros.control import NAMESPACE
from ..ros.node import Node
from ..ros.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from ..runtime.context import RunContext, activate
from .judge import Verdict

TOPIC = "/llfsm/monitor"
NODE = "_monitor"
KEEP = 100


def message(v: Verdict) -> MonitorEvent:
    """The message of a verdict."""
    ns = max(0, v.time_ns)
    p = v.judged.prop
    return MonitorEvent(
        stamp=Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000),
        name=p.name,
        kind=p.kind,
        text=p.text,
        verdict=v.verdict,
        ringlet=max(0, v.where.number or 0),
        machines=[m for m, _ in v.states],
        states=[s for _, s in v.states],
        reads=v.reads,
        variables=v.variables,
        detail=v.detail,
    )


class MonitorTopic:
    """Publishes a monitor's verdicts on TOPIC once the run has a bus."""

    def __init__(self, monitor: Any, ctx: RunContext) -> None:
        self.monitor = monitor
        self.ctx = ctx
        self.publisher: Any = None
        bus = ctx.bus
        if bus is not None and getattr(bus, "initialised", False):
            self._open()
        else:
            ctx.on_init.append(lambda _bus: self._open())

    def _open(self) -> None:
        if self.publisher is not None:
            return
        prev = activate(self.ctx)
        try:
            node = Node(NODE, namespace=NAMESPACE)
            qos = QoSProfile(
                depth=KEEP, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
            )
            self.publisher = node.create_publisher(MonitorEvent, TOPIC, qos)
        finally:
            activate(prev)
        for v in self.monitor.verdicts:  # what was said before the bus came up
            self.publish(v)
        self.monitor.listeners.append(self.publish)

    def publish(self, v: Verdict) -> None:
        self.publisher.publish(message(v))
