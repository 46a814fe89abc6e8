"""`topic info`: a topic's type and how many publishers and subscriptions it has; with `-v`,
each endpoint's node, GID and QoS as `ros2 topic info -v` prints them."""

from __future__ import annotations

from ...progress import Status
from ...ros.transports.dds_graph import Graph, describe_qos, message_type
from ...suggest import did_you_mean
from .. import NOT_FOUND, TIMEOUT, CliError
from ..arguments import full_name
from ..discovery import open_graph


def info(topic: str, *, verbose: bool = False, timeout: float = TIMEOUT) -> str:
    """What `ros2 topic info` prints, once discovery shows the topic (at most `timeout` s)."""
    name = full_name(topic, "topic")
    graph = open_graph()
    try:
        with Status().waiting(f"topic '{name}' to appear", timeout):  # on a terminal only
            graph.spin(timeout, until=lambda: name in graph.topics(include_hidden=True))
        graph.spin(0.2)  # the rest of the topic's endpoints, discovered with the first
        if verbose:  # each endpoint's node
            graph.settle()
        return _describe(graph, name, verbose=verbose)
    finally:
        graph.close()


def _describe(graph: Graph, name: str, *, verbose: bool) -> str:
    types = graph.topics(include_hidden=True).get(name)
    if types is None:
        raise CliError(f"Unknown topic '{name}'{did_you_mean(name, graph.topics(include_hidden=True))}", NOT_FOUND)
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
