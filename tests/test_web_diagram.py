"""The diagrams the web view draws, read as a user reads them (issue 22, "The web view"): guard
labels sit beside their edges, never on one; edges go round states, not through them; a machine
whose graph can be drawn without crossings is; the suspend state is connected to the rest (it
is entered from any state by suspend, and left by resume), not floating below a gap.

The SVG is parsed as the page's browser gets it; curves are sampled into polylines, so what is
measured is what is drawn.
"""

from __future__ import annotations

import itertools
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import pytest
from helpers import MACHINES, write_machine

from llfsm.diagram import layout as lay
from llfsm.diagram import svg as diagram
from llfsm.ros.control import description
from llfsm.targets import load

SVG = "{http://www.w3.org/2000/svg}"
SEEDS = sorted(p.stem for p in MACHINES.glob("*.machine"))


@dataclass(frozen=True)
class Rect:
    x: float
    y: float
    w: float
    h: float
    name: str = ""

    def shrunk(self, by: float) -> Rect:
        return Rect(self.x + by, self.y + by, self.w - 2 * by, self.h - 2 * by, self.name)

    def contains(self, p: tuple[float, float]) -> bool:
        return self.x < p[0] < self.x + self.w and self.y < p[1] < self.y + self.h

    def overlaps(self, o: Rect) -> bool:
        return self.x < o.x + o.w and o.x < self.x + self.w and self.y < o.y + o.h and o.y < self.y + self.h


def _numbers(text: str) -> list[float]:
    return [float(n) for n in re.findall(r"-?\d+(?:\.\d+)?", text)]


def polyline(d: str, steps: int = 24) -> list[tuple[float, float]]:
    """The points of an SVG path of M, L and C commands, curves sampled."""
    pts: list[tuple[float, float]] = []
    for cmd, args in re.findall(r"([MLC])([^MLC]*)", d):
        n = _numbers(args)
        if cmd in "ML":
            pts.append((n[0], n[1]))
        else:
            (x0, y0), (x1, y1, x2, y2, x3, y3) = pts[-1], n
            for i in range(1, steps + 1):
                t = i / steps
                a, b, c, e = (1 - t) ** 3, 3 * (1 - t) ** 2 * t, 3 * (1 - t) * t**2, t**3
                pts.append((a * x0 + b * x1 + c * x2 + e * x3, a * y0 + b * y1 + c * y2 + e * y3))
    return pts


def _cross(p: tuple[float, float], q: tuple[float, float], r: tuple[float, float], s: tuple[float, float]) -> bool:
    def orient(a: tuple[float, float], b: tuple[float, float], c: tuple[float, float]) -> float:
        return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])

    return (orient(p, q, r) * orient(p, q, s) < 0) and (orient(r, s, p) * orient(r, s, q) < 0)


def segment_hits_rect(a: tuple[float, float], b: tuple[float, float], r: Rect) -> bool:
    if r.contains(a) or r.contains(b):
        return True
    corners = [(r.x, r.y), (r.x + r.w, r.y), (r.x + r.w, r.y + r.h), (r.x, r.y + r.h)]
    return any(_cross(a, b, corners[i], corners[(i + 1) % 4]) for i in range(4))


@dataclass
class Drawing:
    states: dict[str, Rect]
    labels: list[Rect]
    edges: list[tuple[str, list[tuple[float, float]]]]  # (class, points)


def parse(svg: str) -> Drawing:
    root = ET.fromstring(svg)
    states: dict[str, Rect] = {}
    labels: list[Rect] = []
    edges: list[tuple[str, list[tuple[float, float]]]] = []
    for g in root.iter(SVG + "g"):
        cls = g.get("class", "").split()
        rect = g.find(SVG + "rect")
        if rect is None:
            continue
        r = Rect(*(float(rect.get(k, "0")) for k in ("x", "y", "width", "height")))
        if "state" in cls or "any-state" in cls:
            states[g.get("data-state") or "*any*"] = Rect(r.x, r.y, r.w, r.h, g.get("data-state") or "*any*")
        elif "guard" in cls:
            text = g.find(SVG + "text")
            labels.append(Rect(r.x, r.y, r.w, r.h, "".join(text.itertext()) if text is not None else ""))
    for p in root.iter(SVG + "path"):
        cls = p.get("class", "")
        if cls.split() and cls.split()[0] in ("transition", "suspend-edge") and "initial" not in cls:
            edges.append((cls, polyline(p.get("d", ""))))
    return Drawing(states, labels, edges)


def crossings(edges: list[tuple[str, list[tuple[float, float]]]], near: list[Rect]) -> int:
    """Points where two edges cross, away from the states (edges meet at a state's side)."""
    found = 0
    for i, (_, a) in enumerate(edges):
        for _, b in edges[i + 1 :]:
            for p, q in itertools.pairwise(a):
                for r, s in itertools.pairwise(b):
                    if _cross(p, q, r, s) and not any(x.shrunk(-6).contains(p) for x in near):
                        found += 1
    return found


def machine_svg(name: str) -> str:
    return diagram.svg(description(load(str(MACHINES / f"{name}.machine"))))


@pytest.mark.parametrize("name", SEEDS)
def test_guard_labels_sit_beside_edges_and_edges_go_round_states(name: str) -> None:
    d = parse(machine_svg(name))
    assert d.labels, "every transition of the seeds has a label"
    for label in d.labels:
        box = label.shrunk(1)
        for cls, pts in d.edges:
            hit = [(a, b) for a, b in itertools.pairwise(pts) if segment_hits_rect(a, b, box)]
            assert not hit, f"{name}: label {label.name!r} lies on an edge ({cls}) at {hit[0]}"
        for other in d.labels:
            assert other is label or not box.overlaps(other.shrunk(1)), (label.name, other.name)
        for state in d.states.values():
            assert not box.overlaps(state), (label.name, state.name)
    for cls, pts in d.edges:
        for state in d.states.values():
            inside = [p for p in pts if state.shrunk(2).contains(p)]
            assert not inside, f"{name}: an edge ({cls}) runs through {state.name} at {inside[0]}"


@pytest.mark.parametrize("name", SEEDS)
def test_the_seed_machines_are_drawn_without_crossings(name: str) -> None:
    """Each seed machine's graph can be drawn in layers without two edges crossing; a layered
    layout with crossing reduction finds such a drawing."""
    d = parse(machine_svg(name))
    assert crossings(d.edges, list(d.states.values())) == 0


@pytest.mark.parametrize("name", SEEDS)
def test_the_suspend_state_is_connected_and_sits_with_the_others(name: str) -> None:
    svg = machine_svg(name)
    desc = description(load(str(MACHINES / f"{name}.machine")))
    suspend = desc["suspend"]
    d = parse(svg)
    into = re.findall(rf'<path class="suspend-edge"[^>]*data-target="{suspend}"', svg)
    out = re.findall(rf'<path class="suspend-edge"[^>]*data-source="{suspend}"', svg)
    assert into and out, "suspend enters the suspend state from any state, resume leaves it"
    lowest = max(r.y for n, r in d.states.items() if n not in (suspend, "*any*"))
    assert d.states[suspend].y <= lowest, "the suspend state sits among the others, not below them"
    assert "suspend" in svg and "resume" in svg


def test_a_machine_with_loops_and_self_transitions_keeps_labels_off_edges(tmp_path: Path) -> None:
    """Back edges, parallel edges and self-loops: each label stays beside its own edge."""
    m = write_machine(
        tmp_path,
        "busy",
        {
            "A": [("B", "after_ms(1)"), ("C", "after_ms(2)"), ("A", "after_ms(3)"), ("D", "False")],
            "B": [("C", "after_ms(10)"), ("A", "after_ms(20) and True"), ("B", "after_ms(30)")],
            "C": [("A", "after_ms(5)"), ("D", "after_ms(6)"), ("D", "after_ms(7) or False")],
            "D": [("B", "after_ms(1000) and not False")],
        },
    )
    d = parse(diagram.svg(description(load(str(m)))))
    for label in d.labels:
        box = label.shrunk(1)
        for cls, pts in d.edges:
            assert not any(segment_hits_rect(a, b, box) for a, b in itertools.pairwise(pts)), (label, cls)
        for state in d.states.values():
            assert not box.overlaps(state), (label.name, state.name)


def test_the_layout_reduces_crossings_a_naive_order_would_have() -> None:
    """Two ranks wired crosswise in the order given: the layout reorders them."""
    nodes = [lay.NodeSpec(n, 40, 20) for n in ("a", "b", "c", "x", "y", "z")]
    edges = [lay.EdgeSpec(s, t) for s, t in (("a", "z"), ("b", "y"), ("c", "x"))]
    out = lay.layered(nodes, edges)
    assert out.crossings == 0
    xs = {k: c[0] for k, c in out.centres.items()}
    assert (xs["a"] < xs["b"] < xs["c"]) == (xs["z"] < xs["y"] < xs["x"])


def test_a_left_to_right_layout_puts_ranks_along_x() -> None:
    nodes = [lay.NodeSpec("talker", 60, 30), lay.NodeSpec("/chatter", 70, 24), lay.NodeSpec("listener", 60, 30)]
    edges = [lay.EdgeSpec("talker", "/chatter"), lay.EdgeSpec("/chatter", "listener")]
    out = lay.layered(nodes, edges, direction="LR")
    xs = [out.centres[n][0] for n in ("talker", "/chatter", "listener")]
    assert xs == sorted(xs) and xs[0] < xs[1] < xs[2]
    assert abs(out.centres["talker"][1] - out.centres["listener"][1]) < 1  # a straight line
