"""A machine's inputs at run time (SPEC 11): the values its next ringlet takes as its snapshot.

An input is read in code by its bare name, which the compiler makes an attribute of the machine
(`self.wall_close`), as a variable.  Its value changes only at the start of one of the machine's
ringlets, as clfsm snapshots external variables: a reader (llfsm.ros.inputs, a PULL subscription
the run session opens for an input bound to a topic) calls `Inputs.set`, which keeps the value
here and puts the scheduler's gate in front of the machine's next ringlet; the gate copies the
values into the machine (`Inputs.snapshot`) before anything of the ringlet runs.  A value that
comes between rounds, when no ringlet runs, goes into the machine at once.  So a ringlet never
sees an input change under it, a machine without inputs pays nothing, and one with inputs pays
only when a new value has come.
"""

from __future__ import annotations

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from .protocols import MachinePort

#: The positions in each entry of a generated class's INPUTS (see templates/machine.py.j2).
NAME, TYPE, DEFAULT, DOMAIN, TOPIC, MSG, FIELD = range(7)


class Inputs:
    """The newest value of each input of one machine, and whether the machine has taken it."""

    __slots__ = ("fresh", "machine", "names", "values")

    def __init__(self, machine: MachinePort) -> None:
        spec = machine.INPUTS
        self.machine = machine
        self.names: tuple[str, ...] = tuple(i[NAME] for i in spec)
        self.values: list[object] = [i[DEFAULT] for i in spec]
        #: A value came since the machine's last snapshot: its next ringlet takes a new one.
        self.fresh = False
        for name, value in zip(self.names, self.values, strict=True):
            setattr(machine, name, value)  # the default, until a first message

    def set(self, index: int, value: object) -> None:
        """A new value for input `index` (a message came): the machine's next ringlet takes it.
        Between rounds (the bus's hook taking messages in, a timer publishing) no ringlet runs,
        so the value goes into the machine at once: what the snapshot would copy, without
        sending the next round through the gate and the scheduler's attention (a third of a
        1 us round's rate with a message every round, bench/verify.py --only inputs).  During
        a ringlet (a machine publishing, a spin call in machine code) the gate takes it."""
        self.values[index] = value
        m = self.machine
        if m._arr.between_rounds:
            setattr(m, self.names[index], value)
            return
        if not self.fresh:
            self.fresh = True
            self.machine._arr.hold_for_inputs(self.machine)

    def snapshot(self) -> None:
        """Copy the newest values into the machine: the start of one of its ringlets."""
        self.fresh = False
        m = self.machine
        for name, value in zip(self.names, self.values, strict=True):
            setattr(m, name, value)
