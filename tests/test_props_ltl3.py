"""LTL3 over a finite run (llfsm.props.automaton.Verdict3): the steps it keeps give what
stepping afresh gives, position by position, whatever came before."""

from __future__ import annotations

import random

import pytest

from llfsm.props.automaton import Verdict3

A, B = ("atom", 0), ("atom", 1)
FORMULAS = [
    ("G", ("implies", A, ("X", B))),
    ("U", A, B),
    ("G", ("F", A)),
    ("F", ("G", ("not", B))),
    ("and", ("G", ("or", A, B)), ("X", ("X", ("not", A)))),
]


@pytest.mark.parametrize("f", FORMULAS, ids=[str(k) for k in range(len(FORMULAS))])
def test_the_steps_kept_give_what_stepping_afresh_gives(f: tuple) -> None:
    rng = random.Random(7)
    kept = Verdict3(f)  # one for every run: what it kept in one run serves the next
    hits = 0
    for _run in range(40):
        kept._now = None  # a new run
        fresh = Verdict3(f)
        fresh.MEMO = 0  # keeps nothing
        labels = [rng.randrange(4) for _ in range(rng.randrange(1, 40))]
        for label in labels:
            hits += (kept._now, label) in kept._memo
            a, b = kept.step(label), fresh.step(label)
            assert a == b, (f, labels)
            if a is not None:
                break
    assert hits > 20
