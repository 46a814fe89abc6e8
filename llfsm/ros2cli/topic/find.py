"""`topic find`: the topics of a given type, as `ros2 topic find TYPE` prints them."""

from __future__ import annotations

from .. import NOT_FOUND, SPIN_TIME, CliError
from ..discovery import discovered, where
from ..lookup import split_type


def find(type_text: str, *, count: bool = False, include_hidden: bool = False, spin_time: float = SPIN_TIME) -> str:
    """The topics that have type TYPE (`pkg/msg/Name`; `pkg/Name` is taken as that), one a line,
    after `spin_time` seconds of discovery; with `count`, their number.  TYPE need not be one
    llfsm has: the graph's names are compared, as ros2 compares them.  None found is status 1
    (ros2 prints nothing)."""
    pkg, kind, name = split_type(type_text, "msg")
    wanted = f"{pkg}/{kind}/{name}"
    with discovered(spin_time) as graph:
        topics = [t for t, types in graph.topics(include_hidden=include_hidden).items() if wanted in types]
    if count:
        return f"{len(topics)}\n"
    if not topics:
        raise CliError(f"no topics of type {wanted} found within {spin_time:g} s ({where()})", NOT_FOUND)
    return "".join(f"{t}\n" for t in topics)
