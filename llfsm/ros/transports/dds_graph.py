"""The ROS 2 graph as DDS discovery shows it: topics, services and nodes of every participant in
the domain, llfsm runs and ROS 2 nodes alike.

What `ros2 topic list`, `ros2 service list` and `ros2 node list` show comes from two sources,
read here as rmw_dds_common's graph cache reads them:

- DDS's built-in topics DCPSPublication and DCPSSubscription: every endpoint with its topic
  name, type name and QoS.  ROS topics are the `rt/` ones (`rt/turtle1/pose` is
  `/turtle1/pose`), services the `rq/…Request` and `rr/…Reply` pairs; type names are mangled
  as `pkg::msg::dds_::Name_` (`pkg/msg/Name`) and `pkg::srv::dds_::Name_Request_` (`pkg/srv/Name`).
- `ros_discovery_info`: each participant's nodes and the GIDs of their endpoints
  (rmw_dds_common/msg/ParticipantEntitiesInfo), which no built-in topic carries.

A command-line reader has no daemon: like `ros2 ... --no-daemon`, it joins the domain, waits a
short bounded time for discovery, and answers from what it has seen.  The participant uses the
transport's discovery settings (dds_config), so it finds what `llfsm run --transport dds` finds.
"""

from __future__ import annotations

import importlib
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ...msgs._message import is_service_class

if TYPE_CHECKING:
    from cyclonedds.domain import DomainParticipant

    from ...msgs._message import Message, Service
    from .dds_read import Samples

TOPIC_PREFIX = "rt"
REQUEST_PREFIX, REPLY_PREFIX = "rq", "rr"
DISCOVERY_TOPIC = "ros_discovery_info"
#: How long a verb that names nodes waits, after its spin time, for the ros_discovery_info of
#: participants already seen (Graph.settle).
SETTLE_S = 5.0
#: How long after its first endpoint a participant with no ros_discovery_info writer yet is
#: waited for (Graph.settle).
PARTICIPANT_GRACE_S = 0.5
#: How long after a participant's first ros_discovery_info the endpoints it names are waited
#: for (Graph.settle): they were made before the sample was written, so they come within the
#: time discovery takes; a peer naming endpoints that never appear delays a verb this much.
ENDPOINT_GRACE_S = 1.0
INFINITE_NS = 0x7FFFFFFFFFFFFFFF  # Cyclone's DDS_INFINITY
#: ros_discovery_info entries kept for participants not (yet) seen alive: a sample can come
#: before its participant's, but a peer can also write gids of participants that never exist.
SPARE_NODE_ENTRIES = 64


def topic_name(dds_name: str) -> str | None:
    """ "/turtle1/pose" for "rt/turtle1/pose"; None for a DDS topic that is not a ROS topic."""
    if dds_name.startswith(TOPIC_PREFIX + "/"):
        return dds_name[len(TOPIC_PREFIX) :]
    return None


def service_name(dds_name: str) -> str | None:
    """ "/spawn" for "rq/spawnRequest" and for "rr/spawnReply"; None for anything else."""
    for prefix, suffix in ((REQUEST_PREFIX, "Request"), (REPLY_PREFIX, "Reply")):
        if (
            dds_name.startswith(prefix + "/")
            and dds_name.endswith(suffix)
            and len(dds_name) > len(prefix) + len(suffix) + 1
        ):
            return dds_name[len(prefix) : -len(suffix)]
    return None


def ros_type(dds_type: str) -> str | None:
    """ "std_msgs/msg/String" for "std_msgs::msg::dds_::String_", "turtlesim/srv/Spawn_Request"
    for "turtlesim::srv::dds_::Spawn_Request_": the one reading of rmw's type-name mangling that
    the transport, the graph, the bag recorder and the page share.  None for a name that is not
    mangled so (a non-ROS writer's type)."""
    head, sep, tail = dds_type.rpartition("::dds_::")
    if not sep or not head or len(tail) < 2 or not tail.endswith("_"):
        return None
    return f"{head}::{tail[:-1]}".replace("::", "/")


def message_type(dds_type: str) -> str:
    """ "std_msgs/msg/String" for "std_msgs::msg::dds_::String_"; a name that is not mangled so
    comes back with `::` as `/` (as rmw_cyclonedds shows a foreign type)."""
    return ros_type(dds_type) or dds_type.replace("::", "/")


def service_type(dds_type: str) -> str | None:
    """ "turtlesim/srv/Spawn" for "turtlesim::srv::dds_::Spawn_Request_" (or `_Response_`)."""
    name = ros_type(dds_type)
    if name is None:
        return None
    for suffix in ("_Request", "_Response"):
        if name.endswith(suffix) and len(name.rsplit("/", 1)[-1]) > len(suffix):
            return name[: -len(suffix)]
    return None


def message_class(dds_type: str) -> type[Message] | None:
    """`geometry_msgs::msg::dds_::Twist_` -> llfsm's Twist class (and a service's
    `pkg::srv::dds_::Name_Request_` -> its request class), or None if llfsm has none."""
    name = ros_type(dds_type)
    cls = None if name is None else _interface(name)
    return cls if getattr(cls, "_TYPE", None) == name else None


def service_class(dds_type: str) -> type[Service] | None:
    """The service class whose request or reply has this DDS type, or None if llfsm has none."""
    name = service_type(dds_type)
    cls = None if name is None else _interface(name)
    return cls if is_service_class(cls) and getattr(cls, "_TYPE", None) == name else None


def _interface(ros_name: str) -> Any:
    """The attribute `Name` of `llfsm.msgs.pkg.kind` for "pkg/kind/Name", or None."""
    parts = ros_name.split("/")
    if len(parts) != 3 or not all(p.isidentifier() for p in parts):
        return None
    try:
        module = importlib.import_module(f"llfsm.msgs.{parts[0]}.{parts[1]}")
    except ImportError:
        return None
    return getattr(module, parts[2], None)


def user_data_value(qos: Any, key: str) -> str | None:
    """`key=value;` from an endpoint's USER_DATA (rmw_cyclonedds's format: `typehash=RIHS01_…;`,
    `clientid=…;`, `serviceid=…;`), or None."""
    if qos is None:
        return None
    from cyclonedds.qos import Policy  # deferred: optional dependency (the name helpers above need none)

    try:
        raw = qos[Policy.Userdata].data
    except (KeyError, AttributeError, TypeError):
        return None
    for item in bytes(raw).decode("utf-8", "replace").split(";"):
        k, sep, v = item.partition("=")
        if sep and k == key:
            return v
    return None


def is_hidden(name: str) -> bool:
    """rclpy's topic_or_service_is_hidden: a name with a part that starts with '_'."""
    return any(part.startswith("_") for part in name.split("/"))


@dataclass(frozen=True)
class Endpoint:
    """One reader or writer somewhere in the domain."""

    gid: bytes  # the endpoint's DDS GUID (16 bytes): rmw's GID
    participant: bytes  # its participant's GUID
    kind: str  # "publisher" or "subscription"
    topic: str  # the DDS topic name ("rt/chatter")
    type_name: str  # the DDS type name ("std_msgs::msg::dds_::String_")
    qos: Any  # cyclonedds.qos.Qos

    @property
    def reliable(self) -> bool:
        from cyclonedds.qos import Policy  # deferred: optional dependency

        return isinstance(self.qos[Policy.Reliability], Policy.Reliability.Reliable)

    @property
    def type_hash(self) -> str:
        """The RIHS01 type hash that rmw (Iron and later) puts in USER_DATA, or 'INVALID' as
        rclpy says when there is none (Humble's peers, non-ROS writers)."""
        value = user_data_value(self.qos, "typehash")
        return value if value and value.startswith("RIHS") else "INVALID"

    @property
    def transient_local(self) -> bool:
        from cyclonedds.qos import Policy  # deferred: optional dependency

        return self.qos[Policy.Durability] == Policy.Durability.TransientLocal


@dataclass(frozen=True)
class NodeName:
    namespace: str
    name: str

    @property
    def full_name(self) -> str:
        return f"{self.namespace.rstrip('/')}/{self.name}"


class Graph:
    """A reader of the domain's graph.  `spin(seconds)` waits for discovery; the queries answer
    from what has been seen so far and leave out this reader's own participant."""

    def __init__(self, participant: DomainParticipant | None = None, say: Callable[[str], None] | None = None) -> None:
        """`say` is told what a peer sent that could not be read (once per peer; stderr by
        default, where a command-line verb's warnings go)."""
        # deferred: optional dependency (cyclonedds), and start-up: the web view imports this
        # module for its name helpers alone, and a graph reader is all that needs these
        from cyclonedds.builtin import (
            BuiltinDataReader,
            BuiltinTopicDcpsParticipant,
            BuiltinTopicDcpsPublication,
            BuiltinTopicDcpsSubscription,
        )

        # deferred: optional dependency and start-up, as the cyclonedds imports above
        from .dds_config import participant as make_participant

        self.participant = participant if participant is not None else make_participant()
        self._own = self.participant.get_guid().bytes
        self._participants_reader = BuiltinDataReader(self.participant, BuiltinTopicDcpsParticipant)
        self._readers = {
            "publisher": BuiltinDataReader(self.participant, BuiltinTopicDcpsPublication),
            "subscription": BuiltinDataReader(self.participant, BuiltinTopicDcpsSubscription),
        }
        self._endpoints: dict[bytes, Endpoint] = {}
        self._participants: set[bytes] = set()
        #: participant -> time.monotonic() its first endpoint was seen (Graph._nodes_known)
        self._first_endpoint: dict[bytes, float] = {}
        self._nodes: dict[bytes, list[tuple[NodeName, list[bytes], list[bytes]]]] = {}
        #: participant -> time.monotonic() its first ros_discovery_info was read (_nodes_known)
        self._told: dict[bytes, float] = {}
        self._info = self._discovery_info_reader(say)

    def _discovery_info_reader(self, say: Callable[[str], None] | None) -> Samples[Any]:
        """A reader of ros_discovery_info with rmw's QoS (reliable, transient local), but a deep
        history: the topic has no key, and every participant's last sample must be kept.  Its
        samples are decoded on llfsm's shared path (dds_read): one that is not a
        ParticipantEntitiesInfo (a node name that is not UTF-8) is dropped, said once per peer,
        and the rest of the graph is still listed."""
        # deferred: optional dependency and start-up, as in __init__
        from cyclonedds.core import Policy, Qos
        from cyclonedds.sub import DataReader
        from cyclonedds.topic import Topic

        from ...msgs._dds import dds_type, from_cdr
        from ...msgs.rmw_dds_common.msg import ParticipantEntitiesInfo
        from .dds_read import Samples, stderr_warning

        qos = Qos(
            Policy.Reliability.Reliable(max_blocking_time=100_000_000),
            Policy.Durability.TransientLocal,
            Policy.History.KeepLast(256),
            Policy.DataRepresentation(use_cdrv0_representation=True),
        )
        topic: Topic[Any] = Topic(self.participant, DISCOVERY_TOPIC, dds_type(ParticipantEntitiesInfo))
        reader = DataReader(self.participant, topic, qos=qos)
        return Samples(
            reader,
            lambda data: from_cdr(data, ParticipantEntitiesInfo),
            DISCOVERY_TOPIC,
            f"a {ParticipantEntitiesInfo._TYPE}",
            say or stderr_warning,
        )

    # -- collecting -------------------------------------------------------------------------

    def update(self) -> None:
        """Take what discovery has delivered since the last call."""
        from cyclonedds.core import InstanceState  # deferred: optional dependency

        for sample in self._participants_reader.take(N=4096):
            key = sample.key.bytes
            if sample.sample_info.instance_state == InstanceState.Alive:
                self._participants.add(key)
            else:
                self._participants.discard(key)
                self._nodes.pop(key, None)
                self._told.pop(key, None)
                self._first_endpoint.pop(key, None)
                for gid in [g for g, e in self._endpoints.items() if e.participant == key]:
                    del self._endpoints[gid]
        for kind, reader in self._readers.items():
            for sample in reader.take(N=4096):
                gid = sample.key.bytes
                if sample.sample_info.instance_state != InstanceState.Alive:
                    self._endpoints.pop(gid, None)
                    continue
                participant = sample.participant_key.bytes
                if participant == self._own:
                    continue
                self._endpoints[gid] = Endpoint(gid, participant, kind, sample.topic_name, sample.type_name, sample.qos)
                self._first_endpoint.setdefault(participant, time.monotonic())
        for info, _sample_info in self._info.take():
            self._take_discovery_info(info)

    def _take_discovery_info(self, info: Any) -> None:
        """One participant's nodes (rmw_dds_common/msg/ParticipantEntitiesInfo): each replaces
        what that participant said before."""
        participant = bytes(info.gid.data)[:16]
        if participant == self._own:
            return
        if participant not in self._nodes and len(self._nodes) >= len(self._participants) + SPARE_NODE_ENTRIES:
            # a peer naming participants that do not exist (any gid can be written): forget those
            for key in [k for k in self._nodes if k not in self._participants]:
                del self._nodes[key]
                self._told.pop(key, None)
        self._told.setdefault(participant, time.monotonic())
        self._nodes[participant] = [
            (
                NodeName(n.node_namespace, n.node_name),
                [bytes(g.data)[:16] for g in n.reader_gid_seq],
                [bytes(g.data)[:16] for g in n.writer_gid_seq],
            )
            for n in info.node_entities_info_seq
        ]

    def spin(self, seconds: float, until: Callable[[], bool] | None = None) -> bool:
        """Collect discovery for `seconds`, or until `until()` holds (then True)."""
        deadline = time.monotonic() + seconds
        while True:
            self.update()
            if until is not None and until():
                return True
            left = deadline - time.monotonic()
            if left <= 0:
                return False
            time.sleep(min(0.05, left))

    def settle(self, seconds: float = SETTLE_S) -> bool:
        """Wait (at most `seconds`) until every participant seen publishing ros_discovery_info
        has delivered it: the nodes of a participant are known only from that sample, and a
        transient-local sample from another vendor can come seconds after its participant and
        endpoints (Fast DDS resends on its heartbeat).  True when none is missing."""
        return self.spin(seconds, until=self._nodes_known)

    def _nodes_known(self) -> bool:
        """Every participant seen has told its nodes, and every endpoint those nodes name has
        been seen (or ENDPOINT_GRACE_S has passed since the participant first told them: a peer
        may name endpoints that never appear, and must not hold a verb up for longer).  A
        participant with a ros_discovery_info writer is waited for until its sample is read,
        and one with no endpoint seen yet until one is (a ROS 2 participant has endpoints: a
        Fast DDS one announces them up to a second after itself).  One with endpoints but no
        ros_discovery_info writer is waited for PARTICIPANT_GRACE_S after its first endpoint
        (the writer may come in a later announcement; a plain DDS participant never has one,
        and is then not waited for)."""
        now = time.monotonic()
        informing = {
            e.participant for e in self._endpoints.values() if e.kind == "publisher" and e.topic == DISCOVERY_TOPIC
        }
        for p in self._participants:
            if p == self._own:
                continue
            nodes = self._nodes.get(p)
            if nodes is None:
                first = self._first_endpoint.get(p)
                if p in informing or first is None or now - first < PARTICIPANT_GRACE_S:
                    return False
                continue
            if now - self._told.get(p, now) >= ENDPOINT_GRACE_S:
                continue
            for _name, readers, writers in nodes:
                if any(g not in self._endpoints for g in readers) or any(g not in self._endpoints for g in writers):
                    return False
        return True

    # -- queries ----------------------------------------------------------------------------

    def endpoints(self) -> list[Endpoint]:
        return list(self._endpoints.values())

    def topics(self, include_hidden: bool = False) -> dict[str, list[str]]:
        """ROS topic name -> its ROS type names (sorted), by name."""
        out: dict[str, set[str]] = {}
        for e in self._endpoints.values():
            name = topic_name(e.topic)
            if name is None or (not include_hidden and is_hidden(name)):
                continue
            out.setdefault(name, set()).add(message_type(e.type_name))
        return {n: sorted(t) for n, t in sorted(out.items())}

    def services(self, include_hidden: bool = False) -> dict[str, list[str]]:
        """ROS service name -> its service type names (sorted), by name."""
        out: dict[str, set[str]] = {}
        for e in self._endpoints.values():
            name = service_name(e.topic)
            if name is None or (not include_hidden and is_hidden(name)):
                continue
            stype = service_type(e.type_name)
            out.setdefault(name, set())
            if stype is not None:
                out[name].add(stype)
        return {n: sorted(t) for n, t in sorted(out.items())}

    def topic_endpoints(self, name: str, kind: str) -> list[Endpoint]:
        """The publishers or subscriptions of ROS topic `name`."""
        dds = f"{TOPIC_PREFIX}{name}"
        return [e for e in self._endpoints.values() if e.topic == dds and e.kind == kind]

    def service_servers(self, name: str) -> list[Endpoint]:
        """The readers of a service's requests: one per server."""
        dds = f"{REQUEST_PREFIX}{name}Request"
        return [e for e in self._endpoints.values() if e.topic == dds and e.kind == "subscription"]

    def nodes(self, include_hidden: bool = False) -> list[NodeName]:
        """Every node of every live participant, as `ros2 node list` lists them."""
        out = []
        for key, nodes in self._nodes.items():
            if key not in self._participants:
                continue
            for node, _, _ in nodes:
                if include_hidden or not node.name.startswith("_"):
                    out.append(node)
        return out

    def owners(self) -> dict[bytes, NodeName]:
        """The node of every endpoint GID that ros_discovery_info names, at once (node_of for a
        whole graph: the web view's drawing of it)."""
        out: dict[bytes, NodeName] = {}
        for key, nodes in self._nodes.items():
            if key in self._participants:
                for node, readers, writers in nodes:
                    out.update(dict.fromkeys(readers, node))
                    out.update(dict.fromkeys(writers, node))
        return out

    def node_of(self, gid: bytes) -> NodeName | None:
        """The node that owns the endpoint with this GID, from ros_discovery_info."""
        for nodes in self._nodes.values():
            for node, readers, writers in nodes:
                if gid in readers or gid in writers:
                    return node
        return None

    def close(self) -> None:
        """Leave the domain now, so peers see this reader go at once."""
        from cyclonedds.core import DDSException  # deferred: optional dependency

        try:
            self.participant.__del__()
        except DDSException:
            pass


def describe_qos(qos: Any) -> list[str]:
    """rclpy's lines for a QoS profile, as `ros2 topic info -v` prints them."""
    from cyclonedds.qos import Policy  # deferred: optional dependency

    rel = qos[Policy.Reliability]
    dur = qos[Policy.Durability]
    hist = qos[Policy.History]
    life = qos[Policy.Lifespan]
    dead = qos[Policy.Deadline]
    live = qos[Policy.Liveliness]
    reliability = "RELIABLE" if isinstance(rel, Policy.Reliability.Reliable) else "BEST_EFFORT"
    durability = {
        Policy.Durability.Volatile: "VOLATILE",
        Policy.Durability.TransientLocal: "TRANSIENT_LOCAL",
        Policy.Durability.Transient: "TRANSIENT",
        Policy.Durability.Persistent: "PERSISTENT",
    }.get(dur, "VOLATILE")
    history = f"KEEP_LAST ({hist.depth})" if isinstance(hist, Policy.History.KeepLast) else "KEEP_ALL"
    liveliness = "AUTOMATIC"
    lease = INFINITE_NS
    if live is not None:
        lease = live.lease_duration
        if isinstance(live, Policy.Liveliness.ManualByTopic):
            liveliness = "MANUAL_BY_TOPIC"
        elif isinstance(live, Policy.Liveliness.ManualByParticipant):
            liveliness = "MANUAL_BY_PARTICIPANT"
    return [
        f"  Reliability: {reliability}",
        f"  History (Depth): {history}",
        f"  Durability: {durability}",
        f"  Lifespan: {_duration(life.lifespan if life is not None else INFINITE_NS)}",
        f"  Deadline: {_duration(dead.deadline if dead is not None else INFINITE_NS)}",
        f"  Liveliness: {liveliness}",
        f"  Liveliness lease duration: {_duration(lease)}",
    ]


def _duration(ns: int) -> str:
    """rclpy's str(Duration): 'Infinite', or the nanoseconds."""
    if ns >= INFINITE_NS:
        return "Infinite"
    return f"{ns} nanoseconds"
