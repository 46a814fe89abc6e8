"""A guard's text as the label of an arrow: on one line, cut short (`llfsm graph`'s formats)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..lang.files import expression

if TYPE_CHECKING:
    from ..lang.model import Input, Machine

#: Characters of guard text on an arrow.
GUARD_MAX = 60


def guard_label(m: Machine, state: str, index: int) -> str:
    """The guard of transition `index` of `state`, whitespace folded, at most GUARD_MAX long."""
    st = m.state(state)
    g = st.transitions[index].guard
    text = " ".join(expression(g.text).split()) if g is not None else "?"
    return text if len(text) <= GUARD_MAX else text[: GUARD_MAX - 3] + "..."


def input_label(i: Input) -> str:
    """An input (SPEC 11) on one line: `wall_close: bool <- /wall_close (std_msgs/msg/Bool data)`,
    or with its domain when it is bound to nothing: `mode: int in [0, 1, 2]`."""
    if i.topic is not None:
        return f"{i.name}: {i.type} <- {i.topic} ({i.msg} {i.field})"
    values = i.values()
    return f"{i.name}: {i.type}" + (f" in [{', '.join(repr(v) for v in values)}]" if values else "")
