"""What the runtime knows of the layers above it: the run's bus and its transport (llfsm.ros,
docs/bus.md and docs/transports.md), which the run context holds for them but never names, and
the text streams it writes to, which may be the session's outputs (llfsm.outputs).

For type checkers only: the context and the tracer import this under TYPE_CHECKING, so a run
never imports it (nor `typing`, which it needs), and a native build (docs/native.md) never
compiles it.
"""

from __future__ import annotations

from typing import Protocol


class RunBus(Protocol):
    """The run's bus (llfsm.ros.bus.Bus), as far as the run and its session need it."""

    @property
    def initialised(self) -> bool:
        """True once `ros.init()` (or the command line) started it."""
        ...

    def init(self) -> None: ...


class RunTransport(Protocol):
    """The transport the run's bus is to use (llfsm.ros.transports), set before the bus is made
    (the in-process one when None)."""

    @property
    def remote(self) -> bool:
        """True when other processes can change what the bus sees."""
        ...

    def close(self) -> None: ...


class TextSink(Protocol):
    """Where a tracer writes its lines: a text stream, or a file of the session's that keeps
    its first write error for the end of the run (llfsm.outputs.StreamedOutput)."""

    def write(self, text: str, /) -> object: ...
    def flush(self) -> None: ...
