"""A machine's part of a configuration, taken from and put back into the machine object itself.

The explorer runs the compiled ringlets on the very objects a run uses; between steps it
captures what of a machine decides its future (`snapshot`) and puts a captured part back
(`restore`).  The pair is written as Python for each machine class when verify loads it (from
the class's tables and the machine's variables, names only: no user text), so that a step costs
a few attribute reads and writes rather than a loop over names.

The part, a tuple: the ringlet the scheduler calls next and, while the machine is held at the
scheduler's gate, the ringlet behind the gate (each as its number, llfsm.runtime.generated: a
state's entry ringlet, its steady ringlet, or the gate); the current state, the pending command,
suspended, the state to resume, finished; then the inputs as last read; then the variables,
frozen by value (llfsm.verify.values).  The entry time (`_t0`) is not part of it: the explorer
keeps each machine's time in its own abstraction (llfsm.verify.explorer).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..lang.bindings import attribute_of
from ..lang.model import Machine as MachineModel
from ..runtime.generated import entry_number, gate_number, numbered_ringlets
from ..runtime.machine import Machine
from .values import SCALARS, Frozen, Handles, Unfreezable, freeze, thaw

#: Positions in a machine's part of a configuration.
RUN, NEXT, STATE, PENDING, SUSPENDED, RESUME_TO, FINISHED = range(7)
#: Where the inputs start.
FIRST_INPUT = 7


class VariableValueError(Exception):
    """A variable holds a value verify cannot compare by value."""

    def __init__(self, machine: str, variable: str, what: str) -> None:
        super().__init__(
            f"machine {machine}: variable {variable} holds {what}, which verify cannot compare by value "
            "(numbers, strings, tuples, lists, dicts, sets, messages and bus handles can be)"
        )
        self.machine = machine
        self.variable = variable


class Codec:
    """`snapshot(m) -> tuple` and `restore(m, part)` for one machine class of an arrangement."""

    def __init__(self, cls: type[Machine], model: MachineModel, gate: Callable[..., Any], handles: Handles) -> None:
        self.cls = cls
        n = len(cls.STATES)
        #: entry and steady ringlet of each state, then the gate: a part names them by number
        self.ringlets: list[Callable[..., Any]] = numbered_ringlets(cls.ENTER, cls.STEADY, gate)
        self.gate_index = gate_number(n)
        #: each state's entry ringlet's number, by state
        self.entries: tuple[int, ...] = tuple(entry_number(s) for s in range(n))
        self.inputs: list[str] = [entry[0] for entry in cls.INPUTS]
        self.variables: list[str] = [v.name for v in model.variables] + [
            attribute_of(s.name, v.name) for s in model.states for v in s.variables
        ]
        #: what a person calls each variable in a counterexample (`x` of state S: `S.x`)
        self.shown_names: list[str] = [v.name for v in model.variables] + [
            f"{s.name}.{v.name}" for s in model.states for v in s.variables
        ]
        self.first_variable = FIRST_INPUT + len(self.inputs)
        self.handles = handles
        self.snapshot, self.restore = self._compile(gate)

    def _compile(self, gate: Callable[..., Any]) -> tuple[Callable[[Any], tuple[Any, ...]], Callable[[Any, Any], None]]:
        kinds = {f: i for i, f in enumerate(self.ringlets)}
        lines = ["def snapshot(m):"]
        if self.variables:  # L{k}: the canonical handle variable k held last (what it holds again)
            lines.append(f"    global {', '.join(f'L{k}' for k in range(len(self.variables)))}")
        lines.append("    r = m._run")
        values = []
        for k, name in enumerate(self.variables):
            lines.append(f"    v{k} = m.{name}")
            lines.append(f"    if v{k}.__class__ not in S and v{k} is not L{k}:")
            lines.append(f"        h = P(id(v{k}))")  # a handle: its canonical one, without a call
            lines.append("        if h is None:")
            lines.append(f"            v{k} = F(v{k}, {k})")
            lines.append("        else:")
            lines.append(f"            v{k} = L{k} = h")
            values.append(f"v{k}")
        parts = ["K[r]", "K[m._next] if r is G else 0", "m._state", "m._pending", "m._suspended"]
        parts += ["m._resume_to", "m._finished"]
        parts += [f"m.{name}" for name in self.inputs] + values
        lines.append(f"    return ({', '.join(parts)},)")
        lines += ["def restore(m, t):", "    m._run = R[t[0]]", "    m._next = R[t[1]]"]
        lines += ["    m._state = t[2]", "    m._pending = t[3]", "    m._suspended = t[4]"]
        lines += ["    m._resume_to = t[5]", "    m._finished = t[6]"]
        for k, name in enumerate(self.inputs):
            lines.append(f"    m.{name} = t[{FIRST_INPUT + k}]")
        for k, name in enumerate(self.variables):
            lines.append(f"    v = t[{self.first_variable + k}]")
            lines.append("    if v.__class__ is Z:")  # a handle is itself: put back as a number is
            lines.append("        v = T(v, H)")
            lines.append(f"    m.{name} = v")
        scope: dict[str, Any] = {
            "S": SCALARS,
            "K": kinds,
            "G": gate,
            "R": self.ringlets,
            "F": self._freeze,
            "T": thaw,
            "H": self.handles,
            "P": self.handles.plain.get,
            "Z": Frozen,
        }
        scope.update((f"L{k}", None) for k in range(len(self.variables)))  # None: no handle yet
        # llfsm's own text (attribute names are identifiers the checker accepted): no user code
        exec(compile("\n".join(lines) + "\n", f"<verify codec of {self.cls.NAME}>", "exec"), scope)
        return scope["snapshot"], scope["restore"]

    def _freeze(self, value: Any, index: int) -> Any:
        try:
            return freeze(value, self.handles)
        except Unfreezable as e:
            raise VariableValueError(self.cls.NAME, self.shown_names[index], str(e)) from None

    def variables_of(self, part: tuple[Any, ...]) -> dict[str, Any]:
        """Shown name -> frozen value, of a part."""
        return dict(zip(self.shown_names, part[self.first_variable :], strict=True))

    def inputs_of(self, part: tuple[Any, ...]) -> dict[str, Any]:
        return dict(zip(self.inputs, part[FIRST_INPUT : self.first_variable], strict=True))

    def entered(self, part: tuple[Any, ...]) -> bool:
        """Whether the machine's next ringlet enters its state (runs OnEntry first)."""
        run = part[NEXT] if part[RUN] == self.gate_index else part[RUN]
        return run == self.entries[part[STATE]]
