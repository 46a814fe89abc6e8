"""layout.yaml: where the editor placed each state of a machine, and each transition's label
(SPEC 13, docs/machine-format.md).

```yaml
states:
  INITIAL: {x: 120, y: 40}     # the centre of the state's box
  END: {x: 120, y: 160}
labels:                        # optional: transition labels, by source state and transition number
  INITIAL:
    0: {x: 150, y: 100}        # the label's top-left corner
```

The file is optional and only about drawing: `build` never reads it (a machine builds to the same
bytes whatever its layout, llfsm.fingerprint leaves it out), `check` validates it (LF073 for a
file that is not of this form, at its line; LF072 for a state or transition it places that the
machine does not have), and the diagrams (llfsm.diagram.svg, `llfsm graph`, the editor) take
their positions from it where it has them.  Read from YAML nodes, with the reader's limits.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import yaml

from ..machinedir import LAYOUT_FILE
from .diagnostics import Diagnostic, diag
from .model import Loc, is_valid_name
from .reader import ReadResult, compose

#: Coordinates beyond this are no drawing anyone made.
MAX_COORD = 1e6

Point = tuple[float, float]


@dataclass
class Placement:
    """What layout.yaml says: state centres, label corners (by source state and transition
    number), and where each entry is written (for check's warnings)."""

    states: dict[str, Point] = field(default_factory=dict)
    labels: dict[tuple[str, int], Point] = field(default_factory=dict)
    state_locs: dict[str, Loc] = field(default_factory=dict)
    label_locs: dict[tuple[str, int], Loc] = field(default_factory=dict)


def placement(read: ReadResult) -> tuple[Placement | None, list[Diagnostic]]:
    """The machine's layout.yaml as the reader read it (None, and nothing to say, without one)."""
    if read.layout_text is None:
        return None, []
    return parse_layout(read.layout_text, str(read.path / LAYOUT_FILE))


def parse_layout(text: str, where: str, loader: type | None = None) -> tuple[Placement | None, list[Diagnostic]]:
    """layout.yaml's text (already read with the reader's limits) as a Placement, or None with
    LF073 at the line where it stops being of the documented form."""

    def refuse(line: int, col: int, msg: str) -> tuple[None, list[Diagnostic]]:
        return None, [diag("LF073", where, line, col, f"layout.yaml: {msg}")]

    if not text.strip():
        return Placement(), []
    root, refusal = compose(text, loader)
    if refusal is not None:
        return refuse(refusal[1], refusal[2], refusal[3].replace("machine.yaml", "layout.yaml"))
    out = Placement()
    if root is None or (isinstance(root, yaml.ScalarNode) and root.value in ("", "~", "null")):
        return out, []
    if not isinstance(root, yaml.MappingNode):
        return refuse(*_at(root), "must be a mapping with `states` (and `labels`)")
    for k, v in root.value:
        if not isinstance(k, yaml.ScalarNode) or k.value not in ("states", "labels"):
            return refuse(*_at(k), f"unknown key {_text(k)} (expected states, labels)")
        if _null(v):
            continue
        if not isinstance(v, yaml.MappingNode):
            return refuse(*_at(v), f"`{k.value}` must be a mapping of state names")
        for sk, sv in v.value:
            name = sk.value if isinstance(sk, yaml.ScalarNode) else None
            if name is None or not is_valid_name(name):
                return refuse(*_at(sk), f"{_text(sk)} is not a state name")
            if k.value == "states":
                point = _point(sv)
                if isinstance(point, str):
                    return refuse(*_at(sv), f"state {name}: {point}")
                out.states[name] = point
                out.state_locs[name] = Loc(file=LAYOUT_FILE, line=_at(sk)[0], column=_at(sk)[1])
                continue
            if not isinstance(sv, yaml.MappingNode):
                return refuse(*_at(sv), f"labels of {name} must be a mapping of transition numbers")
            for ik, iv in sv.value:
                if not isinstance(ik, yaml.ScalarNode) or not ik.value.isdigit() or len(ik.value) > 6:
                    return refuse(*_at(ik), f"{_text(ik)} is not a transition number of {name}")
                point = _point(iv)
                if isinstance(point, str):
                    return refuse(*_at(iv), f"label of transition {ik.value} of {name}: {point}")
                key = (name, int(ik.value))
                out.labels[key] = point
                out.label_locs[key] = Loc(file=LAYOUT_FILE, line=_at(ik)[0], column=_at(ik)[1])
    return out, []


def _point(node: yaml.Node) -> Point | str:
    """`{x: 1, y: 2}` as a point, or what is wrong with it."""
    if not isinstance(node, yaml.MappingNode):
        return "a position is `{x: NUMBER, y: NUMBER}`"
    values: dict[str, float] = {}
    for k, v in node.value:
        key = k.value if isinstance(k, yaml.ScalarNode) else None
        if key not in ("x", "y") or key in values:
            return f"unknown or repeated key {_text(k)} in a position (x, y)"
        if not isinstance(v, yaml.ScalarNode) or v.style:
            return f"{key} must be a number"
        try:
            number = float(v.value)
        except ValueError:
            return f"{key} must be a number, not {_text(v)}"
        if not math.isfinite(number) or abs(number) > MAX_COORD:
            return f"{key} must be a finite number within ±{MAX_COORD:g}"
        values[key] = number
    if len(values) != 2:
        return "a position needs both x and y"
    return values["x"], values["y"]


def _at(node: yaml.Node) -> tuple[int, int]:
    return node.start_mark.line + 1, node.start_mark.column + 1


def _null(node: yaml.Node) -> bool:
    return isinstance(node, yaml.ScalarNode) and not node.style and node.value in ("", "~", "null")


def _text(node: yaml.Node) -> str:
    if isinstance(node, yaml.ScalarNode):
        value = node.value if len(node.value) <= 40 else node.value[:39] + "…"
        return repr(value)
    return "a " + {"MappingNode": "mapping", "SequenceNode": "list"}.get(type(node).__name__, "value")
