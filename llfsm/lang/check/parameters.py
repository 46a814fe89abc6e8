"""Rules on machine.yaml's `parameters:` (the machine variables that are parameters of the node
/llfsm/NAME): each names a variable of Variables.py (LF060), annotated with a type a parameter
can hold (LF061), once (LF062).  docs/parameters.md says what a parameter does at run time.
"""

from __future__ import annotations

from ..model import Machine
from ..parameter_types import PARAMETER_TYPES, parameter_type
from .checking import Checking


def parameters(c: Checking, m: Machine) -> None:
    """LF060, LF061, LF062 for each entry of `parameters:`."""
    if not m.parameters:
        return
    variables = {v.name: v for v in m.variables}
    state_variables = {v.name: s.name for s in m.states for v in s.variables}
    seen: set[str] = set()
    for p in m.parameters:
        if p.name in seen:
            c.at("LF062", p.loc, f"parameter {p.name} is listed twice")
            continue
        seen.add(p.name)
        v = variables.get(p.name)
        if v is None:
            where = (
                f" (it is a variable of state {state_variables[p.name]}; only machine variables can be parameters)"
                if p.name in state_variables
                else c.suggest.did_you_mean(p.name, variables)
            )
            c.at("LF060", p.loc, f"parameter {p.name} is not a machine variable of Variables.py{where}")
            continue
        if parameter_type(v.annotation) is None:
            c.at(
                "LF061",
                p.loc,
                f"parameter {p.name} is annotated `{v.annotation}` ({v.loc.file}:{v.loc.line}); a parameter is "
                f"one of: {', '.join(PARAMETER_TYPES)}",
            )
