"""`llfsm view`: the page for whatever llfsm machines run anywhere on the DDS graph.

It knows them only as any ROS tool does (docs/view.md, "Machines on the graph"): a topic
`/llfsm/M/description` announces a machine M; its description and `/llfsm/M/state` (both
transient local, so the current values arrive at once) give the diagram and the current state;
`/llfsm/M/suspend|resume|restart` steer it.  Topics and services are found through DDS discovery (the built-in
DCPSPublication and DCPSSubscription topics, as rmw_dds_common reads them): `rt/NAME` topics,
and services by their `rq/NAMERequest` readers.

Everything here runs on the view's scheduler thread (a run with no machines whose bus executor
spins); the server's thread only reads what the callbacks stored.

The domain is shared, so every peer is untrusted (issue 18): a description is believed only once
it fits llfsm.diagram.description (else it is dropped, with one warning per machine topic, and the last
good one stays), a state's text is bounded, machine names are ROS name tokens, at most
`MAX_MACHINES` are followed, and nothing a peer sends can raise out of a callback into the bus
executor (which would end the view).  Samples that cannot be decoded at all never get here:
the DDS transport's readers drop them with a warning.
"""

from __future__ import annotations

import hashlib
import re
from collections import deque
from typing import TYPE_CHECKING, Any

from ..diagram.description import MAX_NAME, DescriptionError, parse_description
from ..msgs.std_msgs.msg import String
from ..ros.control import LATCHED, NAMESPACE
from ..ros.transports.dds_graph import message_class, service_class
from .source import HISTORY, Source

if TYPE_CHECKING:
    from ..ros.bus import Bus

#: How often discovery is read (run time, seconds).
DISCOVERY_PERIOD = 0.25
_SUFFIX = "/description"
#: Machines followed at most (each costs two readers; a peer could announce thousands).
MAX_MACHINES = 256
#: States and transitions of all the descriptions kept, together: what a crowd of peers each
#: publishing a description within the model's bounds can make the view hold (some 40 MB).
MAX_TOTAL = 100_000
#: A machine's name, as a ROS name token (what a run's `/llfsm/M/...` topics can carry).
_MACHINE = re.compile(rf"[A-Za-z_][A-Za-z0-9_]{{0,{MAX_NAME - 1}}}")


class _Machine:
    """One machine seen on the graph."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.desc: dict[str, Any] | None = None
        self.raw: bytes | None = None  # digest of the description's text last seen (the same again: nothing to do)
        self.size = 0  # states and transitions of `desc`
        self.accepting: frozenset[str] = frozenset()
        self.state: str | None = None
        self.since = 0.0
        self.history: deque[dict[str, Any]] = deque(maxlen=HISTORY)


class GraphSource(Source):
    """Machines, topics and services of every llfsm run (and ROS 2 node) the DDS graph shows."""

    def __init__(self, bus: Bus) -> None:
        super().__init__(bus, "llfsm_view")
        # deferred: optional dependency (cyclonedds), only for `llfsm view`'s graph
        from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsPublication, BuiltinTopicDcpsSubscription

        dp = bus.transport.dp  # type: ignore[attr-defined]  # the view of a DDS graph runs on a DDS bus
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
    def _take(self, reader: Any) -> list[Any]:
        """Discovery samples, taken one at a time: one that the library cannot turn into Python
        (a peer's name that is not UTF-8) is dropped alone, with one warning, and the rest of the
        round is read (taken as a batch, they would all be lost with it)."""
        out = []
        for _ in range(256):
            try:
                got = reader.take(N=1)
            except Exception as e:
                self.warn(f"discovery: dropped an endpoint that could not be read: {type(e).__name__}", "discovery")
                continue
            if not got:
                break
            out.extend(got)
        return out

    def _discover(self) -> None:
        try:
            self._discover_once()
        except Exception as e:  # never into the bus executor: the next round goes on
            self.warn(f"discovery failed: {type(e).__name__}: {e}", key="discovery failed")

    def _discover_once(self) -> None:
        for s in self._take(self._pubs):
            name, type_name = getattr(s, "topic_name", "") or "", getattr(s, "type_name", "") or ""
            if not name.startswith("rt/"):
                continue
            topic = name[2:]
            if topic not in self._topics_seen:
                self._topics_seen[topic] = message_class(type_name)
            if topic.startswith(NAMESPACE + "/") and topic.endswith(_SUFFIX):
                machine = topic[len(NAMESPACE) + 1 : -len(_SUFFIX)]
                if machine not in self._machines and _MACHINE.fullmatch(machine):
                    if len(self._machines) < MAX_MACHINES:
                        self._follow(machine)
                    else:
                        self.warn(f"more than {MAX_MACHINES} machines on the graph: {topic} not followed", "machines")
        for s in self._take(self._subs):
            name, type_name = getattr(s, "topic_name", "") or "", getattr(s, "type_name", "") or ""
            if name.startswith("rq/") and name.endswith("Request") and len(name) > len("rq/Request"):
                service = name[2 : -len("Request")]
                if service not in self._services_seen:
                    self._services_seen[service] = service_class(type_name)

    def _follow(self, name: str) -> None:
        m = self._machines[name] = _Machine(name)

        topic = f"{NAMESPACE}/{name}{_SUFFIX}"

        def on_description(msg: Any) -> None:
            text = msg.data
            digest = hashlib.sha256(text.encode("utf-8", "surrogatepass")).digest()
            if digest == m.raw:
                return
            m.raw = digest
            try:
                desc = parse_description(text, name)
            except DescriptionError as e:
                self.warn(f"{topic}: dropped a description that does not fit: {e}", key=topic)
                return
            except Exception as e:  # never into the bus executor: it would end the view
                self.warn(f"{topic}: dropped a description that could not be read: {type(e).__name__}", key=topic)
                return
            size = len(desc["states"]) + sum(len(s["transitions"]) for s in desc["states"])
            others = sum(o.size for o in self._machines.values() if o is not m)
            if others + size > MAX_TOTAL:
                self.warn(
                    f"{topic}: dropped a description of {size:,} states and transitions: the view holds "
                    f"{others:,} already, and at most {MAX_TOTAL:,}",
                    key=topic,
                )
                return
            m.accepting = frozenset(s["name"] for s in desc["states"] if s["accepting"])
            m.desc, m.size = desc, size
            if name not in self._order:
                self._order.append(name)

        def on_state(msg: Any) -> None:
            state = _bounded(msg.data)
            now = round(self.clock.now / 1e9, 3)
            if m.state is not None:
                m.history.appendleft({"t": now, "from": m.state, "to": state})
            m.state, m.since = state, now

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
            if state == desc.get("suspend"):
                status = "suspended"
            elif state in m.accepting:
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


def _bounded(text: Any) -> str:
    """A state's name as a peer sent it, cut to what a state's name may be (llfsm.diagram.description)."""
    text = text if isinstance(text, str) else str(text)
    return text if len(text) <= MAX_NAME else text[: MAX_NAME - 1] + "…"
