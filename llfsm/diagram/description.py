"""What a machine's description must be before the view believes it (issue 18, untrusted peers).

`/llfsm/M/description` is a topic on a shared DDS domain: any process can publish anything on
it.  The view draws and samples descriptions on its server thread, so a description that is
not what a run publishes (llfsm.ros.control.description) must be refused before it gets there:
states that are not objects once stopped the page for good (an AttributeError in the push
loop), an index that was a string was written into the SVG as markup, and a description of
thousands of states froze the server for seconds per page.

The model is strict (no coercion: `"1"` is not an index, `1` is not a name) and bounded, and the
cross-references are checked (targets, the initial and the suspend state name states; no state
is named twice), so the drawing code works on data it can trust.  Everything that goes wrong is
one DescriptionError whose message names the field, short enough for a warning line.
"""

from __future__ import annotations

import json
from typing import TYPE_CHECKING, Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from ..lang.files import expression

if TYPE_CHECKING:
    from ..lang.model import Machine

#: Characters of JSON accepted at all (a run's description of a few dozen states is a few KiB).
MAX_TEXT = 4 << 20
#: States in one description (what is drawn is bounded further: llfsm.diagram.svg).
MAX_STATES = 10_000
#: Transitions in one description, all states together.
MAX_TRANSITIONS = 50_000
#: Transitions of one state.
MAX_STATE_TRANSITIONS = 1_000
#: Characters of a machine's or a state's name.
MAX_NAME = 256
#: Characters of a guard's text, and of the machine's description text.
MAX_TEXT_FIELD = 16_384
#: Transition indices (a priority: 0, 1, 2... within a state).
MAX_INDEX = 1_000_000
#: Inputs of one machine, and values in one input's domain.
MAX_INPUTS = 1_000
MAX_DOMAIN = 1_000

Name = Field(min_length=1, max_length=MAX_NAME)


class DescriptionError(ValueError):
    """A description that does not fit the model; the message names the field."""


class _Strict(BaseModel):
    # extra keys are ignored (a newer run may say more), nothing is coerced
    model_config = ConfigDict(strict=True, extra="ignore", frozen=True)


class Transition(_Strict):
    index: int = Field(ge=0, le=MAX_INDEX)
    target: str = Name
    guard: str = Field(default="", max_length=MAX_TEXT_FIELD)


class State(_Strict):
    name: str = Name
    transitions: list[Transition] = Field(default_factory=list, max_length=MAX_STATE_TRANSITIONS)
    accepting: bool = False


Scalar = bool | int | float | Annotated[str, Field(max_length=MAX_TEXT_FIELD)]


class Input(_Strict):
    """An input of the machine (SPEC 11), as llfsm.ros.control.description lists it."""

    name: str = Name
    type: Literal["bool", "int", "float", "str"]
    default: Scalar | None = None
    domain: list[Scalar] = Field(default_factory=list, max_length=MAX_DOMAIN)
    topic: str | None = Field(default=None, max_length=MAX_TEXT_FIELD)
    msg: str | None = Field(default=None, max_length=MAX_NAME)
    field: str | None = Field(default=None, max_length=MAX_TEXT_FIELD)

    def text(self) -> str:
        """One line for the page: `wall_close: bool <- /wall_close (std_msgs/msg/Bool data)`."""
        bound = f" <- {self.topic} ({self.msg} {self.field})" if self.topic is not None else ""
        return f"{self.name}: {self.type}{bound}"


class Description(_Strict):
    name: str = Name
    description: str | None = Field(default="", max_length=MAX_TEXT_FIELD)
    states: list[State] = Field(min_length=1, max_length=MAX_STATES)
    initial: str = Name
    suspend: str | None = Field(default=None, max_length=MAX_NAME)
    inputs: list[Input] = Field(default_factory=list, max_length=MAX_INPUTS)
    #: Wall time (seconds since the epoch) of the run's time 0 (a run on the wall clock says it).
    started: float | None = Field(default=None, ge=0, le=1e11, allow_inf_nan=False)

    @model_validator(mode="after")
    def _references(self) -> Description:
        names: set[str] = set()
        total = 0
        for i, s in enumerate(self.states):
            if s.name in names:
                raise ValueError(f"states.{i}.name: {_quote(s.name)} is named twice")
            names.add(s.name)
            total += len(s.transitions)
        if total > MAX_TRANSITIONS:
            raise ValueError(f"states: {total:,} transitions, at most {MAX_TRANSITIONS:,}")
        for i, s in enumerate(self.states):
            for k, t in enumerate(s.transitions):
                if t.target not in names:
                    raise ValueError(f"states.{i}.transitions.{k}.target: {_quote(t.target)} names no state")
        if self.initial not in names:
            raise ValueError(f"initial: {_quote(self.initial)} names no state")
        if self.suspend is not None and self.suspend not in names:
            raise ValueError(f"suspend: {_quote(self.suspend)} names no state")
        return self


def of_machine(m: Machine) -> dict[str, Any]:
    """The description of a machine directory as read (no build, no run): the shape a run
    publishes (llfsm.ros.control.description), guards as written (inline or in their files,
    without their `# -> TARGET` comment).  What a broken machine cannot describe is left out: a
    transition to no state, a second state of a name.  (layout.yaml's places are svg()'s own
    arguments: llfsm.lang.layout_file.)"""
    names: dict[str, None] = {}
    for s in m.states:
        names.setdefault(s.name, None)
    states = []
    for s in m.states:
        if s.name not in names:
            continue
        del names[s.name]
        states.append(
            {
                "name": s.name,
                "transitions": [
                    {"index": t.index, "target": t.target, "guard": expression(t.guard.text) if t.guard else ""}
                    for t in s.transitions
                    if any(t.target == o.name for o in m.states)
                ],
                "accepting": s.accepting and s.name != m.suspended,
            }
        )
    known = {s["name"] for s in states}
    out: dict[str, Any] = {
        "name": m.name,
        "description": m.description or "",
        "states": states,
        "initial": m.initial if m.initial in known else states[0]["name"],
        "suspend": m.suspended if m.suspended in known else None,
        "inputs": [
            {
                "name": i.name,
                "type": i.type,
                "default": i.default,
                "domain": i.values(),
                "topic": i.topic,
                "msg": i.msg,
                "field": i.field,
            }
            for i in m.inputs
            if i.type in ("bool", "int", "float", "str")
        ],
    }
    return out


def validate(desc: Any, machine: str | None = None) -> dict[str, Any]:
    """The description as a plain dict of checked values (the shape a run publishes), or
    DescriptionError.  `machine`, when given, is the name the topic announced: a description
    must be of the machine whose topic carries it."""
    if not isinstance(desc, dict):
        raise DescriptionError(f"the description is not a JSON object but {_kind(desc)}")
    try:
        model = Description.model_validate(desc)
    except ValidationError as e:
        raise DescriptionError(_first(e)) from None
    if machine is not None and model.name != machine:
        raise DescriptionError(f"name: {_quote(model.name)} is not the machine its topic names ({_quote(machine)})")
    out = model.model_dump()
    if out["description"] is None:
        out["description"] = ""
    return out


def parse_description(text: str, machine: str | None = None) -> dict[str, Any]:
    """`validate` of a description's JSON text (bounded in size and in nesting)."""
    if len(text) > MAX_TEXT:
        raise DescriptionError(f"{len(text):,} characters, at most {MAX_TEXT:,}")
    try:
        desc = json.loads(text)
    except RecursionError:
        raise DescriptionError("not JSON: nested too deeply") from None
    except ValueError as e:
        raise DescriptionError(f"not JSON: {e}") from None
    return validate(desc, machine)


def _first(e: ValidationError) -> str:
    """The first error of a validation, as `field.path: what` (and how many more)."""
    errors = e.errors(include_url=False, include_input=False)
    if not errors:
        return "does not fit"
    first = errors[0]
    loc = ".".join(str(p) for p in first.get("loc", ()))
    msg = str(first.get("msg", "invalid"))
    own = msg.removeprefix("Value error, ")  # our cross-reference checks say where themselves
    text = own if own != msg else f"{loc}: {msg}" if loc else msg
    more = len(errors) - 1
    return text + (f" (and {more} more)" if more else "")


def _quote(text: str, limit: int = 40) -> str:
    """A peer's text for a warning line: repr (control characters escaped), cut short."""
    return repr(text if len(text) <= limit else text[: limit - 1] + "…")


def _kind(value: Any) -> str:
    return {list: "an array", str: "a string", int: "a number", float: "a number", bool: "a boolean"}.get(
        type(value), "null" if value is None else type(value).__name__
    )
