"""The verbs' own endpoints on the ROS domain: a DataReader for the verbs that listen (`topic
echo`, `topic hz`), a hidden node of llfsm's bus for the verbs that talk (`topic pub`, `service
call`).

The listeners read with a DataReader of their own, of the message's DDS form
(llfsm/msgs/_dds.py), because they choose QoS as `ros2` does, from what the graph shows of the
publishers; the graph reader on the same participant tells the type and QoS of what is there.
The talkers are a node of llfsm's own bus on the DDS transport, as `ros2` makes a node of
rclpy: the transport's publisher and client (request header, client id, readiness) serve them
unchanged, and the node is announced on the graph (docs/transports.md).

cyclonedds is an optional dependency: its imports here are deferred, and `wire()` is the one
place its absence becomes the verbs' one-line NEEDS_CYCLONEDDS error.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from ..msgs import Message
from ..ros import bus_of
from ..ros.node import Node
from ..ros.transports.dds_config import DiscoveryError
from ..ros.transports.dds_graph import Graph
from ..runtime.clock import WallClock
from ..runtime.context import RunContext, activate
from . import CliError
from .discovery import NEEDS_CYCLONEDDS

#: rclpy's "sensor_data" depth, which `ros2 topic echo` and `ros2 topic hz` read with.
ECHO_DEPTH = 5


def wire() -> Any:
    """The DDS forms of llfsm's messages (llfsm/msgs/_dds.py: `dds_type`, `from_cdr`)."""
    try:
        # deferred: cyclonedds is optional, and its absence is a CliError here, not at import
        import cyclonedds  # noqa: F401

        from ..msgs import _dds
    except ImportError as e:
        raise CliError(NEEDS_CYCLONEDDS.format(e)) from None
    return _dds


def reader_qos(reliable: bool, transient_local: bool, depth: int) -> Any:
    """A reader's QoS: rclpy's profile as rmw_cyclonedds sets it (XCDR1), reliability and
    durability as asked."""
    from cyclonedds.core import Policy, Qos  # deferred: cyclonedds is optional (wire() said so)

    return Qos(
        Policy.Reliability.Reliable(max_blocking_time=100_000_000) if reliable else Policy.Reliability.BestEffort,
        Policy.Durability.TransientLocal if transient_local else Policy.Durability.Volatile,
        Policy.History.KeepLast(depth),
        Policy.DataRepresentation(use_cdrv0_representation=True),
    )


def topic_reader(graph: Graph, name: str, cls: type[Message], *, reliable: bool, transient_local: bool) -> Any:
    """A DataReader of ROS topic `name` on the graph's participant, with ros2's reader QoS."""
    wire_type = wire().dds_type(cls)
    # deferred: cyclonedds is optional (wire() said so)
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    qos = reader_qos(reliable, transient_local, ECHO_DEPTH)
    return DataReader(graph.participant, Topic(graph.participant, f"rt{name}", wire_type), qos=qos)


def samples(reader: Any, name: str, cls: type[Message]) -> Any:
    """The decoded messages of a verb's reader, on llfsm's one decoding path
    (llfsm/ros/transports/dds_read.py): a sample that is not a `cls` (a string that is not
    UTF-8) is dropped with one warning on stderr per peer, and the verb goes on."""
    decode = wire().from_cdr
    from ..ros.transports.dds_read import Samples  # deferred: imports cyclonedds, which is optional

    return Samples(reader, lambda data: decode(data, cls), name, f"a {cls._TYPE}")


class Waiter:
    """Blocks until one of the readers has data, at most a given time (a wait set: no polling)."""

    def __init__(self, graph: Graph, *readers: Any) -> None:
        # deferred: cyclonedds is optional (wire() said so)
        from cyclonedds.core import InstanceState, ReadCondition, SampleState, ViewState, WaitSet

        self.waitset = WaitSet(graph.participant)
        self.conditions = [ReadCondition(r, SampleState.NotRead | ViewState.Any | InstanceState.Any) for r in readers]
        for c in self.conditions:
            self.waitset.attach(c)

    def wait(self, seconds: float) -> bool:
        return self.waitset.wait(max(0, int(seconds * 1e9))) > 0


@contextmanager
def hidden_node(name: str) -> Iterator[tuple[Node, Graph]]:
    """A hidden ROS node of llfsm's own bus on the DDS transport (announced on the graph as
    `ros2`'s own `_ros2cli_...` nodes are), and a graph reader on the same participant."""
    wire()
    from ..ros.transports.dds import DdsTransport  # deferred: imports cyclonedds, which is optional

    ctx = RunContext(WallClock())
    try:
        transport = DdsTransport()
    except DiscoveryError as e:
        raise CliError(str(e)) from None
    ctx.transport = transport
    prev = activate(ctx)
    try:
        bus = bus_of(ctx)
        bus.initialised = True
        node = Node(name, start_parameter_services=False, enable_rosout=False)
        yield node, Graph(transport.dp)
    finally:
        transport.close()
        activate(prev)
