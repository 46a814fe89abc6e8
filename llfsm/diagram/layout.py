"""A small layered layout of a machine's states, in the manner of Sugiyama: enough for the few
to few dozen states of an LLFSM (no Graphviz, nothing fetched).

1. Layers: breadth-first depth from the initial state, following transitions in priority
   order; states it never reaches (the suspend state, usually) go on a layer below.
2. Order within a layer: a few sweeps of the barycentre heuristic (each state moves towards the
   mean position of its neighbours), which removes most crossings of small graphs.

The input is a checked description (llfsm.diagram.description); llfsm.diagram.svg draws the
edges between the boxes placed here.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

NODE_H = 34
LAYER_GAP = 96
NODE_GAP = 56
MARGIN = 24
CHAR_W = 8.0  # of the 13 px state names


@dataclass
class Box:
    name: str
    layer: int
    x: float = 0.0  # centre
    y: float = 0.0  # top
    w: float = 0.0

    @property
    def left(self) -> float:
        return self.x - self.w / 2

    @property
    def right(self) -> float:
        return self.x + self.w / 2

    @property
    def bottom(self) -> float:
        return self.y + NODE_H

    @property
    def mid(self) -> float:
        return self.y + NODE_H / 2


def layout(desc: dict[str, Any]) -> tuple[dict[str, Box], float, float]:
    """Boxes by state name, and the drawing's width and height."""
    states = [s["name"] for s in desc["states"]]
    out: dict[str, list[str]] = {s["name"]: [t["target"] for t in s["transitions"]] for s in desc["states"]}
    layer: dict[str, int] = {}
    frontier = [desc["initial"]] if desc["initial"] in out else states[:1]
    for s in frontier:
        layer[s] = 0
    while frontier:
        nxt = []
        for s in frontier:
            for t in out.get(s, []):
                if t not in layer:
                    layer[t] = layer[s] + 1
                    nxt.append(t)
        frontier = nxt
    bottom = max(layer.values(), default=-1) + 1
    for s in states:  # unreached: on a layer of their own below the rest
        layer.setdefault(s, bottom)
    layers: list[list[str]] = [[] for _ in range(max(layer.values(), default=0) + 1)]
    for s in states:
        layers[layer[s]].append(s)
    layers = [lay for lay in layers if lay]
    for i, lay in enumerate(layers):
        for s in lay:
            layer[s] = i
    neighbours: dict[str, set[str]] = {s: set() for s in states}
    for s, targets in out.items():
        for t in targets:
            if t != s and t in neighbours:
                neighbours[s].add(t)
                neighbours[t].add(s)
    for _ in range(4):  # barycentre sweeps
        pos = {s: i / max(1, len(lay) - 1) for lay in layers for i, s in enumerate(lay)}
        for lay in layers:
            keyed = []
            for i, s in enumerate(lay):
                ns = [pos[n] for n in neighbours[s] if layer[n] != layer[s]]
                keyed.append((sum(ns) / len(ns) if ns else pos[s], i, s))
            lay[:] = [s for _, _, s in sorted(keyed)]
    boxes: dict[str, Box] = {}
    widths = []
    for i, lay in enumerate(layers):
        row = [Box(s, i, w=max(92.0, CHAR_W * len(s) + 30)) for s in lay]
        widths.append(sum(b.w for b in row) + NODE_GAP * (len(row) - 1))
        for b in row:
            boxes[b.name] = b
    inner = max(widths, default=0.0)
    for i, lay in enumerate(layers):
        x = MARGIN + (inner - widths[i]) / 2
        for s in lay:
            b = boxes[s]
            b.x, b.y = x + b.w / 2, MARGIN + 18 + i * (NODE_H + LAYER_GAP)
            x += b.w + NODE_GAP
    width = MARGIN * 2 + inner
    height = MARGIN * 2 + 18 + len(layers) * NODE_H + (len(layers) - 1) * LAYER_GAP
    return boxes, width, height
