"""The base class of every compiled machine, and the clfsm macros machine code calls.

A compiled machine is a subclass plus two functions per state (its ringlets): ENTER[state]
runs OnEntry and then what STEADY[state] runs, the guards in order, firing the first true one
(OnExit, then the target becomes current and its ENTER ringlet is next) or else Internal.  The
scheduler calls `machine._run(machine)`: `_run` is the function for the machine's next ringlet,
so a state that was not just entered never tests an "entered" flag, and a round is a list of
plain calls.  A ringlet returns the index of the transition that fired, or None; an accepting
state finishes the machine itself.  Everything here is small because it sits on the hot path.
"""

from __future__ import annotations

from .inputs import Inputs

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from collections.abc import Callable
    from typing import Any, ClassVar

    from _typeshed import IdentityFunction

    from .clock import Clock
    from .protocols import ArrangementPort

if __file__.endswith((".so", ".pyd")):  # compiled by mypyc (`--native`), which reads this decorator
    from mypy_extensions import mypyc_attr
else:  # plain Python (source or bytecode) has nothing to do with it, and mypy_extensions imports typing

    def mypyc_attr(*attrs: str, **kwattrs: object) -> IdentityFunction:  # mypy_extensions' signature
        return lambda cls: cls


#: Returned by the ringlet of an accepting state: the machine has finished.
FINISHED = -1

# Control commands a machine can have pending (docs/semantics.md, "A ringlet, step by step", step 1).
SUSPEND, RESUME, RESTART = "suspend", "resume", "restart"

if TYPE_CHECKING:
    #: A ringlet takes the machine (typed Any: each generated class types its own ringlets,
    #: which take that class, not Machine, and a callable's parameter cannot be narrowed).
    Ringlet = Callable[[Any], "int | None"]
    #: A state's OnSuspend or OnResume section, if it has one (Any: as a ringlet's).
    Hook = Callable[[Any], None] | None


#: The instance attributes of the base class (its __slots__; reserved names for user variables).
_SLOTS = (
    "_arr",
    "_clock",
    "_finished",
    "_held",
    "_id",
    "_inputs",
    "_next",
    "_pending",
    "_resume_to",
    "_run",
    "_state",
    "_suspended",
    "_t0",
)


class UnknownMachineError(LookupError):
    """A macro named a machine that is not part of the arrangement."""


@mypyc_attr(allow_interpreted_subclasses=True)  # a machine mypyc could not compile stays plain
class Machine:
    """Base of generated machines.  Class attributes are filled in by the generated subclass."""

    NAME: ClassVar[str] = ""
    STATES: ClassVar[tuple[str, ...]] = ()
    INITIAL: ClassVar[int] = 0
    SUSPENDED: ClassVar[int] = 0
    ACCEPTING: ClassVar[tuple[int, ...]] = ()
    #: The ringlet that enters each state (OnEntry, then the steady part) ...
    ENTER: ClassVar[tuple[Ringlet, ...]] = ()
    #: ... and the ringlet of a state already entered (guards, OnExit, Internal).
    STEADY: ClassVar[tuple[Ringlet, ...]] = ()
    ON_SUSPEND: ClassVar[tuple[Hook, ...]] = ()
    ON_RESUME: ClassVar[tuple[Hook, ...]] = ()
    #: The machine directory the class was compiled from, relative to its module's folder.
    SOURCE_DIR: ClassVar[str] = ""
    #: machine.yaml's description, and per state its transitions in priority order as
    #: (target index, guard text as written): what /llfsm/NAME/description and the web view show.
    DESCRIPTION: ClassVar[str] = ""
    TRANSITIONS: ClassVar[tuple[tuple[tuple[int, str], ...], ...]] = ()
    #: machine.yaml's inputs, one entry each: (name, type, default, domain, topic, msg, field);
    #: topic, msg and field are None for an input bound to nothing (llfsm.runtime.inputs).
    INPUTS: ClassVar[tuple[tuple[Any, ...], ...]] = ()
    #: machine.yaml's `parameters:`, each (variable, rclpy's type name: "DOUBLE", "INTEGER_ARRAY"
    #: ...): parameters of the node /llfsm/NAME (llfsm.ros.control), set between ringlets
    #: (Arrangement.set_variables).
    PARAMETERS: ClassVar[tuple[tuple[str, str], ...]] = ()
    #: Variables.py's variables, each (name, annotation as written), in order: what the
    #: debugger shows and how it types a value set while paused (llfsm.debug).
    VARIABLES: ClassVar[tuple[tuple[str, str], ...]] = ()

    # Slots make attribute access on the hot path as cheap as CPython allows; generated classes
    # add their variables to them.
    __slots__ = _SLOTS

    def __init__(self, arrangement: ArrangementPort[Machine], machine_id: int = 0) -> None:
        #: The arrangement that runs the machine (llfsm.runtime.scheduler.Arrangement, typed by
        #: its port: the scheduler imports this module, not the reverse).
        self._arr = arrangement
        self._clock: Clock = arrangement.clock
        self._id = machine_id
        self._state: int = self.INITIAL
        self._t0: int = 0  # run-clock time (ns) the current state was entered (states using after*)
        self._pending: str | None = None
        self._suspended: bool = False
        self._resume_to: int | None = None
        self._finished: bool = False
        #: The inputs' newest values (llfsm.runtime.inputs); None for a machine without inputs.
        self._inputs: Inputs | None = Inputs(self) if self.INPUTS else None
        #: What the scheduler calls, `_run(self)`: the ringlet of the next turn (the initial
        #: state counts as entered), or, while a command is pending or the machine is suspended,
        #: `_held`, the scheduler's gate, with the real ringlet kept in `_next`.  So the round loop
        #: needs no test at all for the common case.
        self._held: Ringlet = arrangement._gate_fn
        self._run: Ringlet = self.ENTER[self.INITIAL]
        self._next: Ringlet = self._run

    @property
    def _entered(self) -> bool:
        """The current state was entered since the last ringlet: its next ringlet runs OnEntry."""
        run = self._next if self._run is self._held else self._run
        return run is self.ENTER[self._state]

    @_entered.setter
    def _entered(self, value: bool) -> None:
        fn = (self.ENTER if value else self.STEADY)[self._state]
        if self._run is self._held:
            self._next = fn
        else:
            self._run = fn

    def _initialise(self) -> None:
        """Set the machine and state variables (generated classes override this).  Called once
        every machine of the arrangement is known, so initialisers may use the macros."""

    # -- the clfsm macros (CLMacros.h), in scope in every section and guard -----------------
    def after(self, s: float) -> bool:
        """More than `s` seconds of run time have passed since this state was entered."""
        return self._clock.now - self._t0 > s * 1_000_000_000

    def after_ms(self, ms: float) -> bool:
        return self._clock.now - self._t0 > ms * 1_000_000

    def after_us(self, us: float) -> bool:
        return self._clock.now - self._t0 > us * 1_000

    def state_name(self) -> str:
        return self.STATES[self._state]

    def machine_name(self) -> str:
        return self.NAME

    def machine_id(self) -> int:
        return self._id

    def suspend(self, name: str) -> None:
        self._arr.command(name, SUSPEND)

    def resume(self, name: str) -> None:
        self._arr.command(name, RESUME)

    def restart(self, name: str) -> None:
        self._arr.command(name, RESTART)

    def suspend_self(self) -> None:
        self._arr.command(self.NAME, SUSPEND)

    def is_suspended(self, name: str) -> bool:
        return self._arr.machine(name)._suspended

    def is_running(self, name: str) -> bool:
        m = self._arr.machine(name)
        return not (m._suspended or m._finished)

    def state_name_of(self, name: str) -> str:
        m = self._arr.machine(name)
        return m.STATES[m._state]

    # -- used by generated code on rare paths ------------------------------------------------
    def _enter_suspend_state(self) -> None:
        """A transition targeted the suspend state: the machine is now suspended.

        There is no remembered state, so a later resume goes to the initial state.
        """
        self._arr.suspend_now(self, remember=None)


#: Names generated code and the runtime use on a machine instance: user variables must not
#: take them (checked by `llfsm check`, rule LF013).
RESERVED = frozenset({"self"} | {n for n in vars(Machine) if not n.startswith("__")} | set(_SLOTS))

#: The macros: bare names in machine code that the compiler turns into `self.<name>`.
MACROS = frozenset(
    {
        "after",
        "after_ms",
        "after_us",
        "state_name",
        "machine_name",
        "machine_id",
        "suspend",
        "resume",
        "restart",
        "suspend_self",
        "is_suspended",
        "is_running",
        "state_name_of",
    }
)
