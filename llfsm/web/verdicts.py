"""The monitor's verdicts for the page (docs/view.md, "monitor"; docs/monitor.md): what runs
publish on `/llfsm/monitor` (llfsm_msgs/msg/MonitorEvent), read by the page's node, so that `llfsm
run --monitor ... --web` and `llfsm view` of any run on the domain show the same marks.

What a peer sends is bounded before it is kept (SPEC 18): the newest KEEP verdicts, each text cut
at MAX_TEXT characters and each list at MAX_MACHINES machines; the rest counted.
"""

from __future__ import annotations

from collections import deque
from typing import Any

from ..msgs.llfsm_msgs.msg import MonitorEvent
from ..ros.node import Node
from ..ros.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

TOPIC = "/llfsm/monitor"
#: Verdicts the page is sent at most (the newest), and the longest text and list kept of each.
KEEP = 20
MAX_TEXT = 500
MAX_MACHINES = 64


def _cut(text: str) -> str:
    return text if len(text) <= MAX_TEXT else text[: MAX_TEXT - 1] + "…"


def entry(msg: MonitorEvent) -> dict[str, Any]:
    """A verdict as the snapshot carries it (the keys of llfsm.monitor.judge.Verdict.as_dict)."""
    pairs = list(zip(msg.machines[:MAX_MACHINES], msg.states[:MAX_MACHINES], strict=False))
    return {
        "property": _cut(msg.name),
        "kind": _cut(msg.kind),
        "text": _cut(msg.text),
        "verdict": _cut(msg.verdict),
        "time": round(msg.stamp.sec + msg.stamp.nanosec / 1e9, 3),
        "ringlet": msg.ringlet,
        "states": {_cut(m): _cut(s) for m, s in pairs},
        "reads": [_cut(m) for m in msg.reads[:MAX_MACHINES]],
        "variables": _cut(msg.variables),
        "detail": _cut(msg.detail),
    }


class Verdicts:
    """The verdicts heard on TOPIC (a subscription of the page's node, TRANSIENT_LOCAL: a page
    opened late is handed what was said before)."""

    def __init__(self, node: Node) -> None:
        self.kept: deque[dict[str, Any]] = deque(maxlen=KEEP)
        self.count = 0
        qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        node.create_subscription(MonitorEvent, TOPIC, self._heard, qos)

    def _heard(self, msg: MonitorEvent) -> None:
        self.kept.append(entry(msg))
        self.count += 1

    def sample(self) -> dict[str, Any]:
        """The snapshot's `monitor` field: how many verdicts came, and the newest (oldest first)."""
        return {"count": self.count, "verdicts": list(self.kept)}
