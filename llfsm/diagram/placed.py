"""A machine's diagram where layout.yaml placed its states (docs/machine-format.md): the states
at the editor's places, the others where the layered layout (llfsm.diagram.layout) put them,
each transition a straight line between the borders of its two boxes (a pair of opposite
transitions drawn side by side), its label where the editor put it or beside its middle.
The drawing is moved so that nothing lies left of or above its margin."""

from __future__ import annotations

import math
from collections.abc import Hashable, Mapping, Sequence

from .layout import LABEL_OFFSET, MARGIN, EdgeSpec, Layout, NodeSpec, Route

#: How far apart the two lines of a pair of opposite transitions run.
PAIR_GAP = 8.0
#: Room between the placed states and the row of those layout.yaml does not place.
ROW_GAP = 40.0


def fixed(
    base: Layout,
    nodes: Sequence[NodeSpec],
    edges: Sequence[EdgeSpec],
    centres: Mapping[Hashable, tuple[float, float]],
    labels: Mapping[int, tuple[float, float]],
    above: Mapping[Hashable, Hashable] | None = None,
) -> Layout:
    """The nodes of `centres` there, the others in a row below them (in the layered layout's
    order), `above[n]` (a node) just above node n; every edge straight between the boxes'
    borders.  `labels`: edge index -> its label's top-left corner (else beside the middle)."""
    size = {n.id: (n.w, n.h) for n in nodes}
    at = {n.id: centres[n.id] for n in nodes if n.id in centres}
    above = above or {}
    row_y = max((y + size[i][1] / 2 for i, (_, y) in at.items()), default=0.0) + ROW_GAP
    x = min((x - size[i][0] / 2 for i, (x, _) in at.items()), default=0.0)
    over = {node: under for under, node in above.items() if under in at and node in size}  # above a placed node
    for n in sorted(
        (n for n in nodes if n.id not in at and n.id not in over), key=lambda n: base.centres.get(n.id, (0, 0))[::-1]
    ):
        at[n.id] = (x + n.w / 2, row_y + n.h / 2)
        x += n.w + ROW_GAP
    for node, under in over.items():
        at[node] = (at[under][0], at[under][1] - size[under][1] / 2 - ROW_GAP - size[node][1] / 2)
    pairs = {(e.src, e.dst) for e in edges}
    routes: list[Route] = []
    for k, e in enumerate(edges):
        if e.src == e.dst or e.src not in at or e.dst not in at:
            continue
        (x0, y0), (x1, y1) = at[e.src], at[e.dst]
        dx, dy = x1 - x0, y1 - y0
        length = math.hypot(dx, dy) or 1.0
        side = (0.0, -1.0) if abs(dx) > abs(dy) else (1.0, 0.0)  # a label above a line across, right of one down
        shift = (0.0, 0.0)
        if (e.dst, e.src) in pairs:  # a pair: each line (and its label) to its own side of the centre line
            side = (-dy / length, dx / length)
            shift = (side[0] * PAIR_GAP / 2, side[1] * PAIR_GAP / 2)
        a = _border((x0 + shift[0], y0 + shift[1]), (x1 + shift[0], y1 + shift[1]), size[e.src])
        b = _border((x1 + shift[0], y1 + shift[1]), (x0 + shift[0], y0 + shift[1]), size[e.dst])
        label = labels.get(k)
        if label is None and e.label is not None:
            w, h = e.label
            mx, my = (a[0] + b[0]) / 2, (a[1] + b[1]) / 2
            label = (mx + side[0] * (w / 2 + LABEL_OFFSET) - w / 2, my + side[1] * (h / 2 + LABEL_OFFSET) - h / 2)
        routes.append(Route(k, [a, b], label))
    xs = [x - size[i][0] / 2 for i, (x, _) in at.items()] + [r.label[0] for r in routes if r.label]
    ys = [y - size[i][1] / 2 for i, (_, y) in at.items()] + [r.label[1] for r in routes if r.label]
    dx, dy = MARGIN - min(xs, default=MARGIN), MARGIN - min(ys, default=MARGIN)
    moved = {i: (x + dx, y + dy) for i, (x, y) in at.items()}
    for r in routes:
        r.points = [(x + dx, y + dy) for x, y in r.points]
        if r.label is not None:
            r.label = (r.label[0] + dx, r.label[1] + dy)
    right = [x + size[i][0] / 2 for i, (x, _) in moved.items()]
    right += [r.label[0] + (edges[r.edge].label or (0.0, 0.0))[0] for r in routes if r.label]
    bottom = [y + size[i][1] / 2 for i, (_, y) in moved.items()]
    bottom += [r.label[1] + (edges[r.edge].label or (0.0, 0.0))[1] for r in routes if r.label]
    width, height = max(right, default=0.0) + MARGIN, max(bottom, default=0.0) + MARGIN
    return Layout(moved, routes, width, height, "free", base.ranks)


def straight(points: Sequence[tuple[float, float]]) -> str:
    """SVG path data of a polyline."""
    return " ".join(f"{'M' if i == 0 else 'L'}{x:.1f} {y:.1f}" for i, (x, y) in enumerate(points))


def _border(centre: tuple[float, float], toward: tuple[float, float], size: tuple[float, float]) -> tuple[float, float]:
    """Where the line from a box's centre toward a point leaves the box."""
    (x, y), (tx, ty), (w, h) = centre, toward, size
    dx, dy = tx - x, ty - y
    if dx == 0 and dy == 0:
        return x, y
    scale = min(w / 2 / abs(dx) if dx else math.inf, h / 2 / abs(dy) if dy else math.inf)
    return x + dx * scale, y + dy * scale
