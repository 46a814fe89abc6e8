"""`--record`: a bus subscriber that sees every topic and writes a rosbag2 bag beside the run.

The recorder is a tap on the bus (`Bus.add_tap`): a reader on every topic, those that exist and
those made later, like `ros2 bag record -a`.  Delivery costs the round one append of
(time, topic, message) to a queue; the message is the copy the bus makes for each reader, so
nobody changes it afterwards.  A writer thread serialises the queued messages to CDR and
writes them in batches, in short slices with pauses while the run is busy, so neither a slow
disk nor the writing itself holds up the rounds (bench/bag.py measures it).

Timestamps are the run clock under `--clock sim` (nanoseconds from the start of the run: two
runs give the same bag, byte for byte) and the wall clock (nanoseconds since the epoch)
otherwise, as rosbag2 stamps messages with their arrival time.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from typing import TYPE_CHECKING, Any

from .errors import BagError
from .typesupport import TypeSupport
from .writer import BagWriter, qos_profile

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable

    from ..ros.bus import Bus, Topic

SIM_CLOCK_KEY = "llfsm.clock"  # in the bag's custom_data
BATCH_S = 0.05  # how often an idle writer thread looks at the queue
# The writer works in slices and pauses between them while a backlog lasts: in a busy run,
# Python's GIL lets one thread run at a time, and the rounds keep most of it (the writer gets
# back a slice of 0.5 ms per pause and switch interval, 2 + 5 ms); whatever is left is written when the run
# sleeps between rounds, or after the last round.
SLICE_S = 0.0005
PAUSE_S = 0.002
CHUNK_S = 1.0  # wall clock: end the MCAP chunk in progress this often, so the file keeps up


class _Tap:
    """The recorder's reader on one topic: what `Publisher.publish` hands a copy to."""

    __slots__ = ("_clock", "_queue", "_wall", "key")

    def __init__(self, recorder: Recorder, topic: Topic) -> None:
        self._queue = recorder.queue
        self._clock = recorder.clock
        self._wall = recorder.wall
        self.key = topic

    def _deliver(self, msg: Any) -> None:
        self._queue.append((time.time_ns() if self._wall else self._clock.now, self.key, msg))


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
        self.writer = BagWriter(path, storage)
        self.types = TypeSupport()
        self.types.store  # noqa: B018  (loaded now, before the first round, not by the writer mid-run)
        self.queue: deque[tuple[int, Topic, Any]] = deque()
        self.clock: Any = None
        self.wall = True
        self.error: str | None = None
        self.skipped: dict[str, str] = {}  # topic -> why it is not in the bag
        self._report = report
        self._conns: dict[Topic, Any] = {}
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._taps: list[tuple[Topic, _Tap]] = []

    # -- the run's side ------------------------------------------------------------------------
    def attach(self, bus: Bus) -> None:
        """Tap every topic of the bus (from now on) and start the writer thread."""
        self.clock = bus.clock
        self.wall = bus.clock.kind != "sim"
        if not self.wall:  # the times are run times: --play keeps them as they are
            self.writer.custom[SIM_CLOCK_KEY] = "sim"
        bus.add_tap(self._on_topic)
        self._thread = threading.Thread(target=self._run, name="llfsm-bag-writer", daemon=True)
        self._thread.start()

    def _on_topic(self, topic: Topic) -> None:
        if self.selected is not None and topic.name not in self.selected:
            return
        tap = _Tap(self, topic)
        topic.readers.append(tap)  # type: ignore[arg-type]  # a reader as far as publish() is concerned
        self._taps.append((topic, tap))

    # -- the writer thread -------------------------------------------------------------------------
    def _run(self) -> None:
        last_chunk = time.monotonic()
        while True:
            stopping = self._stop.wait(BATCH_S)  # a batch every BATCH_S; everything at the end
            try:
                while True:
                    more = self._drain(final=stopping)
                    now = time.monotonic()
                    end_chunk = self.wall and now - last_chunk >= CHUNK_S
                    if end_chunk:
                        last_chunk = now
                    if not more or end_chunk:
                        self.writer.sync(end_chunk)
                    if not more:
                        break
                    time.sleep(PAUSE_S)  # rounds first: a busy run keeps most of the interpreter
            except Exception as e:  # a full disk above all; whatever it is, the bag is closed around it
                self._failed(e)
                return
            if stopping:
                return

    def _drain(self, final: bool) -> bool:
        """Write queued messages: all of them at the end, else about SLICE_S worth.  True if
        some are left."""
        queue, writer, conns = self.queue, self.writer, self._conns
        clock = time.perf_counter
        deadline = clock() + SLICE_S
        k = 0
        while queue:
            t, topic, msg = queue.popleft()
            entry = conns.get(topic)
            if entry is None:
                entry = conns[topic] = self._connection(topic)
            if entry is not False:
                conn, serialize = entry
                writer.write(conn, t, serialize(msg))
            k += 1
            if not final and k % 32 == 0 and clock() > deadline:
                return bool(queue)
        return False

    def _connection(self, topic: Topic) -> Any:
        try:
            definition, type_hash = self.types.definition(topic.type._TYPE)
            serialize = self.types.serializer(topic.type)
        except BagError as e:
            self.skipped[topic.name] = str(e)
            self._say(f"--record: {topic.name} is not recorded: {e}")
            return False
        qos = [qos_profile() for _ in range(max(1, topic.publishers))]
        return self.writer.connection(topic.name, topic.type._TYPE, definition, type_hash, qos), serialize

    def _failed(self, e: BaseException) -> None:
        self._detach()
        try:
            self.writer.fail(e)
        except BagError as err:
            self.error = f"--record: {err}"
        self._say(self.error or f"--record: {e}")

    def _say(self, text: str) -> None:
        if self._report is not None:
            self._report(text)

    def _detach(self) -> None:
        for topic, tap in self._taps:
            try:
                topic.readers.remove(tap)  # type: ignore[arg-type]
            except ValueError:
                pass
        self._taps.clear()
        self.queue.clear()

    # -- the end -----------------------------------------------------------------------------------
    def close(self) -> str | None:
        """Write what is queued and close the bag.  Returns the error message, if recording
        failed (it was reported when it happened), else None."""
        if self._thread is not None:
            self._stop.set()
            self._thread.join()
            self._thread = None
        if self.error is not None:
            return self.error
        self._detach_quietly()
        try:
            self.writer.close()
        except BagError as e:
            self.error = f"--record: {e}"
            self._say(self.error)
        return self.error

    def _detach_quietly(self) -> None:
        for topic, tap in self._taps:
            if tap in topic.readers:
                topic.readers.remove(tap)  # type: ignore[arg-type]
        self._taps.clear()
