"""Running a goal's execute callback without holding up the machines (docs/actions.md,
"Serving a goal").

One thread runs the machines and the executor, so an execute callback that loops or sleeps
until its goal is done, as rclpy examples do on their executor's threads, would stop every
machine of the run.  An execute callback may instead hand control back and resume later:

- a generator (`def execute(goal_handle): ... yield ...; return result`): each `yield` gives the
  machines their turn.  `yield` alone resumes in the executor's next turn (after the next round
  of machines), `yield 0.5` after half a second of run time, `yield future` once the future is
  done (a service call's, a goal's);
- a coroutine (`async def execute(goal_handle)`), as rclpy allows: `await future` resumes once
  the future is done;
- a plain function runs to its end at once, as in rclpy.

Every step runs as executor work, in the executor's fixed order, so a run under `--clock sim`
is the same every time.  What the callback returns is the goal's result.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable, Coroutine, Generator
from typing import TYPE_CHECKING, Any, cast

from ..timer import Timer

if TYPE_CHECKING:
    from ..bus import Bus

Steps = Generator[Any, None, Any] | Coroutine[Any, Any, Any]


class Execution:
    """One goal's execute callback, run as a task of the executor: `start()` queues its first
    step, each step runs until the callback yields or returns, `done(value)` is called with
    what it returned.  An exception from the callback is handed to `failed` and raised on, so
    that the run reports it as it reports any exception in machine code."""

    __slots__ = ("_bus", "_call", "_closed", "_done", "_failed", "_steps")

    def __init__(
        self,
        bus: Bus,
        call: Callable[[], Any],
        done: Callable[[Any], None],
        failed: Callable[[BaseException], None],
    ) -> None:
        self._bus = bus
        self._call = call
        self._done = done
        self._failed = failed
        self._steps: Steps | None = None
        self._closed = False

    def start(self) -> None:
        self._bus.queue(self)

    def _run(self) -> None:
        """Executor work: the first call of the callback, or the next step of its generator."""
        if self._closed:
            return
        if self._steps is None:
            try:
                value = self._call()
            except BaseException as e:
                self._fail(e)
                raise
            if not (inspect.isgenerator(value) or inspect.iscoroutine(value)):
                self._finish(value)
                return
            self._steps = cast("Steps", value)
        self._step(None)

    def _step(self, error: BaseException | None) -> None:
        """Resume the generator (with `error` raised where it yielded, if given) until it
        yields again or returns."""
        steps = self._steps
        assert steps is not None
        try:
            waits_for = steps.send(None) if error is None else steps.throw(error)
        except StopIteration as stop:
            self._finish(stop.value)
            return
        except BaseException as e:
            self._fail(e)
            raise
        self._wait(waits_for)

    def _finish(self, value: Any) -> None:
        self._closed = True
        self._done(value)

    def _fail(self, error: BaseException) -> None:
        self._closed = True
        self._failed(error)

    def _wait(self, waits_for: Any) -> None:
        """Resume once what the callback yielded allows it.  Anything else than nothing, a
        number or a future is a TypeError raised where it was yielded (the report names the
        user's line)."""
        if waits_for is None:
            self._bus.queue(self)
        elif isinstance(waits_for, int | float) and not isinstance(waits_for, bool):
            if waits_for == math.inf:
                self._step(ValueError("an execute callback cannot pause forever (yield inf): return instead"))
                return
            if not waits_for > 0:  # 0, a negative number, NaN: the next turn
                self._bus.queue(self)
                return
            timer: Timer | None = None

            def wake() -> None:
                if timer is not None:
                    timer.cancel()
                self._bus.queue(self)

            timer = Timer(self._bus, waits_for, wake)
        elif callable(getattr(waits_for, "add_done_callback", None)):
            waits_for.add_done_callback(lambda _future: self._bus.queue(self))
        else:
            self._step(
                TypeError(
                    "an execute callback yields nothing, a number of seconds or a future (the machines' "
                    f"turn, a pause, a wait), not {type(waits_for).__name__} ({waits_for!r})"
                )
            )

    def close(self) -> None:
        """Stop here: the generator's `finally` blocks run, no step runs again."""
        self._closed = True
        if self._steps is not None:
            self._steps.close()
