"""The choices of one step (SPEC 11; docs/verify.md): every valuation of the inputs of the
machine whose turn it is, each interval of its time in its state, and with `--interrupt` whether
`ros.ok()` falls before the ringlet, numbered in a fixed order so that a path is a list of
choice numbers and replays exactly (step.py runs a step with one of them).

Made as they are gone through, never as one list up front (SPEC 18): an arrangement whose
inputs multiply to more valuations than --max-states allows configurations is refused before
exploring (`input_product_refusal`).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator, Sequence
from typing import Any

from .store import Loaded


class Valuations(Sequence[tuple[Any, ...]]):
    """Every valuation of a machine's inputs, in the order of `itertools.product` over their
    domains: made one at a time, never as one list up front (SPEC 18), unless there are few."""

    #: Up to this many valuations are kept as a list (faster to go through again).
    KEEP = 4096

    def __init__(self, domains: list[tuple[Any, ...]]) -> None:
        self.domains = domains
        self.size = math.prod(len(d) for d in domains)
        self.kept: list[tuple[Any, ...]] | None = list(itertools.product(*domains)) if self.size <= self.KEEP else None

    def __len__(self) -> int:
        return self.size

    def __iter__(self) -> Iterator[tuple[Any, ...]]:
        return iter(self.kept) if self.kept is not None else itertools.product(*self.domains)

    def __getitem__(self, k: int) -> tuple[Any, ...]:  # type: ignore[override]  # no slices
        if self.kept is not None:
            return self.kept[k]
        out = []
        for d in reversed(self.domains):  # the last domain varies fastest
            k, r = divmod(k, len(d))
            out.append(d[r])
        return tuple(reversed(out))


class Choices(Sequence[tuple[tuple[Any, ...], int, bool]]):
    """The choices of one step, (input values, time, interrupt) in a fixed order (the values
    varying fastest, then the time, then the interrupt), made as they are gone through."""

    __slots__ = ("interrupts", "times", "valuations")

    def __init__(self, valuations: Valuations, times: Sequence[int], interrupts: tuple[bool, ...]) -> None:
        self.valuations, self.times, self.interrupts = valuations, times, interrupts

    def __len__(self) -> int:
        return len(self.valuations) * len(self.times) * len(self.interrupts)

    def __iter__(self) -> Iterator[tuple[tuple[Any, ...], int, bool]]:
        for it in self.interrupts:
            for tm in self.times:
                for v in self.valuations:
                    yield v, tm, it

    def __getitem__(self, c: int) -> tuple[tuple[Any, ...], int, bool]:  # type: ignore[override]  # no slices
        if not 0 <= c < len(self):
            raise IndexError(c)
        nv, nt = len(self.valuations), len(self.times)
        return self.valuations[c % nv], self.times[c // nv % nt], self.interrupts[c // (nv * nt)]


def input_product_refusal(loaded: Loaded, max_states: int) -> str | None:
    """Why an arrangement cannot be explored as its inputs' domains are: a machine whose inputs
    multiply to more valuations a ringlet than --max-states allows configurations."""
    for cls in loaded.classes:
        sizes = [(entry[0], len(entry[3])) for entry in cls.INPUTS]
        product = math.prod(n for _name, n in sizes)
        if product > max_states:
            names = ", ".join(f"{name} ({n})" for name, n in sizes if n > 1)
            return (
                f"machine {cls.NAME}: its inputs {names} multiply to {product:,} valuations a ringlet, more than "
                f"--max-states ({max_states:,}) allows configurations: make their domains smaller or split them"
            )
    return None
