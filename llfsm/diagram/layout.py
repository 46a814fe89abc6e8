"""A layered layout of a directed graph, in Sugiyama's manner, as Graphviz's `dot` lays graphs
out: the web view's machine diagrams and its graph of nodes and topics (docs/view.md), with no
Graphviz and nothing fetched.

1. Cycles: a depth-first search from the nodes in the order given (a machine's initial state
   first, transitions in priority order) reverses the edges that close a cycle, so that the
   rest reads forward; a reversed edge is drawn back against the flow.
2. Ranks: the longest path from the sources, each edge at least one rank long (two when any
   edge has a label: the label gets the rank in between, as dot places labels).
3. Every edge that spans ranks becomes a chain through one small dummy per rank it crosses;
   its label is a dummy as wide as the label, and the edge passes at that dummy's left side,
   so a label sits beside its edge, never on it, and no other edge passes through it.
4. Order within ranks: barycentre sweeps down and up, each followed by transposing neighbours
   while that removes crossings; the order with the fewest crossings seen is kept (crossings
   counted per pair of ranks in O(E log V)): ordering.py.
5. Positions along the ranks: each rank in turn is placed as close as its order and the gaps
   allow to the weighted mean of its neighbours (long edges weigh most, so they run straight),
   solved exactly by pooling adjacent violators.
6. Routes: within a rank's band an edge runs straight through its dummy, so the curves between
   ranks are the only places where edges meet; nodes and labels are never crossed.

The graph is small (a diagram draws a bounded number of states: llfsm.diagram.svg), and the
work per sweep is near linear, so the hostile descriptions `llfsm view` must survive are laid
out in bounded time.  Everything is deterministic: the same graph gives the same layout.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Hashable, Sequence
from dataclasses import dataclass, field

from .ordering import RANDOM_STARTS as RANDOM_STARTS  # the ordering's setting, named here as before
from .ordering import _order, _total_crossings

#: Gaps along a rank: between two nodes, between a node and an edge, between two edges.
NODE_GAP = 36.0
EDGE_GAP = 14.0
DUMMY_GAP = 8.0
#: Room between two ranks, at least and at most (more when edges between them run far sideways).
RANK_GAP_MIN = 18.0
RANK_GAP_MAX = 64.0
MARGIN = 16.0
#: Where a label starts beside the edge that carries it.
LABEL_OFFSET = 5.0
#: Sweeps of the ordering (fewer on a big graph: see ordering._sweeps).
SWEEPS = 24
#: Coordinate passes over all ranks.
PLACEMENT_PASSES = 12


@dataclass
class NodeSpec:
    """A node to place: its id, its size (width, height), and room to keep after it along its
    rank (a self-loop and its labels)."""

    id: Hashable
    w: float
    h: float
    after: float = 0.0


@dataclass
class EdgeSpec:
    """An edge to route; `label` is the size (width, height) of its label, if it has one.  A
    `back` edge is laid out against the flow whatever the search finds (the way back of a pair,
    such as a resume beside its suspend)."""

    src: Hashable
    dst: Hashable
    label: tuple[float, float] | None = None
    back: bool = False


@dataclass
class Route:
    """An edge as laid out: points from its source to its target (the first and last on the
    nodes' borders), and its label's top-left corner."""

    edge: int  # the index of its EdgeSpec
    points: list[tuple[float, float]]
    label: tuple[float, float] | None = None
    reversed: bool = False  # drawn against the flow (it closed a cycle)


@dataclass
class Layout:
    """Nodes' centres by id, the edges' routes (self-loops have none: the renderer draws them
    beside their node, in the room `after` kept), the drawing's size and its direction."""

    centres: dict[Hashable, tuple[float, float]]
    routes: list[Route]
    width: float
    height: float
    direction: str
    ranks: dict[Hashable, int] = field(default_factory=dict)
    crossings: int = 0


@dataclass
class _V:
    """A node of the proper graph: a real node, a label, or a plain dummy of an edge."""

    key: int
    rank: int
    breadth: float  # along the rank
    depth: float  # across it
    kind: str  # "node", "label", "dummy"
    before: float = 0.0  # extent before the anchor, along the rank
    after: float = 0.0  # extent after it
    x: float = 0.0  # the anchor's position along the rank
    up: list[int] = field(default_factory=list)
    down: list[int] = field(default_factory=list)
    spec: Hashable = None


def layered(
    nodes: Sequence[NodeSpec], edges: Sequence[EdgeSpec], direction: str = "TB", sweeps: int = SWEEPS
) -> Layout:
    """Lay the graph out, ranks from top to bottom ("TB") or from left to right ("LR")."""
    if direction not in ("TB", "LR"):
        raise ValueError(f"direction must be TB or LR, not {direction!r}")
    index = {n.id: i for i, n in enumerate(nodes)}
    live = [(k, e) for k, e in enumerate(edges) if e.src in index and e.dst in index and e.src != e.dst]
    flip = _reversed_edges(
        len(nodes), [(index[e.dst], index[e.src]) if e.back else (index[e.src], index[e.dst]) for _, e in live]
    )
    flip = [f != e.back for f, (_, e) in zip(flip, live, strict=True)]
    span = 2 if any(e.label is not None for _, e in live) else 1
    oriented = [
        (k, index[e.dst], index[e.src], True) if flipped else (k, index[e.src], index[e.dst], False)
        for (k, e), flipped in zip(live, flip, strict=True)
    ]
    rank = _ranks(len(nodes), [(a, b) for _, a, b, _ in oriented], span)
    lr = direction == "LR"
    vs: list[_V] = []
    for i, n in enumerate(nodes):
        breadth, depth = (n.h, n.w) if lr else (n.w, n.h)
        vs.append(_V(i, rank[i], breadth, depth, "node", breadth / 2, breadth / 2 + n.after, spec=n.id))
    chains: list[tuple[int, list[int], bool]] = []
    direct = _direct(oriented, rank)
    for k, a, b, flipped in oriented:
        chain = [a]
        label = edges[k].label
        if k in direct:  # beyond the budget: one curve, no room kept along the way (see _direct)
            chains.append((k, [a, b], flipped))
            continue
        middle = rank[a] + (rank[b] - rank[a]) // 2
        for r in range(rank[a] + 1, rank[b]):
            if label is not None and r == middle:
                lb, ld = (label[1], label[0]) if lr else label
                v = _V(len(vs), r, lb, ld, "label", 0.0, LABEL_OFFSET + lb)
            else:
                v = _V(len(vs), r, 0.0, 0.0, "dummy")
            vs.append(v)
            chain.append(v.key)
        chain.append(b)
        for u, w in itertools.pairwise(chain):
            vs[u].down.append(w)
            vs[w].up.append(u)
        chains.append((k, chain, flipped))
    layers = _order(vs, max(rank, default=0) + 1, sweeps)
    crossings = _total_crossings(vs, layers)
    _place(vs, layers, [chain for k, chain, _ in chains if k not in direct])
    return _routes(vs, layers, chains, nodes, direction, crossings, direct, [e.label is not None for e in edges])


#: Most dummies the proper graph gets.  A long edge costs one per rank it crosses, and every
#: step of the layout visits each: a 300-state machine whose states all lead to END (the how-to's
#: `not ros.ok()` everywhere) would make 90,000 of them and take half a minute.  Beyond the budget
#: the longest edges are drawn as one curve from their source to their target, keeping no room
#: along the way (they may pass behind a state); the shorter ones are laid out as before.
MAX_DUMMIES = 6000


def _direct(oriented: list[tuple[int, int, int, bool]], rank: list[int]) -> set[int]:
    """The edges (by index) that get no dummies: the longest, until the rest fit the budget."""
    spans = sorted(((rank[b] - rank[a] - 1, k) for k, a, b, _ in oriented), reverse=True)
    total = sum(span for span, _ in spans)
    out: set[int] = set()
    for span, k in spans:
        if total <= MAX_DUMMIES or span <= 1:
            break
        out.add(k)
        total -= span
    return out


# -- 1. cycles -------------------------------------------------------------------------------------


def _reversed_edges(n: int, edges: list[tuple[int, int]]) -> list[bool]:
    """Which edges close a cycle in a depth-first search from the nodes in order (iterative: a
    long chain of states must not hit Python's recursion limit)."""
    out: list[list[tuple[int, int]]] = [[] for _ in range(n)]
    for k, (a, b) in enumerate(edges):
        out[a].append((k, b))
    state = [0] * n  # 0 unseen, 1 on the stack, 2 done
    flip = [False] * len(edges)
    for root in range(n):
        if state[root]:
            continue
        state[root] = 1
        stack = [(root, 0)]
        while stack:
            v, i = stack[-1]
            if i < len(out[v]):
                stack[-1] = (v, i + 1)
                k, w = out[v][i]
                if state[w] == 1:
                    flip[k] = True
                elif state[w] == 0:
                    state[w] = 1
                    stack.append((w, 0))
            else:
                state[v] = 2
                stack.pop()
    return flip


# -- 2. ranks ---------------------------------------------------------------------------------------


def _ranks(n: int, edges: list[tuple[int, int]], span: int) -> list[int]:
    """Longest path from the sources; then each source but the first node is moved down to just
    above its nearest successor (a source left on rank 0 would pull long edges across the
    drawing)."""
    succ: list[list[int]] = [[] for _ in range(n)]
    indeg = [0] * n
    for a, b in edges:
        succ[a].append(b)
        indeg[b] += 1
    order = [v for v in range(n) if indeg[v] == 0]
    rank = [0] * n
    left = indeg[:]
    i = 0
    while i < len(order):
        v = order[i]
        i += 1
        for w in succ[v]:
            rank[w] = max(rank[w], rank[v] + span)
            left[w] -= 1
            if left[w] == 0:
                order.append(w)
    for v in range(1, n):
        if indeg[v] == 0 and succ[v]:
            rank[v] = max(rank[v], min(rank[w] for w in succ[v]) - span)
    return rank


# -- 4. order within ranks: ordering.py ------------------------------------------------------------


# -- 5. positions along the ranks ---------------------------------------------------------------------


def _gap(a: _V, b: _V) -> float:
    if a.kind == "node" and b.kind == "node":
        return NODE_GAP
    if a.kind == "node" or b.kind == "node":
        return EDGE_GAP
    return DUMMY_GAP


def _weight(a: _V, b: _V) -> float:
    """Gansner's weights: an edge between two dummies is kept straightest."""
    dummies = (a.kind != "node") + (b.kind != "node")
    return (1.0, 2.0, 8.0)[dummies]


def _place(vs: list[_V], layers: list[list[int]], chains: list[list[int]]) -> None:
    """Pack, then alternate passes towards the neighbours with straightening the long edges, so
    that the nodes settle around edges that already run straight."""
    for layer in layers:  # packed from the left
        x = 0.0
        prev: _V | None = None
        for k in layer:
            v = vs[k]
            if prev is not None:
                x += prev.after + _gap(prev, v) + v.before
            v.x = x
            prev = v
    for it in range(PLACEMENT_PASSES):
        seq = range(len(layers)) if it % 2 == 0 else range(len(layers) - 1, -1, -1)
        for r in seq:
            _place_rank(vs, layers[r])
        if it % 3 == 2:
            _straighten(vs, layers, chains)
    _straighten(vs, layers, chains)


def _place_rank(vs: list[_V], layer: list[int]) -> None:
    """The rank nearest its neighbours' mean positions, in its order with its gaps: weighted
    least squares under `x[i+1] - x[i] >= gap[i]`, by pooling adjacent violators."""
    if not layer:
        return
    targets, weights, offsets = [], [], []
    offset = 0.0
    for i, k in enumerate(layer):
        v = vs[k]
        if i:
            p = vs[layer[i - 1]]
            offset += p.after + _gap(p, v) + v.before
        total = w_sum = 0.0
        for u in v.up + v.down:
            w = _weight(v, vs[u])
            total += w * vs[u].x
            w_sum += w
        if w_sum == 0.0:  # alone: stay, gently
            total, w_sum = 0.01 * v.x, 0.01
        targets.append(total / w_sum - offset)
        weights.append(w_sum)
        offsets.append(offset)
    blocks: list[list[float]] = []  # [weighted sum, weight, count]
    for t, w in zip(targets, weights, strict=True):
        blocks.append([t * w, w, 1])
        while len(blocks) > 1 and blocks[-2][0] / blocks[-2][1] > blocks[-1][0] / blocks[-1][1]:
            s, w2, c = blocks.pop()
            blocks[-1][0] += s
            blocks[-1][1] += w2
            blocks[-1][2] += c
    i = 0
    for s, w, c in blocks:
        y = s / w
        for _ in range(int(c)):
            vs[layer[i]].x = y + offsets[i]
            i += 1


def _straighten(vs: list[_V], layers: list[list[int]], chains: list[list[int]]) -> None:
    """Make each edge's run of dummies (its label's included) one vertical line where their
    neighbours leave room: a long edge that shifts a little at every rank reads as a wiggle."""
    slot = {}
    for layer in layers:
        for i, k in enumerate(layer):
            slot[k] = i

    def room(k: int) -> tuple[float, float]:
        v, layer, i = vs[k], layers[vs[k].rank], slot[k]
        lo, hi = -math.inf, math.inf
        if i > 0:
            p = vs[layer[i - 1]]
            lo = p.x + p.after + _gap(p, v) + v.before
        if i + 1 < len(layer):
            n = vs[layer[i + 1]]
            hi = n.x - n.before - _gap(v, n) - v.after
        return lo, hi

    def align(run: list[int]) -> bool:
        lo, hi = -math.inf, math.inf
        for d in run:
            a, b = room(d)
            lo, hi = max(lo, a), min(hi, b)
        if lo > hi:
            return False
        xs = sorted(vs[d].x for d in run)
        x = min(max(xs[len(xs) // 2], lo), hi)
        for d in run:
            vs[d].x = x
        return True

    for _ in range(3):
        for chain in chains:
            run = chain[1:-1]
            if len(run) > 1 and not align(run):  # no room for all: each side of the label alone
                labels = [i for i, d in enumerate(run) if vs[d].kind == "label"]
                if labels:
                    align(run[: labels[0]])
                    align(run[labels[0] + 1 :])


# -- 6. routes ------------------------------------------------------------------------------------------


def _routes(
    vs: list[_V],
    layers: list[list[int]],
    chains: list[tuple[int, list[int], bool]],
    nodes: Sequence[NodeSpec],
    direction: str,
    crossings: int,
    direct: set[int] | frozenset[int] = frozenset(),
    labelled: Sequence[bool] = (),
) -> Layout:
    lo = min((v.x - v.before for v in vs), default=0.0)
    hi = max((v.x + v.after for v in vs), default=0.0)
    for v in vs:
        v.x += MARGIN - lo
    thickness = [max((vs[k].depth for k in layer), default=0.0) for layer in layers]
    # room between ranks grows with how far sideways the edges between them run
    gaps = []
    for r in range(len(layers) - 1):
        far = max((abs(vs[k].x - vs[w].x) for k in layers[r] for w in vs[k].down), default=0.0)
        gaps.append(min(RANK_GAP_MAX, max(RANK_GAP_MIN, 0.22 * far)))
    top: list[float] = []
    y = MARGIN
    for r, t in enumerate(thickness):
        top.append(y)
        y += t + (gaps[r] if r < len(gaps) else 0.0)
    depth_total = y + MARGIN
    breadth_total = hi - lo + 2 * MARGIN

    def at(b: float, d: float) -> tuple[float, float]:
        return (d, b) if direction == "LR" else (b, d)

    def centre_d(v: _V) -> float:
        return top[v.rank] + thickness[v.rank] / 2

    # ports: the edges leaving a node downward (or entering it from above) spread along its side,
    # in the order of where they go, so that they do not cross at the node
    out_port: dict[tuple[int, int], float] = {}
    in_port: dict[tuple[int, int], float] = {}
    for side, ports in (("down", out_port), ("up", in_port)):
        for v in vs:
            if v.kind != "node":
                continue
            ends = getattr(v, side)
            n = len(ends)
            if not n:
                continue
            step = min(12.0, max(0.0, v.breadth - 14.0) / max(1, n - 1))
            ordered = sorted(range(n), key=lambda i: (vs[ends[i]].x, i))
            for slot, i in enumerate(ordered):
                ports[(v.key, i)] = v.x + (slot - (n - 1) / 2) * step
    used_out: dict[int, int] = {}
    used_in: dict[int, int] = {}
    routes = []
    for k, chain, flipped in chains:
        a, b = vs[chain[0]], vs[chain[-1]]
        if k in direct:  # one curve between the middles of the two sides, its label beside its middle
            p0, p1 = at(a.x, centre_d(a) + a.depth / 2), at(b.x, centre_d(b) - b.depth / 2)
            points = [p1, p0] if flipped else [p0, p1]
            mid = ((p0[0] + p1[0]) / 2 + LABEL_OFFSET, (p0[1] + p1[1]) / 2)
            routes.append(Route(k, points, mid if labelled[k] else None, flipped))
            continue
        i = used_out.get(a.key, 0)
        used_out[a.key] = i + 1
        j = used_in.get(b.key, 0)
        used_in[b.key] = j + 1
        points = [at(out_port[(a.key, i)], centre_d(a) + a.depth / 2)]
        label = None
        for key in chain[1:-1]:
            v = vs[key]
            t = top[v.rank]
            points.append(at(v.x, t))
            points.append(at(v.x, t + thickness[v.rank]))
            if v.kind == "label":
                ld = top[v.rank] + (thickness[v.rank] - v.depth) / 2
                label = at(v.x + LABEL_OFFSET, ld)
        points.append(at(in_port[(b.key, j)], centre_d(b) - b.depth / 2))
        if flipped:
            points.reverse()
        routes.append(Route(k, points, label, flipped))
    centres = {nodes[v.key].id: at(v.x, centre_d(v)) for v in vs if v.kind == "node"}
    ranks = {nodes[v.key].id: v.rank for v in vs if v.kind == "node"}
    w, h = at(breadth_total, depth_total)
    return Layout(centres, routes, w, h, direction, ranks, crossings)


def path(points: Sequence[tuple[float, float]], direction: str = "TB") -> str:
    """SVG path data through a route's points: straight where the route runs within a rank,
    a curve that leaves and arrives along the flow between ranks."""
    if not points:
        return ""
    x0, y0 = points[0]
    out = [f"M{x0:.1f} {y0:.1f}"]
    for x1, y1 in points[1:]:
        if (direction == "TB" and math.isclose(x0, x1)) or (direction == "LR" and math.isclose(y0, y1)):
            out.append(f"L{x1:.1f} {y1:.1f}")
        elif direction == "TB":
            m = (y1 - y0) / 2
            out.append(f"C{x0:.1f} {y0 + m:.1f} {x1:.1f} {y1 - m:.1f} {x1:.1f} {y1:.1f}")
        else:
            m = (x1 - x0) / 2
            out.append(f"C{x0 + m:.1f} {y0:.1f} {x1 - m:.1f} {y1:.1f} {x1:.1f} {y1:.1f}")
        x0, y0 = x1, y1
    return " ".join(out)
