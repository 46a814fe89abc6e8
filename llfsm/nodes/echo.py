"""`llfsm run --echo TOPIC`: print each message of a topic as YAML, `---` between, like
`ros2 topic echo`.  The reader attaches when the topic first appears (a machine usually
creates its publisher in INITIAL), so no message published on it is missed."""

from __future__ import annotations

import sys
from typing import IO, TYPE_CHECKING

from ..msgs import to_yaml
from ..ros.bus import Bus, Topic
from ..ros.names import expand
from ..ros.node import Node

if TYPE_CHECKING:
    from ..msgs import Message


def echo(bus: Bus, topic: str, out: IO[str] | None = None) -> None:
    name = expand(topic, "llfsm_echo", "/")
    stream = out if out is not None else sys.stdout
    shown = [0]

    def attach(t: Topic) -> None:
        node = Node.__new__(Node)  # a hidden node: not listed in the graph, not remapped
        node._bus, node._name, node._ns, node._destroyed, node._entities = bus, "llfsm_echo", "/", False, []

        def show(msg: Message) -> None:
            shown[0] += 1
            stream.write(to_yaml(msg) + "---\n")
            stream.flush()

        node.create_subscription(t.type, name, show, 1000)

    def silent_topic() -> None:
        """After the run: an --echo that printed nothing says why, instead of looking like a
        topic that was published on and somehow lost."""
        if shown[0]:
            return
        if name in bus.topics:
            why = f"nothing was published on {name} during the run"
        else:
            # deferred: start-up (only an --echo that heard nothing looks for a close name)
            import difflib

            topics = sorted(t for t in bus.topics if not t.startswith("/rosout"))
            close = difflib.get_close_matches(name, topics, n=3, cutoff=0.6)
            hint = f"; did you mean {' or '.join(close)}?" if close else f" (topics: {', '.join(topics) or 'none'})"
            why = f"no node published or subscribed to {name} during the run{hint}"
        sys.stderr.write(f"llfsm: --echo {topic}: {why}\n")

    bus.watch(name, attach)
    bus.ctx.at_end.append(silent_topic)
