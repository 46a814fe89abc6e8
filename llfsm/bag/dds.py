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
    from typing import Any

    from ..msgs import Message
    from ..progress import Status
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

    def spin(
        self,
        until: Callable[[], bool] = lambda: False,
        duration: float | None = None,
        tick: Callable[[], None] | None = None,
    ) -> None:
        """Spin until `until()`, `duration` seconds or Ctrl-C; `tick()` after each pass (the
        status line of a terminal, which throttles itself)."""
        end = None if duration is None else time.monotonic() + duration
        while not self.stopped and not until():
            if end is not None and time.monotonic() >= end:
                return
            self.bus.spin_once(20_000_000)
            if tick is not None:
                tick()


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
    status: Status | None = None,
) -> str | None:
    """Record until Ctrl-C (or `duration` seconds); the error message if recording failed.
    `status` (a terminal's) shows what is being recorded: the topics and their counts."""
    # deferred: start-up (`bag play` never loads the recorder, nor `bag record` the player)
    from ..ros.node import Node
    from .recorder import Recorder

    names = [t if t.startswith("/") else "/" + t for t in topics]
    session = _Session()
    recorder = Recorder(out, storage, report=report)
    counts: dict[str, int] = {}
    started = time.monotonic()
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
                if status is not None and status.enabled:
                    deliver = _counted(deliver, counts, topic.name)
                node.create_subscription(topic.type, topic.name, deliver, QUEUE_DEPTH)

        for name in names:
            bus.watch(name, subscribe)
        if all_topics:

            def found(name: str, cls: type[Message]) -> None:
                subscribe(bus.topic(name, cls, "subscribe to"))

            def skipped(name: str, dds_type: str) -> None:
                # deferred: start-up (only a topic llfsm cannot record needs its type's ROS name)
                from ..ros.transports.dds_graph import message_type

                if report is not None:  # the type as ROS names it (pkg/msg/Name), not in its DDS form
                    report(
                        f"bag record: {name} is not recorded: llfsm has no class for its type "
                        f"{message_type(dds_type)} (the messages llfsm ships, or a package of yours "
                        "in LLFSM_INTERFACE_PATH or share/ of AMENT_PREFIX_PATH)"
                    )

            node.create_timer(SCAN_S, _all_topics(bus, found, skipped))

        def tick() -> None:
            assert status is not None
            status.show(_recording(out, names, all_topics, counts, time.monotonic() - started))

        session.spin(duration=duration, tick=tick if status is not None and status.enabled else None)
        if status is not None:
            status.clear()
    return recorder.close()


def _counted(deliver: Callable[[Any], None], counts: dict[str, int], name: str) -> Callable[[Any], None]:
    """`deliver`, counting the messages of `name` for the status line (a terminal's only)."""
    counts[name] = 0

    def counting(msg: Any) -> None:
        counts[name] += 1
        deliver(msg)

    return counting


def _recording(out: str, names: list[str], all_topics: bool, counts: dict[str, int], elapsed: float) -> str:
    """`recording 2 topics to DIR: 120 messages (/a 60, /b 60), 12 s`, or what it waits for."""
    from ..progress import seconds  # deferred: start-up (a status line is drawn on a terminal only)

    if not counts:
        what = "any topic" if all_topics else ", ".join(names)
        return f"recording to {out}: waiting for {what} to be published, {seconds(elapsed)}"
    total = sum(counts.values())
    n = len(counts)
    each = ", ".join(f"{t} {c}" for t, c in sorted(counts.items()))
    return (
        f"recording {n} topic{'s' if n != 1 else ''} to {out}: {total} message{'s' if total != 1 else ''} "
        f"({each}), {seconds(elapsed)}"
    )


def play(
    path: str,
    rate: float = 1.0,
    loop: bool = False,
    topics: Iterable[str] = (),
    delay: float = 0.0,
    status: Status | None = None,
) -> int:
    """Play the bag to the DDS graph; the number of messages published.  `status` (a
    terminal's) shows how far it is: messages and bag time."""
    # deferred: start-up, as in record
    from ..progress import seconds
    from .player import Player

    player = Player(path, topics, rate, loop)
    session = _Session()
    total = len(player.messages)
    length = player.length / 1e9
    with session.active():
        if delay > 0:  # discovery: let subscribers of other processes match first
            started = time.monotonic()

            def waiting() -> None:
                assert status is not None
                status.show(f"playing {path}: starting in {seconds(delay - (time.monotonic() - started))}")

            session.spin(duration=delay, tick=waiting if status is not None and status.enabled else None)
        player.attach(session.bus)
        started = time.monotonic()

        def tick() -> None:
            assert status is not None
            at = min(length, (time.monotonic() - started) * rate) if not loop else (time.monotonic() - started) * rate
            status.show(f"playing {path}: {player.published} of {total} messages, {at:.1f} s of {length:.1f} s")

        session.spin(until=lambda: player.done, tick=tick if status is not None and status.enabled else None)
        session.spin(duration=0.3)  # reliable writers hand over their last samples
        if status is not None:
            status.clear()
    return player.published
