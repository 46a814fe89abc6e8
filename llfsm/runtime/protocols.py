"""What the runtime knows of the layers above it: the run's bus and its transport (llfsm.ros,
docs/bus.md and docs/transports.md), which the run context holds for them but never names.

For type checkers only: the context imports this under TYPE_CHECKING, so a run never imports
it (nor `typing`, which it needs), and a native build (docs/native.md) never compiles it.
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
