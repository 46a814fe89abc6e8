"""SPEC 18, verify's bounds (issue 28, items 2, 3, 6, 7): what a property, a machine or the inputs
can cost.  Each case runs `llfsm verify` in a process of its own under an address-space limit
and a timeout, so that a case that would eat the machine fails instead of taking it down."""

from __future__ import annotations

import json
import re
import resource
import sys
from pathlib import Path

import pytest
from helpers import Run, llfsm, llfsm_process, write_machine

#: The address space a case may use (the interpreter and llfsm's imports take about 150 MB).
LIMIT = 1 << 30


def _limited(limit: int = LIMIT) -> object:
    def set_limit() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))

    return set_limit


def verify_process(*args: object, timeout: float = 60, limit: int = LIMIT) -> Run:
    return llfsm_process("verify", *args, timeout=timeout, preexec_fn=_limited(limit))


def one_clear_line(r: Run) -> str:
    """The one line llfsm writes for a refusal: no traceback, nothing else."""
    assert "Traceback" not in r.stderr, r.stderr
    lines = [x for x in r.stderr.splitlines() if x.startswith("llfsm: ")]
    assert len(lines) == 1, r.stderr
    return lines[0]


def _ring(tmp_path: Path, states: int = 12) -> Path:
    """A machine of `states` states in a ring, a counter modulo `states` beside it."""
    names = [f"S{i}" for i in range(states)]
    return write_machine(
        tmp_path,
        "ring",
        {s: [(names[(i + 1) % states], "True")] for i, s in enumerate(names)},
        {f"{s}_OnEntry": f"k = {i}" for i, s in enumerate(names)},
        variables="k: int = 0\n",
    )


# -- item 2: the automaton of an `ltl:` property --------------------------------------------------------


def test_a_six_term_ltl_property_is_judged_quickly_and_its_time_counted(tmp_path: Path) -> None:
    ring = _ring(tmp_path)
    formula = " & ".join(f"G F ring.k == {i}" for i in range(6))
    r = verify_process(ring, "--property", f"ltl: {formula}", "--format", "json", timeout=120)
    assert r.status == 0, r.stderr
    doc = json.loads(r.stdout)
    assert doc["properties"][0]["verdict"] == "holds"
    # the report's time is the whole check's: exploring and judging
    assert doc["seconds"] >= doc["properties"][0]["seconds"] > 0


def test_an_automaton_past_the_bound_is_refused_in_one_line(tmp_path: Path) -> None:
    ring = _ring(tmp_path, 3)
    # sixteen different eventualities: 2^32 elementary sets; refused before memory runs out
    formula = " & ".join(f"G F ring.k == {i}" for i in range(16))
    r = verify_process(ring, "--property", f"ltl: {formula}", timeout=120)
    assert r.status == 2, r.stderr
    line = one_clear_line(r)
    assert "automaton" in line and "states" in line


def test_repeated_conjuncts_are_one(tmp_path: Path) -> None:
    ring = _ring(tmp_path, 3)
    formula = " & ".join(["G F ring.k == 0"] * 16)
    r = verify_process(ring, "--property", f"ltl: {formula}", timeout=60)
    assert r.status == 0, r.stderr
    assert "holds" in r.stdout


def test_judging_an_ltl_property_shows_progress() -> None:
    from llfsm.props.automaton import Automaton
    from llfsm.props.formula import core, neg
    from llfsm.verify.ltl import Structure, check_ltl

    # a structure of 3,000 configurations in a ring, each labelled with atom 0 every other one
    n = 3_000
    structure = Structure(n, lambda c: [(c + 1) % n], [c & 1 for c in range(n)], [1] * n, 1)
    seen: list[int] = []
    f = ("G", ("F", ("atom", 0)))
    aut = Automaton(core(neg(f)))
    assert check_ltl(structure, aut, [0], progress=lambda nodes, _s: seen.append(nodes), every=0) is None
    assert seen and seen[-1] >= 1024


# -- item 3: memory -----------------------------------------------------------------------------------


def _growing_list(tmp_path: Path) -> Path:
    return write_machine(
        tmp_path,
        "grow",
        {"A": [("A", "True")]},
        {"A_OnEntry": "items.append(len(items))"},
        variables="items: list = []\n",
    )


def test_max_memory_stops_the_exploration_naming_what_grew_in_size(tmp_path: Path) -> None:
    r = verify_process(_growing_list(tmp_path), "--max-memory", "200MB", timeout=120)
    assert r.status == 3, r.stderr
    assert "Traceback" not in r.stderr
    assert "memory" in r.stdout and "grow.items" in r.stdout and "in size" in r.stdout


def _growing_blob(tmp_path: Path) -> Path:
    """A value 200 kB longer at every step: the configurations take memory in the square of the
    steps (256 of them, 6.5 GB)."""
    return write_machine(
        tmp_path,
        "blob",
        {"A": [("A", "True")]},
        {"A_OnEntry": 'blob = blob + b"x" * 200_000'},
        variables='blob: bytes = b""\n',
    )


def test_max_memory_stops_a_value_growing_megabytes_a_step_near_the_bound(tmp_path: Path) -> None:
    # verify looked every 256 new configurations: with --max-memory 100 MB it stopped at 6.67 GB
    # in use (or, under this test's 1 GiB address space, at 100 configurations by a MemoryError);
    # it now looks sooner as the configurations grow, and stops about where the bound is passed
    # (the 32nd configuration holds 6.4 MB; 100 MB is reached by about the 25th)
    r = verify_process(_growing_blob(tmp_path), "--max-memory", "100MB", timeout=120)
    assert r.status == 3, (r.status, r.stderr[-2000:])
    said = re.search(r"\(([\d.]+) (MB|GB) in use, --max-memory 100 MB; ([\d,]+) configurations", r.stdout)
    assert said is not None, r.stdout
    in_use = float(said.group(1)) * (1000 if said.group(2) == "GB" else 1)
    assert in_use < 150 and int(said.group(3).replace(",", "")) <= 40, said.group(0)


def test_the_default_memory_bound_is_half_of_what_the_process_may_use(tmp_path: Path) -> None:
    # no --max-memory: under a 400 MiB address-space limit the exploration stops at about half of
    # it with status 3, not with a MemoryError, a traceback or a kill; a value that grows by
    # 200 kB a step gets there in about sixty configurations (a second or two)
    r = verify_process(_growing_blob(tmp_path), timeout=120, limit=400 << 20)
    assert r.status == 3, (r.status, r.stderr[-2000:])
    assert "Traceback" not in r.stderr
    assert "stopped at the memory bound" in r.stdout and "--max-memory 210 MB" in r.stdout and "blob.blob" in r.stdout


@pytest.mark.slow
def test_the_default_memory_bound_holds_for_a_list_growing_an_item_a_step(tmp_path: Path) -> None:
    # the same under 1 GiB with the growing list of issue 28 (35,842 configurations took 5 GB):
    # the exploration slows as the list grows (each configuration freezes it), about two minutes
    r = verify_process(_growing_list(tmp_path), timeout=300)
    assert r.status == 3, (r.status, r.stderr[-2000:])
    assert "Traceback" not in r.stderr
    assert "memory" in r.stdout and "grow.items" in r.stdout


def test_a_bad_max_memory_is_a_usage_error(tmp_path: Path) -> None:
    r = llfsm("verify", _growing_list(tmp_path), "--max-memory", "lots")
    assert r.status == 2
    assert "--max-memory: not a size" in r.stderr


def _many_inputs(tmp_path: Path, n: int) -> Path:
    inputs = "inputs:\n" + "".join(f"  b{k}:\n    type: bool\n" for k in range(n))
    return write_machine(tmp_path, "wide", {"A": [("END", "b0 and b1")], "END": None}, yaml_extra=inputs)


def test_an_input_product_beyond_the_state_limit_is_refused_naming_the_inputs(tmp_path: Path) -> None:
    r = verify_process(_many_inputs(tmp_path, 26), timeout=60, limit=LIMIT)
    assert r.status == 2, (r.status, r.stderr[-2000:])
    line = one_clear_line(r)
    assert "wide" in line and "b0" in line and "b25" in line and "67,108,864" in line


def test_inputs_are_valued_lazily_in_the_order_of_their_product() -> None:
    import itertools

    from llfsm.verify.step import Choices, Valuations

    many = Valuations([(False, True)] * 24)  # 16,777,216 valuations: never a list
    assert many.kept is None and len(many) == 1 << 24
    assert many[0] == (False,) * 24 and many[(1 << 24) - 1] == (True,) * 24
    assert next(iter(many)) == (False,) * 24
    domains = [(0, 1, 2)] * 8 + [("a", "b")]  # past the size kept as a list
    lazy = Valuations(domains)
    assert lazy.kept is None
    assert list(lazy) == list(itertools.product(*domains))
    assert [lazy[k] for k in (0, 1, 7, 4000, len(lazy) - 1)] == [
        list(itertools.product(*domains))[k] for k in (0, 1, 7, 4000, len(lazy) - 1)
    ]
    choices = Choices(lazy, range(2, 4), (False, True))
    assert list(choices) == [(v, t, i) for i in (False, True) for t in (2, 3) for v in itertools.product(*domains)]
    assert [choices[c] for c in (0, len(lazy), len(choices) - 1)] == [
        list(choices)[c] for c in (0, len(lazy), len(choices) - 1)
    ]


# -- item 6: formulas nested or chained too deep ------------------------------------------------------


def test_long_chains_and_deep_nesting_are_one_line_each(tmp_path: Path) -> None:
    ring = _ring(tmp_path, 3)
    for op in ("U", "->", "&", "|"):
        formula = f" {op} ".join(["true"] * 900)  # within the 10,000 characters a property may have
        r = verify_process(ring, "--property", f"ltl: {formula}", timeout=60)
        assert r.status == 2, (op, r.stderr[-500:])
        assert "deep" in one_clear_line(r) or "levels" in one_clear_line(r)
    r = verify_process(ring, "--property", "ltl: " + "X " * 1000 + "ring.k == 0", timeout=60)
    assert r.status == 2 and "levels" in one_clear_line(r)


# -- item 7: repetition ---------------------------------------------------------------------------------


def test_a_string_repeated_beyond_the_bound_is_refused_before_anything_runs(tmp_path: Path) -> None:
    ring = _ring(tmp_path, 3)
    for text in (
        'always: len("x" * 3000000000) > 0',
        "always: len((1, 2) * 10**9) > 0",
        'always: len(3000000000 * "x")',
    ):
        r = verify_process(ring, "--property", text, timeout=30)
        assert r.status == 2, (text, r.stderr[-500:])
        line = one_clear_line(r)
        assert "repeated" in line or "**" in line, line


def test_a_variable_repeated_beyond_the_bound_is_refused_where_it_is_evaluated(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "s", {"A": [("A", "True")]}, variables='s: str = "ab"\n')
    r = verify_process(m, "--property", "always: len(s.s * 2000000000) > 0", timeout=30)
    assert r.status == 2, r.stderr[-500:]
    line = one_clear_line(r)
    assert "repeat" in line


if sys.platform != "linux":  # pragma: no cover
    import pytest

    pytest.skip("address-space limits are Linux's", allow_module_level=True)
