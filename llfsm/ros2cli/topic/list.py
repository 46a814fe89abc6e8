"""`topic list`: the topics discovery shows, with `-t` their types, with `-v` a count of
publishers and subscribers each."""

from __future__ import annotations

from ...ros.transports.dds_graph import Graph
from .. import NOT_FOUND, SPIN_TIME, CliError
from ..discovery import discovered, where


def list_(
    *,
    show_types: bool = False,
    count: bool = False,
    include_hidden: bool = False,
    verbose: bool = False,
    spin_time: float = SPIN_TIME,
) -> str:
    """What `ros2 topic list` prints after `spin_time` seconds of discovery."""
    with discovered(spin_time) as graph:
        topics = graph.topics(include_hidden=include_hidden)
        if count:
            return f"{len(topics)}\n"
        if not topics:
            raise CliError(f"no topics found within {spin_time:g} s ({where()})", NOT_FOUND)
        if verbose:
            return _verbose(graph, topics, "publisher") + "\n" + _verbose(graph, topics, "subscription") + "\n"
        return "".join(
            f"{name} [{', '.join(types)}]\n" if show_types else f"{name}\n" for name, types in topics.items()
        )


def _verbose(graph: Graph, topics: dict[str, list[str]], kind: str) -> str:
    out = [("Published" if kind == "publisher" else "Subscribed") + " topics:\n"]
    word = "publisher" if kind == "publisher" else "subscriber"
    for name, types in topics.items():
        n = len(graph.topic_endpoints(name, kind))
        if n:
            out.append(f" * {name} [{', '.join(types)}] {n} {word}{'s' if n > 1 else ''}\n")
    return "".join(out)
