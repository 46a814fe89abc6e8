"""What the lower parts of the runtime know of the parts above them, and what the runtime knows
of the layers above it: typed against these, the package reads bottom up, as it imports.

Within the runtime (docs/architecture.md, "runtime/"): a machine sends its commands to the
arrangement that runs it, and its inputs hold the machine for the arrangement's gate, but the
scheduler (llfsm.runtime.scheduler) imports the machine, not the reverse: the machine and its
inputs see the scheduler's `Arrangement` as an `ArrangementPort`, the inputs see the machine as a
`MachinePort`, and the run context holds the arrangement as a port too.

Above the runtime: the run's bus and its transport (llfsm.ros, docs/bus.md and
docs/transports.md), which the run context holds for them but never names, and the text
streams it writes to, which may be the session's outputs (llfsm.outputs).

For type checkers only: the runtime imports this under TYPE_CHECKING, so a run never imports it
(nor `typing`, which it needs), and a native build (docs/native.md) never compiles it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, ClassVar, Protocol, TypeVar

from .clock import Clock

#: The machine class an arrangement runs (llfsm.runtime.machine.Machine).
M = TypeVar("M")


class ArrangementPort(Protocol[M]):
    """What a machine, its inputs and the run context need of the arrangement that runs the
    machines `M` (llfsm.runtime.scheduler.Arrangement)."""

    clock: Clock
    #: `--keep-accepting`: an accepting state does not finish its machine.
    keep_accepting: bool
    #: The between-round hooks are running: no ringlet is.
    between_rounds: bool
    #: The gate every held machine's `_run` points at.
    _gate_fn: Callable[[M], int | None]

    @property
    def machines(self) -> Sequence[M]:
        """The machines, in load order."""
        ...

    def machine(self, name: str) -> M:
        """The machine of that name (UnknownMachineError if none)."""
        ...

    def command(self, name: str, cmd: str) -> None:
        """Suspend, resume or restart a machine at the start of its next ringlet."""
        ...

    def suspend_now(self, m: M, remember: int | None) -> None: ...

    def hold_for_inputs(self, m: M) -> None:
        """New input values: the gate goes in front of the machine's next ringlet."""
        ...

    def finish(self, m: M) -> None:
        """The machine reached an accepting state: unload it."""
        ...

    def interrupt(self, signum: int = ...) -> None:
        """As a Ctrl-C (signum 0: a stop asked for from inside the run)."""
        ...


class MachinePort(Protocol):
    """What a machine's inputs (llfsm.runtime.inputs) need of the machine
    (llfsm.runtime.machine.Machine)."""

    INPUTS: ClassVar[tuple[tuple[Any, ...], ...]]

    @property
    def _arr(self) -> ArrangementPort[Any]: ...


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
