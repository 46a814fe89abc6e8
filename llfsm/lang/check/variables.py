"""Rules on the variables machine.yaml's states and the Variables.py files declare: names llfsm
reserves, names declared twice, state variables that shadow machine variables or meet another
name where the compiled class stores them (LF013, LF033, LF035).

The code of the initialisers is checked with all other code (llfsm.lang.check.code).
"""

from __future__ import annotations

from ...runtime.machine import MACROS, RESERVED
from ..bindings import attribute_of
from ..model import Loc, Machine, Variable
from .checking import Checking

#: The methods the compiled class defines per state (their names must stay free).
GENERATED_PREFIXES = ("ringlet_", "on_entry_", "internal_", "on_exit_", "on_suspend_", "on_resume_")


def declarations(c: Checking, m: Machine) -> None:
    """LF013, LF033, LF035 for the machine's and every state's variables."""
    generated = {f"{p}{s.name}" for s in m.states for p in GENERATED_PREFIXES}
    state_attrs: dict[str, tuple[str, str]] = {}  # attribute -> (state, variable) it stores
    machine_vars: dict[str, Variable] = {}
    for v in m.variables:
        reserved(c, v.name, v.loc, generated)
        if v.name in machine_vars:
            c.at("LF035", v.loc, f"machine variable {v.name} is declared twice")
        machine_vars[v.name] = v
    for s in m.states:
        seen: set[str] = set()
        for v in s.variables:
            reserved(c, v.name, v.loc, generated)
            if v.name in seen:
                c.at("LF035", v.loc, f"variable {v.name} of state {s.name} is declared twice")
                continue
            seen.add(v.name)
            if v.name in machine_vars:
                c.at("LF033", v.loc, f"state variable {v.name} of {s.name} shadows the machine variable {v.name}")
            # state variables live in attributes STATE__name: names with `__` can meet
            attr = attribute_of(s.name, v.name)
            clash = (
                f"the machine variable {attr}"
                if attr in machine_vars
                else f"variable {state_attrs[attr][1]} of state {state_attrs[attr][0]}"
                if attr in state_attrs
                else f"the method {attr} llfsm generates"
                if attr in generated
                else None
            )
            if clash is not None:
                c.at("LF013", v.loc, f"variable {v.name} of state {s.name} is stored as {attr}, as is {clash}")
            elif attr.startswith("__"):
                c.at(
                    "LF013",
                    v.loc,
                    f"variable {v.name} of state {s.name} is stored as {attr}, a name Python mangles; rename the state",
                )
            state_attrs.setdefault(attr, (s.name, v.name))


def reserved(c: Checking, name: str, loc: Loc, generated: set[str]) -> None:
    """LF013 for a declared variable whose name llfsm or Python takes for itself."""
    if (
        name in RESERVED
        or name in MACROS
        or name.startswith("_llfsm")
        or name in generated
        or name.startswith("__")  # a dunder, or a private name that Python would mangle
    ):
        what = (
            "an llfsm macro"
            if name in MACROS
            else "a private name, which Python mangles inside the compiled class"
            if name.startswith("__") and not name.endswith("__")
            else "reserved by llfsm"
        )
        c.at("LF013", loc, f"variable name {name!r} is {what}; choose another name")
