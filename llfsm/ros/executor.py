"""The executor, as `rclpy.executors`: timers and queued work, run in one fixed order.

Everything runs on the scheduler's thread.  The executor runs between rounds (registered in
the run context) and inside `spin_once` / `spin_until_future_complete`, always in the same
order (due timers, then queued work first in, first out), so a run under the sim clock is
reproducible byte for byte.  With a remote transport it also takes what arrived from other
processes (`transport.poll`, a cheap check when nothing did) and waits on it instead of
sleeping blindly.  See docs/bus.md (Spinning, Timers, Determinism).

The bus (bus.py) is the executor of its run plus the graph it keeps (nodes, topics, services):
one object, so the scheduler's hook between rounds and a subscription's `queue` stay one call.
"""

from __future__ import annotations

import heapq
import itertools
from collections import deque
from collections.abc import Callable
from enum import Enum
from typing import TYPE_CHECKING, Protocol

from .task import Future

if TYPE_CHECKING:
    from ..runtime.clock import Clock
    from ..runtime.context import RunContext
    from .transports.base import ServiceView, Transport, Work

#: With a remote transport, how often (run time) the executor looks for data from other
#: processes between back-to-back rounds: the look is a cheap status check of one wait set.
POLL_NS = 100_000


class FutureReturnCode(Enum):
    """What `spin_until_future_complete` returns (rclcpp's names)."""

    SUCCESS = 0
    INTERRUPTED = 1
    TIMEOUT = 2

    def __str__(self) -> str:
        return self.name


class TimerEntry(Protocol):
    """A timer as the executor keeps it in its heap (llfsm.ros.timer.Timer)."""

    _due: int
    period_ns: int

    @property
    def _cancelled(self) -> bool: ...

    def _call(self) -> None: ...


class _Call:
    """A function queued from another thread (`Executor.call_soon_threadsafe`)."""

    __slots__ = ("fn",)

    def __init__(self, fn: Callable[[], object]) -> None:
        self.fn = fn

    def _run(self) -> None:
        self.fn()


class Executor:
    """Timers and queued work of one run, and when to run them; the bus (bus.py) is one."""

    #: The run's transport, and its poll when it can bring anything in (never for the
    #: in-process one); the bus sets both before it starts the transport.
    transport: Transport
    _poll: Callable[..., bool] | None
    #: Servers of this process by name (kept by the bus): a request to none is TIMEOUT at once.
    services: dict[str, ServiceView]

    def __init__(self, ctx: RunContext) -> None:
        self.ctx = ctx
        self.clock: Clock = ctx.clock
        self.initialised = False
        self.shut = False
        self.timers: list[tuple[int, int, TimerEntry]] = []  # heap of (due ns, sequence, timer)
        self.ready: deque[Work] = deque()  # work items with a _run() method
        #: Work that runs once the turn's other work is done (queue_last): what many items of one
        #: turn change, said once (an action server's status array after a cancel of all goals).
        self.last: list[Work] = []
        self._seq = itertools.count()

    def call_soon_threadsafe(self, fn: Callable[[], object]) -> None:
        """Run fn() on the scheduler's thread, between rounds (or inside a spin call), in the
        order of the calls.  The one door for other threads (the web view's server) into the
        bus: deque.append is atomic, and setting the wake time to 0 (one store) makes the
        scheduler spin the executor after its current round."""
        self.queue(_Call(fn))

    def nobody_here(self, what: str) -> None:
        """A wait for what no node of this process provides (the bus says how to reach others)."""

    def ok(self) -> bool:
        """`ros.ok()`: between the first `ros.init()` and `ros.shutdown()` or Ctrl-C."""
        return self.initialised and not self.shut and not self.ctx.interrupted

    # -- timers ------------------------------------------------------------------------------
    def add_timer(self, timer: TimerEntry, due: int) -> None:
        heapq.heappush(self.timers, (due, next(self._seq), timer))
        self.ctx.wake_at(due)  # attention: the scheduler spins the executor when it falls due

    def queue(self, work: Work) -> None:
        """Queue work (a subscription with messages, a service request) for the executor."""
        self.ready.append(work)
        self.ctx.wake = 0  # attention: the scheduler spins the executor after this round

    def queue_last(self, work: Work) -> None:
        """Run `work` at the end of the executor's turn, after the work queued before it and
        the work that work queues for this turn: the caller queues it once per change it
        coalesces (a flag of its own says whether it is queued already)."""
        self.last.append(work)
        self.ctx.wake = 0

    def _run_last(self) -> None:
        while self.last:
            last, self.last = self.last, []
            for work in last:
                work._run()

    def _run_ready(self) -> None:
        """The oldest queued item, then what it left for the end of the turn."""
        self.ready.popleft()._run()
        if self.last:
            self._run_last()

    def next_timer_due(self) -> int | None:
        while self.timers and self.timers[0][2]._cancelled:
            heapq.heappop(self.timers)
        return self.timers[0][0] if self.timers else None

    def _fire_due_timers(self, now: int, *, in_turn: bool = False) -> bool:
        """Call the timers due at `now`; then, unless a turn of spin_some goes on after them,
        what they left for the end of the turn."""
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
        if self.last and not in_turn:
            self._run_last()
        return fired

    # -- spinning ------------------------------------------------------------------------------
    def spin_some(self) -> None:
        """Between rounds: what arrived from other processes, due timers, then the work queued
        before this call (first in, first out), then what all of it left for the turn's end."""
        if self._poll is not None:
            self._poll(False)
        if self.timers and self.timers[0][0] <= self.clock.now:
            self._fire_due_timers(self.clock.now, in_turn=True)
        ready = self.ready
        for _ in range(len(ready)):
            ready.popleft()._run()
        if self.last:
            self._run_last()
        self._rearm()

    def spin_control(self, answers: Callable[[ServiceView], bool]) -> None:
        """While the run is paused (llfsm.debug): take in what arrived from other processes,
        answer the requests to the services `answers` accepts (control, parameters, the
        debugger's) and run what other threads handed in (`call_soon_threadsafe`: the page's
        work, which runs no machine code); everything else (callbacks of machine code and of
        nodes, requests to their services) stays queued, in order, for when the run goes on.
        No timer fires: the run clock stands (so the transport is asked to look whatever the
        time says: `poll(True)`)."""
        if self._poll is not None:
            self._poll(True)
        ready = self.ready
        if not ready:
            return
        kept: deque[Work] = deque()
        for _ in range(4 * len(ready) + 16):  # work a served item queues is served too, within bounds
            if not ready:
                break
            work = ready.popleft()
            server = self.services.get(getattr(work, "service", None) or "")
            if isinstance(work, _Call) or (server is not None and answers(server)):
                work._run()
            else:
                kept.append(work)
        ready.extendleft(reversed(kept))

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
            self._run_ready()
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
                self._run_ready()
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
                self.nobody_here(f"{future._service} has no server")
                return FutureReturnCode.TIMEOUT  # no server: nothing in this process can answer
            if self._poll is not None and self._poll() and future.done():
                return FutureReturnCode.SUCCESS  # the reply was in what the poll took: no wait
            if self.timers and self.timers[0][0] <= self.clock.now:
                self._fire_due_timers(self.clock.now)
                continue
            if self.ready:
                self._run_ready()
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
                    if self._poll is not None:  # always, with a remote future: typed for mypy
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


# -- rclpy's spin functions ---------------------------------------------------------------------------


class OnBus(Protocol):
    """What the spin functions need of the node they are given: the executor of its run."""

    @property
    def _bus(self) -> Executor: ...


def _ns(timeout_sec: float | None) -> int | None:
    if timeout_sec is None:
        return None
    if isinstance(timeout_sec, bool) or not isinstance(timeout_sec, int | float) or timeout_sec < 0:
        raise ValueError(f"timeout_sec must be a number of seconds >= 0 or None, not {timeout_sec!r}")
    return round(timeout_sec * 1e9)


def spin_once(node: OnBus, *, timeout_sec: float | None = 0) -> None:
    """Run one callback, timer or service request if one is ready; else wait up to timeout_sec
    for the next timer (the sim clock jumps there, the wall clock sleeps)."""
    bus = node._bus
    timeout = _ns(timeout_sec)
    if timeout is None:
        timeout = (bus.ctx.deadline - bus.clock.now) if bus.ctx.deadline is not None else 0
    bus.spin_once(timeout)


def spin_until_future_complete(node: OnBus, future: Future, timeout_sec: float | None = None) -> FutureReturnCode:
    """Spin until the future is done (SUCCESS), ok() turns false (INTERRUPTED), or the timeout
    passes (TIMEOUT).  A request to a service that has no server is TIMEOUT at once: nothing in
    this process could ever answer it, so it never hangs."""
    if not isinstance(future, Future):
        raise TypeError(f"spin_until_future_complete(): expected a Future, not {type(future).__name__}")
    return node._bus.spin_until(future, None if timeout_sec is None else _ns(timeout_sec))


def spin(node: OnBus) -> None:
    """Spin until ok() turns false or the run's --duration; inside a machine prefer spin_once."""
    bus = node._bus
    while bus.ok():
        if bus.ctx.deadline is not None and bus.clock.now >= bus.ctx.deadline:
            return
        if bus.transport.remote:  # other processes can always bring something: wait for it
            bus.spin_once(100_000_000)
            continue
        if not bus.spin_once(0) and bus.next_timer_due() is None:
            return  # nothing can ever happen: do not hang
        if not bus.ready:
            due = bus.next_timer_due()
            if due is not None and due > bus.clock.now:
                bus.clock.sleep_until(due)
