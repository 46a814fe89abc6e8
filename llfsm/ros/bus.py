"""The in-process bus: topics, services, timers and the one executor that dispatches them.

Everything runs on the scheduler's thread.  The executor runs between rounds (registered in
the run context) and inside `spin_once` / `spin_until_future_complete`, always in the same
order (due timers, then queued work first in, first out), so a run under the sim clock is
reproducible byte for byte.

Delivery: publishing copies the message once per reader (so a machine may keep mutating and
re-publishing one object, as the seed machines do); a PULL reader keeps only the newest
message; a PUSH subscription queues up to its QoS depth, dropping the oldest.  A topic's taps
(`Topic.taps`) are the exception: readers that take what they need from the message during
`publish` and keep nothing (a recorder encodes it at once) are handed the message itself,
since a copy would only be thrown away.

The bus delivers within its process itself; the run's transport (transports/) carries traffic
to and from other processes.  With the in-process transport nothing else happens; with DDS the
executor also takes what arrived (`transport.poll`, a cheap check when nothing did) and waits
on it instead of sleeping blindly.
"""

from __future__ import annotations

import heapq
import itertools
import os
import sys
import time
from collections import deque
from collections.abc import Callable
from enum import Enum
from typing import IO, TYPE_CHECKING, Any, cast

from ..runtime.context import RunContext, current
from .names import Remap
from .transports.base import RemoteClient, Transport
from .transports.inproc import InProcess

#: With a remote transport, how often (run time) the executor looks for data from other
#: processes between back-to-back rounds: the look is a cheap status check of one wait set.
POLL_NS = 100_000

if TYPE_CHECKING:
    from ..msgs._message import Message
    from .node import Node, Subscription, Timer


class FutureReturnCode(Enum):
    """What `spin_until_future_complete` returns (rclcpp's names)."""

    SUCCESS = 0
    INTERRUPTED = 1
    TIMEOUT = 2

    def __str__(self) -> str:
        return self.name


class Future:
    """The result of an asynchronous service call (`client.call_async`)."""

    __slots__ = ("_callbacks", "_cancelled", "_done", "_exception", "_remote", "_result", "_service")

    def __init__(self, service: str | None = None, remote: RemoteClient | None = None) -> None:
        self._remote = remote  # the transport's client that sent the request to another process
        self._done = False
        self._cancelled = False
        self._result: Any = None
        self._exception: BaseException | None = None
        self._callbacks: list[Callable[[Future], None]] = []
        self._service = service  # the service the request went to, if any

    def done(self) -> bool:
        return self._done

    def cancelled(self) -> bool:
        return self._cancelled

    def cancel(self) -> None:
        if not self._done:
            self._cancelled = True
            self._finish()

    def result(self) -> Any:
        """The response, or None while not done (rclpy's behaviour); re-raises a server error."""
        if self._exception is not None:
            raise self._exception
        return self._result

    def exception(self) -> BaseException | None:
        return self._exception

    def set_result(self, result: Any) -> None:
        self._result = result
        self._finish()

    def set_exception(self, exc: BaseException) -> None:
        self._exception = exc
        self._finish()

    def add_done_callback(self, fn: Callable[[Future], None]) -> None:
        if self._done:
            fn(self)
        else:
            self._callbacks.append(fn)

    def _finish(self) -> None:
        self._done = True
        callbacks, self._callbacks = self._callbacks, []
        for fn in callbacks:
            fn(self)

    def __repr__(self) -> str:
        state = "cancelled" if self._cancelled else "done" if self._done else "pending"
        return f"<Future {state}{' for ' + self._service if self._service else ''}>"


class Topic:
    """A named channel: its type and the readers attached to it."""

    __slots__ = ("latched", "name", "on_readers", "published", "publishers", "readers", "taps", "type")

    def __init__(self, name: str, type_: type[Message]) -> None:
        self.name = name
        self.type = type_
        self.readers: list[Subscription] = []
        #: Called as fn(msg) with each published message itself, not a copy, while `publish`
        #: runs: for readers that must not keep it (`--record` encodes it there and then).  They
        #: count as subscriptions.
        self.taps: list[Callable[[Message], None]] = []
        self.publishers = 0
        self.published = 0
        #: What TRANSIENT_LOCAL publishers kept for late subscribers: publisher -> last messages.
        self.latched: dict[Any, deque[Message]] = {}
        #: Called as fn(topic, joining) when a subscription is about to join (True) or has left
        #: (False): lets a publisher publish only while someone listens (llfsm.ros.control).
        self.on_readers: list[Callable[[Topic, bool], None]] = []


class _Request:
    """A service request waiting for the executor."""

    __slots__ = ("bus", "future", "request", "service")

    def __init__(self, bus: Bus, service: str, request: Message, future: Future) -> None:
        self.bus, self.service, self.request, self.future = bus, service, request, future

    def _run(self) -> None:
        server = self.bus.services.get(self.service)
        if server is None or self.future.done():
            return  # no server (any more): the future stays pending; spin_until_future_complete says TIMEOUT
        server._serve(self.request, self.future)


class _Call:
    """A function queued from another thread (`Bus.call_soon_threadsafe`)."""

    __slots__ = ("fn",)

    def __init__(self, fn: Callable[[], object]) -> None:
        self.fn = fn

    def _run(self) -> None:
        self.fn()


class Bus:
    """The graph of one run: nodes, topics, services, timers and pending work."""

    def __init__(self, ctx: RunContext) -> None:
        self.ctx = ctx
        self.clock = ctx.clock
        self.initialised = False
        self.shut = False
        self.nodes: list[Node] = []
        self.topics: dict[str, Topic] = {}
        self.services: dict[str, Any] = {}  # name -> node.ServiceServer
        self.clients: dict[str, int] = {}  # service name -> number of clients
        self.timers: list[tuple[int, int, Timer]] = []  # heap of (due ns, sequence, timer)
        self.ready: deque[Any] = deque()  # work items with a _run() method
        self.remaps: list[Remap] = []
        self.parameters: dict[tuple[str | None, str], Any] = {}  # (node or None, name) -> override
        #: Called with each new topic whose name is a key here (`--echo` waits for its topic).
        self.watchers: dict[str, list[Callable[[Topic], None]]] = {}
        #: Called with every topic, those made later too (`add_tap`: `--record` puts its taps on them).
        self.taps: list[Callable[[Topic], None]] = []
        self._seq = itertools.count()
        self.log_to_stdout = os.environ.get("RCUTILS_LOGGING_USE_STDOUT", "0") == "1"
        #: None: whatever sys.stderr (or sys.stdout) is when a line is logged, so that a
        #: redirection made after the bus started is honoured.
        self.log_stream: IO[str] | None = None
        self.transport: Transport = cast("Transport | None", ctx.transport) or InProcess()
        #: The transport's poll when it can bring anything in (never for the in-process one).
        self._poll = self.transport.poll if self.transport.remote else None
        self.transport.start(self)
        ctx.between_rounds.append(self.spin_some)
        if self._poll is not None:
            ctx.wake = 0  # look at the transport after the first round, then every POLL_NS

    # -- lifecycle ---------------------------------------------------------------------------
    def init(self) -> None:
        """Initialise (the first `ros.init()`, or the command line before nodes start); then
        run the run's on-init hooks once (`ctx.on_init`: the machines' state topics
        and control services join the graph with the first node, never in a run without one)."""
        if self.initialised:
            return
        self.initialised = True
        hooks, self.ctx.on_init = self.ctx.on_init, []
        for fn in hooks:
            fn(self)

    def call_soon_threadsafe(self, fn: Callable[[], object]) -> None:
        """Run fn() on the scheduler's thread, between rounds (or inside a spin call), in the
        order of the calls.  The one door for other threads (the web view's server) into the
        bus: deque.append is atomic, and setting the wake time to 0 (one store) makes the
        scheduler spin the executor after its current round."""
        self.queue(_Call(fn))

    def ok(self) -> bool:
        return self.initialised and not self.shut and not self.ctx.interrupted

    # -- topics ------------------------------------------------------------------------------
    def topic(self, name: str, type_: type[Message], role: str) -> Topic:
        t = self.topics.get(name)
        if t is None:
            t = self.topics[name] = Topic(name, type_)
            for fn in self.watchers.pop(name, []):
                fn(t)
            for fn in self.taps:
                fn(t)
        elif t.type is not type_:
            raise TypeError(f"cannot {role} {name} as {type_._TYPE}: the topic already carries {t.type._TYPE}")
        return t

    # -- timers ------------------------------------------------------------------------------
    def add_timer(self, timer: Timer, due: int) -> None:
        heapq.heappush(self.timers, (due, next(self._seq), timer))
        self.ctx.wake_at(due)  # attention: the scheduler spins the executor when it falls due

    def queue(self, work: Any) -> None:
        """Queue work (a subscription with messages, a service request) for the executor."""
        self.ready.append(work)
        self.ctx.wake = 0  # attention: the scheduler spins the executor after this round

    def watch(self, name: str, fn: Callable[[Topic], None]) -> None:
        """Call fn(topic) once the topic exists (now, if it already does), in this process or,
        with a remote transport, once a publisher of it appears in another process."""
        if name in self.topics:
            fn(self.topics[name])
            return
        self.watchers.setdefault(name, []).append(fn)
        if self.transport.remote:

            def found(type_: type[Message]) -> None:
                if name not in self.topics:
                    self.topic(name, type_, "subscribe to")  # calls the watchers

            self.transport.discover(name, found)

    def add_tap(self, fn: Callable[[Topic], None]) -> None:
        """Call fn(topic) for every topic: each existing one now, each new one when it is made.
        A recorder puts its tap in each topic's `Topic.taps` this way (llfsm.bag.recorder)."""
        self.taps.append(fn)
        for t in list(self.topics.values()):
            fn(t)

    def next_timer_due(self) -> int | None:
        while self.timers and self.timers[0][2]._cancelled:
            heapq.heappop(self.timers)
        return self.timers[0][0] if self.timers else None

    def _fire_due_timers(self, now: int) -> bool:
        timers = self.timers
        fired = False
        sim = self.clock.kind == "sim"
        while timers and timers[0][0] <= now:
            due, _seq, timer = heapq.heappop(timers)
            if timer._cancelled or timer._due != due:
                continue
            nxt = due + timer.period_ns
            if not sim and nxt <= now:  # wall clock: skip missed periods, as rcl does
                nxt = now + timer.period_ns - (now - due) % timer.period_ns
            timer._due = nxt
            heapq.heappush(timers, (nxt, next(self._seq), timer))
            self.ctx.wake_at(nxt)
            fired = True
            timer._call()
        return fired

    # -- the executor --------------------------------------------------------------------------
    def spin_some(self) -> None:
        """Between rounds: what arrived from other processes, due timers, then the work queued
        before this call (first in, first out)."""
        if self._poll is not None:
            self._poll(False)
        if self.timers and self.timers[0][0] <= self.clock.now:
            self._fire_due_timers(self.clock.now)
        ready = self.ready
        for _ in range(len(ready)):
            ready.popleft()._run()
        self._rearm()

    def _rearm(self) -> None:
        """Tell the scheduler when the executor has work again (RunContext.wake).  With a
        remote transport, data from other processes arrives without telling anyone: look again
        after POLL_NS of run time (the poll between rounds is a cheap status check)."""
        if self.ready:
            self.ctx.wake = 0
            return
        if self.timers:
            self.ctx.wake_at(self.timers[0][0])
        if self._poll is not None:
            self.ctx.wake_at(self.clock.now + POLL_NS)

    def spin_once(self, timeout_ns: int) -> bool:
        """One piece of work: a due timer, or the oldest queued item; else wait up to timeout_ns
        for the next timer or (with a remote transport) for data from another process (the sim
        clock jumps, the wall clock sleeps).  True if work ran."""
        came = self._poll() if self._poll is not None else False
        now = self.clock.now
        if self.timers and self.timers[0][0] <= now:
            return self._fire_due_timers(now)
        if self.ready:
            self.ready.popleft()._run()
            return True
        if timeout_ns <= 0 or came:
            return came  # something came in (a PULL message, a match): the caller looks first
        due = self.next_timer_due()
        deadline = now + timeout_ns
        if self._poll is not None:
            self.transport.wait(deadline if due is None else min(due, deadline))
            self._poll()
            if self.timers and self.timers[0][0] <= self.clock.now:
                return self._fire_due_timers(self.clock.now)
            if self.ready:
                self.ready.popleft()._run()
                return True
            return False
        if due is None or due > deadline:
            self.clock.sleep_until(deadline)
            return False
        self.clock.sleep_until(due)
        return self._fire_due_timers(self.clock.now)

    def spin_until(self, future: Future, timeout_ns: int | None) -> FutureReturnCode:
        deadline = None if timeout_ns is None else self.clock.now + timeout_ns
        if self.ctx.deadline is not None:
            deadline = self.ctx.deadline if deadline is None else min(deadline, self.ctx.deadline)
        while True:
            if future.done():
                return FutureReturnCode.SUCCESS
            if not self.ok():
                return FutureReturnCode.INTERRUPTED
            remote = future._remote
            if remote is not None:
                if not remote.can_still_answer(future):
                    return FutureReturnCode.TIMEOUT  # no server in any process, or it went away
            elif future._service is not None and future._service not in self.services:
                return FutureReturnCode.TIMEOUT  # no server: nothing in this process can answer
            if self._poll is not None:
                self._poll()
            if self.timers and self.timers[0][0] <= self.clock.now:
                self._fire_due_timers(self.clock.now)
                continue
            if self.ready:
                self.ready.popleft()._run()
                continue
            due = self.next_timer_due()
            if remote is not None:
                # another process may still answer: wait for data, a timer or the deadline,
                # and look again at least every 100 ms (a server that vanished)
                until = self.clock.now + 100_000_000
                for t in (due, deadline):
                    if t is not None:
                        until = min(until, t)
                self.transport.wait(until)
                if deadline is not None and self.clock.now >= deadline and not future.done():
                    self._poll()
                    if not future.done():
                        return FutureReturnCode.TIMEOUT
                continue
            # nothing ready: only a timer can still change anything
            if due is None:
                return FutureReturnCode.TIMEOUT  # would block forever: say so at once
            if deadline is not None and due > deadline:
                self.clock.sleep_until(deadline)
                return FutureReturnCode.TIMEOUT
            self.clock.sleep_until(due)

    # -- services ----------------------------------------------------------------------------
    def call(self, service: str, request: Message) -> Future:
        future = Future(service)
        self.queue(_Request(self, service, request, future))
        return future

    # -- logging -------------------------------------------------------------------------------
    def log_output(self) -> IO[str]:
        if self.log_stream is not None:
            return self.log_stream
        return sys.stdout if self.log_to_stdout else sys.stderr

    def stamp(self) -> tuple[int, int]:
        """Seconds and nanoseconds for log lines: run time under the sim clock, else wall time."""
        ns = self.clock.now if self.clock.kind == "sim" else time.time_ns()
        return divmod(ns, 1_000_000_000)

    # -- introspection ---------------------------------------------------------------------------
    def graph(self) -> dict[str, Any]:
        """Nodes, topics (type, publishers, subscriptions, messages) and services: for the CLI."""
        return {
            "nodes": sorted(n.get_fully_qualified_name() for n in self.nodes if not n._destroyed),
            "topics": {
                name: {
                    "type": t.type._TYPE,
                    "publishers": t.publishers,
                    "subscriptions": len(t.readers) + len(t.taps),
                    "messages": t.published,
                }
                for name, t in sorted(self.topics.items())
            },
            "services": {name: s.type._TYPE for name, s in sorted(self.services.items())},
        }


def bus_of(ctx: RunContext | None = None) -> Bus:
    """The bus of the active run (made on first use)."""
    ctx = ctx if ctx is not None else current()
    bus = cast("Bus | None", ctx.bus)  # the context holds what this made, typed as the runtime sees it
    if bus is None:
        bus = ctx.bus = Bus(ctx)
    return bus
