"""`topic pub`: publish a message VALUES fill, at a rate, as `ros2 topic pub` does.

The publisher is one of a hidden node of llfsm's own bus on the DDS transport
(llfsm/ros2cli/endpoints.py), so it is announced on the graph and speaks the transport's QoS.
"""

from __future__ import annotations

import os
import sys
import time
from typing import Any, TextIO

from ...msgs import Message
from ...ros.node import Node
from ...ros.transports.dds_graph import Graph
from .. import NOT_FOUND, TIMEOUT, CliError
from ..arguments import full_name, parse_values, stamp
from ..discovery import where
from ..endpoints import hidden_node
from ..lookup import message_class, use_working_directory
from . import check_types

#: rclpy's default QoS depth ("default" profile), which `ros2 topic pub` publishes with.
PUB_DEPTH = 10


def pub(
    topic: str,
    type_text: str,
    values: str = "{}",
    *,
    period: float = 1.0,
    print_nth: int = 1,
    times: int = 0,
    wait_matching: int = 0,
    keep_alive: float = 0.1,
    timeout: float = TIMEOUT,
    out: TextIO | None = None,
) -> None:
    """`ros2 topic pub`: publish the message every `period` seconds, `times` times (0: until
    interrupted), after `wait_matching` subscriptions have matched (at most `timeout` s)."""
    out = out or sys.stdout
    name = full_name(topic)
    use_working_directory()
    cls = message_class(type_text)
    msg, stamps = parse_values(cls, values)
    with hidden_node(f"_llfsm_cli_{os.getpid()}") as (node, graph):
        publisher = node.create_publisher(cls, name, PUB_DEPTH)
        if wait_matching:
            _wait_for_subscriptions(graph, publisher, name, cls, wait_matching, timeout, out)
        out.write("publisher: beginning loop\n")
        count = 0
        next_at = time.monotonic()
        while True:
            stamp(stamps)
            count += 1
            if print_nth and count % print_nth == 0:
                out.write(f"publishing #{count}: {msg!r}\n\n")
                out.flush()
            publisher.publish(msg)
            if times and count >= times:
                break
            next_at += period
            while (left := next_at - time.monotonic()) > 0:
                node._bus.spin_once(int(left * 1e9))  # answers discovery meanwhile
        _linger(node, publisher, keep_alive)


def _linger(node: Node, publisher: Any, keep_alive: float) -> None:
    """Stay `keep_alive` seconds (as ros2 does) and until what was sent is acknowledged, at most
    a second more: a reliable message must reach the wire before the participant goes."""
    from cyclonedds.util import duration  # deferred: cyclonedds is optional (hidden_node checked it loads)

    for writer in getattr(publisher._remote, "writers", ()):
        writer.wait_for_acks(duration(seconds=1))
    end = time.monotonic() + keep_alive
    while (left := end - time.monotonic()) > 0:
        node._bus.spin_once(int(left * 1e9))


def _wait_for_subscriptions(
    graph: Graph, publisher: Any, name: str, cls: type[Message], n: int, timeout: float, out: TextIO
) -> None:
    deadline = time.monotonic() + timeout
    said = False
    while publisher.get_subscription_count() < n:
        publisher.node._bus.spin_once(0)
        graph.update()
        check_types(name, cls, graph.topic_endpoints(name, "subscription"))
        if time.monotonic() >= deadline:
            found = publisher.get_subscription_count()
            raise CliError(
                f"Timed out waiting for subscribers: expected {n} matching subscription(s) on '{name}' "
                f"within {timeout:g} s, found {found} ({where()})",
                NOT_FOUND,
            )
        if not said:
            out.write(f"Waiting for at least {n} matching subscription(s)...\n")
            out.flush()
            said = True
        time.sleep(0.05)
