# The C module under the stdlib's signal module (CPython's Modules/signalmodule.c): the same
# functions, with plain ints where signal.py wraps them in the Signals and Handlers enums.
# llfsm.runtime imports it to skip those enums at start-up.  Only what llfsm uses.
from collections.abc import Callable
from types import FrameType
from typing import Any

# a handler is a callable, or the SIG_DFL/SIG_IGN ints; signal() gives back whatever was set,
# or None for a handler installed outside Python (the runtime keeps those to put them back, typed
# with this, imported under TYPE_CHECKING)
_Handler = Callable[[int, FrameType | None], Any] | int | None

SIG_DFL: int
SIG_IGN: int
SIGALRM: int
SIGHUP: int
SIGINT: int
SIGKILL: int
SIGTERM: int
SIGUSR1: int
SIGUSR2: int
ITIMER_REAL: int

def signal(signalnum: int, handler: _Handler, /) -> _Handler: ...
def getsignal(signalnum: int, /) -> _Handler: ...
def set_wakeup_fd(fd: int, /, *, warn_on_full_buffer: bool = ...) -> int: ...
def setitimer(which: int, seconds: float, interval: float = ..., /) -> tuple[float, float]: ...
def pidfd_send_signal(pidfd: int, sig: int, siginfo: None = ..., flags: int = ..., /) -> None: ...
def default_int_handler(signalnum: int, frame: FrameType | None, /) -> Any: ...
