"""`topic list`, `topic info`, `node list`, `service list`: the graph as the `ros2` verbs print it.

Each function takes a `Graph` (llfsm/ros/transports/dds_graph.py) that has already spun for
discovery, and returns the text to print; "nothing found" is a CliError with status 1, the
one thing llfsm says where `ros2` prints nothing at all.
"""

from __future__ import annotations

from contextlib import contextmanager
from typing import TYPE_CHECKING

from . import CliError

if TYPE_CHECKING:
    from collections.abc import Iterator

    from ..ros.transports.dds_graph import Graph

NOT_FOUND = 1
NEEDS_CYCLONEDDS = "the ros2-style verbs speak DDS through the cyclonedds package, which does not load here ({})"


def open_graph() -> Graph:
    """A graph reader on the ROS domain the environment names, or a CliError saying why not."""
    from ..ros.transports.dds_config import DiscoveryError

    try:
        from ..ros.transports.dds_graph import Graph

        return Graph()
    except ImportError as e:
        raise CliError(NEEDS_CYCLONEDDS.format(e)) from None
    except DiscoveryError as e:
        raise CliError(str(e)) from None


@contextmanager
def discovered(spin_time: float) -> Iterator[Graph]:
    """A graph reader that has listened to discovery for `spin_time` (closed afterwards): what
    the list verbs print from."""
    graph = open_graph()
    try:
        graph.spin(spin_time)
        yield graph
    finally:
        graph.close()


def where() -> str:
    """The domain searched, for "nothing found" messages."""
    from ..ros.transports.dds_config import settings

    d = settings()
    return f"ROS domain {d.domain_id}, discovery range {d.range}"


def topic_list(
    graph: Graph,
    *,
    show_types: bool = False,
    count: bool = False,
    include_hidden: bool = False,
    verbose: bool = False,
    spin_time: float = 0.0,
) -> str:
    topics = graph.topics(include_hidden=include_hidden)
    if count:
        return f"{len(topics)}\n"
    if not topics:
        raise CliError(f"no topics found within {spin_time:g} s ({where()})", NOT_FOUND)
    if verbose:
        return _verbose(graph, topics, "publisher") + "\n" + _verbose(graph, topics, "subscription") + "\n"
    return "".join(f"{name} [{', '.join(types)}]\n" if show_types else f"{name}\n" for name, types in topics.items())


def _verbose(graph: Graph, topics: dict[str, list[str]], kind: str) -> str:
    out = [("Published" if kind == "publisher" else "Subscribed") + " topics:\n"]
    word = "publisher" if kind == "publisher" else "subscriber"
    for name, types in topics.items():
        n = len(graph.topic_endpoints(name, kind))
        if n:
            out.append(f" * {name} [{', '.join(types)}] {n} {word}{'s' if n > 1 else ''}\n")
    return "".join(out)


def topic_info(graph: Graph, name: str, *, verbose: bool = False) -> str:
    """`ros2 topic info`: type and counts; with `verbose`, each endpoint's node, GID and QoS."""
    from ..ros.transports.dds_graph import describe_qos, message_type

    types = graph.topics(include_hidden=True).get(name)
    if types is None:
        raise CliError(f"Unknown topic '{name}'", NOT_FOUND)
    end = "\n\n" if verbose else "\n"
    type_str = types[0] if len(types) == 1 else str(types)
    out = [f"Type: {type_str}{end}"]
    for kind, title in (("publisher", "Publisher count"), ("subscription", "Subscription count")):
        endpoints = sorted(graph.topic_endpoints(name, kind), key=lambda e: e.gid)
        out.append(f"{title}: {len(endpoints)}{end}")
        if not verbose:
            continue
        for e in endpoints:
            node = graph.node_of(e.gid)
            lines = [
                f"Node name: {node.name if node else '_NODE_NAME_UNKNOWN_'}",
                f"Node namespace: {node.namespace if node else '_NODE_NAMESPACE_UNKNOWN_'}",
                f"Topic type: {message_type(e.type_name)}",
                f"Topic type hash: {e.type_hash}",
                f"Endpoint type: {'PUBLISHER' if kind == 'publisher' else 'SUBSCRIPTION'}",
                f"GID: {'.'.join(f'{b:02x}' for b in e.gid)}",
                "QoS profile:",
                *describe_qos(e.qos),
            ]
            out.append("\n".join(lines) + end)
    if len(types) > 1:
        out.append(f"WARNING: topic '{name}' has more than one type: {', '.join(types)}\n")
    return "".join(out)


def node_list(graph: Graph, *, include_hidden: bool = False, count: bool = False, spin_time: float = 0.0) -> str:
    names = sorted(n.full_name for n in graph.nodes(include_hidden=include_hidden))
    if count:
        return f"{len(names)}\n"
    if not names:
        raise CliError(f"no nodes found within {spin_time:g} s ({where()})", NOT_FOUND)
    return "".join(f"{n}\n" for n in names)


def duplicate_nodes(graph: Graph) -> bool:
    names = [n.full_name for n in graph.nodes(include_hidden=True)]
    return len(names) != len(set(names))


def service_list(
    graph: Graph, *, show_types: bool = False, count: bool = False, include_hidden: bool = False, spin_time: float = 0.0
) -> str:
    services = graph.services(include_hidden=include_hidden)
    if count:
        return f"{len(services)}\n"
    if not services:
        raise CliError(f"no services found within {spin_time:g} s ({where()})", NOT_FOUND)
    return "".join(f"{name} [{', '.join(types)}]\n" if show_types else f"{name}\n" for name, types in services.items())
