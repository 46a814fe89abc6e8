"""`llfsm graph --format dot`: a machine's diagram in Graphviz's language, guards on the arrows,
built from the text alone (SVG and PNG are drawn by llfsm itself: llfsm.diagram.svg, .png)."""

from __future__ import annotations

import json
from typing import TYPE_CHECKING

from .text import guard_label, input_label

if TYPE_CHECKING:
    from ..lang.model import Machine


def _dot_str(text: str) -> str:
    return json.dumps(text)  # a JSON string is a valid DOT quoted string


def dot(m: Machine) -> str:
    out = [
        f"digraph {_dot_str(m.name)} {{",
        "    rankdir=LR;",
        '    node [shape=box, style=rounded, fontname="Helvetica"];',
        '    edge [fontname="Helvetica", fontsize=10];',
        '    __start [shape=point, label=""];',
        f"    __start -> {_dot_str(m.initial)};",
    ]
    for s in m.states:
        if s.implicit:
            continue
        attrs = ", peripheries=2" if s.accepting and s.name != m.suspended else ""
        out.append(f"    {_dot_str(s.name)} [label={_dot_str(s.name)}{attrs}];")
    if m.inputs:  # SPEC 11: what the machine reads from outside, in a note (`\l`: a left-aligned line)
        lines = ["inputs", *(input_label(i) for i in m.inputs)]
        note = "".join(_dot_str(line)[1:-1] + "\\l" for line in lines)
        out.append(f'    __inputs [shape=note, label="{note}"];')
    for s in m.states:
        for t in s.transitions:
            label = f"{t.index}. {guard_label(m, s.name, t.index)}"
            out.append(f"    {_dot_str(s.name)} -> {_dot_str(t.target)} [label={_dot_str(label)}];")
    out.append("}")
    return "\n".join(out) + "\n"
