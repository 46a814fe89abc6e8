"""`--record`: a bus subscriber that sees every topic and writes a rosbag2 bag beside the run.

The recorder taps the bus (`Bus.add_tap`): a tap on every topic (`Topic.taps`), those that exist
and those made later, like `ros2 bag record -a`.  (On the DDS transport it subscribes to each
topic instead, so that what other processes publish is recorded too.)  A tap is handed the
published message itself, not the copy a subscription gets: its encoding is the snapshot.
Delivery costs the round one C call where the message has a fixed size (a Twist, a Pose: the
tap of llfsm/bag/_tap.c reads the message's slots and appends the pipe record, head and CDR, to
the recorder's Spool; where the C part is not built, the generated `_stamped_<Name>` does the
same with one `struct.pack`), or the message's CDR encoding, the head (one more pack) and an
extend of the Spool where it does not.  Whole records only are appended, so that a run
stopped by a signal mid-message leaves none half-written: no object waits per message, and
nothing else happens per message in this process.  A thread of the run takes what the Spool
holds in batches and writes it to the bag writer process (`_writer_process`), which writes the
bag on another core: neither the disk nor the storage libraries hold up a round.
A topic is described to the writer (definition, type hash, QoS) once, by the thread; the
writer makes its connection when the topic's first message comes, so connections and their
ids follow the order of first messages, as the same run always has them.  The thread holds
the interpreter only to take the bytes waiting (one C call and one copy, nothing per
message); it writes with the GIL released, and the writer process runs at a lower priority
than the run.

Timestamps are the run clock under `--clock sim` (nanoseconds from the start of the run: two
runs give the same bag, byte for byte) and the wall clock (nanoseconds since the epoch)
otherwise, as rosbag2 stamps messages with their arrival time.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
import time
from typing import IO, TYPE_CHECKING, Any

from ._writer_process import FRAME, RECORD
from .errors import BagError
from .typesupport import Spool, TypeSupport, loaded_message_classes, preload_native
from .writer import qos_profile

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable

    from ..ros.bus import Bus, Topic

SIM_CLOCK_KEY = "llfsm.clock"  # in the bag's custom_data
BATCH_S = 0.05  # how often the thread takes the records waiting
# The thread takes all the bytes waiting and writes them in frames of at most this many:
# writing to the pipe releases the GIL (and waits there while the writer process is behind).
PIECE = 1 << 20  # bytes
CHUNK_S = 1.0  # wall clock: end the MCAP chunk in progress this often, so the file keeps up
START_TIMEOUT_S = 60.0
# Under the sim clock a run may make messages faster than any writer stores them (rounds back
# to back): past this many bytes waiting (the buffer and the batch being piped), the run waits
# for the writer before its next round, so memory stays bounded.  Under the wall clock the
# run never waits (a bus would have to pass ~250,000 messages a second of real time).
HIGH_WATER = 256 << 20  # bytes
CHECK_NS = 100_000_000  # run time between two looks at the bytes waiting (sim clock)
QUEUE_DEPTH = 1000  # a subscription's queue between two executor passes (DDS)


class _WallClock:
    """`now` in wall-clock nanoseconds since the epoch, for a generated record function that
    reads `clock.now` (the sim clock's own attribute)."""

    __slots__ = ()

    @property
    def now(self) -> int:
        return time.time_ns()


_WALL = _WallClock()
#: The recorder's node while it is being made (its own topics appear then, and wait).
_MAKING = object()


class Recorder:
    """Records the topics of one bus into one bag."""

    def __init__(
        self,
        path: str,
        storage: str = "mcap",
        topics: Iterable[str] = (),
        *,
        report: Callable[[str], None] | None = None,
    ) -> None:
        self.selected = {t if t.startswith("/") else "/" + t for t in topics} or None
        self.path = path
        self.types = TypeSupport()
        # the messages' pipe records (RECORD header, CDR bytes), appended by the run's thread,
        # taken whole by the sending thread: each append and each take is one C call, atomic
        # under the GIL (and cheap: no object per message).
        self.records = Spool()
        self._ids: dict[Topic, int] = {}
        #: Topics the writer has not heard of, with their publishers' offered QoS when it was taken
        #: on the scheduler's thread (None: the sending thread takes it).
        self._undescribed: list[tuple[int, Topic, list[dict[str, Any]] | None]] = []
        self.clock: Any = None
        self.wall = True
        self.error: str | None = None
        self.count: int | None = None  # messages in the closed bag
        self._report = report
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._listener: threading.Thread | None = None
        self._taps: list[tuple[Topic, Callable[[Any], None]]] = []
        #: Tapped topics that have had no message yet (described when the first comes, or at the end).
        self._first: dict[Topic, int] = {}
        self._bus: Bus | None = None
        self._started = False
        self._node: Any = None  # with a remote transport: the recorder's node and subscriptions
        self._pending: list[Topic] = []  # topics that appeared while that node was being made
        # the writer runs this same llfsm, installed or not
        root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
        env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in (root, os.environ.get("PYTHONPATH")) if p))
        self._proc = subprocess.Popen(
            [sys.executable, "-m", "llfsm.bag._writer_process", os.fspath(path), storage],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            env=env,
        )
        assert self._proc.stdin is not None and self._proc.stdout is not None
        self._pipe: IO[bytes] = self._proc.stdin
        # loaded while the writer starts: before the first round, not mid-run
        self.types.store  # noqa: B018
        preload_native(loaded_message_classes())
        first = self._proc.stdout.readline()
        reply = json.loads(first) if first else {"error": "the bag writer did not start"}
        if "error" in reply:
            self._proc.wait(START_TIMEOUT_S)
            raise BagError(reply["error"])
        self._replies: list[dict[str, Any]] = []
        self.high_water = HIGH_WATER
        self._in_flight = 0  # bytes of the batch the sending thread is piping
        self.waited = 0  # times the run waited for the writer (sim clock)
        self._ctx: Any = None

    # -- the run's side ------------------------------------------------------------------------
    def attach(self, bus: Bus) -> None:
        """Tap every topic of the bus (from now on) and start the sending thread."""
        self.start(bus, tap=True)

    def start(self, bus: Bus, tap: bool) -> None:
        """Start the sending thread; with `tap`, record every topic of the bus.  Without it,
        whoever subscribes with `reader(topic)` decides (`llfsm bag record`)."""
        self.clock = bus.clock
        self.wall = bus.clock.kind != "sim"
        if not self.wall:  # the times are run times: --play keeps them as they are
            self._send(b"X", json.dumps({SIM_CLOCK_KEY: "sim"}).encode())
        if tap:
            self._bus = bus
            bus.add_tap(self._on_topic)
        if not self.wall:
            self._ctx = bus.ctx
            self._ctx.between_rounds.append(self._backpressure)
            self._ctx.wake_at(bus.clock.now + CHECK_NS)
        self._started = True
        self._listener = threading.Thread(target=self._listen, name="llfsm-bag-replies", daemon=True)
        self._listener.start()
        self._thread = threading.Thread(target=self._run, name="llfsm-bag-sender", daemon=True)
        self._thread.start()

    def _on_topic(self, topic: Topic) -> None:
        if self.selected is not None and topic.name not in self.selected:
            return
        if not self._started:  # before the first round: the definition now, not mid-run
            try:
                self.types.definition(topic.type._TYPE)
            except BagError:
                pass  # said when its first message comes
        if self._bus is not None and self._bus.transport.remote:
            self._subscribe(topic)
            return
        deliver = self.reader(topic, wall=self.wall, described=False)
        if deliver is None:
            return
        key = self._ids[topic]
        # a transient-local topic that was there before the recorder (the --node nodes start
        # first): what its publishers keep is recorded now, as rosbag2's subscription, which
        # takes the durability offered, gets it (turtlesim's first /rosout lines)
        kept = [msg for msgs in list(topic.latched.values()) for msg in list(msgs)]
        if kept:
            self._undescribed.append((key, topic, self._offered(topic)))
            for msg in kept:
                deliver(msg)
            topic.taps.append(deliver)
            self._taps.append((topic, deliver))
            return

        def first(msg: Any) -> None:
            """The topic's first message: its publishers' QoS is taken now, on the scheduler's
            thread, so that the bag is the same whenever the sending thread describes it (under
            the sim clock, byte for byte); then the plain tap takes its place."""
            self._undescribed.append((key, topic, self._offered(topic)))
            self._first.pop(topic, None)
            taps = topic.taps
            if first in taps:
                taps[taps.index(first)] = deliver
            deliver(msg)

        topic.taps.append(first)
        self._first[topic] = key
        self._taps += [(topic, first), (topic, deliver)]

    def _subscribe(self, topic: Topic) -> None:
        """With a transport that reaches other processes (DDS), a tap would see only what this
        process publishes: the recorder subscribes instead, as any subscriber, and hears both."""
        # deferred: start-up (the recorder is made before the run's bus exists; only attaching needs the bus)
        from ..ros.node import Node
        from ..runtime.context import activate

        assert self._bus is not None
        if self._node is _MAKING:  # the node's own topics (its /rosout) appear while it is made
            self._pending.append(topic)
            return
        prev = activate(self._bus.ctx)
        try:
            if self._node is None:
                self._node = _MAKING
                try:
                    self._node = Node("rosbag2_recorder")
                except BaseException:
                    self._node = None
                    raise
                for pending in self._pending:
                    self._subscribe(pending)
                self._pending.clear()
            deliver = self.reader(topic, wall=True)
            if deliver is not None:
                self._node.create_subscription(topic.type, topic.name, deliver, QUEUE_DEPTH)
        finally:
            activate(prev)

    def reader(self, topic: Topic, wall: bool, described: bool = True) -> Callable[[Any], None] | None:
        """What records a message of `topic` (a tap, or a subscription's callback), stamped with
        the wall clock or the run clock; None (said) if its type cannot be encoded.  The first
        reader of a topic gives it its id in the pipe and, unless the caller describes the
        topic itself (`described=False`), queues it to be described."""
        try:
            cdr = self.types.serializer(topic.type)
        except BagError as e:
            self._say(f"--record: {topic.name} is not recorded: {e}")
            return None
        key = self._ids.get(topic)
        if key is None:
            key = self._ids[topic] = len(self._ids) + 1
            if described:
                self._undescribed.append((key, topic, None))
        clock = _WALL if wall else self.clock  # either has the time in `now`
        stamped = self.types.stamped(topic.type)
        if stamped is not None:  # a fixed-size message: head and CDR at once
            return stamped(self.records, key, clock)
        extend = self.records.extend
        pack = RECORD.pack

        def deliver(msg: Any) -> None:
            data = cdr(msg)
            extend(pack(key, clock.now, len(data)) + data)

        return deliver

    def _backpressure(self) -> None:
        """Between rounds (sim clock): wait while more than `high_water` bytes are waiting for
        the writer.  The bag is the same either way; only the wall time of the run changes."""
        thread, ctx = self._thread, self._ctx
        if len(self.records) + self._in_flight > self.high_water and thread is not None:
            self.waited += 1
            while (
                len(self.records) + self._in_flight > self.high_water // 2
                and thread.is_alive()
                and self.error is None
                and not ctx.interrupted  # Ctrl-C: the run ends now, the bag is closed after it
            ):
                time.sleep(0.002)  # the sending thread pipes meanwhile (it needs the GIL too)
        ctx.wake_at(self.clock.now + CHECK_NS)

    # -- the sending thread -------------------------------------------------------------------------
    def _send(self, kind: bytes, payload: bytes | memoryview) -> None:
        self._pipe.write(FRAME.pack(kind, len(payload)))
        self._pipe.write(payload)

    def _run(self) -> None:
        last_chunk = time.monotonic()
        try:
            while True:
                stopping = self._stop.wait(BATCH_S)  # a batch every BATCH_S; everything at the end
                self._drain()
                now = time.monotonic()
                end_chunk = self.wall and now - last_chunk >= CHUNK_S
                if end_chunk:
                    last_chunk = now
                self._send(b"S", b"\x01" if end_chunk else b"\x00")
                self._pipe.flush()
                if stopping:
                    return
        except (BrokenPipeError, OSError, ValueError):
            self._detach()  # the writer has gone (its reply says why)

    def _drain(self) -> None:
        """Send every byte waiting, taken all at once (one copy), in pieces of the one copy."""
        records = self.records
        self._in_flight = len(records)  # counted before the take, so the run never misses these bytes
        batch = memoryview(records.take())
        n = self._in_flight = len(batch)
        # after taking the batch: every topic with a record in it is in the list by now
        if self._undescribed:
            self._describe()
        try:
            for i in range(0, n, PIECE):
                self._send(b"M", batch[i : i + PIECE])
                self._in_flight = n - i - PIECE
        finally:
            self._in_flight = 0

    def _describe(self) -> None:
        """Tell the writer about the topics it has not heard of (before their records)."""
        todo = self._undescribed[:]
        del self._undescribed[: len(todo)]
        for key, topic, offered in todo:
            info: dict[str, Any] = {"id": key, "topic": topic.name, "type": topic.type._TYPE}
            try:
                definition, type_hash = self.types.definition(topic.type._TYPE)
            except BagError as e:  # said by the writer when the first message comes, if one does
                info["error"] = f"--record: {topic.name} is not recorded: {e}"
            else:
                qos = offered if offered is not None else self._offered(topic)
                info.update(definition=definition, hash=type_hash, qos=qos)
            self._send(b"T", json.dumps(info).encode())

    def _offered(self, topic: Topic) -> list[dict[str, Any]]:
        """Each publisher's offered QoS, as rosbag2 records what discovery reports: its
        reliability and durability (a best-effort sensor topic is replayed best effort)."""
        # deferred: start-up, as in _subscribe
        from ..ros.publisher import Publisher
        from ..ros.qos import ReliabilityPolicy

        bus = self._bus
        pubs = []
        if bus is not None:  # a snapshot: this runs on the sending thread
            pubs = [
                e
                for n in list(bus.nodes)
                for e in list(n._entities)
                if isinstance(e, Publisher) and e._topic is topic and not e._destroyed
            ]
        if not pubs:
            return [qos_profile() for _ in range(max(1, topic.publishers))]
        return [
            qos_profile(
                durability="transient_local" if p.transient_local else "volatile",
                reliability="best_effort" if p.reliability == ReliabilityPolicy.BEST_EFFORT else "reliable",
            )
            for p in pubs
        ]

    # -- replies -------------------------------------------------------------------------------------
    def _listen(self) -> None:
        out = self._proc.stdout
        assert out is not None
        for line in out:
            try:
                reply = json.loads(line)
            except ValueError:
                continue
            self._replies.append(reply)
            if "error" in reply and self.error is None:
                self.error = f"--record: {reply['error']}"
                self._detach()
                self._say(self.error)
            elif "count" in reply:
                self.count = int(reply["count"])
            elif "warning" in reply:
                self._say(str(reply["warning"]))

    def _say(self, text: str) -> None:
        if self._report is not None:
            self._report(text)

    def _detach(self) -> None:
        for topic, tap in list(self._taps):
            if tap in topic.taps:
                topic.taps.remove(tap)
        self._taps.clear()
        self.records.take()  # dropped: the writer has gone

    # -- the end -----------------------------------------------------------------------------------
    def close(self) -> str | None:
        """Send what is waiting, close the bag and wait for the writer.  Returns the error
        message if recording failed (it was reported when it happened), else None."""
        if self._ctx is not None and self._backpressure in self._ctx.between_rounds:
            self._ctx.between_rounds.remove(self._backpressure)
        for topic, key in sorted(self._first.items(), key=lambda item: item[1]):  # listed with no messages
            self._undescribed.append((key, topic, self._offered(topic)))
        self._first.clear()
        if self._thread is not None:
            self._stop.set()
            self._thread.join()
            self._thread = None
        self._detach()
        try:
            self._send(b"C", b"")
            self._pipe.close()
        except (BrokenPipeError, OSError, ValueError):
            pass
        self._proc.wait()
        if self._listener is not None:
            self._listener.join()
        else:  # never attached: read the closing reply here
            assert self._proc.stdout is not None
            for line in self._proc.stdout:
                reply = json.loads(line)
                if "error" in reply and self.error is None:
                    self.error = f"--record: {reply['error']}"
                    self._say(self.error)
        if self.error is None and self.count is None and self._proc.returncode != 0:
            self.error = f"--record: the bag writer stopped unexpectedly (status {self._proc.returncode})"
            self._say(self.error)
        return self.error
