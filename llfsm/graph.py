"""`llfsm graph`: a machine's diagram, guards on the arrows.  Built from the text alone."""

from __future__ import annotations

import json
import shutil
import subprocess

from .model import Machine


class GraphError(Exception):
    pass


def _guard(m: Machine, state: str, index: int) -> str:
    st = m.state(state)
    g = st.transitions[index].guard
    text = " ".join(g.text.split()) if g is not None else "?"
    return text if len(text) <= 60 else text[:57] + "..."


def mermaid(m: Machine) -> str:
    out = ["stateDiagram-v2"]
    if m.description:
        out.append(f"    %% {' '.join(m.description.split())}")
    out.append(f"    [*] --> {m.initial}")
    for s in m.states:
        if s.implicit:
            continue
        for t in s.transitions:
            label = _guard(m, s.name, t.index).replace(";", "#59;")  # `;` would end the mermaid statement
            out.append(f"    {s.name} --> {t.target} : {t.index}. {label}")
        if s.accepting and s.name != m.suspended:
            out.append(f"    {s.name} --> [*]")
    return "\n".join(out) + "\n"


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
    for s in m.states:
        for t in s.transitions:
            label = f"{t.index}. {_guard(m, s.name, t.index)}"
            out.append(f"    {_dot_str(s.name)} -> {_dot_str(t.target)} [label={_dot_str(label)}];")
    out.append("}")
    return "\n".join(out) + "\n"


def render_image(m: Machine, fmt: str) -> bytes:
    """SVG or PNG through Graphviz's `dot`, when it is installed."""
    exe = shutil.which("dot")
    if exe is None:
        raise GraphError(
            f"--format {fmt} needs Graphviz's `dot` program, which is not installed "
            "(e.g. `apt install graphviz`); --format mermaid and --format dot work without it"
        )
    proc = subprocess.run([exe, f"-T{fmt}"], input=dot(m).encode(), capture_output=True, timeout=60)
    if proc.returncode != 0:
        raise GraphError(f"dot failed: {proc.stderr.decode(errors='replace').strip()}")
    return proc.stdout
