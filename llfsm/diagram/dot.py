"""`llfsm graph --format dot|svg|png`: a machine's diagram as Graphviz text, guards on the arrows,
and as an image through Graphviz's `dot` program when it is installed.  Built from the text alone."""

from __future__ import annotations

import json
import shutil
import subprocess
from typing import TYPE_CHECKING

from .text import guard_label, input_label

if TYPE_CHECKING:
    from ..lang.model import Machine


class DiagramError(Exception):
    """An image could not be made (no Graphviz, or `dot` failed)."""


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


def render_image(m: Machine, fmt: str) -> bytes:
    """SVG or PNG through Graphviz's `dot`, when it is installed."""
    exe = shutil.which("dot")
    if exe is None:
        raise DiagramError(
            f"--format {fmt} needs Graphviz's `dot` program, which is not installed "
            "(e.g. `apt install graphviz`); --format mermaid and --format dot work without it"
        )
    proc = subprocess.run([exe, f"-T{fmt}"], input=dot(m).encode(), capture_output=True, timeout=60)
    if proc.returncode != 0:
        raise DiagramError(f"dot failed: {proc.stderr.decode(errors='replace').strip()}")
    return proc.stdout
