"""`llfsm graph --format mermaid`: a machine's diagram as a Mermaid state diagram."""

from __future__ import annotations

from typing import TYPE_CHECKING

from .text import guard_label, input_label

if TYPE_CHECKING:
    from ..lang.model import Machine


def mermaid(m: Machine) -> str:
    out = ["stateDiagram-v2"]
    if m.description:
        out.append(f"    %% {' '.join(m.description.split())}")
    for i in m.inputs:  # SPEC 11: what the machine reads from outside, as comments
        out.append(f"    %% input {input_label(i)}")
    out.append(f"    [*] --> {m.initial}")
    for s in m.states:
        if s.implicit:
            continue
        for t in s.transitions:
            label = guard_label(m, s.name, t.index).replace(";", "#59;")  # `;` would end the mermaid statement
            out.append(f"    {s.name} --> {t.target} : {t.index}. {label}")
        if s.accepting and s.name != m.suspended:
            out.append(f"    {s.name} --> [*]")
    return "\n".join(out) + "\n"
