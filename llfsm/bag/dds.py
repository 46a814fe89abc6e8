"""`llfsm bag record` and `llfsm bag play` over DDS: bags of what llfsm runs and ROS 2 nodes
say on the network, and bags played back to them, as `ros2 bag record/play` do.

Both run a small bus of their own on the DDS transport (the discovery settings of
`llfsm run --transport dds`: ROS_DOMAIN_ID, ROS_AUTOMATIC_DISCOVERY_RANGE, ...), on the wall
clock, until Ctrl-C (record) or the end of the bag (play).
- record: a node `rosbag2_recorder` subscribes to each topic as its first publisher appears
  (the named topics, or with -a every ROS topic on the graph, found through DDS's built-in
  DCPSPublication topic as rmw finds them) and hands what arrives, stamped with its arrival
  time, to the same recorder and writer process as `--record`.
- play: the `--play` player (node `rosbag2_player`), its publishers on DDS.
"""

from __future__ import annotations

import signal
import time
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING

from .errors import BagError

if TYPE_CHECKING:
    from ..msgs import Message
    from ..ros.bus import Bus, Topic

QUEUE_DEPTH = 1000  # per topic, between two executor passes
SCAN_S = 0.1  # -a: how often the graph is looked at for new topics


class _Session:
    """A bus on the DDS transport, active while the verb runs; Ctrl-C or SIGTERM ends it."""

    def __init__(self) -> None:
        # deferred: start-up (every `llfsm` command imports this module's verbs; only a running verb loads the bus)
        from ..ros.bus import bus_of
        from ..ros.transports import make
        from ..runtime import RunContext, WallClock

        try:
            transport = make("dds")
        except (ImportError, ValueError) as e:
            raise BagError(str(e)) from None
        self.ctx = RunContext(WallClock())
        self.ctx.transport = transport
        self.bus: Bus = bus_of(self.ctx)
        self.bus.initialised = True
        self.stopped = False

    @contextmanager
    def active(self) -> Iterator[None]:
        # deferred: start-up, as in __init__
        from ..runtime.context import activate

        def stop(_signum: int, _frame: object) -> None:
            self.stopped = True

        prev = activate(self.ctx)
        old = {s: signal.signal(s, stop) for s in (signal.SIGINT, signal.SIGTERM)}
        try:
            yield
        finally:
            for s, h in old.items():
                signal.signal(s, h)
            try:
                self.bus.transport.close()
            finally:
                activate(prev)

    def spin(self, until: Callable[[], bool] = lambda: False, duration: float | None = None) -> None:
        end = None if duration is None else time.monotonic() + duration
        while not self.stopped and not until():
            if end is not None and time.monotonic() >= end:
                return
            self.bus.spin_once(20_000_000)


def _all_topics(
    bus: Bus, found: Callable[[str, type[Message]], None], skipped: Callable[[str, str], None]
) -> Callable[[], None]:
    """A scan of DCPSPublication for ROS topics (`rt/...`): found(name, class) once per topic."""
    # deferred: optional dependency (cyclonedds) and start-up, as in _Session
    from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsPublication

    from ..ros.transports.dds_graph import message_class

    dp = bus.transport.dp  # type: ignore[attr-defined]  # the session's bus is on DDS (_Session)
    reader = BuiltinDataReader(dp, BuiltinTopicDcpsPublication)
    seen: set[str] = set()

    def scan() -> None:
        for s in reader.take(N=256):
            dds_name = getattr(s, "topic_name", "") or ""
            if not dds_name.startswith("rt/"):
                continue
            name = dds_name[2:]
            if name in seen or any(part.startswith("_") for part in name.split("/")):
                continue  # hidden topics stay out, as ros2 bag record -a leaves them
            seen.add(name)
            cls = message_class(getattr(s, "type_name", "") or "")
            if cls is None:
                skipped(name, getattr(s, "type_name", "?"))
            else:
                found(name, cls)

    return scan


def record(
    out: str,
    topics: Iterable[str],
    all_topics: bool,
    storage: str = "mcap",
    report: Callable[[str], None] | None = None,
    duration: float | None = None,
) -> str | None:
    """Record until Ctrl-C (or `duration` seconds); the error message if recording failed."""
    # deferred: start-up (`bag play` never loads the recorder, nor `bag record` the player)
    from ..ros.node import Node
    from .recorder import Recorder

    names = [t if t.startswith("/") else "/" + t for t in topics]
    session = _Session()
    recorder = Recorder(out, storage, report=report)
    with session.active():
        bus = session.bus
        recorder.start(bus, tap=False)
        node = Node("rosbag2_recorder")
        subscribed: set[str] = set()

        def subscribe(topic: Topic) -> None:
            if topic.name in subscribed:
                return
            subscribed.add(topic.name)
            deliver = recorder.reader(topic, wall=True)
            if deliver is not None:
                node.create_subscription(topic.type, topic.name, deliver, QUEUE_DEPTH)

        for name in names:
            bus.watch(name, subscribe)
        if all_topics:

            def found(name: str, cls: type[Message]) -> None:
                subscribe(bus.topic(name, cls, "subscribe to"))

            def skipped(name: str, dds_type: str) -> None:
                if report is not None:
                    report(f"bag record: {name} is not recorded: llfsm has no class for its type {dds_type}")

            node.create_timer(SCAN_S, _all_topics(bus, found, skipped))
        session.spin(duration=duration)
    return recorder.close()


def play(
    path: str,
    rate: float = 1.0,
    loop: bool = False,
    topics: Iterable[str] = (),
    delay: float = 0.0,
) -> int:
    """Play the bag to the DDS graph; the number of messages published."""
    # deferred: start-up, as in record
    from .player import Player

    player = Player(path, topics, rate, loop)
    session = _Session()
    with session.active():
        if delay > 0:  # discovery: let subscribers of other processes match first
            session.spin(duration=delay)
        player.attach(session.bus)
        session.spin(until=lambda: player.done)
        session.spin(duration=0.3)  # reliable writers hand over their last samples
    return player.published
