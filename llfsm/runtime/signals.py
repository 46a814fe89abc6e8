"""A run's signals (docs/cli.md, "Signals"): Ctrl-C, SIGTERM and SIGHUP routed to the
arrangement for the duration of a run, and a second one, or machine code that holds the run past
the grace time, stopped where it is.  (Apart from the scheduler, whose round loops never see
them.)"""

from __future__ import annotations

import _signal as signal  # the signal module without its enums: enum is a tenth of a run's start-up

from .errors import RunStopped, signal_name
from .generated import is_generated

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


def _in_machine_code(frame: FrameType | None) -> bool:
    """Whether a generated module's code is on the stack (a signal handler's view of it)."""
    while frame is not None:
        if is_generated(frame.f_code.co_filename):
            return True
        frame = frame.f_back
    return False


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
            signal.setitimer(signal.ITIMER_REAL, arr._grace_ns / 1e9 + STUCK_SLACK_S)
        else:
            stop(frame, f"stopped by a second {signal_name(signum)}")

    def alarm(_signum: int, frame: FrameType | None) -> None:
        if arr.watchdog is not None:
            arr.watchdog.answer()
        if arr._interrupts:
            grace = arr._grace_ns / 1e9
            sig = signal_name(arr._signal or 0)
            held = grace + STUCK_SLACK_S
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
