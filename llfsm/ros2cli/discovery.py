"""The DDS view of the ROS graph as the verbs use it: opening it, waiting for discovery, and
the words for "nothing found".

The reading itself (participants, endpoints, ros_discovery_info) is `Graph` in
llfsm/ros/transports/dds_graph.py; this module turns its failures into `CliError`s and holds
the waits every verb group shares.  "Nothing found" is status 1, the one thing llfsm says where
`ros2` prints nothing at all; it names the domain searched (docs/transports.md).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

from ..progress import Status
from ..ros.transports.dds_config import DiscoveryError, settings
from ..ros.transports.dds_graph import Graph
from ..suggest import did_you_mean
from . import NOT_FOUND, CliError

NEEDS_CYCLONEDDS = "the ros2-style verbs speak DDS through the cyclonedds package, which does not load here ({})"


def open_graph() -> Graph:
    """A graph reader on the ROS domain the environment names, or a CliError saying why not."""
    try:
        return Graph()
    except ImportError as e:
        raise CliError(NEEDS_CYCLONEDDS.format(e)) from None
    except DiscoveryError as e:
        raise CliError(str(e)) from None


@contextmanager
def discovered(spin_time: float) -> Iterator[Graph]:
    """A graph reader that has listened to discovery for `spin_time`, and then until every
    participant seen has told its nodes and their endpoints have been seen (at most SETTLE_S
    more: Fast DDS resends its ros_discovery_info only on its heartbeat), closed afterwards:
    what the list verbs print from."""
    graph = open_graph()
    try:
        graph.spin(spin_time)
        graph.settle()
        yield graph
    finally:
        graph.close()


def where() -> str:
    """The domain searched, for "nothing found" messages."""
    d = settings()
    return f"ROS domain {d.domain_id}, discovery range {d.range}"


def wait_for_topic_types(graph: Graph, name: str, timeout: float) -> list[str]:
    """The topic's types once discovery shows it; exit 1 when it does not within `timeout`."""
    with Status().waiting(f"topic '{name}' to appear", timeout):  # on a terminal only
        found = graph.spin(timeout, until=lambda: name in graph.topics(include_hidden=True))
    if not found:
        hint = did_you_mean(name, graph.topics(include_hidden=True))
        raise CliError(f"topic '{name}' not found within {timeout:g} s ({where()}){hint}", NOT_FOUND)
    return graph.topics(include_hidden=True)[name]
