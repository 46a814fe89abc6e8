"""The kinds of property (SPEC 11, 16): one table that parsing, `llfsm verify`, the monitor,
the exports and the help text all read.

Each kind says how its text is written (one condition, a pair, or a temporal formula), the
formula it stands for, how `verify` judges it (on the fly as configurations are found, or on the
explored structure afterwards), how a run's monitor judges it (at every ringlet boundary, as
pending obligations, three-valued LTL, at the end, or not at all and why), and whether it may
carry `within:`.  A new kind is a row here; nothing else compares kind names as strings.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

Formula = tuple[Any, ...]

#: How a kind's text is written.
CONDITION, PAIR, TEMPORAL = "condition", "pair", "temporal"
#: How `verify` judges a kind.
ON_THE_FLY, LTL, CTL = "on the fly", "ltl", "ctl"
#: How a run's monitor judges a kind.
EVERY_BOUNDARY, OBLIGATIONS, THREE_VALUED, AT_THE_END = "every boundary", "obligations", "three-valued", "at the end"


@dataclass(frozen=True)
class Kind:
    name: str
    #: CONDITION, PAIR (`[A, B]`) or TEMPORAL (an `ltl:`/`ctl:` formula)
    form: str
    #: what a person reads in `--help` and docs/verify.md: the property holds when...
    holds_when: str
    #: the formula of a CONDITION or PAIR kind over its atoms (a, or a and b)
    formula: Callable[..., Formula] | None
    #: ON_THE_FLY (decided as each configuration is found), LTL or CTL (on the structure)
    verify: str
    #: EVERY_BOUNDARY, OBLIGATIONS, THREE_VALUED, AT_THE_END; or None: the monitor refuses it
    monitor: str | None
    #: why the monitor refuses it (when `monitor` is None)
    monitor_refusal: str = ""
    #: may carry `within: DURATION` (a deadline)
    takes_within: bool = False
    #: a safety kind: violated by one configuration (its monitor verdict is final at once)
    safety: bool = False
    #: ON_THE_FLY kinds: the value of the atom that decides the property in a configuration...
    decided_by: bool = True
    #: ...and whether such a configuration proves it (a witness: reachable) or refutes it
    witness: bool = False


KINDS_TABLE: tuple[Kind, ...] = (
    Kind(
        "always",
        CONDITION,
        "P holds in every reachable configuration",
        lambda a: ("G", a),
        ON_THE_FLY,
        EVERY_BOUNDARY,
        safety=True,
        decided_by=False,
    ),
    Kind(
        "never",
        CONDITION,
        "P holds in none",
        lambda a: ("G", ("not", a)),
        ON_THE_FLY,
        EVERY_BOUNDARY,
        safety=True,
    ),
    Kind(
        "reachable",
        CONDITION,
        "P holds in some reachable configuration",
        lambda a: ("E", ("F", a)),
        ON_THE_FLY,
        AT_THE_END,
        witness=True,
    ),
    Kind(
        "eventually",
        CONDITION,
        "on every fair path P holds at some point (LTL F P)",
        lambda a: ("F", a),
        LTL,
        AT_THE_END,
    ),
    Kind(
        "leads_to",
        PAIR,
        "whenever A holds, B holds then or later (LTL G (A -> F B)); `within: D`: at most D later",
        lambda a, b: ("G", ("implies", a, ("F", b))),
        LTL,
        OBLIGATIONS,
        takes_within=True,
    ),
    Kind(
        "ctl",
        TEMPORAL,
        "the CTL formula holds in the initial configuration, quantifiers over fair paths",
        None,
        CTL,
        None,
        monitor_refusal="a CTL formula quantifies over every path from a configuration, and a run is one path",
    ),
    Kind(
        "ltl",
        TEMPORAL,
        "the LTL formula holds on every fair path (a run: satisfied, violated or pending so far)",
        None,
        LTL,
        THREE_VALUED,
    ),
)

BY_NAME: dict[str, Kind] = {k.name: k for k in KINDS_TABLE}
#: The kinds' names, in the table's order.
KINDS: tuple[str, ...] = tuple(BY_NAME)


def kind(name: str) -> Kind:
    """The kind of that name (KeyError for none)."""
    return BY_NAME[name]


def help_text() -> str:
    """The kinds as `--property` and `--monitor-property` list them."""
    return "; ".join(f"{k.name} ({k.holds_when})" for k in KINDS_TABLE)
