"""Machines of a given size for bench/edit.py: a ring of states, each with a guard to the next
and one back to the first, OnEntry code in each, as a person would write them."""

from __future__ import annotations

from pathlib import Path


def ring(folder: Path, name: str, states: int) -> Path:
    d = folder / f"{name}.machine"
    d.mkdir(parents=True)
    names = [f"S{i:03d}" for i in range(states)]
    lines = [f"description: a ring of {states} states (bench/edit.py)", "states:"]
    for i, s in enumerate(names):
        nxt = names[(i + 1) % states]
        lines += [f"  - name: {s}", f"    transitions: [{nxt}, {names[0]}]"]
        (d / f"State_{s}_Transition_0.expr").write_text(f"# -> {nxt}\nafter_ms({10 + i})\n")
        (d / f"State_{s}_Transition_1.expr").write_text(f"# -> {names[0]}\ncount > {1000 + i}\n")
        (d / f"State_{s}_OnEntry.py").write_text(f"count += 1\nlast = {i}\n")
    (d / "machine.yaml").write_text("\n".join(lines) + "\n")
    (d / "Variables.py").write_text("count: int = 0\nlast: int = 0\n")
    return d
