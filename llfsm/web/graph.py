"""`llfsm view`: the page for whatever llfsm machines run anywhere on the DDS graph.

It knows them only as any ROS tool does (SPEC §8): a topic `/llfsm/M/description` announces a
machine M; its description and `/llfsm/M/state` (both transient local, so the current values
arrive at once) give the diagram and the current state; `/llfsm/M/suspend|resume|restart`
steer it.  Topics and services are found through DDS discovery (the built-in
DCPSPublication and DCPSSubscription topics, as rmw_dds_common reads them): `rt/NAME` topics,
and services by their `rq/NAMERequest` readers.

Everything here runs on the view's scheduler thread (a run with no machines whose bus executor
spins); the server's thread only reads what the callbacks stored.
"""

from __future__ import annotations

import json
from collections import deque
from typing import TYPE_CHECKING, Any

from ..msgs.std_msgs.msg import String
from ..ros.control import LATCHED, NAMESPACE
from . import values
from .source import HISTORY, Source

if TYPE_CHECKING:
    from ..ros.bus import Bus

#: How often discovery is read (run time, seconds).
DISCOVERY_PERIOD = 0.25
_SUFFIX = "/description"


def _message_type(dds_type: str, kind: str) -> Any:
    """`pkg::msg::dds_::Name_` -> the class (None if llfsm has none); services by `_Request_`."""
    head, sep, tail = dds_type.rpartition("::dds_::")
    if not sep or not tail.endswith("_"):
        return None
    name = tail[:-1]
    if kind == "srv":
        if not name.endswith("_Request"):
            return None
        name = name[: -len("_Request")]
    try:
        return values.resolve_type(f"{head.replace('::', '/')}/{name}", kind)
    except values.BadValue:
        return None


class _Machine:
    """One machine seen on the graph."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.desc: dict[str, Any] | None = None
        self.state: str | None = None
        self.since = 0.0
        self.history: deque[dict[str, Any]] = deque(maxlen=HISTORY)


class GraphSource(Source):
    """Machines, topics and services of every llfsm run (and ROS 2 node) the DDS graph shows."""

    def __init__(self, bus: Bus) -> None:
        super().__init__(bus, "llfsm_view")
        from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsPublication, BuiltinTopicDcpsSubscription

        dp = bus.transport.dp  # type: ignore[attr-defined]
        self._pubs = BuiltinDataReader(dp, BuiltinTopicDcpsPublication)
        self._subs = BuiltinDataReader(dp, BuiltinTopicDcpsSubscription)
        self._topics_seen: dict[str, Any] = {}
        self._services_seen: dict[str, Any] = {}
        self._machines: dict[str, _Machine] = {}
        self._order: list[str] = []
        self._keep: list[Any] = []
        self.node.create_timer(DISCOVERY_PERIOD, self._discover)
        self._discover()

    # -- discovery (scheduler thread) ------------------------------------------------------------------
    def _discover(self) -> None:
        for s in self._pubs.take(N=256):
            name, type_name = getattr(s, "topic_name", "") or "", getattr(s, "type_name", "") or ""
            if not name.startswith("rt/"):
                continue
            topic = name[2:]
            if topic not in self._topics_seen:
                self._topics_seen[topic] = _message_type(type_name, "msg")
            if topic.startswith(NAMESPACE + "/") and topic.endswith(_SUFFIX):
                machine = topic[len(NAMESPACE) + 1 : -len(_SUFFIX)]
                if "/" not in machine and machine not in self._machines:
                    self._follow(machine)
        for s in self._subs.take(N=256):
            name, type_name = getattr(s, "topic_name", "") or "", getattr(s, "type_name", "") or ""
            if name.startswith("rq/") and name.endswith("Request") and len(name) > len("rq/Request"):
                service = name[2 : -len("Request")]
                if service not in self._services_seen:
                    self._services_seen[service] = _message_type(type_name, "srv")

    def _follow(self, name: str) -> None:
        m = self._machines[name] = _Machine(name)

        def on_description(msg: Any) -> None:
            try:
                desc = json.loads(msg.data)
            except ValueError:
                return
            if isinstance(desc, dict) and desc.get("name") == name and isinstance(desc.get("states"), list):
                m.desc = desc
                if name not in self._order:
                    self._order.append(name)

        def on_state(msg: Any) -> None:
            now = round(self.clock.now / 1e9, 3)
            if m.state is not None:
                m.history.appendleft({"t": now, "from": m.state, "to": msg.data})
            m.state, m.since = msg.data, now

        base = f"{NAMESPACE}/{name}"
        self._keep.append(self.node.create_subscription(String, base + _SUFFIX, on_description, LATCHED))
        self._keep.append(self.node.create_subscription(String, base + "/state", on_state, LATCHED))

    # -- what the page is sent (server thread) ------------------------------------------------------------
    def machines(self) -> list[dict[str, Any]]:
        out = []
        for name in list(self._order):
            desc = self._machines[name].desc
            if desc is not None:
                out.append(desc)
        return out

    def machine_rows(self) -> list[dict[str, Any]]:
        rows = []
        for name in list(self._order):
            m = self._machines[name]
            desc = m.desc or {}
            state = m.state or desc.get("initial", "")
            accepting = {s["name"] for s in desc.get("states", []) if s.get("accepting")}
            if state == desc.get("suspend"):
                status = "suspended"
            elif state in accepting:
                status = "finished"
            else:
                status = "running"
            rows.append(
                {
                    "name": name,
                    "state": state,
                    "status": status,
                    "pending": None,
                    "since": m.since,
                    "transitions": list(m.history),
                }
            )
        return rows

    def topic_types(self) -> dict[str, Any]:
        seen = dict(self._topics_seen)
        seen.pop("/ros_discovery_info", None)
        return seen

    def service_types(self) -> dict[str, Any]:
        return dict(self._services_seen)

    def _published(self, name: str) -> int:
        return 0  # other processes publish: the page's reader counts what arrives
