"""LTL formulas as generalized Büchi automata, built on the fly and bounded (SPEC 11, 18), and
the three-valued verdict of a finite run (SPEC 16).

The automaton of a core formula (llfsm.props.formula.core: true, atoms, not, and, X, U) is the
elementary-set construction (Baier and Katoen, Principles of Model Checking, 5.2): a state is
the set of the formula's atoms, X- and U-subformulas true at a position; a transition reads the
next position's atoms; each `a U b` gives an acceptance set.  Its states are made only as a
check reaches them: `successors(q, label)` chooses, for the next position with those atoms,
the X and U subformulas true there, one at a time in an order where each is decided after its
parts, and drops a choice as soon as it breaks a rule, so the 2^n sets of the textbook
construction are never enumerated.

Bounds: a formula with more than MAX_TEMPORAL X and U subformulas is refused before anything is
built (its automaton may need 2^n states), and building stops with AutomatonTooLarge past
MAX_STATES states; both are one line for the user (docs/verify.md, "Limits").

`Verdict3` judges a finite run (LTL3: Bauer, Leucker, Schallhart, 2011): the automata of the
formula and of its negation follow the run; the formula is violated once no state of the
first can go on for ever, satisfied once none of the second can, pending otherwise.
"""

from __future__ import annotations

from collections.abc import Iterator

from .atoms import PropertyError
from .formula import Formula, core, neg
from .graph import reachable_accepting_cycle

#: At most this many X and U subformulas in one formula (after rewriting F, G, ->, |).
MAX_TEMPORAL = 20
#: At most this many automaton states are built for one formula.
MAX_STATES = 50_000


class AutomatonTooLarge(PropertyError):
    """The automaton of a formula would pass the bounds (the message says which)."""


def _subformulas(f: Formula) -> list[Formula]:
    """The subformulas of `f` (negations looked through), each once, parts before wholes."""
    out: dict[Formula, None] = {}
    stack: list[tuple[Formula, bool]] = [(f, False)]
    while stack:
        g, done = stack.pop()
        if g[0] == "not":
            stack.append((g[1], False))
            continue
        if done or g[0] in ("atom", "true"):
            out.setdefault(g, None)
            continue
        if g in out:
            continue
        stack.append((g, True))
        stack.extend((x, False) for x in reversed(g[1:]))
    return list(out)


class Automaton:
    """The automaton accepting exactly the paths that satisfy the core formula `f`.

    States are numbered as they are made; `atoms` are the atom numbers the formula reads, and a
    label is a bit mask over them (bit k: atoms[k] holds)."""

    def __init__(self, f: Formula, max_states: int = MAX_STATES, text: str = "") -> None:
        self.formula = f
        self.max_states = max_states
        self.text = text
        subs = _subformulas(f)
        self.atoms = sorted({g[1] for g in subs if g[0] == "atom"})
        self._bit = {a: 1 << k for k, a in enumerate(self.atoms)}
        #: the X and U subformulas, parts before wholes: what a state chooses
        self.chosen = [g for g in subs if g[0] in ("X", "U")]
        if len(self.chosen) > MAX_TEMPORAL:
            raise AutomatonTooLarge(
                f"{text or 'the formula'}: its automaton could need 2^{len(self.chosen)} states "
                f"({len(self.chosen)} X and U subformulas once F, G, -> and | are rewritten; at most {MAX_TEMPORAL}): "
                "split it into several properties"
            )
        self.untils = [g for g in self.chosen if g[0] == "U"]
        position = {g: k for k, g in enumerate(self.chosen)}
        #: per X subformula: (the position after which its part can be judged, the X, its part)
        self._nexts = [
            (max((position[h] for h in _subformulas(g[1]) if h in position), default=-1), g, g[1])
            for g in self.chosen
            if g[0] == "X"
        ]
        self.states: list[tuple[int, frozenset[Formula]]] = []  # (label, the X and U true)
        self._ids: dict[tuple[int, frozenset[Formula]], int] = {}
        self._moves: dict[tuple[int, int], list[int]] = {}
        self._initial: dict[int, list[int]] = {}
        self.accepting: list[int] = []  # per state: a bit per acceptance set (per U) it is in

    @property
    def count(self) -> int:
        return len(self.states)

    @property
    def acceptance_sets(self) -> int:
        return len(self.untils)

    # -- what a state makes true ----------------------------------------------------------------
    def holds(self, g: Formula, label: int, true: frozenset[Formula] | dict[Formula, bool]) -> bool:
        op = g[0]
        if op == "not":
            return not self.holds(g[1], label, true)
        if op == "true":
            return True
        if op == "atom":
            return bool(label & self._bit[g[1]])
        if op == "and":
            return self.holds(g[1], label, true) and self.holds(g[2], label, true)
        return bool(true.get(g, False)) if isinstance(true, dict) else g in true

    def _state(self, label: int, true: frozenset[Formula]) -> int:
        key = (label, true)
        q = self._ids.get(key)
        if q is None:
            if len(self.states) >= self.max_states:
                raise AutomatonTooLarge(
                    f"{self.text or 'the formula'}: its automaton passed {self.max_states:,} states: "
                    "split it into several properties"
                )
            q = self._ids[key] = len(self.states)
            self.states.append(key)
            acc = 0
            for k, u in enumerate(self.untils):
                if u not in true or self.holds(u[2], label, true):
                    acc |= 1 << k
            self.accepting.append(acc)
        return q

    # -- the states, made as they are asked for -----------------------------------------------------
    def _choices(self, label: int, previous: int | None) -> Iterator[frozenset[Formula]]:
        """Every consistent set of X and U subformulas true at a position with atoms `label`,
        after the state `previous` (None: the first position)."""
        prev_label, prev_true = self.states[previous] if previous is not None else (0, frozenset())
        chosen = self.chosen
        true: dict[Formula, bool] = {}
        # the X subformulas of `previous` say what holds here: checked once their part is decided
        checks: dict[int, list[tuple[Formula, bool]]] = {}
        if previous is not None:
            for last, x, part in self._nexts:
                checks.setdefault(last, []).append((part, x in prev_true))
        for want in checks.get(-1, ()):
            if self.holds(want[0], label, true) != want[1]:
                return

        def assign(k: int) -> Iterator[frozenset[Formula]]:
            if k == len(chosen):
                yield frozenset(g for g, v in true.items() if v)
                return
            g = chosen[k]
            options: tuple[bool, ...] = (False, True)
            if g[0] == "U":
                if self.holds(g[2], label, true):
                    options = (True,)
                elif not self.holds(g[1], label, true):
                    options = (False,)
                # a at the previous position and b not: a U b holds here iff it held there
                if (
                    previous is not None
                    and not self.holds(g[2], prev_label, prev_true)
                    and self.holds(g[1], prev_label, prev_true)
                ):
                    options = tuple(v for v in options if v == (g in prev_true))
            for v in options:
                true[g] = v
                if all(self.holds(f, label, true) == want for f, want in checks.get(k, ())):
                    yield from assign(k + 1)
            true.pop(g, None)

        yield from assign(0)

    def initial(self, label: int) -> list[int]:
        """The states a path whose first position has atoms `label` may start in."""
        out = self._initial.get(label)
        if out is None:
            out = [self._state(label, t) for t in self._choices(label, None) if self.holds(self.formula, label, t)]
            self._initial[label] = out
        return out

    def successors(self, q: int, label: int) -> list[int]:
        """The states after `q` at a position with atoms `label`."""
        key = (q, label)
        out = self._moves.get(key)
        if out is None:
            out = self._moves[key] = [self._state(label, t) for t in self._choices(label, q)]
        return out

    def labels(self) -> range:
        return range(1 << len(self.atoms))


class Verdict3:
    """LTL3 over a finite run, position by position: `step(label)` reads one position (atoms as
    a bit mask over `atoms`) and returns True (satisfied whatever follows), False (violated
    whatever follows) or None (pending).

    The two automata are followed as sets of states, the subset construction made as the run
    goes; each (sets, label) seen is kept with its outcome, so a monitor that judges a formula at
    every boundary pays a dict look-up for a step taken before (at most MEMO of them are kept)."""

    #: The most steps kept (a set of states is a few small ints: a few MB at most).
    MEMO = 4096

    def __init__(self, f: Formula, text: str = "") -> None:
        self.yes = Automaton(core(f), text=text)
        self.no = Automaton(core(neg(f)), text=text)
        self.atoms = sorted(set(self.yes.atoms) | set(self.no.atoms))
        self._now: tuple[tuple[int, ...], tuple[int, ...]] | None = None
        self._alive: dict[tuple[int, int], bool] = {}
        self._memo: dict[tuple[object, int], tuple[tuple[tuple[int, ...], tuple[int, ...]], bool | None]] = {}

    def _local(self, aut: Automaton, label: int) -> int:
        """A label over all the atoms as the automaton's own (its atoms are a subset)."""
        out = 0
        for k, a in enumerate(aut.atoms):
            if label >> self.atoms.index(a) & 1:
                out |= 1 << k
        return out

    def step(self, label: int) -> bool | None:
        key = (self._now, label)
        hit = self._memo.get(key)
        if hit is not None:
            self._now = hit[0]
            return hit[1]
        if self._now is None:
            yes = tuple(self.yes.initial(self._local(self.yes, label)))
            no = tuple(self.no.initial(self._local(self.no, label)))
        else:
            ly, ln = self._local(self.yes, label), self._local(self.no, label)
            yes = tuple(sorted({r for q in self._now[0] for r in self.yes.successors(q, ly)}))
            no = tuple(sorted({r for q in self._now[1] for r in self.no.successors(q, ln)}))
        self._now = (yes, no)
        if not any(self._goes_on(self.yes, 0, q) for q in yes):
            out: bool | None = False
        elif not any(self._goes_on(self.no, 1, q) for q in no):
            out = True
        else:
            out = None
        if len(self._memo) < self.MEMO:
            self._memo[key] = (self._now, out)
        return out

    def _goes_on(self, aut: Automaton, which: int, q: int) -> bool:
        """Whether some infinite word is accepted from state q: a cycle reachable from it that
        meets every acceptance set (the automaton explored over every label)."""
        key = (which, q)
        known = self._alive.get(key)
        if known is not None:
            return known

        def succ(r: int) -> list[int]:
            return sorted({s for label in aut.labels() for s in aut.successors(r, label)})

        full = (1 << aut.acceptance_sets) - 1
        found = reachable_accepting_cycle(q, succ, lambda r: aut.accepting[r], full)
        self._alive[key] = found
        return found
