# What type checkers know of llfsm.bag._tap, the recorder's tap and buffer in C (_tap.c): an
# extension module carries no annotations.  setup.py builds it where a C compiler is; where it
# is not built, llfsm.bag.typesupport uses ByteSpool and the generated `_stamped_<Name>`.
from collections.abc import Callable
from typing import Protocol

from _typeshed import ReadableBuffer

class _Clock(Protocol):
    # the tap reads `now` once per message; anything with an int `now` will do (the run clock)
    @property
    def now(self) -> int: ...

class Spool:
    """The recorder's buffer of pipe records: appended to by taps, taken whole by its thread."""

    def extend(self, data: ReadableBuffer, /) -> None: ...
    def take(self) -> bytes: ...
    def __len__(self) -> int: ...

class Tap:
    """Appends one fixed-size message's pipe record to `out`, as `fallback` (the generated
    `_stamped_<Name>` tap) would, and hands it whatever is not the ordinary case."""

    def __init__(
        self,
        out: Spool,
        key: int,
        clock: _Clock,
        layout: tuple[tuple[str, str], ...],
        fallback: Callable[[object], None],
    ) -> None: ...
    def __call__(self, msg: object, /) -> None: ...
    @property
    def fallbacks(self) -> int: ...
