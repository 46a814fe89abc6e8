"""Step 4 of the layered layout (layout.py): the order of the nodes within each rank, the one
that crosses the fewest edges that a few sweeps find.

Barycentre (or median) sweeps down and up, each followed by transposing neighbours while that
removes crossings, from the order given, its mirror image and a few seeded shuffles (small
graphs only); the order with the fewest crossings seen is kept, then sifted.  Crossings are
counted per pair of ranks in O(E log V) (`_inversions`).  Everything is deterministic: the same
graph gives the same order.
"""

from __future__ import annotations

import random
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .layout import _V

#: Shuffled orders the sweeps also start from, on a small graph.
RANDOM_STARTS = 12


def _sweeps(vs: list[_V], sweeps: int) -> int:
    """Fewer sweeps on a big proper graph: a bounded diagram must still be laid out quickly."""
    if len(vs) > 3000:
        return min(sweeps, 4)
    if len(vs) > 800:
        return min(sweeps, 8)
    return sweeps


def _order(vs: list[_V], n_ranks: int, sweeps: int) -> list[list[int]]:
    """The order with the fewest crossings that sweeps from a few starts find: the order given,
    its mirror image and a few shuffles (seeded), with barycentres and with medians (a small
    graph only: the heuristics get stuck in different places, and a diagram is worth the few
    milliseconds)."""
    layers: list[list[int]] = [[] for _ in range(n_ranks)]
    # first order: each rank by the mean position of what is above it, rank 0 as given
    for v in sorted(vs, key=lambda v: (v.rank, v.key)):
        layers[v.rank].append(v.key)
    pos = [0.0] * len(vs)
    for r, layer in enumerate(layers):
        if r:
            layer.sort(key=lambda k: (_mean([pos[u] for u in vs[k].up], pos[k]), k))
        for i, k in enumerate(layer):
            pos[k] = i
    starts = [(layers, False)]
    if len(vs) <= 400:
        mirrored = [layer[::-1] for layer in layers]
        starts += [(layers, True), (mirrored, False), (mirrored, True)]
        shuffle = random.Random(len(vs)).shuffle  # seeded: the same graph, the same layout
        for i in range(RANDOM_STARTS):
            mixed = [layer[:] for layer in layers]
            for layer in mixed:
                shuffle(layer)
            starts.append((mixed, bool(i % 2)))
    best: list[list[int]] = layers
    best_c = -1
    for start, median in starts:
        found, c = _sweep(vs, [layer[:] for layer in start], _sweeps(vs, sweeps), median)
        if best_c < 0 or c < best_c:
            best, best_c = found, c
        if best_c == 0:
            break
    if best_c > 0 and len(vs) <= 400:
        best_c = _sift(vs, best, best_c)
    return best


def _sift(vs: list[_V], layers: list[list[int]], crossings: int) -> int:
    """Move each node in turn to the place in its rank where it crosses least (sifting): what
    the sweeps, which move whole ranks at once, cannot reach."""
    pos = [0.0] * len(vs)
    for layer in layers:
        for i, k in enumerate(layer):
            pos[k] = i
    for _ in range(4):
        for layer in layers:
            for v in list(layer):
                others = [w for w in layer if w != v]
                left = [_pair(vs, w, v, pos) for w in others]  # w stays left of v
                right = [_pair(vs, v, w, pos) for w in others]  # w stays right of v
                cost = sum(right)
                best_p, best_cost = 0, cost
                for p, _w in enumerate(others):
                    cost += left[p] - right[p]
                    if cost < best_cost:
                        best_p, best_cost = p + 1, cost
                here = layer.index(v)
                stay = sum(left[:here]) + sum(right[here:])
                if best_cost < stay:
                    others.insert(best_p, v)
                    layer[:] = others
                    for i, k in enumerate(layer):
                        pos[k] = i
        c = _total_crossings(vs, layers)
        if c >= crossings:
            return c
        crossings = c
    return crossings


def _sweep(vs: list[_V], layers: list[list[int]], sweeps: int, median: bool) -> tuple[list[list[int]], int]:
    n_ranks = len(layers)
    pos = [0.0] * len(vs)
    for layer in layers:
        for i, k in enumerate(layer):
            pos[k] = i
    best = [layer[:] for layer in layers]
    best_c = _total_crossings(vs, layers)
    stale = 0
    small = len(vs) <= 1500
    for it in range(sweeps):
        if best_c == 0:
            break
        down = it % 2 == 0
        seq = range(1, n_ranks) if down else range(n_ranks - 2, -1, -1)
        for r in seq:
            layer = layers[r]
            ref = layers[r - 1] if down else layers[r + 1]
            scale = (len(ref) - 1) / max(1, len(layer) - 1)
            keyed = []
            for i, k in enumerate(layer):
                at = [pos[u] for u in (vs[k].up if down else vs[k].down)]
                key = _median(at, i * scale) if median else _mean(at, i * scale)
                keyed.append((key, i, k))
            keyed.sort()
            layers[r] = [k for _, _, k in keyed]
            for i, k in enumerate(layers[r]):
                pos[k] = i
        if small:
            _transpose(vs, layers, pos)
        c = _total_crossings(vs, layers)
        if c < best_c:
            best, best_c, stale = [layer[:] for layer in layers], c, 0
        else:
            stale += 1
            if stale >= 6:
                break
    return best, best_c


def _median(values: list[float], default: float) -> float:
    if not values:
        return default
    s = sorted(values)
    m = len(s) // 2
    return s[m] if len(s) % 2 else (s[m - 1] + s[m]) / 2


def _mean(values: list[float], default: float) -> float:
    return sum(values) / len(values) if values else default


def _transpose(vs: list[_V], layers: list[list[int]], pos: list[float]) -> None:
    """Swap neighbours within a rank while that lowers the crossings with both adjacent ranks."""
    for _ in range(4):
        improved = False
        for layer in layers:
            for i in range(len(layer) - 1):
                a, b = layer[i], layer[i + 1]
                if _pair(vs, a, b, pos) > _pair(vs, b, a, pos):
                    layer[i], layer[i + 1] = b, a
                    pos[a], pos[b] = pos[b], pos[a]
                    improved = True
        if not improved:
            return


def _pair(vs: list[_V], a: int, b: int, pos: list[float]) -> int:
    """Crossings between a's edges and b's when a stands left of b."""
    c = 0
    for side in ("up", "down"):
        na, nb = getattr(vs[a], side), getattr(vs[b], side)
        for x in na:
            px = pos[x]
            for y in nb:
                if px > pos[y]:
                    c += 1
    return c


def _total_crossings(vs: list[_V], layers: list[list[int]]) -> int:
    total = 0
    for r in range(len(layers) - 1):
        lower_pos = {k: i for i, k in enumerate(layers[r + 1])}
        pairs = []
        for i, k in enumerate(layers[r]):
            for w in vs[k].down:
                pairs.append((i, lower_pos[w]))
        total += _inversions([b for _, b in sorted(pairs)], len(layers[r + 1]))
    return total


def _inversions(seq: list[int], size: int) -> int:
    """Pairs i < j with seq[i] > seq[j], with a Fenwick tree."""
    tree = [0] * (size + 1)
    count = 0
    for seen, x in enumerate(seq):
        i, below = x + 1, 0
        while i > 0:
            below += tree[i]
            i -= i & -i
        count += seen - below
        i = x + 1
        while i <= size:
            tree[i] += 1
            i += i & -i
    return count
