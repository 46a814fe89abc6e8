"""The monitor judges a property only where its value can change (docs/monitor.md, "Cost"): the
verdicts must be exactly those of judging every ringlet boundary, run for run (ringlet numbers,
states, variables), over machines that change their variables through other names, command each
other, publish, take parameters from outside, and finish."""

from __future__ import annotations

import ast
import sys
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner
from helpers import write_machine
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from llfsm.cli import cli
from llfsm.monitor import Monitor
from llfsm.monitor.bounds import merge_bounds
from llfsm.props.file import PropertySource
from llfsm.runtime import SimClock
from llfsm.runtime.context import RunContext
from llfsm.runtime.reads import class_reads
from llfsm.runtime.scheduler import Arrangement
from llfsm.targets import load


def _machines(root: Path) -> list[Path]:
    a = write_machine(
        root,
        "a",
        {
            "INIT": [("GROW", "True")],
            "GROW": [("WAIT", "after_ms(2)")],
            "WAIT": [("GROW", "after_ms(3) and len(items) < 9")],
        },
        code={
            "INIT_OnEntry": "alias = items\nkeep(box)\n",
            "GROW_OnEntry": "n += 1\n",
            "GROW_Internal": "if n % 2 == 0:\n    alias.append(n)\n",
            "WAIT_OnEntry": "seen = f'{n} {len(items)}'\n",
            "WAIT_Internal": "poke()\n",
        },
        variables="n: int = 0\nitems: list = []\nalias: list = []\nseen: str = ''\nquiet: int = 7\nbox: list = []\n",
        # box is handed to a function of a helper module, which keeps it; another changes it
        includes="from monitor_keeper import keep, poke\n",
    )
    (root / "monitor_keeper.py").write_text(
        "KEPT = []\ndef keep(x):\n    KEPT.append(x)\ndef poke():\n    KEPT[-1].append(1)\n"
    )
    b = write_machine(
        root,
        "b",
        {"S1": [("S2", "after_ms(7)")], "S2": [("S1", "after_ms(5)")]},
        code={"S2_OnEntry": 'suspend("a")\nk += 1\n', "S1_OnEntry": 'if k:\n    resume("a")\n'},
        variables="k: int = 0\n",
    )
    c = write_machine(
        root,
        "c",
        {
            "START": [("PUB", "True")],
            "PUB": [("IDLE", "True")],
            "IDLE": [("PUB", "after_ms(4)"), ("END", "k > 5")],
            "END": None,
        },
        code={
            "START_OnEntry": 'ros.init()\nnode = ros.Node("c")\npub = node.create_publisher(Int32, "/tick", 10)\n',
            "PUB_OnEntry": "k += 1\npub.publish(Int32(data=k))\n",
        },
        variables="k: int = 0\nnode: object = None\npub: object = None\n",
        includes="from llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import Int32\n",
    )
    return [a, b, c]


PROPERTIES = [
    ("always", "a.n < 4"),
    ("never", "len(a.items) >= 2"),
    ("never", 'suspended(a) and state(b) == "S1"'),
    ("always", 'state(a) != "WAIT" or a.seen != ""'),
    ("never", "a.quiet != 7"),
    ("never", "len(a.box) >= 3"),
    ("always", 'not published("/tick") or state(c) == "PUB"'),
    ("never", 'published("/tick") and c.k == 3'),
    ("reachable", "finished(c)"),
    ("eventually", 'state(b) == "S2" and suspended(a)'),
    ("leads_to", '[state(b) == "S2", state(a) == "GROW"]'),
    ("ltl", 'G (published("/tick") -> F state(c) == "IDLE")'),
    ("ltl", 'F G state(c) == "END"'),
    ("ltl", 'G (state(a) == "WAIT" -> state(a) == "WAIT" U state(a) == "GROW")'),
]


def _run(classes: list[Any], sources: list[PropertySource], targeted: bool, period: int = 1_000_000) -> list[str]:
    lines: list[str] = []
    ctx = RunContext(SimClock(period))
    arr = Arrangement(classes, context=ctx)
    monitor = Monitor(sources, classes, "log", lines.append, targeted=targeted)
    monitor.attach(arr)
    told = []

    def parameters() -> None:  # a parameter set from outside once, between rounds
        if ctx.clock.now >= 23_000_000 and not told:
            told.append(1)
            arr.set_variables("a", {"quiet": 8})
        ctx.wake_at(23_000_000)

    ctx.between_rounds.append(parameters)
    ctx.wake_at(0)
    arr.run(90_000_000)
    return lines


@pytest.fixture(scope="module")
def classes(tmp_path_factory: pytest.TempPathFactory) -> list[Any]:
    return [load(str(p)) for p in _machines(tmp_path_factory.mktemp("m"))]


@pytest.mark.parametrize("kind, text", PROPERTIES, ids=[f"{k}-{n}" for n, (k, _) in enumerate(PROPERTIES)])
def test_each_property_gets_the_verdicts_of_judging_every_boundary(classes: list[Any], kind: str, text: str) -> None:
    src = [PropertySource(kind, text)]
    every = _run(classes, src, targeted=False)
    assert every, "each property here gets a verdict"
    assert _run(classes, src, targeted=True) == every


def test_all_properties_together_and_at_another_period(classes: list[Any]) -> None:
    src = [PropertySource(k, t) for k, t in PROPERTIES]
    assert _run(classes, src, targeted=True, period=700_000) == _run(classes, src, targeted=False, period=700_000)


def test_what_a_ringlet_can_change_is_read_from_its_code(classes: list[Any]) -> None:
    a = class_reads(classes[0])
    assert a is not None
    # alias = items makes the two one object: a ringlet changing either changes both
    assert a.group["alias"] == a.group["items"]
    # n handed to alias.append joins their group too (a value put into a list can be reached there)
    grown = {"_llfsm_enter_INIT", "_llfsm_enter_GROW", "_llfsm_steady_GROW"}
    assert a.changers("items") == a.changers("n") == grown
    # WAIT's OnEntry reads n and items only as values (an f-string, len) and assigns seen alone
    assert a.changers("seen") == {"_llfsm_enter_WAIT"}
    assert a.changers("quiet") == set()  # nothing of a's own changes it: a parameter from outside does
    assert a.is_escaped("box") and not a.is_escaped("quiet")


# -- numbers stepped by a constant, and several checks at one return -----------------------------


class Wrap(int):
    """An int that wraps at 127 as a byte does (numpy.int8 would): stepping it up can make it
    smaller, so a check left out because `x += 1` cannot lower x must come back for it."""

    def __add__(self, other: object) -> Wrap:
        return Wrap((int(self) + int(other) + 128) % 256 - 128)  # type: ignore[call-overload]

    def __sub__(self, other: object) -> Wrap:
        return self + -int(other)  # type: ignore[call-overload]


def _stepper(root: Path) -> Any:
    """up and down stepped by constants (up in UP, down in DOWN, both the other way elsewhere),
    set back in RESET; items only read."""
    return load(
        str(
            write_machine(
                root,
                "s",
                {
                    "INIT": [("UP", "True")],
                    "UP": [("DOWN", "after_ms(3)")],
                    "DOWN": [("RESET", "after_ms(2) and down < -15"), ("UP", "after_ms(2)")],
                    "RESET": [("UP", "True")],
                },
                code={
                    "UP_OnEntry": "up += 1\ndown -= 2\n",
                    "UP_Internal": "up += 1\nhits += 1\n",
                    "DOWN_OnEntry": "down += -1\nup -= 3\n",
                    "RESET_OnEntry": "up = 0\ndown = 10\n",
                },
                variables="up: int = 0\ndown: int = 10\nhits: int = 0\nitems: list = [1]\n",
            )
        )
    )


STEPPED = [
    ("always", "s.up >= 0"),  # left out where up only grows
    ("never", "s.up > 6"),  # left out where up only falls
    ("always", "not (s.up > 6 and s.down < 100)"),  # the same, under `not`
    ("always", "s.up <= 6 and s.up >= -100"),  # bounded both ways: never left out
    ("always", "s.down <= 10"),
    ("never", 's.down < 0 and state(s) == "DOWN"'),
    ("always", 'state(s) != "UP" or s.up >= 1'),  # the state moves: never left out on entering UP
    ("always", "s.items[3] > 0 or s.up >= -100"),  # raises: violated at the first boundary
    ("never", "s.hits >= 4 and s.up < 2"),
    ("leads_to", "[s.up > 3, s.down > 5]"),
    ("ltl", "G (s.up >= 0 -> F s.down <= 10)"),
]


def _run_set(
    cls: Any,
    sources: list[PropertySource],
    targeted: bool,
    sets: dict[int, dict[str, object]],
    start: dict[str, object] | None = None,
) -> tuple[list[str], Any]:
    """A run of `cls` whose variables are set from outside (the scheduler's gate) as `sets` says
    when, after starting with the values `start` gives."""
    lines: list[str] = []
    ctx = RunContext(SimClock(1_000_000))
    arr = Arrangement([cls], context=ctx)
    for name, value in (start or {}).items():
        setattr(arr.machines[0], name, value)
    Monitor(sources, [cls], "log", lines.append, targeted=targeted).attach(arr)
    pending = dict(sets)

    def parameters() -> None:
        for t in [t for t in pending if ctx.clock.now >= t]:
            arr.set_variables(arr.machines[0].NAME, pending.pop(t))
        if pending:
            ctx.wake_at(min(pending))

    ctx.between_rounds.append(parameters)
    ctx.wake_at(0)
    arr.run(90_000_000)
    return lines, arr.machines[0]


@pytest.fixture(scope="module")
def stepper(tmp_path_factory: pytest.TempPathFactory) -> Any:
    return _stepper(tmp_path_factory.mktemp("s"))


@pytest.mark.parametrize("kind, text", STEPPED, ids=[f"{k}-{n}" for n, (k, _) in enumerate(STEPPED)])
def test_checks_left_out_where_a_ringlet_steps_a_number_give_the_same_verdicts(
    stepper: Any, kind: str, text: str
) -> None:
    src = [PropertySource(kind, text)]
    sets: dict[int, dict[str, object]] = {23_000_000: {"up": -1}, 41_000_000: {"up": 2.5, "down": 12}}
    every, _m = _run_set(stepper, src, False, sets)
    assert every
    assert _run_set(stepper, src, True, sets)[0] == every


def test_all_stepped_properties_checked_together_at_each_return(stepper: Any) -> None:
    """Several safety checks at one return are one test first (each variable read once), then
    one by one where that test fails: which fail, and in which order, must not change."""
    src = [PropertySource(k, t) for k, t in STEPPED] + [
        PropertySource("never", "s.up >= 5 and s.down < 0"),
        PropertySource("always", "s.down > -30 and s.hits < 40"),
        PropertySource("never", "s.up == 3"),
    ]
    every, _m = _run_set(stepper, src, False, {30_000_000: {"up": 4}})
    assert sum("violated" in line for line in every) >= 6
    targeted, m = _run_set(stepper, src, True, {30_000_000: {"up": 4}})
    assert targeted == every
    assert type(m)._llfsm_mon_numeric == {"up", "down"}  # checks were left out


def test_a_stepped_variable_set_to_something_else_than_a_number_is_checked_again(stepper: Any) -> None:
    """`up += 1` cannot lower an int, but it can lower a byte that wraps: a value of another type
    set from outside brings the left-out checks back for the rest of the run."""
    src = [PropertySource("always", "s.up >= 0")]
    every, _m = _run_set(stepper, src, False, {23_000_000: {"up": Wrap(120)}})
    assert any("violated" in line and "s.up=-" in line for line in every), every
    targeted, m = _run_set(stepper, src, True, {23_000_000: {"up": Wrap(120)}})
    assert targeted == every
    assert type(m)._llfsm_mon_numeric == set()


def test_a_stepped_variable_that_starts_as_something_else_than_a_number_is_checked(stepper: Any) -> None:
    src = [PropertySource("always", "s.up >= 0")]
    every, _m = _run_set(stepper, src, False, {}, start={"up": Wrap(120)})
    assert any("violated" in line and "s.up=-" in line for line in every), every
    targeted, m = _run_set(stepper, src, True, {}, start={"up": Wrap(120)})
    assert targeted == every
    assert type(m)._llfsm_mon_numeric == set()


def test_variables_made_one_object_by_their_initial_values(tmp_path: Path) -> None:
    """`alias: list = items` in Variables.py: a ringlet appending to alias changes items; `box:
    list = SHARED`: a helper module's function changes box without the ringlet naming it."""
    d = write_machine(
        tmp_path,
        "h",
        {"A": [("A", "True")]},
        code={"A_OnEntry": "alias.append(1)\ngrow()\n"},
        variables="items: list = []\nalias: list = items\nbox: list = SHARED\n",
        includes="from monitor_shared import SHARED, grow\n",
    )
    (tmp_path / "monitor_shared.py").write_text("SHARED = []\ndef grow():\n    SHARED.append(0)\n")
    cls = load(str(d))
    shared = sys.modules["monitor_shared"].SHARED
    for text in ("len(h.items) >= 3", "len(h.box) >= 4"):
        src = [PropertySource("never", text)]
        shared.clear()
        every = _run_set(cls, src, False, {})[0]
        shared.clear()
        assert every and _run_set(cls, src, True, {})[0] == every


# -- bounds of one number merged into one test ---------------------------------------------------

BOUNDS = [
    ("always", "s.up < 4"),
    ("always", "s.up <= 5"),
    ("never", "s.up > 7"),
    ("always", "9 > s.up"),
    ("always", "s.down > -3"),
    ("always", "s.down >= -20"),
    ("never", "s.down < -25.5"),
    ("always", "s.down <= 10"),
    ("always", "not s.hits >= 6"),
    ("always", "s.hits < 8"),
    ("always", "s.up % 7 != 6"),  # `*` and `%` of numbers as operators, not the bounded helpers
    ("always", "s.hits * 3 < s.down * 2 + 30"),
]


def test_bounds_of_one_number_merged_into_one_test_give_the_same_verdicts(stepper: Any) -> None:
    """Several constant bounds of one number at one return are tested as one comparison each way
    first (`-3 < down <= 10`): which fail, when, and in which order must not change."""
    src = [PropertySource(k, t) for k, t in BOUNDS]
    sets: dict[int, dict[str, object]] = {23_000_000: {"up": -1}, 41_000_000: {"up": 2.5, "down": 12}}
    every, _m = _run_set(stepper, src, False, sets)
    assert sum("violated" in line for line in every) >= 5
    targeted, m = _run_set(stepper, src, True, sets)
    assert targeted == every
    assert "hits" in type(m)._llfsm_mon_numeric  # merged (its checks are never left out: it only grows)


class Liar(int):
    """An int that says it is below 1000 always, and below anything else only while under 3: the
    tightest bound no longer implies the others, so a merged test must not stand for them."""

    def __lt__(self, other: object) -> bool:
        return other == 1000 or int(self) < 3

    def __add__(self, other: object) -> Liar:
        return Liar(int(self) + int(other))  # type: ignore[call-overload]


def test_merged_bounds_of_a_variable_set_to_something_else_than_a_number_are_checked_one_by_one(
    tmp_path: Path,
) -> None:
    cls = load(str(write_machine(tmp_path, "s", {"A": [("A", "True")]}, code={"A_OnEntry": "up += 1\n"},
                                 variables="up: int = 0\n")))  # fmt: skip
    src = [PropertySource("always", "s.up < 1000"), PropertySource("always", "s.up < 2000")]
    every, _m = _run_set(cls, src, False, {5_000_000: {"up": Liar(0)}})
    assert any("s.up < 2000 violated" in line for line in every), every
    targeted, m = _run_set(cls, src, True, {5_000_000: {"up": Liar(0)}})
    assert targeted == every
    assert type(m)._llfsm_mon_numeric == set()


class Text(str):
    """Text that machine code can step (`up += 2` keeps it): set from outside, it reaches the
    checks of `%` and `*`, which the bounded helpers refuse for text."""

    def __add__(self, other: object) -> Text:
        return self


def test_arithmetic_of_a_variable_set_to_text_is_bounded_as_in_an_atom(tmp_path: Path) -> None:
    """`s.up % 2` of a number is Python's `%` in the ringlet's check; set to text from outside,
    the bounded helper refuses it (violated, saying why) exactly where judging every boundary
    does."""
    cls = load(str(write_machine(tmp_path, "s", {"A": [("A", "True")]}, code={"A_OnEntry": "up += 2\n"},
                                 variables="up: int = 0\n")))  # fmt: skip
    src = [PropertySource("always", "s.up % 2 == 0"), PropertySource("always", "s.up * 2 != 5")]
    every, _m = _run_set(cls, src, False, {5_000_000: {"up": Text("%d")}})
    assert sum("violated" in line for line in every) == 1, every
    targeted, m = _run_set(cls, src, True, {5_000_000: {"up": Text("%d")}})
    assert targeted == every
    assert type(m)._llfsm_mon_numeric == set()


# -- pinned variables, terms the bounds decide, residues kept ------------------------------------


def _counter(root: Path, step: int = 1, start: int = 0) -> Any:
    """One state entered again each ringlet, stepping `up`; `lim` and `scale` only read."""
    d = write_machine(root, "p", {"A": [("A", "True")]}, code={"A_OnEntry": f"up += {step}\n"},
                      variables=f"up: int = {start}\nlim: int = 3\nscale: float = 2.0\n")  # fmt: skip
    return load(str(d))


PINNED = [
    ("always", "p.up < p.lim * 4"),  # lim pinned to 3: the bound up < 12, merged with the others
    ("always", "p.up <= p.lim * p.scale + 100"),
    ("never", "p.up == -1"),  # decided by up >= 0 where the test passes: left out of it
    ("always", "p.up >= 0"),
]


@pytest.mark.parametrize(
    "sets, pins",
    [
        ({}, {"lim": 3, "scale": 2.0}),
        ({5_000_000: {"lim": 2}}, {}),  # a parameter from outside: the variant that pins nothing
        ({5_000_000: {"lim": 3.0}}, {}),  # equal, but a float: pinned as the int it was
        ({4_000_000: {"up": -1}}, {"lim": 3, "scale": 2.0}),  # what the bounds decide, violated
    ],
    ids=["as-started", "lim-set", "lim-set-to-float", "up-set-below"],
)
def test_pinned_variables_and_decided_terms_give_the_same_verdicts(
    tmp_path: Path, sets: dict[int, dict[str, object]], pins: dict[str, object]
) -> None:
    """Numbers no ringlet changes are compiled into the checks as their values (`up < lim * 4`
    is `up < 12`) and terms the bounds decide are left out of the test that all hold: a value
    set from outside must still be judged where judging every boundary judges it."""
    cls = _counter(tmp_path)
    src = [PropertySource(k, t) for k, t in PINNED]
    every, _m = _run_set(cls, src, False, sets)
    assert any("p.up < p.lim * 4 violated" in line for line in every), every
    targeted, m = _run_set(cls, src, True, sets)
    assert targeted == every
    assert type(m)._llfsm_mon_pins == pins


def test_a_pinned_variable_set_in_the_debugger_reaches_the_checks(tmp_path: Path) -> None:
    """`set p.lim = 0` at the debugger's prompt while paused: the check compiled with lim = 3
    must not stand for the rest of the run (the next ringlet violates `up < lim * 100`)."""
    d = write_machine(tmp_path, "p", {"A": [("A", "True")]}, code={"A_OnEntry": "up += 1\n"},
                      variables="up: int = 0\nlim: int = 3\n")  # fmt: skip
    args = ["run", "--clock", "sim", "--duration", "20ms", str(d), "--on-violation", "pause"]
    props = ["--monitor-property", "never: p.up == 4", "--monitor-property", "always: p.up < p.lim * 100"]
    res = CliRunner().invoke(cli, [*args, *props], input="set p.lim = 0\nc\nc\n")
    assert res.exit_code == 0, res.output
    violated = [x for x in res.stderr.splitlines() if "violated at" in x]
    assert len(violated) == 2, res.stderr
    assert "always: p.up < p.lim * 100 violated" in violated[1] and "ringlet 5: p A; p.lim=0, p.up=5" in violated[1]


@pytest.mark.parametrize(
    "sets",
    [{}, {5_000_000: {"up": 4}}, {5_000_000: {"up": float(2**53)}}, {5_000_000: {"up": 5}}],
    ids=["as-started", "set-off-residue", "set-to-a-float-that-rounds", "set-on-residue"],
)
def test_a_residue_the_ringlets_keep_is_left_out_and_comes_back_for_a_float(
    tmp_path: Path, sets: dict[int, dict[str, object]]
) -> None:
    """`up += 3` keeps `up % 3` of an int, so `always: up % 3 == 2` is not checked there; a float
    (2**53 + 3 rounds to 2**53 + 4) brings the check back for the rest of the run."""
    cls = _counter(tmp_path, step=3, start=2)
    src = [PropertySource("always", "p.up % 3 == 2"), PropertySource("always", "p.up % 2 == 0 or p.up > -5")]
    every, _m = _run_set(cls, src, False, sets)
    targeted, m = _run_set(cls, src, True, sets)
    assert targeted == every
    if sets and 5 not in sets[5_000_000].values():
        assert any("p.up % 3 == 2 violated" in line for line in every), every
    expected = set() if sets and type(next(iter(sets.values()))["up"]) is float else {"up"}
    assert type(m)._llfsm_mon_integral == expected


def test_bounds_decide_the_equalities_they_exclude() -> None:
    def terms(*texts: str) -> tuple[list[str], set[str]]:
        out, used = merge_bounds([ast.parse(t, mode="eval").body for t in texts], lambda _v: True)
        return [ast.unparse(t) for t in out], used

    assert terms("self.x >= 0", "self.x < 50", "self.x != -1", "not self.x == 50") == (["0 <= self.x < 50"], {"x"})
    assert terms("self.x > 0", "self.x != 0") == (["self.x > 0"], {"x"})  # strict: 0 is outside
    assert terms("self.x >= 0", "self.x != 0", "self.x != 7") == (["self.x >= 0", "self.x != 0", "self.x != 7"], set())
    assert terms("self.x == 3", "self.x <= 3", "self.x >= 3")[0] == ["3 <= self.x <= 3"]  # c <= x <= c: x == c
    assert terms("self.y != -1", "self.x >= 0") == (["self.y != -1", "self.x >= 0"], set())  # another number


# a random table: properties drawn from the kinds of term the variant folds, values set from outside
_TERMS = [
    "p.up < {c}", "p.up >= {c}", "p.up == {c}", "p.up != {c}", "not p.up > {c}", "p.up % {m} == {r}",
    "p.up % {m} != {r}", "p.up < p.lim * {c}", "p.up > p.lim - {c}", "p.up * p.scale < {c} + p.lim",
    'state(p) != "A" or p.up > {c}', "p.lim == 3 and p.up != {c}",
]  # fmt: skip
_VALUES: list[object] = [-1, 0, 2, 3, 7, 9, 2.5, float(2**53), True, -4.0]


@settings(max_examples=12, derandomize=True, deadline=None, suppress_health_check=list(HealthCheck))
@given(st.data())
def test_folded_checks_give_the_verdicts_of_judging_every_boundary(tmp_path_factory: Any, data: Any) -> None:
    step = data.draw(st.sampled_from([1, 2, 3, -2]))
    cls = _counter(tmp_path_factory.mktemp("r"), step=step, start=data.draw(st.sampled_from([0, 2, 5])))
    src = []
    for _ in range(data.draw(st.integers(2, 7))):
        terms = [data.draw(st.sampled_from(_TERMS)) for _ in range(data.draw(st.integers(1, 2)))]
        c, m, r = data.draw(st.integers(-6, 40)), data.draw(st.sampled_from([2, 3])), data.draw(st.integers(0, 2))
        kind = data.draw(st.sampled_from(["always", "never"]))
        src.append(PropertySource(kind, " and ".join(terms).format(c=c, m=m, r=r)))
    sets: dict[int, dict[str, object]] = {}
    for t in data.draw(st.lists(st.integers(1, 40), max_size=3, unique=True)):
        sets[t * 1_000_000] = {data.draw(st.sampled_from(["up", "lim", "scale"])): data.draw(st.sampled_from(_VALUES))}
    assert _run_set(cls, src, True, sets)[0] == _run_set(cls, src, False, sets)[0]
