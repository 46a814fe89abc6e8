"""`llfsm view`: the page for whatever llfsm machines run anywhere on the DDS graph.

It knows them only as any ROS tool does (docs/view.md, "Machines on the graph"): a topic
`/llfsm/M/description` announces a machine M; its description and `/llfsm/M/state` (both
transient local, so the current values arrive at once) give the diagram and the current state;
`/llfsm/M/suspend|resume|restart` steer it.  Topics and services are found through DDS discovery (the built-in
DCPSPublication and DCPSSubscription topics, as rmw_dds_common reads them): `rt/NAME` topics,
and services by their `rq/NAMERequest` readers.

Everything here runs on the view's scheduler thread (a run with no machines whose bus executor
spins); the server's thread only reads what the callbacks stored.

Two runs of the same machine on one domain publish on the same topics and serve the same
services.  The view keeps them apart by the participant (the run) each sample comes from: a
machine is a (name, participant) pair, read with DDS readers of its own whose samples say
their writer.  The first run of a name seen keeps the name; another is `NAME@PARTICIPANT` (the
first 8 hex digits of its participant's GUID), so neither card mixes the other's transitions.
(Without DDS, as when a test feeds the view in process, one participant is assumed.)

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
import time
from collections import deque
from typing import TYPE_CHECKING, Any

from ..diagram.description import MAX_NAME, DescriptionError, parse_description
from ..msgs.std_msgs.msg import String
from ..ros.control import LATCHED, NAMESPACE
from ..ros.transports.dds_graph import Graph, message_class, service_class
from .rosgraph import from_dds, robust_graph
from .source import HISTORY, CommandError, Source

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
#: Endpoints of other participants the view keeps track of at most (a topic or a service is
#: listed while one of its endpoints lives; a peer could make them by the hundred thousand).
MAX_ENDPOINTS = 200_000
#: Discovery samples taken per look (DISCOVERY_PERIOD): a peer making and deleting topics by the
#: thousand is followed within seconds, and a look stays short.
DISCOVERY_BATCH = 1024
#: A machine's name, as a ROS name token (what a run's `/llfsm/M/...` topics can carry).
_MACHINE = re.compile(rf"[A-Za-z_][A-Za-z0-9_]{{0,{MAX_NAME - 1}}}")


class _Machine:
    """One machine of one run seen on the graph.  Times are kept as they came (a state sample's
    wall time, or the view's own run time when a sample has none) and shown in the run's time
    once its description says when the run started."""

    def __init__(self, name: str, key: str, participant: str) -> None:
        self.name = name  # the machine's name (its topics': /llfsm/NAME/...)
        self.key = key  # what the page calls it: the name, or NAME@PARTICIPANT for another run of it
        self.participant = participant  # the run's participant GUID ("" when not known)
        self.desc: dict[str, Any] | None = None
        self.raw: bytes | None = None  # digest of the description's text last seen (the same again: nothing to do)
        self.size = 0  # states and transitions of `desc`
        self.accepting: frozenset[str] = frozenset()
        self.state: str | None = None
        self.since: _When = _When(None, 0.0)
        self.history: deque[tuple[_When, str, str]] = deque(maxlen=HISTORY)
        self.started: float | None = None  # the run's time 0, wall seconds (its description says)
        self.pending: str | None = None  # a command from this page not yet seen applied
        self.pending_at = 0  # wall ns when it was sent
        self.gone = False  # its run has left the graph

    def run_time(self, when: _When) -> float:
        """A time in the run's own seconds when the run said when it started, else the view's."""
        if when.wall_ns is not None and self.started is not None:
            return round(max(0.0, when.wall_ns / 1e9 - self.started), 3)
        return when.view


class _When:
    """When something happened: the sample's wall time (ns since the epoch, if it had one) and
    the view's run time (seconds)."""

    __slots__ = ("view", "wall_ns")

    def __init__(self, wall_ns: int | None, view: float) -> None:
        self.wall_ns, self.view = wall_ns, view


#: How often a machine's own readers are taken from (run time, seconds): its transitions' times.
MACHINE_PERIOD = 0.05
#: A machine topic's reader keeps this many samples (several runs' latched states arrive at once).
MACHINE_DEPTH = 32


class _Readers:
    """A machine's description and state, read with DDS readers of the view's own whose samples
    name their writer, so that two runs of the machine stay two machines.  Decoded on llfsm's
    one path for what peers send (llfsm.ros.transports.dds_read)."""

    def __init__(self, dp: Any, name: str, warn: Any) -> None:
        # deferred: optional dependency (cyclonedds), imported by the view's DDS source only
        from cyclonedds.core import Policy, Qos
        from cyclonedds.sub import DataReader
        from cyclonedds.topic import Topic

        from ..msgs import _dds
        from ..ros.transports.dds_read import Samples

        qos = Qos(
            Policy.Reliability.Reliable(max_blocking_time=100_000_000),
            Policy.Durability.TransientLocal,
            Policy.History.KeepLast(MACHINE_DEPTH),
            Policy.DataRepresentation(use_cdrv0_representation=True),
        )
        wire = _dds.dds_type(String)
        self.samples = {}
        for part in ("description", "state"):
            topic = f"{NAMESPACE}/{name}/{part}"
            reader: Any = DataReader(dp, Topic(dp, "rt" + topic, wire), qos=qos)
            self.samples[part] = Samples(
                reader, lambda data: _dds.from_cdr(data, String), topic, "a std_msgs/msg/String", warn
            )
        self._peers: dict[int, str] = {}

    def take(self, part: str) -> list[tuple[str, Any, int | None]]:
        """(participant, message, the writer's wall time in ns) of each sample that came, oldest first."""
        samples = self.samples[part]
        return [
            (self._peer(samples.reader, info.publication_handle), msg, _stamp(info)) for msg, info in samples.take()
        ]

    def runs(self) -> set[str] | None:
        """The participants whose state writers are matched now (None if DDS cannot say)."""
        reader = self.samples["state"].reader
        try:
            return {self._peer(reader, h) for h in reader.get_matched_publications()}
        except Exception:
            return None

    def _peer(self, reader: Any, handle: int) -> str:
        peer = self._peers.get(handle)
        if peer is None:
            try:
                key = reader.get_matched_publication_data(handle).participant_key
            except Exception:  # the writer has gone meanwhile: its samples still count, as one run's
                key = None
            peer = key.hex if key is not None and hasattr(key, "hex") else f"writer-{handle:x}"
            if len(self._peers) > 4 * MAX_MACHINES:
                self._peers.clear()
            self._peers[handle] = peer
        return peer


def _stamp(info: Any) -> int | None:
    stamp = getattr(info, "source_timestamp", None)
    return stamp if isinstance(stamp, int) and stamp > 0 else None


class GraphSource(Source):
    """Machines, topics and services of every llfsm run (and ROS 2 node) the DDS graph shows."""

    kind = "view"

    def __init__(self, bus: Bus) -> None:
        super().__init__(bus, "llfsm_view")
        # deferred: optional dependency (cyclonedds), only for `llfsm view`'s graph
        from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsPublication, BuiltinTopicDcpsSubscription
        from cyclonedds.core import InstanceState

        dp = bus.transport.dp  # type: ignore[attr-defined]  # the view of a DDS graph runs on a DDS bus
        self._pubs = BuiltinDataReader(dp, BuiltinTopicDcpsPublication)
        self._subs = BuiltinDataReader(dp, BuiltinTopicDcpsSubscription)
        self._topics_seen: dict[str, Any] = {}  # topics with endpoints (the page's own left out): their class
        self._services_seen: dict[str, Any] = {}
        self._own = dp.get_guid().bytes
        self._alive_state = InstanceState.Alive
        #: Endpoints of other participants: GID -> ("topic" or "service", name); and how many
        #: each topic and service has (the last one gone, it is forgotten).
        self._endpoints: dict[bytes, tuple[str, str]] = {}
        self._ends: dict[str, dict[str, int]] = {"topic": {}, "service": {}}
        self._machines: dict[tuple[str, str], _Machine] = {}  # (name, participant) -> the machine of that run
        self._by_key: dict[str, _Machine] = {}  # the page's name for each
        self._order: list[str] = []  # keys, in the order their descriptions came
        self._followed: set[str] = set()
        self._readers_of: dict[str, _Readers] = {}
        self._keep: list[Any] = []
        self._counts: dict[str, int] = {}  # samples of each machine topic received
        self._dds: Graph | None = robust_graph(dp, self.warn)
        self.node.create_timer(DISCOVERY_PERIOD, self._discover)
        self._discover()

    # -- discovery (scheduler thread) ------------------------------------------------------------------
    def _take(self, reader: Any) -> list[Any]:
        """Discovery samples, taken one at a time: one that the library cannot turn into Python
        (a peer's name that is not UTF-8) is dropped alone, with one warning, and the rest of the
        round is read (taken as a batch, they would all be lost with it)."""
        out = []
        for _ in range(DISCOVERY_BATCH):
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
        try:
            if self._dds is not None:
                self._dds.update()
                self.remote_graph = from_dds(self._dds)
            self._which_runs_are_gone()
        except Exception as e:  # the graph and the runs' liveliness are read again next round
            self.warn(f"the graph could not be read: {type(e).__name__}: {e}", key="graph failed")

    def _which_runs_are_gone(self) -> None:
        """A machine whose run no longer writes its state has ended with its run: its card says
        so and its buttons are disabled."""
        for name, readers in list(self._readers_of.items()):
            alive = readers.runs()
            if alive is None:
                continue
            for (n, peer), m in list(self._machines.items()):
                if n == name and m.state is not None:
                    m.gone = peer not in alive

    def _discover_once(self) -> None:
        for s in self._take(self._pubs):
            self._endpoint(s, "publisher")
        for s in self._take(self._subs):
            self._endpoint(s, "subscription")

    def _endpoint(self, s: Any, kind: str) -> None:
        """One discovery sample: an endpoint that came (a topic or a service is known while it
        has one, the page's own left out) or went (the last one gone: the topic or service is
        forgotten, and the page's reader or client of it deleted)."""
        gid = s.key.bytes
        if s.sample_info.instance_state != self._alive_state:
            known = self._endpoints.pop(gid, None)
            if known is not None:
                self._lose(*known)
            return
        if gid in self._endpoints or s.participant_key.bytes == self._own:
            return
        name, type_name = getattr(s, "topic_name", "") or "", getattr(s, "type_name", "") or ""
        if name.startswith("rt/"):
            what, topic = "topic", name[2:]
        elif name.startswith("rq/") and name.endswith("Request") and len(name) > len("rq/Request"):
            what, topic = "service", name[2 : -len("Request")]
        else:
            return
        if len(self._endpoints) >= MAX_ENDPOINTS:
            self.warn(f"more than {MAX_ENDPOINTS:,} endpoints on the graph: the view follows no more", "endpoints")
            return
        self._endpoints[gid] = (what, topic)
        ends = self._ends[what]
        ends[topic] = ends.get(topic, 0) + 1
        if what == "service":
            if kind == "subscription" and self._services_seen.get(topic) is None:  # its server names the type
                self._services_seen[topic] = service_class(type_name)
            self._services_seen.setdefault(topic, None)
            return
        if topic not in self._topics_seen:
            self._topics_seen[topic] = message_class(type_name)
        if kind == "publisher" and topic.startswith(NAMESPACE + "/") and topic.endswith(_SUFFIX):
            machine = topic[len(NAMESPACE) + 1 : -len(_SUFFIX)]
            if machine not in self._followed and _MACHINE.fullmatch(machine):
                if len(self._followed) < MAX_MACHINES:
                    self._follow(machine)
                else:
                    self.warn(f"more than {MAX_MACHINES} machines on the graph: {topic} not followed", "machines")

    def _lose(self, what: str, name: str) -> None:
        ends = self._ends[what]
        left = ends.get(name, 0) - 1
        if left > 0:
            ends[name] = left
            return
        ends.pop(name, None)
        if what == "service":
            self._services_seen.pop(name, None)
            for key in [k for k in self._clients if k[0] == name]:
                self.node.destroy_client(self._clients.pop(key))
            return
        self._topics_seen.pop(name, None)
        self._counts.pop(name, None)
        self._asked.discard(name)
        self._stats.pop(name, None)
        self._unwatch(name)

    def _follow(self, name: str) -> None:
        """Read machine `name`'s description and state, each run's apart when DDS says which
        run sent what (a transport with a participant), else as one machine; and its run's
        debugger state (llfsm.web.debugging)."""
        self._followed.add(name)
        if self.debug is not None:
            follow = getattr(self.debug, "follow", None)
            if follow is not None:
                follow(name)
        dp = getattr(self.bus.transport, "dp", None)
        if dp is not None:
            readers = _Readers(dp, name, lambda text: self.warn(text))
            self._readers_of[name] = readers
            if len(self._readers_of) == 1:
                self.node.create_timer(MACHINE_PERIOD, self._take_machines)
            return
        base = f"{NAMESPACE}/{name}"
        self._keep.append(
            self.node.create_subscription(
                String, base + _SUFFIX, lambda msg: self._on_description(name, "", msg), LATCHED
            )
        )
        self._keep.append(
            self.node.create_subscription(String, base + "/state", lambda msg: self._on_state(name, "", msg), LATCHED)
        )

    def _take_machines(self) -> None:
        try:
            for name, readers in list(self._readers_of.items()):
                for peer, msg, _stamp_ns in readers.take("description"):
                    self._count(f"{NAMESPACE}/{name}{_SUFFIX}")
                    self._on_description(name, peer, msg)
                for peer, msg, stamp_ns in readers.take("state"):
                    self._count(f"{NAMESPACE}/{name}/state")
                    self._on_state(name, peer, msg, stamp_ns)
        except Exception as e:  # never into the bus executor: the next round goes on
            self.warn(f"machines: reading failed: {type(e).__name__}: {e}", key="machines failed")

    def _count(self, topic: str) -> None:
        self._counts[topic] = self._counts.get(topic, 0) + 1

    def _machine_topic(self, name: str) -> tuple[int, str] | None:
        """A machine topic's samples as the view received them (every run's, latched ones too)."""
        if not name.startswith(NAMESPACE + "/"):
            return None
        return self._counts.get(name, 0), "a machine's state or description: the diagrams show it"

    def _machine(self, name: str, peer: str) -> _Machine | None:
        """The machine `name` of the run `peer`, made on its first sample (None beyond the bound)."""
        m = self._machines.get((name, peer))
        if m is not None:
            return m
        if len(self._machines) >= MAX_MACHINES:
            self.warn(
                f"more than {MAX_MACHINES} machines on the graph: {name} of {peer or 'a run'} not followed", "machines"
            )
            return None
        first = not any(n == name for n, _ in self._machines)
        key = name if first or not peer else self._other_key(name, peer)
        m = self._machines[(name, peer)] = self._by_key[key] = _Machine(name, key, peer)
        return m

    def _other_key(self, name: str, peer: str) -> str:
        """NAME@xxxxxxxx for another run of a machine: eight hex digits of its participant's GUID
        after the vendor and host part (the first eight are the same for runs on one host),
        more when those are taken."""
        for width in (8, 16, len(peer)):
            key = f"{name}@{peer[8 : 8 + width] if width < len(peer) else peer}"
            if key not in self._by_key:
                return key
        return f"{name}@{peer}#{len(self._machines)}"

    def _on_description(self, name: str, peer: str, msg: Any) -> None:
        topic = f"{NAMESPACE}/{name}{_SUFFIX}"
        m = self._machine(name, peer)
        if m is None:
            return
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
        m.started = desc.get("started")
        # the page names the machine by its key: another run of it is a card of its own
        m.desc, m.size = {**desc, "name": m.key, "machine": name, "participant": peer}, size
        if m.key not in self._order:
            self._order.append(m.key)

    def _on_state(self, name: str, peer: str, msg: Any, stamp_ns: int | None = None) -> None:
        m = self._machine(name, peer)
        if m is None:
            return
        state = _bounded(msg.data)
        when = _When(stamp_ns, round(self.clock.now / 1e9, 3))
        if m.state is not None:
            m.history.appendleft((when, m.state, state))
        m.state, m.since = state, when
        # a command applied publishes the state it leads to: one sent after the command was
        if m.pending is not None and (stamp_ns is None or stamp_ns >= m.pending_at):
            m.pending = None

    # -- what the page is sent (server thread) ------------------------------------------------------------
    def machines(self) -> list[dict[str, Any]]:
        out = []
        for key in list(self._order):
            desc = self._by_key[key].desc
            if desc is not None:
                out.append(desc)
        return out

    def machine_rows(self) -> list[dict[str, Any]]:
        rows = []
        for key in list(self._order):
            m = self._by_key[key]
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
                    "name": m.key,
                    "machine": m.name,
                    "participant": m.participant,
                    "runs": sum(1 for n, _ in list(self._machines) if n == m.name),
                    "ended": m.gone,
                    "state": state,
                    "status": status,
                    "pending": m.pending,
                    "since": m.run_time(m.since),
                    "run_time": m.started is not None,
                    "transitions": [{"t": m.run_time(when), "from": a, "to": b} for when, a, b in list(m.history)],
                }
            )
        return rows

    def has_machine(self, name: str) -> bool:
        return name in self._order

    def machine_name(self, key: str) -> str:
        """The machine's own name for the page's name of it (NAME@xxxxxxxx for a twin)."""
        m = self._by_key.get(key)
        return m.name if m is not None else key

    async def command(self, machine: str, verb: str) -> dict[str, Any]:
        """A command to `machine` (the page's name for it).  The control services are named by
        the machine's name alone: another run of the same machine serves them too, and DDS
        hands the request to every server, so the response says how many runs were asked."""
        if verb not in ("suspend", "resume", "restart"):
            raise CommandError(f"unknown command {verb!r}: suspend, resume or restart")
        m = self._by_key.get(machine) if machine in self._order else None
        if m is None:
            raise CommandError(f"no machine named {machine!r} on the graph")
        twins = [o for (n, _), o in list(self._machines.items()) if n == m.name]
        sent = time.time_ns()
        response = await self._call(f"{NAMESPACE}/{m.name}/{verb}", "std_srvs/srv/Trigger", "")
        for o in twins:  # each run serving the service was asked; each shows it pending until it publishes
            if response.success and (o.pending is None or o.pending_at < sent):
                o.pending, o.pending_at = verb, sent
        result = {"success": response.success, "message": response.message}
        runs = len(twins)
        if runs > 1:
            result["message"] = (
                f"{response.message} (the {runs} runs of {m.name} on this domain share "
                f"{NAMESPACE}/{m.name}/{verb}: each of them was asked)"
            )
        return result

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
