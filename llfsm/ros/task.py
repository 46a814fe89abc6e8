"""Futures, as `rclpy.task`: what `client.call_async` returns and spin calls wait on.

A future completes in the executor's turn (a local server's answer) or when the transport brings
in a reply from another process; see docs/bus.md (Services, clients and futures).
"""

from __future__ import annotations

from collections.abc import Callable, Generator
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .transports.base import RemoteClient


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

    def __await__(self) -> Generator[Future, None, Any]:
        """`await future` in a coroutine the executor runs (an action's execute callback):
        yields the future itself until it is done, then gives its result, as rclpy's does."""
        while not self._done:
            yield self
        return self.result()

    def _finish(self) -> None:
        self._done = True
        callbacks, self._callbacks = self._callbacks, []
        for fn in callbacks:
            fn(self)

    def __repr__(self) -> str:
        state = "cancelled" if self._cancelled else "done" if self._done else "pending"
        return f"<Future {state}{' for ' + self._service if self._service else ''}>"
