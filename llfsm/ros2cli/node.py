"""`node list`: the nodes of the ROS graph, llfsm's and ROS 2's, as `ros2 node list` prints
them (node names come from ros_discovery_info, so the list waits for it to settle)."""

from __future__ import annotations

from . import NOT_FOUND, SPIN_TIME, CliError
from .discovery import discovered, where

#: What ros2 prints on stderr, before the list, when two nodes share a name.
DUPLICATE_NAMES = (
    "WARNING: Be aware that there are nodes in the graph that share an exact name, "
    "which can have unintended side effects."
)


def list_(*, include_hidden: bool = False, count: bool = False, spin_time: float = SPIN_TIME) -> tuple[str, str | None]:
    """What `ros2 node list` prints, and the warning it prints on stderr first (or None)."""
    with discovered(spin_time) as graph:
        graph.settle()  # the nodes of participants already seen
        names = sorted(n.full_name for n in graph.nodes(include_hidden=include_hidden))
        every_name = [n.full_name for n in graph.nodes(include_hidden=True)]
    warning = DUPLICATE_NAMES if len(every_name) != len(set(every_name)) and not count else None
    if count:
        return f"{len(names)}\n", warning
    if not names:
        raise CliError(f"no nodes found within {spin_time:g} s ({where()})", NOT_FOUND)
    return "".join(f"{n}\n" for n in names), warning
