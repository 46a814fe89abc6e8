"""LTL over the explored structure, under fairness (SPEC 11; docs/verify.md, "Fairness").

The negation of the formula becomes a generalized Büchi automaton by the elementary-set
construction (Baier and Katoen, Principles of Model Checking, 5.2): its states are the maximal
consistent sets of subformulas of the closure, a transition reads the configuration's atoms,
and each `a U b` gives an acceptance set.  The product with the structure is explored from the
initial configuration; the formula fails exactly when the product has a reachable cycle that
visits every acceptance set of the automaton and every fairness set of the structure (one per
machine: its time passes), and that cycle, with a shortest path to it, is the counterexample: a
lasso of configurations.

Formulas are small, so the automaton's states are enumerated outright.
"""

from __future__ import annotations

import itertools
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from .graph import cycle_through, nontrivial, sccs

Formula = tuple[Any, ...]
TRUE: Formula = ("true",)


def core(f: Formula) -> Formula:
    """`f` with only true, atoms, not, and, X, U (F, G, or, implies rewritten)."""
    op = f[0]
    if op in ("atom", "true"):
        return f
    if op == "not":
        return neg(core(f[1]))
    if op == "and":
        return ("and", core(f[1]), core(f[2]))
    if op == "or":
        return neg(("and", neg(core(f[1])), neg(core(f[2]))))
    if op == "implies":
        return neg(("and", core(f[1]), neg(core(f[2]))))
    if op == "X":
        return ("X", core(f[1]))
    if op == "U":
        return ("U", core(f[1]), core(f[2]))
    if op == "F":
        return ("U", TRUE, core(f[1]))
    if op == "G":
        return neg(("U", TRUE, neg(core(f[1]))))
    raise ValueError(f"not an LTL operator: {op}")


def neg(f: Formula) -> Formula:
    return f[1] if f[0] == "not" else ("not", f)


def _subformulas(f: Formula, out: dict[Formula, None]) -> None:
    if f[0] == "not":
        _subformulas(f[1], out)
        return
    for sub in f[1:] if f[0] not in ("atom",) else ():
        _subformulas(sub, out)
    out[f] = None


@dataclass
class Automaton:
    """A generalized Büchi automaton for a core formula over atoms (their local numbers)."""

    states: list[frozenset[Formula]]  # the true positive subformulas of each state
    initial: list[int]
    #: per state, per label (bits of the atoms it reads): the successor states
    moves: list[dict[int, list[int]]]
    labels: list[int]  # per state, the atoms true in it (bits)
    accepting: list[list[bool]]  # per acceptance set, per state
    atoms: list[int]  # the atom numbers the formula reads, ascending


def automaton(f: Formula) -> Automaton:
    """The automaton accepting exactly the paths that satisfy the core formula `f`."""
    subs: dict[Formula, None] = {}
    _subformulas(f, subs)
    positives = list(subs)  # children before parents
    atoms = sorted({g[1] for g in positives if g[0] == "atom"})
    free = [g for g in positives if g[0] in ("atom", "X", "U")]
    untils = [g for g in positives if g[0] == "U"]
    nexts = [g for g in positives if g[0] == "X"]

    def holds(g: Formula, true: frozenset[Formula]) -> bool:
        if g[0] == "not":
            return not holds(g[1], true)
        if g[0] == "true":
            return True
        if g[0] == "and":
            return holds(g[1], true) and holds(g[2], true)
        return g in true

    states: list[frozenset[Formula]] = []
    for bits in itertools.product((False, True), repeat=len(free)):
        true = frozenset(g for g, b in zip(free, bits, strict=True) if b)
        ok = True
        for u in untils:
            a, b = u[1], u[2]
            if holds(b, true) and u not in true:
                ok = False  # b holds: a U b holds
            elif u in true and not holds(b, true) and not holds(a, true):
                ok = False  # a U b holds but neither does: impossible now
        if ok:
            states.append(true)
    labels = [sum(1 << atoms.index(g[1]) for g in s if g[0] == "atom") for s in states]
    initial = [k for k, s in enumerate(states) if holds(f, s)]
    moves: list[dict[int, list[int]]] = []
    for s in states:
        by_label: dict[int, list[int]] = {}
        for k2, s2 in enumerate(states):
            if any((x in s) != holds(x[1], s2) for x in nexts):
                continue
            if any((u in s) != (holds(u[2], s) or (holds(u[1], s) and u in s2)) for u in untils):
                continue
            by_label.setdefault(labels[k2], []).append(k2)
        moves.append(by_label)
    accepting = [[(u not in s) or holds(u[2], s) for s in states] for u in untils]
    return Automaton(states, initial, moves, labels, accepting, atoms)


@dataclass
class Lasso:
    """A counterexample: configurations from the initial one, the loop starting at `loop`
    (the last configuration steps to `path[loop]`)."""

    path: list[int]
    loop: int


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


def check_ltl(structure: Structure, formula: Formula, atom_ids: Sequence[int]) -> Lasso | None:
    """None if every fair path from the initial configuration satisfies `formula` (atoms are
    numbered locally; atom_ids gives each one's bit in the structure's labels); else a lasso."""
    aut = automaton(core(neg(formula)))
    bits = [atom_ids[a] for a in aut.atoms]
    nb = len(aut.states)
    local: dict[int, int] = {}

    def label(c: int) -> int:
        v = local.get(c)
        if v is None:
            lab = structure.labels[c]
            v = local[c] = sum(1 << k for k, b in enumerate(bits) if lab >> b & 1)
        return v

    def succ(node: int) -> list[int]:
        c, b = divmod(node, nb)
        moves = aut.moves[b]
        out = []
        for c2 in structure.succ(c):
            for b2 in moves.get(label(c2), ()):
                out.append(c2 * nb + b2)
        return out

    starts = [0 * nb + b for b in aut.initial if aut.labels[b] == label(0)]
    # the reachable product, breadth first (its BFS tree gives the shortest prefix)
    parent: dict[int, int] = {s: -1 for s in starts}
    depth: dict[int, int] = {s: 0 for s in starts}
    order: list[int] = list(starts)
    queue = deque(starts)
    succ_cache: dict[int, list[int]] = {}

    def cached(node: int) -> list[int]:
        out = succ_cache.get(node)
        if out is None:
            out = succ_cache[node] = succ(node)
        return out

    while queue:
        v = queue.popleft()
        for w in cached(v):
            if w not in parent:
                parent[w] = v
                depth[w] = depth[v] + 1
                order.append(w)
                queue.append(w)

    def accepts(acc: list[bool]) -> Callable[[int], bool]:
        return lambda node: acc[node % nb]

    def fair_in(k: int) -> Callable[[int], bool]:
        return lambda node: bool(structure.fair[node // nb] >> k & 1)

    want = [accepts(acc) for acc in aut.accepting] + [fair_in(k) for k in range(structure.fair_sets)]
    best: Lasso | None = None
    for comp in sccs(order, cached, lambda _n: True):
        if not nontrivial(comp, cached) or not all(any(w(n) for n in comp) for w in want):
            continue
        if best is not None and min(depth[n] for n in comp) >= len(best.path):
            continue  # its prefix alone is no shorter than the lasso found
        members = set(comp)
        entry = min(comp, key=depth.__getitem__)  # the member nearest the initial configuration
        cycle = cycle_through(entry, want, cached, members.__contains__)
        nodes = _prefix(parent, entry) + cycle[1:-1]  # the last of the cycle is the entry again
        lasso = Lasso([n // nb for n in nodes], depth[entry])
        if best is None or len(lasso.path) < len(best.path):
            best = lasso
    return best


def _prefix(parent: dict[int, int], node: int) -> list[int]:
    out = [node]
    while parent[out[-1]] != -1:
        out.append(parent[out[-1]])
    return out[::-1]
