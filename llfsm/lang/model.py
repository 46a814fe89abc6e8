"""The in-memory form of a machine directory.

Every element keeps the file and line it came from, so that any later stage (checker,
compiler, run-time error reports) can point the user at what they wrote rather than at
something llfsm generated.  The model is plain data: building it never runs user code.
"""

from __future__ import annotations

import keyword
import re
from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field

NAME_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")

#: Longest machine name (characters; names are ASCII).  The name becomes file names: the
#: module NAME.py and `build`'s temporary `.NAME.py.<pid>.<random>.tmp` beside it, which must
#: stay within the file system's 255-byte NAME_MAX.  Check and build agree through this rule.
MAX_MACHINE_NAME = 200

#: The five code sections a state may have, in the order they are documented.
SECTIONS = ("OnEntry", "OnExit", "Internal", "OnSuspend", "OnResume")

#: Name of the implicit suspend state when a machine declares none.
IMPLICIT_SUSPENDED = "SUSPENDED"


def is_valid_name(name: str) -> bool:
    """Machine, state and variable names share one rule: a Python identifier, not a keyword."""
    return bool(NAME_RE.match(name)) and not keyword.iskeyword(name)


class Loc(BaseModel):
    """A position in a file of the machine directory (1-based line and column)."""

    model_config = ConfigDict(frozen=True)

    file: str
    line: int = 1
    column: int = 1


class Variable(BaseModel):
    """`count: int = 0` in Variables.py or State_S_Variables.py."""

    name: str
    annotation: str
    initial: str | None = None  # source text of the initialiser, None when omitted
    loc: Loc


#: The types an input may have (SPEC 11), and the Python type of their values.
INPUT_TYPES: dict[str, type] = {"bool": bool, "int": int, "float": float, "str": str}

#: A scalar value in machine.yaml (an input's default or a value of its domain).
Scalar = bool | int | float | str


class Input(BaseModel):
    """An input (external variable) under `inputs:` in machine.yaml: a value from outside the
    machine, read-only in its code, taken as a snapshot at the start of each of its ringlets,
    optionally bound to a field of the newest message on a topic (docs/machine-format.md)."""

    name: str
    type: str  # bool | int | float | str (anything else is a check error, LF048)
    default: Scalar | None = None  # as written; None when missing
    domain: list[Scalar] | None = None  # as written; None when missing (bool: both values)
    topic: str | None = None
    msg: str | None = None
    field: str | None = None
    loc: Loc  # where the name is written
    #: where each key's value is written (type, default, domain, topic, msg, field)
    locs: dict[str, Loc] = Field(default_factory=dict)

    @property
    def bound(self) -> bool:
        """Bound to a topic: at run time it takes a field of the newest message there."""
        return self.topic is not None

    def values(self) -> list[Scalar]:
        """The values `llfsm verify` explores: the domain, or both values of a bool."""
        if self.domain is not None:
            return list(self.domain)
        return [False, True] if self.type == "bool" else []


class Code(BaseModel):
    """One code file: a section of a state, Includes.py, or a guard expression.

    A guard written inline in machine.yaml (`{to: T, guard: EXPR}`) is a Code too, under the
    name its file would have (State_S_Transition_N.expr), so that every stage keys it as any
    other guard; `origin` says where its text really is, and `place` turns a position in the
    text into one in machine.yaml for whoever reports it."""

    file: str  # the file name inside the machine directory, e.g. State_PUBLISH_OnEntry.py
    text: str
    loc: Loc
    #: An inline guard: where its text's first character is in machine.yaml.
    origin: Loc | None = None
    #: An inline guard written as a block (`guard: |`): the column of its lines after the first.
    #: None when positions past its first line cannot be told (a folded or escaped scalar).
    block_column: int | None = None
    #: An inline guard whose text is exactly what machine.yaml holds from `origin` (a plain or
    #: quoted scalar without escapes, on one line): columns map one to one.
    exact: bool = False

    @property
    def is_empty(self) -> bool:
        return not self.text.strip()

    @property
    def inline(self) -> bool:
        return self.origin is not None

    def place(self, line: int, column: int) -> Loc:
        """Where a (1-based) position in the text is in the machine directory."""
        o = self.origin
        if o is None:
            return Loc(file=self.file, line=line, column=column)
        if self.block_column is not None:
            col = (o.column if line == 1 else self.block_column) + column - 1
            return Loc(file=o.file, line=o.line + line - 1, column=col)
        if self.exact and line == 1:
            return Loc(file=o.file, line=o.line, column=o.column + column - 1)
        return o


class Transition(BaseModel):
    index: int
    target: str
    guard: Code | None = None  # None when it is neither inline nor in its .expr file (a check error)
    loc: Loc  # where the target is named in machine.yaml
    #: An inline guard whose State_S_Transition_N.expr exists as well (a check error, LF070).
    file_too: bool = False


class State(BaseModel):
    name: str
    transitions: list[Transition] = Field(default_factory=list)
    sections: dict[str, Code] = Field(default_factory=dict)  # only the non-missing ones
    variables: list[Variable] = Field(default_factory=list)
    variables_file: Code | None = None  # State_S_Variables.py as written
    loc: Loc
    implicit: bool = False  # the implicit suspend state added by llfsm

    @property
    def accepting(self) -> bool:
        return not self.transitions


class MachineParameter(BaseModel):
    """A machine variable listed under `parameters:` in machine.yaml: a parameter of the node
    /llfsm/NAME (docs/parameters.md).  `loc` is where machine.yaml names it."""

    name: str
    loc: Loc


class Machine(BaseModel):
    """A whole machine directory.  `path` is the directory as the user named it."""

    name: str
    path: Path
    description: str | None = None
    initial: str
    suspended: str
    states: list[State]
    includes: Code | None = None
    variables: list[Variable] = Field(default_factory=list)
    variables_file: Code | None = None  # Variables.py as written
    inputs: list[Input] = Field(default_factory=list)
    initial_loc: Loc = Loc(file="machine.yaml")
    suspended_loc: Loc = Loc(file="machine.yaml")
    parameters: list[MachineParameter] = Field(default_factory=list)

    def state(self, name: str) -> State:
        for s in self.states:
            if s.name == name:
                return s
        raise KeyError(name)


class MachineYaml(BaseModel):
    """The schema of machine.yaml, as published by `llfsm schema`.

    The reader validates by hand (to report each problem with its YAML line); this model is
    the single description of the format that the JSON Schema is generated from.
    """

    model_config = ConfigDict(extra="forbid", title="machine.yaml")

    description: str | None = Field(None, description="One line saying what the machine does.")
    initial: str | None = Field(
        None,
        description="Name of the initial state; default: the first state.",
        pattern="^" + NAME_RE.pattern[:-2] + "$",
    )
    suspended: str | None = Field(
        None,
        description="Name of the suspend state; default: a state named SUSPENDED if present, "
        "else an implicit empty one.",
        pattern="^" + NAME_RE.pattern[:-2] + "$",
    )
    states: list[YamlState] = Field(
        ..., min_length=1, description="The states, in order; the order is the state index."
    )
    inputs: dict[str, YamlInput] | None = Field(
        None,
        description="External variables: read-only in code, taken as a snapshot at the start of each "
        "ringlet; optionally bound to a field of the newest message on a topic (docs/verify.md).",
        json_schema_extra={"propertyNames": {"pattern": "^" + NAME_RE.pattern[:-2] + "$"}},
    )
    parameters: list[str] | None = Field(
        None,
        description="Machine variables that are parameters of the node /llfsm/<machine>: `llfsm param set` "
        "(or ros2 param set, -p, --params-file) gives one a value before the machine's next ringlet.  Each "
        "must be a variable of Variables.py annotated bool, int, float, str or list[...] of one of them.",
    )


class YamlTransition(BaseModel):
    model_config = ConfigDict(extra="forbid", title="transition")

    to: str = Field(..., pattern="^" + NAME_RE.pattern[:-2] + "$", description="The target state.")
    guard: str | None = Field(
        None,
        min_length=1,
        description="The guard, one Python expression, written here instead of in "
        "State_<state>_Transition_N.expr (not both).  Left out: the guard is in that file.",
    )


class YamlState(BaseModel):
    model_config = ConfigDict(extra="forbid", title="state")

    name: str = Field(..., pattern="^" + NAME_RE.pattern[:-2] + "$", description="State name.")
    transitions: list[str | YamlTransition] = Field(
        default_factory=list,
        description="The transitions in priority order: a target state's name (position N is guarded by "
        "State_<name>_Transition_N.expr), or `{to: TARGET, guard: EXPR}` with the guard inline.  "
        "No transitions: an accepting state.",
    )


class YamlInput(BaseModel):
    model_config = ConfigDict(extra="forbid", title="input")

    type: Literal["bool", "int", "float", "str"] = Field(..., description="The type of its values.")
    default: Scalar | None = Field(
        None, description="Its value until a first message arrives (default: false, 0, 0.0 or an empty string)."
    )
    domain: list[Scalar] | None = Field(
        None, min_length=1, description="The values `llfsm verify` explores (a bool: both, by default)."
    )
    topic: str | None = Field(None, description="At run time, read from the newest message on this topic.")
    msg: str | None = Field(
        None, pattern=r"^[a-z][a-z0-9_]*/msg/[A-Z][A-Za-z0-9]*$", description="The topic's message type."
    )
    field: str | None = Field(None, description="The field of the message, dotted for a nested one (linear.x).")


MachineYaml.model_rebuild()
