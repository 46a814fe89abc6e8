"""`llfsm run --echo TOPIC`: print each message of a topic as YAML, `---` between, like
`ros2 topic echo`.  The reader attaches when the topic first appears (a machine usually
creates its publisher in INITIAL), so no message published on it is missed."""

from __future__ import annotations

import sys
from typing import IO

from ..ros.bus import Bus, Topic
from ..ros.names import expand


def echo(bus: Bus, topic: str, out: IO[str] | None = None) -> None:
    from ..msgs import to_yaml
    from ..ros.node import Node

    name = expand(topic, "llfsm_echo", "/")
    stream = out if out is not None else sys.stdout

    def attach(t: Topic) -> None:
        node = Node.__new__(Node)  # a hidden node: not listed in the graph, not remapped
        node._bus, node._name, node._ns, node._destroyed, node._entities = bus, "llfsm_echo", "/", False, []

        def show(msg: object) -> None:
            stream.write(to_yaml(msg) + "---\n")
            stream.flush()

        node.create_subscription(t.type, name, show, 1000)

    bus.watch(name, attach)
