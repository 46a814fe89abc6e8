"""The graph of nodes and topics, as rqt_graph draws it, and the actions it shows (docs/view.md).

rqt_graph's "Nodes/Topics" view: a node is an ellipse, a topic a box, an arrow runs from each
publisher to its topic and from the topic to each subscriber; ranks from left to right, laid
out by llfsm.diagram.layout.  As rqt_graph hides "debug" names by default, the drawing leaves
out /rosout, /parameter_events, /clock, hidden names (a part that starts with `_`, such as an
action's `_action/...` endpoints) and the page's own node.

The graph comes from the run's bus (nodes and their entities, read as plain attributes) and,
over DDS, from discovery (llfsm.ros.transports.dds_graph: endpoints and ros_discovery_info, as
`ros2 node info` reads them).  Actions are found by their names alone, as `ros2 action list`
finds them: a service `NAME/_action/send_goal` is an action NAME whose type is its type without
`_SendGoal`; its server is the node serving that service, its clients the nodes calling it.

What a DDS peer names may be anything, so every name and type is escaped in the SVG, and the
drawing is bounded (`MAX_DRAWN`), saying what it left out.
"""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass
from html import escape
from typing import TYPE_CHECKING, Any

from ..diagram.layout import EdgeSpec, NodeSpec, layered, path
from ..ros.client import Client
from ..ros.publisher import Publisher
from ..ros.subscription import Subscription
from ..ros.transports.dds_graph import Graph, is_hidden, message_type, service_name, service_type, topic_name

if TYPE_CHECKING:
    from ..ros.bus import Bus

ACTION_INFIX = "/_action/"
SEND_GOAL = "/_action/send_goal"
#: Topics rqt_graph's "Hide: Debug" leaves out (and hidden names, below).
DEBUG_TOPICS = frozenset({"/rosout", "/parameter_events", "/clock", "/statistics"})
#: Nodes and topics drawn at most (the graph of a whole domain can be big, and a peer can make it
#: so): nodes first, then the topics with the most connections.
MAX_DRAWN = 150
#: Nodes and actions listed beside the drawing at most (the parameters panel, the actions table):
#: the rest are counted (`nodes_total`, `actions_total`).
MAX_LISTED_NODES = 300
MAX_LISTED_ACTIONS = 100
#: Characters of a name shown in the drawing (the whole name is in its tooltip).
NAME_MAX = 48
CHAR_W = 7.3  # DejaVu Sans Mono at 12 px (0.602 em), style.css
_NOT_XML = re.compile("[^\t\n\r\x20-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")


@dataclass(frozen=True)
class Action:
    name: str
    type: str
    servers: tuple[str, ...]
    clients: tuple[str, ...]


@dataclass(frozen=True)
class RosGraph:
    """Nodes (fully qualified names), topics (name, type), edges (node, topic, "pub" or "sub")
    and actions, each sorted: two graphs are equal when what they show is."""

    nodes: tuple[str, ...] = ()
    topics: tuple[tuple[str, str], ...] = ()
    edges: tuple[tuple[str, str, str], ...] = ()
    actions: tuple[Action, ...] = ()

    def merged(self, other: RosGraph) -> RosGraph:
        """This graph and another's (the run's own bus and the DDS graph beyond it)."""
        topics = dict(self.topics)
        for name, type_ in other.topics:
            topics.setdefault(name, type_)
        actions: dict[str, Action] = {a.name: a for a in self.actions}
        for a in other.actions:
            mine = actions.get(a.name)
            if mine is None:
                actions[a.name] = a
            else:
                actions[a.name] = Action(
                    a.name,
                    mine.type or a.type,
                    tuple(sorted({*mine.servers, *a.servers})),
                    tuple(sorted({*mine.clients, *a.clients})),
                )
        return RosGraph(
            tuple(sorted({*self.nodes, *other.nodes})),
            tuple(sorted(topics.items())),
            tuple(sorted({*self.edges, *other.edges})),
            tuple(actions[k] for k in sorted(actions)),
        )

    def data(self) -> dict[str, Any]:
        """What the page is sent besides the drawing: nodes and actions for its lists, each
        bounded (MAX_LISTED_NODES, MAX_LISTED_ACTIONS), with how many there are."""
        return {
            "nodes": list(self.nodes[:MAX_LISTED_NODES]),
            "nodes_total": len(self.nodes),
            "actions": [
                {"name": a.name, "type": a.type, "servers": list(a.servers[:20]), "clients": list(a.clients[:20])}
                for a in self.actions[:MAX_LISTED_ACTIONS]
            ],
            "actions_total": len(self.actions),
        }


def _action_type(service_type_name: str) -> str:
    return service_type_name.removesuffix("_SendGoal")


def from_bus(bus: Bus, leave_out: object = None) -> RosGraph:
    """The graph of the nodes of this process (`leave_out`: the page's own node).  Plain reads
    of lists the scheduler's thread changes: each is copied before it is walked."""
    nodes: list[str] = []
    edges: set[tuple[str, str, str]] = set()
    calls: dict[str, set[str]] = {}
    for node in list(bus.nodes):
        if node is leave_out or node._destroyed:
            continue
        name = node.get_fully_qualified_name()
        nodes.append(name)
        for e in list(node._entities):
            if isinstance(e, Publisher) and not e._destroyed:
                edges.add((name, e.topic_name, "pub"))
            elif isinstance(e, Subscription) and not e._destroyed:
                edges.add((name, e.topic_name, "sub"))
            elif isinstance(e, Client) and e.srv_name.endswith(SEND_GOAL):
                calls.setdefault(e.srv_name, set()).add(name)
    topics = {name: t.type._TYPE for name, t in list(bus.topics.items())}
    actions = []
    for srv, server in sorted(list(bus.services.items())):
        if srv.endswith(SEND_GOAL):
            owner = server.node.get_namespace().rstrip("/") + "/" + server.node.get_name()
            actions.append(
                Action(
                    srv[: -len(SEND_GOAL)],
                    _action_type(server.type._TYPE),
                    (owner,),
                    tuple(sorted(calls.pop(srv, set()))),
                )
            )
    for srv, clients in sorted(calls.items()):  # clients of a server in another process, or of none
        actions.append(Action(srv[: -len(SEND_GOAL)], "", (), tuple(sorted(clients))))
    used = {t for _, t, _ in edges}
    return RosGraph(
        tuple(sorted(nodes)),
        tuple(sorted((n, t) for n, t in topics.items() if n in used)),
        tuple(sorted(edges)),
        tuple(sorted(actions, key=lambda a: a.name)),
    )


def from_dds(graph: Graph) -> RosGraph:
    """The graph DDS discovery shows (the reader's own participant left out): each endpoint's
    node from ros_discovery_info; an endpoint of no known node (a participant that has not
    said, or a plain DDS one) is left out, as `ros2 node info` cannot place it either."""
    owners = graph.owners()
    nodes = sorted({n.full_name for n in graph.nodes()})
    shown = set(nodes)
    edges: set[tuple[str, str, str]] = set()
    topics: dict[str, str] = {}
    servers: dict[str, set[str]] = {}
    clients: dict[str, set[str]] = {}
    kinds: dict[str, str] = {}
    for e in graph.endpoints():
        owner = owners.get(e.gid)
        node = owner.full_name if owner is not None else None
        topic = topic_name(e.topic)
        if topic is not None:
            topics.setdefault(topic, message_type(e.type_name))
            if node in shown:
                edges.add((node, topic, "pub" if e.kind == "publisher" else "sub"))
            continue
        srv = service_name(e.topic)
        if srv is None or not srv.endswith(SEND_GOAL):
            continue
        if e.topic.startswith("rq/"):
            kind = service_type(e.type_name)
            if kind:
                kinds[srv] = _action_type(kind)
            side = servers if e.kind == "subscription" else clients
            if node is not None:
                side.setdefault(srv, set()).add(node)
    actions = [
        Action(srv[: -len(SEND_GOAL)], kinds.get(srv, ""), tuple(sorted(servers.get(srv, ()))), tuple(sorted(c)))
        for srv, c in [(s, clients.get(s, set())) for s in sorted({*servers, *clients, *kinds})]
    ]
    used = {t for _, t, _ in edges}
    return RosGraph(
        tuple(nodes),
        tuple(sorted((n, t) for n, t in topics.items() if n in used)),
        tuple(sorted(edges)),
        tuple(actions),
    )


class _OneAtATime:
    """A discovery reader taken one sample at a time, as GraphSource._take does: a sample that
    cannot be read is dropped alone (said once), not with its whole batch."""

    def __init__(self, reader: Any, warn: Any) -> None:
        self.reader, self.warn = reader, warn

    def take(self, N: int = 1) -> list[Any]:
        out: list[Any] = []
        for _ in range(N):
            try:
                got = self.reader.take(N=1)
            except Exception as e:
                self.warn(f"discovery: dropped an endpoint that could not be read: {type(e).__name__}", "discovery")
                continue
            if not got:
                break
            out.extend(got)
        return out


def robust_graph(dp: Any, warn: Any) -> Graph:
    """A reader of the DDS graph (llfsm.ros.transports.dds_graph) on the participant `dp`, whose
    discovery readers drop a sample that cannot be read alone: the graph a page draws comes
    from whatever any peer announces."""
    graph = Graph(dp, say=lambda text: warn(text))
    # the readers Graph.update takes from, each wrapped (Graph takes batches of 4096)
    graph._participants_reader = _OneAtATime(graph._participants_reader, warn)  # type: ignore[assignment]
    graph._readers = {kind: _OneAtATime(r, warn) for kind, r in graph._readers.items()}  # type: ignore[misc]
    return graph


def visible(g: RosGraph) -> RosGraph:
    """What rqt_graph shows with its debug names hidden."""

    def shown(name: str) -> bool:
        return name not in DEBUG_TOPICS and not is_hidden(name)

    nodes = tuple(n for n in g.nodes if not is_hidden(n))
    keep = set(nodes)
    edges = tuple(e for e in g.edges if e[0] in keep and shown(e[1]))
    used = {t for _, t, _ in edges}
    return RosGraph(nodes, tuple(t for t in g.topics if t[0] in used), edges, g.actions)


# -- the drawing -----------------------------------------------------------------------------------


def _esc(text: object) -> str:
    return escape(_NOT_XML.sub("\ufffd", str(text)), quote=True)


def _short(name: str) -> str:
    return name if len(name) <= NAME_MAX else name[: NAME_MAX - 1] + "…"


def svg(g: RosGraph) -> str:
    """The drawing of a graph (already filtered by `visible` if wanted): nodes as ellipses,
    topics as boxes, publisher -> topic -> subscriber; at most MAX_DRAWN of them."""
    types = dict(g.topics)
    degree: dict[str, int] = {}
    for _, t, _ in g.edges:
        degree[t] = degree.get(t, 0) + 1
    nodes = list(g.nodes[:MAX_DRAWN])
    room = MAX_DRAWN - len(nodes)
    topics = sorted(types, key=lambda t: (-degree.get(t, 0), t))[: max(0, room)]
    drawn_nodes, drawn_topics = set(nodes), set(topics)
    edges = [e for e in g.edges if e[0] in drawn_nodes and e[1] in drawn_topics]
    left_out = len(g.nodes) - len(nodes) + len(types) - len(topics)
    if not nodes and not topics:
        return (
            '<svg xmlns="http://www.w3.org/2000/svg" class="rosgraph" viewBox="0 0 320 40" width="320" height="40">'
            '<text class="empty" x="10" y="24">no nodes on the graph yet</text></svg>'
        )
    specs = []
    for n in nodes:
        w = CHAR_W * len(_short(n)) * 1.12 + 30
        specs.append(NodeSpec(("n", n), w, 34))
    for t in topics:
        specs.append(NodeSpec(("t", t), CHAR_W * len(_short(t)) + 20, 26))
    links = [EdgeSpec(("n", n), ("t", t)) if kind == "pub" else EdgeSpec(("t", t), ("n", n)) for n, t, kind in edges]
    placed = layered(specs, links, direction="LR")
    size = {s.id: (s.w, s.h) for s in specs}
    marker = "graph-arrow-" + hashlib.sha256(repr(g).encode("utf-8", "surrogatepass")).hexdigest()[:10]
    parts: list[str] = []
    for route, (n, t, kind) in zip(placed.routes, edges, strict=True):
        points = list(route.points)
        if kind == "pub":  # from the node's ellipse: its border, not its bounding box's
            points[0] = _on_ellipse(points[0], placed.centres[("n", n)], size[("n", n)])
        else:
            points[-1] = _on_ellipse(points[-1], placed.centres[("n", n)], size[("n", n)])
        title = _esc(f"{n} publishes {t}" if kind == "pub" else f"{n} subscribes to {t}")
        parts.append(
            f'<path class="link {kind}" data-node="{_esc(n)}" data-topic="{_esc(t)}" '
            f'd="{path(points, "LR")}" marker-end="url(#{marker})"><title>{title}</title></path>'
        )
    for n in nodes:
        (x, y), (w, h) = placed.centres[("n", n)], size[("n", n)]
        parts.append(
            f'<g class="ros-node" data-node="{_esc(n)}"><title>node {_esc(n)}</title>'
            f'<ellipse cx="{x:.1f}" cy="{y:.1f}" rx="{w / 2:.1f}" ry="{h / 2:.1f}"/>'
            f'<text x="{x:.1f}" y="{y + 4:.1f}">{_esc(_short(n))}</text></g>'
        )
    for t in topics:
        (x, y), (w, h) = placed.centres[("t", t)], size[("t", t)]
        kind = types.get(t) or "type unknown"
        parts.append(
            f'<g class="ros-topic" data-topic="{_esc(t)}"><title>topic {_esc(t)} ({_esc(kind)})</title>'
            f'<rect x="{x - w / 2:.1f}" y="{y - h / 2:.1f}" width="{w:.1f}" height="{h:.0f}"/>'
            f'<text x="{x:.1f}" y="{y + 4:.1f}">{_esc(_short(t))}</text></g>'
        )
    width, height = placed.width, placed.height
    note = ""
    if left_out:
        note = (
            f'<text class="omitted" x="10" y="{height + 14:.0f}">{left_out:,} more nodes and topics not drawn '
            f"(at most {MAX_DRAWN})</text>"
        )
        height += 24
        width = max(width, 420)
    return (
        f'<svg xmlns="http://www.w3.org/2000/svg" class="rosgraph" viewBox="0 0 {width:.0f} {height:.0f}" '
        f'width="{width:.0f}" height="{height:.0f}" role="img" aria-label="nodes and topics">'
        f'<defs><marker id="{marker}" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="7" markerHeight="7" '
        f'orient="auto-start-reverse"><path d="M0 0 L10 5 L0 10 z" class="arrowhead"/></marker></defs>'
        f"{''.join(parts)}{note}</svg>"
    )


def _on_ellipse(
    point: tuple[float, float], centre: tuple[float, float], size: tuple[float, float]
) -> tuple[float, float]:
    """Where the horizontal through `point` meets the ellipse's border, on the point's side."""
    (px, py), (cx, cy), (w, h) = point, centre, size
    a, b = w / 2, h / 2
    dy = max(-b, min(b, py - cy))
    dx = a * (1 - (dy / b) ** 2) ** 0.5
    return (cx + dx if px >= cx else cx - dx, py)
