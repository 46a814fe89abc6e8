"""A run's signals (docs/cli.md, "Signals"): Ctrl-C, SIGTERM and SIGHUP routed to the
arrangement for the duration of a run, and a second one, or machine code that holds the run past
the grace time, stopped where it is.  (Apart from the scheduler, whose round loops never see
them.)"""

from __future__ import annotations

import _signal as signal  # the signal module without its enums: enum is a tenth of a run's start-up
import os
import time

from .clock import WallClock
from .errors import RunStopped, signal_name
from .generated import is_generated
from .watchdog import cpu_and_wait

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from _signal import _Handler
    from collections.abc import Callable
    from types import FrameType, TracebackType

    from .scheduler import Arrangement
    from .watchdog import Watchdog

    SignalHandler = Callable[[int, FrameType | None], None]

#: Signals that interrupt a run: Ctrl-C, `kill`, and a closed terminal (SIGHUP).
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
#: After a first interrupt, machine code that still holds the run this long (seconds of real
#: time) beyond the grace time is stopped where it is, as a second interrupt would stop it.
STUCK_SLACK_S = 0.5
#: A run not held by a section when the grace time and the slack have passed (_not_held) is
#: given this much longer to end by its rounds.
STARVED_S = 10.0


def _in_machine_code(frame: FrameType | None) -> bool:
    """Whether a generated module's code is on the stack (a signal handler's view of it)."""
    while frame is not None:
        if is_generated(frame.f_code.co_filename):
            return True
        frame = frame.f_back
    return False


def _not_held(arr: Arrangement, frame: FrameType | None) -> bool:
    """Whether a run still running after its grace time and slack is not held by a section:
    its own work is under way (unloading a finished machine's node can take seconds when many
    DDS peers leave at once), or it was waiting for the CPU, not running, since the interrupt
    (many runs stopped at once on few cores).  Then its rounds end it, and the timer waits on."""
    ran, waited = cpu_and_wait(os.getpid())
    if waited - arr._cpu_wait[1] >= STUCK_SLACK_S and ran - arr._cpu_wait[0] < STUCK_SLACK_S:
        return True  # starved: whatever it was in, it had no time to finish it
    return not _in_machine_code(frame) and not _waits_for_a_far_round(frame)


def _waits_for_a_far_round(frame: FrameType | None) -> bool:
    """Whether the scheduler sleeps until a round further off than the slack (the wall clock's
    period, a timer far ahead): a run found there when the grace time has passed ends at once,
    not after the wait.  A short sleep between rounds (the idle time) is no such wait."""
    if frame is None:
        return False
    clock = frame.f_locals.get("self")
    if not isinstance(clock, WallClock):
        return False
    if frame.f_code is WallClock.advance.__code__ and clock.period:
        until = clock._next
    elif frame.f_code is WallClock.sleep_until.__code__:
        until = frame.f_locals.get("t", 0)
    else:
        return False
    return isinstance(until, int) and until - clock.read() > STUCK_SLACK_S * 1e9


def signals_handled(arr: Arrangement) -> _SignalsHandled:
    """Route SIGINT/SIGTERM/SIGHUP to the arrangement for the duration of a run (a `with`).

    The first one asks the machines to finish (the scheduler sees it between rounds).  A second
    one, or the grace time passing in real time while machine code still loops or blocks (a real
    timer, SIGALRM, catches that), raises RunStopped from the handler: Python delivers it inside
    whatever code is running, machine code included, and a blocking `time.sleep` ends with it,
    so nothing a section does can keep the run from stopping."""

    def stop(frame: FrameType | None, text: str) -> None:
        if arr.running:
            # outside machine code (the scheduler sleeping between rounds, the bus) there is no
            # place of the user's to name: the run ends as the grace time's end would end it
            raise RunStopped(arr._signal or signal.SIGINT, text, in_machine_code=_in_machine_code(frame))

    def handler(signum: int, frame: FrameType | None) -> None:
        if arr.watchdog is not None:
            arr.watchdog.answer()  # this handler could run: the run is not stuck in a C call
        first = not arr._interrupts
        arr.interrupt(signum)
        if first:
            arr._cpu_wait = cpu_and_wait(os.getpid())  # _not_held counts from here
            signal.setitimer(signal.ITIMER_REAL, arr._grace_ns / 1e9 + STUCK_SLACK_S)
            if arr.watchdog is not None:
                arr.watchdog.keep_answering(arr._grace_ns / 1e9 + STARVED_S)
        else:
            stop(frame, f"stopped by a second {signal_name(signum)}")

    def alarm(_signum: int, frame: FrameType | None) -> None:
        if arr.watchdog is not None:
            arr.watchdog.answer()
        if arr._interrupts:
            grace = arr._grace_ns / 1e9
            waited = time.monotonic() - arr._interrupted_at
            if waited < grace + STARVED_S and _not_held(arr, frame):
                signal.setitimer(signal.ITIMER_REAL, STUCK_SLACK_S)  # the rounds will end the run
                return
            sig = signal_name(arr._signal or 0)
            held = grace + STUCK_SLACK_S if waited < grace + STARVED_S else round(waited, 1)
            stop(frame, f"stopped by {sig}: still running {held:g} s after it (grace time {grace:g} s)")

    return _SignalsHandled(handler, alarm, arr.watchdog)


class _SignalsHandled:
    """The handlers of signals_handled, installed on entry and the old ones put back on exit.
    (Not contextlib.contextmanager: contextlib is a tenth of a run's start-up.)"""

    def __init__(self, handler: SignalHandler, alarm: SignalHandler, watchdog: Watchdog | None) -> None:
        self.handler = handler
        self.alarm = alarm
        self.watchdog = watchdog
        self.old: dict[int, _Handler] = {}

    def __enter__(self) -> None:
        self.old = {s: signal.signal(s, self.handler) for s in STOP_SIGNALS}
        self.old[signal.SIGALRM] = signal.signal(signal.SIGALRM, self.alarm)
        if self.watchdog is not None:  # after the handlers: every signal it sees is one they answer
            self.watchdog.arm()

    def __exit__(self, t: type[BaseException] | None, e: BaseException | None, tb: TracebackType | None) -> None:
        if self.watchdog is not None:
            self.watchdog.disarm()
        signal.setitimer(signal.ITIMER_REAL, 0)
        for s, h in self.old.items():
            signal.signal(s, h)
