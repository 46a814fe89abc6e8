"""CTL over the explored structure, by fixpoints, under fairness (SPEC 11; docs/verify.md).

Path quantifiers range over fair paths (every machine's time passes: llfsm.verify.explorer),
as fair CTL is usually defined (Clarke, Grumberg, Peled, Model Checking, 6.5): a configuration
is fair when a fair path starts there (E_f G true); `EG f` holds where a path inside `f` reaches
a strongly connected set of `f` configurations that has a cycle and meets every fairness set;
`EX f` and `E[f U g]` ask for a fair configuration at the end; A-formulas are their duals.
Sets of configurations are bytearrays, one byte per configuration.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from typing import Any

from ..props.graph import nontrivial, sccs
from .ltl import Structure

Formula = tuple[Any, ...]
Set = bytearray


class CTL:
    def __init__(self, structure: Structure, atom_ids: Sequence[int]) -> None:
        self.s = structure
        self.atom_ids = atom_ids
        n = structure.count
        self.pred: list[list[int]] = [[] for _ in range(n)]
        for c in range(n):
            for d in structure.succ(c):
                self.pred[d].append(c)
        self.fair = self.eg(bytearray(b"\x01" * n))

    def sat(self, f: Formula) -> Set:
        n = self.s.count
        op = f[0]
        if op == "true":
            return bytearray(b"\x01" * n)
        if op == "atom":
            bit = self.atom_ids[f[1]]
            labels = self.s.labels
            return bytearray(labels[c] >> bit & 1 for c in range(n))
        if op == "not":
            return _not(self.sat(f[1]))
        if op == "and":
            return _and(self.sat(f[1]), self.sat(f[2]))
        if op == "or":
            return _or(self.sat(f[1]), self.sat(f[2]))
        if op == "implies":
            return _or(_not(self.sat(f[1])), self.sat(f[2]))
        if op in ("A", "E"):
            path = f[1]
            kind = path[0]
            if op == "E":
                if kind == "X":
                    return self.ex(self.sat(path[1]))
                if kind == "F":
                    return self.eu(bytearray(b"\x01" * n), self.sat(path[1]))
                if kind == "G":
                    return self.eg(self.sat(path[1]))
                return self.eu(self.sat(path[1]), self.sat(path[2]))
            if kind == "X":
                return _not(self.ex(_not(self.sat(path[1]))))
            if kind == "F":
                return _not(self.eg(_not(self.sat(path[1]))))
            if kind == "G":
                return _not(self.eu(bytearray(b"\x01" * n), _not(self.sat(path[1]))))
            a, b = self.sat(path[1]), self.sat(path[2])
            not_b = _not(b)
            return _not(_or(self.eu(not_b, _and(_not(a), not_b)), self.eg(not_b)))
        raise ValueError(f"not a CTL operator: {op}")

    def ex(self, f: Set) -> Set:
        target = _and(f, self.fair)
        out = bytearray(self.s.count)
        for d in range(self.s.count):
            if target[d]:
                for c in self.pred[d]:
                    out[c] = 1
        return out

    def eu(self, f: Set, g: Set) -> Set:
        """E[f U g]: a path through f to a fair configuration of g."""
        out = _and(g, self.fair)
        queue = deque(c for c in range(self.s.count) if out[c])
        while queue:
            d = queue.popleft()
            for c in self.pred[d]:
                if not out[c] and f[c]:
                    out[c] = 1
                    queue.append(c)
        return out

    def eg(self, f: Set) -> Set:
        """EG f under fairness: inside f, a way to a fair strongly connected part of f."""
        s = self.s
        need = s.fair_sets
        fair = s.fair

        def succ(c: int) -> Sequence[int]:
            return s.succ(c)

        out = bytearray(s.count)
        queue: deque[int] = deque()
        for comp in sccs(range(s.count), succ, lambda c: bool(f[c])):
            if not nontrivial(comp, lambda c: [d for d in succ(c) if f[d]]):
                continue
            if all(any(fair[c] >> k & 1 for c in comp) for k in range(need)):
                for c in comp:
                    out[c] = 1
                    queue.append(c)
        while queue:
            d = queue.popleft()
            for c in self.pred[d]:
                if not out[c] and f[c]:
                    out[c] = 1
                    queue.append(c)
        return out


def _not(a: Set) -> Set:
    return bytearray(1 - x for x in a)


def _and(a: Set, b: Set) -> Set:
    return bytearray(x & y for x, y in zip(a, b, strict=True))


def _or(a: Set, b: Set) -> Set:
    return bytearray(x | y for x, y in zip(a, b, strict=True))
