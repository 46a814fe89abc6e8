"""`node list|info`: the nodes of the ROS graph, llfsm's and ROS 2's, as `ros2 node` prints
them (node names come from ros_discovery_info, so the verbs wait for it to settle).

`info` sorts a node's endpoints into what `ros2 node info` shows: its readers and writers of
ROS topics (`rt/...`) are subscribers and publishers, its readers of service requests
(`rq/...Request`) servers and its writers of them clients, and an action is the feedback topic
of its five endpoints (`<name>/_action/feedback`: published by the server, read by clients),
as rcl_action finds actions.
"""

from __future__ import annotations

from ..ros.transports.dds_graph import Endpoint, Graph, NodeName, is_hidden, message_type, service_name, service_type
from ..ros.transports.dds_graph import topic_name as ros_topic_name
from ..suggest import did_you_mean
from . import NOT_FOUND, SPIN_TIME, TIMEOUT, CliError
from .discovery import discovered, where

#: What ros2 prints on stderr, before the list, when two nodes share a name.
DUPLICATE_NAMES = (
    "WARNING: Be aware that there are nodes in the graph that share an exact name, "
    "which can have unintended side effects."
)


def list_(*, include_hidden: bool = False, count: bool = False, spin_time: float = SPIN_TIME) -> tuple[str, str | None]:
    """What `ros2 node list` prints, and the warning it prints on stderr first (or None)."""
    with discovered(spin_time) as graph:  # settled: the nodes of every participant seen
        names = sorted(n.full_name for n in graph.nodes(include_hidden=include_hidden))
        every_name = [n.full_name for n in graph.nodes(include_hidden=True)]
    warning = DUPLICATE_NAMES if len(every_name) != len(set(every_name)) and not count else None
    if count:
        return f"{len(names)}\n", warning
    if not names:
        raise CliError(f"no nodes found within {spin_time:g} s ({where()})", NOT_FOUND)
    return "".join(f"{n}\n" for n in names), warning


#: What ros2 prints on stderr, before the info, when several nodes have the name asked for.
INFO_NONUNIQUE = (
    'There are {count} nodes in the graph with the exact name "{name}". '
    "You are seeing information about only one of them."
)
_ACTION_FEEDBACK = "/_action/feedback"
_FEEDBACK_TYPE = "_FeedbackMessage"


def info(
    node_name: str, *, include_hidden: bool = False, spin_time: float = SPIN_TIME, timeout: float = TIMEOUT
) -> tuple[str, str | None]:
    """What `ros2 node info NODE` prints, and the warning it prints on stderr first (or None).
    NODE is the node's full name (`/turtlesim`; `turtlesim` is taken as `/turtlesim`).  A node
    not seen within `timeout` is status 1, with the close names the graph has."""
    full = node_name if node_name.startswith("/") else "/" + node_name
    with discovered(spin_time) as graph:
        graph.spin(timeout, until=lambda: any(n.full_name == full for n in graph.nodes(include_hidden=True)))
        graph.settle()  # the endpoints of the node's participant, named in its ros_discovery_info
        names = [n.full_name for n in graph.nodes(include_hidden=True)]
        count = names.count(full)
        if not count:
            raise CliError(f"Unable to find node '{full}'{did_you_mean(full, names)}", NOT_FOUND)
        sections = _sections(graph, full, include_hidden)
    warning = INFO_NONUNIQUE.format(count=count, name=full) if count > 1 else None
    out = [f"{full}\n"]
    for title, entries in sections:
        out.append(f"  {title}:\n")
        # ros2 prints the entries with print(*entries, sep="\n"): an empty section is a blank line
        out.append("".join(f"    {name}: {', '.join(types)}\n" for name, types in entries) or "\n")
    return "".join(out), warning


def _sections(graph: Graph, full: str, include_hidden: bool) -> list[tuple[str, list[tuple[str, list[str]]]]]:
    """(title, [(name, types)]) in ros2's order, each sorted by name as rmw's graph cache is."""
    mine: list[Endpoint] = []
    for e in graph.endpoints():
        owner: NodeName | None = graph.node_of(e.gid)
        if owner is not None and owner.full_name == full:
            mine.append(e)
    found: dict[str, dict[str, set[str]]] = {
        k: {} for k in ("subscribers", "publishers", "servers", "clients", "action_servers", "action_clients")
    }

    def add(section: str, name: str, type_name: str | None) -> None:
        if include_hidden or not is_hidden(name):
            types = found[section].setdefault(name, set())
            if type_name:
                types.add(type_name)

    for e in mine:
        topic = ros_topic_name(e.topic)
        if topic is not None:
            add("publishers" if e.kind == "publisher" else "subscribers", topic, message_type(e.type_name))
            if topic.endswith(_ACTION_FEEDBACK):
                action = topic[: -len(_ACTION_FEEDBACK)]
                kind = message_type(e.type_name)
                add(
                    "action_servers" if e.kind == "publisher" else "action_clients",
                    action,
                    kind.removesuffix(_FEEDBACK_TYPE) if kind.endswith(_FEEDBACK_TYPE) else None,
                )
            continue
        service = service_name(e.topic)
        if service is not None and e.topic.endswith("Request"):
            add("servers" if e.kind == "subscription" else "clients", service, service_type(e.type_name))
    titles = (
        ("Subscribers", "subscribers"),
        ("Publishers", "publishers"),
        ("Service Servers", "servers"),
        ("Service Clients", "clients"),
        ("Action Servers", "action_servers"),
        ("Action Clients", "action_clients"),
    )
    return [(title, [(n, sorted(t)) for n, t in sorted(found[key].items())]) for title, key in titles]
