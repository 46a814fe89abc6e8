"""`--play`: a bag's messages published into a run at their recorded times.

A node (`rosbag2_player`, as `ros2 bag play` names its node) publishes on each played topic.
A timer on the run clock publishes every message whose time has come, at the first executor
pass at or after it.  Times are taken relative to the bag's first message (as `ros2 bag play`
does) and divided by the rate; a bag llfsm recorded under `--clock sim` says so in its
custom_data, and its times, which are run times, are kept as they are.  So record -> play ->
record under the sim clock gives the same messages at the same times, and what nodes published
from the executor (teleop, turtlesim) is replayed exactly where it happened.  What a machine
published during a round is replayed at the executor pass before that round (one period
earlier for callbacks, the same round for PULL readers).

Types: llfsm's class when it has one; otherwise the class is compiled from the definition the
bag embeds (see `typesupport.class_from_definition`), or the bag is refused naming the type.
Everything is checked before the run starts.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

from ..suggest import did_you_mean
from .errors import BagError
from .reader import BagReader
from .recorder import SIM_CLOCK_KEY
from .typesupport import TypeSupport, class_from_definition, scratch_folder

if TYPE_CHECKING:
    from ..msgs import Message
    from ..ros.bus import Bus

NODE_NAME = "rosbag2_player"


def _format_name(fmt: Any) -> str:
    name = getattr(fmt, "name", str(fmt)).upper()
    return {"MSG": "ros2msg", "IDL": "ros2idl"}.get(name, "")


class Player:
    """The messages of one bag, ready to be published into a run."""

    def __init__(self, path: str, topics: Iterable[str] = (), rate: float = 1.0, loop: bool = False) -> None:
        if not rate > 0:
            raise BagError(f"the play rate must be greater than 0, not {rate:g}")
        self.path = path
        self.rate = rate
        self.loop = loop
        wanted = {t if t.startswith("/") else "/" + t for t in topics}
        types = TypeSupport()
        folder = None
        with BagReader(path) as reader:
            conns = [c for c in reader.connections if not wanted or c.topic in wanted]
            missing = wanted - {c.topic for c in reader.connections}
            if missing:
                first = sorted(missing)[0]
                hint = did_you_mean(first, {c.topic for c in reader.connections})
                raise BagError(f"{path}: the bag has no topic {', '.join(sorted(missing))}{hint}")
            self.topics: dict[str, type[Message]] = {}
            decoders: dict[int, Any] = {}
            for c in conns:
                known = self.topics.get(c.topic)
                if known is not None:
                    if c.msgtype != known._TYPE:
                        raise BagError(f"{path}: {c.topic} carries two types, {known._TYPE} and {c.msgtype}")
                    decoders[c.id] = decoders[next(x.id for x in conns if x.topic == c.topic)]
                    continue
                if folder is None:
                    folder = scratch_folder()
                try:
                    cls = class_from_definition(c.msgtype, _format_name(c.msgdef.format), c.msgdef.data or "", folder)
                except BagError as e:  # the type's names and definition come from the bag: say which bag
                    raise BagError(f"{path}: {e}") from None
                self.topics[c.topic] = cls
                decoders[c.id] = types.deserializer(cls)
            # a bag llfsm recorded under the sim clock holds run times: they stay as they are
            # (so record -> play -> record gives the same bag); any other bag starts at once
            start = 0 if reader.custom_data.get(SIM_CLOCK_KEY) == "sim" else reader.start_time
            self.messages: list[tuple[int, str, Any]] = []
            if conns:  # decoded now: a damaged message is refused before the run starts
                for c, t, data in reader.messages(conns):
                    try:
                        msg = decoders[c.id](data)
                    except Exception as e:
                        raise BagError(
                            f"{path}: a {c.msgtype} message on {c.topic} (at {t} ns) cannot be decoded: {e}"
                        ) from None
                    self.messages.append((t - start, c.topic, msg))
        self.length = self.messages[-1][0] if self.messages else 0
        self._next = 0
        self._offset = 0  # run time at which the current pass over the bag began
        self._publishers: dict[str, Any] = {}
        self.published = 0

    def attach(self, bus: Bus) -> None:
        """Create the player's node, publishers and timer on the bus of a run."""
        # deferred: start-up (the player reads its bag before the run's bus exists; only attaching needs the bus)
        from ..ros.node import Node
        from ..runtime.context import activate

        prev = activate(bus.ctx)
        try:
            bus.initialised = True  # like the --node nodes: the player is up before the first round
            node = Node(NODE_NAME)
            for topic, cls in self.topics.items():
                try:
                    self._publishers[topic] = node.create_publisher(cls, topic, 10)
                except (TypeError, ValueError) as e:  # the run already has the topic with another type
                    raise BagError(f"{self.path}: {topic} cannot be played into this run: {e}") from None
            clock = bus.clock
            period = getattr(clock, "period", None) if clock.kind == "sim" else None
            self._offset = clock.now
            node.create_timer((period or 1_000_000) / 1e9, self._tick)
            self._clock = clock
        finally:
            activate(prev)

    def _due(self, i: int) -> int:
        return self._offset + round(self.messages[i][0] / self.rate)

    def _tick(self) -> None:
        now = self._clock.now
        msgs = self.messages
        while True:
            while self._next < len(msgs) and self._due(self._next) <= now:
                _rel, topic, msg = msgs[self._next]
                self._publishers[topic].publish(msg)
                self._next += 1
                self.published += 1
            if self._next < len(msgs) or not self.loop or not msgs:
                return
            self._next = 0  # --loop: start over once the last message is out
            self._offset = now

    @property
    def done(self) -> bool:
        return self._next >= len(self.messages) and not self.loop
