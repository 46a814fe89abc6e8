"""The run context: what one run of an arrangement shares with the bus and the nodes.

The bus (`llfsm.ros`) keeps its graph here rather than in module globals, so that every run
(and every test) starts from a clean slate, and reads the run clock and the interrupt state
from here so that `ros.ok()` turns false on Ctrl-C exactly as rclpy's does.

The bus and its transport belong to llfsm.ros (docs/bus.md, docs/transports.md), a layer above the runtime, so the
context types them by the little it knows of them (llfsm.runtime.protocols); the bus's own
module reads them back as what it made.
"""

from __future__ import annotations

from .clock import Clock, SimClock, WallClock

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from collections.abc import Callable
    from typing import Any

    from .protocols import ArrangementPort, RunBus, RunTransport
    from .trace import Tracer


#: A run time no run reaches: "never" for wake times and durations.
FOREVER = 1 << 62


class RunContext:
    def __init__(self, clock: Clock | None = None) -> None:
        self.clock: Clock = clock if clock is not None else WallClock()
        if isinstance(self.clock, SimClock):
            self.clock.on_jump = self._time_jumped  # a jump of the sim clock (a spin call) raises attention
        #: Set on the first SIGINT/SIGTERM: `ros.ok()` is false from then on.
        self.interrupted = False
        #: Called between rounds, in order, once the run time reaches `wake`: the bus executor
        #: dispatches callbacks and timers.
        self.between_rounds: list[Callable[[], None]] = []
        #: The run time from which the scheduler must call `between_rounds` after a round; until
        #: then a round costs nothing beyond the machines' own ringlets.  Whoever queues work
        #: raises the scheduler's attention by lowering it: `wake = 0` for work to do after this
        #: round (a message for a callback, a service request), `wake_at(t)` for a timer.  The
        #: scheduler sets it to FOREVER just before it calls the hooks, and the hooks arm it
        #: again for whatever they still hold.  A hook that must run after every round sets
        #: `wake = 0` each time it runs.  Setting it is atomic, so another thread may do it.
        self.wake: int = FOREVER
        #: A machine finished: what its variables held may be held no more, and the bus looks
        #: between rounds (llfsm.ros.lifetimes).
        self.references_dropped = False
        #: Called once when the run ends (nodes write their pictures, close windows).
        self.at_end: list[Callable[[], None]] = []
        #: The run's arrangement (set by the Arrangement itself): nodes that end the run (teleop's
        #: `q`) and the machines' topics on the bus (llfsm.ros.control) find it here.  Typed by its
        #: port: the scheduler, above this module, is what sets it.
        self.arrangement: ArrangementPort[Any] | None = None
        #: The transport for the bus to use when it is made; None: the in-process one.
        self.transport: RunTransport | None = None
        #: The run's bus, made on first use (llfsm.ros.bus.bus_of); None until then.
        self.bus: RunBus | None = None
        #: Called once, with the bus, when it is initialised (the first `ros.init()`, or the
        #: command line before nodes start): the machines' state topics and control services
        #: join the graph with the first node, never in a run without one.  (Any: the bus is
        #: llfsm.ros.bus.Bus, which the runtime cannot name.)
        self.on_init: list[Callable[[Any], object]] = []
        #: The machines' nodes on the bus (llfsm.ros.control.MachineGraph, a tracer), once made.
        self.machine_graph: Tracer | None = None
        #: Named outputs (`--image`) that could not be written: the run then ends with status 1.
        self.output_errors: list[str] = []
        self.round = 0
        #: Run time at which the run will end (--duration), if any: blocking waits inside
        #: machine code (spin calls) never wait past it.
        self.deadline: int | None = None

    def _time_jumped(self) -> None:
        self.wake = 0

    def wake_at(self, t: int) -> None:
        """Make the scheduler call the between-round hooks once the run time reaches t."""
        if t < self.wake:
            self.wake = t


_current: RunContext | None = None


def current() -> RunContext:
    """The active run's context; outside a run, a wall-clock context made on first use."""
    global _current
    if _current is None:
        _current = RunContext()
    return _current


def activate(ctx: RunContext | None) -> RunContext | None:
    """Make `ctx` the active context; returns the previous one so callers can restore it."""
    global _current
    prev, _current = _current, ctx
    return prev
