"""LTL over the explored structure, under fairness (SPEC 11; docs/verify.md, "Fairness").

The negation of the formula becomes a generalized Büchi automaton (llfsm.props.automaton: built
on the fly, bounded); its product with the structure is explored from the initial
configuration, the automaton's states made as the product reaches them; the formula fails
exactly when the product has a reachable cycle that visits every acceptance set of the
automaton and every fairness set of the structure (one per machine: its time passes), and that
cycle, with a shortest path to it, is the counterexample: a lasso of configurations.

The product is bounded like the exploration (`max_nodes`, and the memory check the caller
passes in); `progress` is told how far it got about once a second.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from ..props.automaton import Automaton
from ..props.graph import cycle_through, nontrivial, sccs


@dataclass
class Lasso:
    """A counterexample: configurations from the initial one, the loop starting at `loop`
    (the last configuration steps to `path[loop]`)."""

    path: list[int]
    loop: int


class ProductLimit(Exception):
    """The product of the structure and the automaton passed its bound (the message says which)."""


class Structure:
    """What the checks read of an exploration: successors, labels, fairness, the initial one."""

    def __init__(
        self,
        count: int,
        succ: Callable[[int], Sequence[int]],
        labels: Sequence[int],
        fair: Sequence[int],
        fair_sets: int,
    ) -> None:
        self.count = count
        self.succ = succ
        self.labels = labels
        self.fair = fair
        #: how many fairness sets (bits of `fair`) a fair cycle must visit
        self.fair_sets = fair_sets


def check_ltl(
    structure: Structure,
    aut: Automaton,
    atom_ids: Sequence[int],
    progress: Callable[[int, int], None] | None = None,
    every: float = 1.0,
    max_nodes: int | None = None,
    memory_ok: Callable[[], bool] | None = None,
) -> Lasso | None:
    """None if every fair path from the initial configuration is rejected by `aut` (the
    automaton of the negated formula: atoms numbered locally, atom_ids giving each one's bit in
    the structure's labels); else a lasso.  `progress(product nodes, automaton states)` is
    called about every `every` seconds while the product is explored."""
    bits = [atom_ids[a] for a in aut.atoms]
    local: dict[int, int] = {}

    def label(c: int) -> int:
        v = local.get(c)
        if v is None:
            lab = structure.labels[c]
            v = local[c] = sum(1 << k for k, b in enumerate(bits) if lab >> b & 1)
        return v

    # product nodes are numbered as found; `node` -> (configuration, automaton state)
    ids: dict[tuple[int, int], int] = {}
    nodes: list[tuple[int, int]] = []
    parent: list[int] = []
    depth: list[int] = []
    succ_cache: dict[int, list[int]] = {}

    def node(c: int, q: int, par: int) -> tuple[int, bool]:
        key = (c, q)
        n = ids.get(key)
        if n is not None:
            return n, False
        n = ids[key] = len(nodes)
        nodes.append(key)
        parent.append(par)
        depth.append(depth[par] + 1 if par >= 0 else 0)
        return n, True

    def cached(n: int) -> list[int]:
        out = succ_cache.get(n)
        if out is None:
            c, q = nodes[n]
            out = []
            for c2 in structure.succ(c):
                for q2 in aut.successors(q, label(c2)):
                    out.append(node(c2, q2, n)[0])
            succ_cache[n] = out
        return out

    queue: deque[int] = deque()
    for q in aut.initial(label(0)):
        n, new = node(0, q, -1)
        if new:
            queue.append(n)
    last = time.monotonic()
    count = 0
    while queue:
        v = queue.popleft()
        before = len(nodes)
        cached(v)
        queue.extend(range(before, len(nodes)))
        count += 1
        if max_nodes is not None and len(nodes) > max_nodes:
            raise ProductLimit(f"the product with the formula's automaton passed {max_nodes:,} states")
        if not count & 0x3FF:
            if memory_ok is not None and not memory_ok():
                raise ProductLimit("the product with the formula's automaton passed the memory bound (--max-memory)")
            if progress is not None:
                now = time.monotonic()
                if now - last >= every:
                    last = now
                    progress(len(nodes), aut.count)
    full = (1 << aut.acceptance_sets) - 1

    def accepting(k: int) -> Callable[[int], bool]:
        return lambda n: bool(aut.accepting[nodes[n][1]] >> k & 1)

    def fair_in(k: int) -> Callable[[int], bool]:
        return lambda n: bool(structure.fair[nodes[n][0]] >> k & 1)

    want = [accepting(k) for k in range(aut.acceptance_sets)] + [fair_in(k) for k in range(structure.fair_sets)]
    best: Lasso | None = None
    for comp in sccs(range(len(nodes)), cached, lambda _n: True):
        if not nontrivial(comp, cached):
            continue
        acc = 0
        for n in comp:
            acc |= aut.accepting[nodes[n][1]]
        fair = all(any(structure.fair[nodes[n][0]] >> k & 1 for n in comp) for k in range(structure.fair_sets))
        if acc & full != full or not fair:
            continue
        if best is not None and min(depth[n] for n in comp) >= len(best.path):
            continue  # its prefix alone is no shorter than the lasso found
        members = set(comp)
        entry = min(comp, key=depth.__getitem__)  # the member nearest the initial configuration
        cycle = cycle_through(entry, want, cached, members.__contains__)
        path = _prefix(parent, entry) + cycle[1:-1]  # the last of the cycle is the entry again
        lasso = Lasso([nodes[n][0] for n in path], depth[entry])
        if best is None or len(lasso.path) < len(best.path):
            best = lasso
    return best


def _prefix(parent: list[int], node: int) -> list[int]:
    out = [node]
    while parent[out[-1]] != -1:
        out.append(parent[out[-1]])
    return out[::-1]
