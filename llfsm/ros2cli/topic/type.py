"""`topic type`: the type (or types) of a topic, once discovery shows it."""

from __future__ import annotations

from .. import TIMEOUT
from ..arguments import full_name
from ..discovery import open_graph, wait_for_topic_types


def type_(topic: str, *, timeout: float = TIMEOUT) -> str:
    """What `ros2 topic type` prints: one type a line."""
    name = full_name(topic, "topic")
    graph = open_graph()
    try:
        types = wait_for_topic_types(graph, name, timeout)
    finally:
        graph.close()
    return "".join(f"{t}\n" for t in types)
