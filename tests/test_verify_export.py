"""Exports of `llfsm verify` (SPEC 11): SPIN gives llfsm's verdict for every property of random
small arrangements (hypothesis), SMV exports are NuSMV input (a grammar check here; NuSMV
itself when it is on PATH), DOT draws the structure."""

from __future__ import annotations

import re
import shutil
import subprocess
import tempfile
from pathlib import Path

import pytest
from helpers import MACHINES, llfsm, write_machine
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from llfsm.verify.explorer import Options
from llfsm.verify.export import promela, smv
from llfsm.verify.judge import verify
from llfsm.verify.load import PropertySource, load_arrangement

SPIN = shutil.which("spin")
GCC = shutil.which("gcc") or shutil.which("cc")
needs_spin = pytest.mark.skipif(
    SPIN is None or GCC is None,
    reason="SPIN (Debian's `spin`) and a C compiler are needed: `make test` installs spin where it can "
    "(apt-get as root); elsewhere `apt-get install spin`",
)

# -- random small arrangements --------------------------------------------------------------------------


@st.composite
def arrangements(draw: st.DrawFn) -> tuple[list[dict], list[tuple[str, str]], int | None]:  # type: ignore[type-arg]
    """1 or 2 machines of 2-4 states: guards over a variable v, a bool input x, after_ms, the
    other machine's suspension; OnEntry counting v, or suspending, resuming, restarting the other;
    and properties over their states, variables, suspension and end."""
    n = draw(st.sampled_from([2, 1, 2]))
    names = ["m0", "m1"][:n]
    machines = []
    for i, name in enumerate(names):
        other = names[1 - i] if n == 2 else None
        k = draw(st.sampled_from([3, 2, 4]))
        states = [f"S{j}" for j in range(k)]
        has_input = draw(st.booleans())
        atoms = ["after_ms(10)", "True", "v == 1", "v != 2", "False", "v == 0", "after_ms(20)"]
        if has_input:
            atoms += ["x", "not x"]
        if other:
            atoms += [f'is_suspended("{other}")', f'not is_running("{other}")']
        simple = st.sampled_from(atoms)
        guard = st.one_of(simple, st.tuples(simple, st.sampled_from(["and", "or"]), simple).map(" ".join))
        actions = ["v = (v + 1) % 3", "pass", "v = 0"]
        if other:
            actions += [f'suspend("{other}")', f'resume("{other}")', f'restart("{other}")']
        spec: dict[str, list[tuple[str, str]] | None] = {}
        code = {}
        for j, s in enumerate(states):
            count = draw(st.sampled_from([1, 2, 0 if j else 1]))
            spec[s] = [(draw(st.sampled_from(states)), draw(guard)) for _ in range(count)] or None
            code[f"{s}_OnEntry"] = draw(st.sampled_from(actions))
        machines.append({"name": name, "states": spec, "code": code, "input": has_input})
    atom_texts = []
    for m in machines:
        nm = m["name"]
        atom_texts += [f'state({nm}) == "{s}"' for s in m["states"]]
        atom_texts += [f"{nm}.v == 0", f"{nm}.v == 2", f"suspended({nm})", f"finished({nm})"]
        if m["input"]:
            atom_texts.append(f"{nm}.x")
    atom = st.sampled_from(atom_texts)
    shapes = st.sampled_from(["always", "never", "reachable", "eventually", "leads_to", "GF", "FG", "U", "GU"])
    props = []
    for _ in range(draw(st.integers(2, 4))):
        shape, a, b = draw(shapes), draw(atom), draw(atom)
        props.append(
            {
                "always": ("always", a),
                "never": ("never", a),
                "reachable": ("reachable", a),
                "eventually": ("eventually", a),
                "leads_to": ("leads_to", f"{a}, {b}"),
                "GF": ("ltl", f"G F ({a})"),
                "FG": ("ltl", f"F G ({a})"),
                "U": ("ltl", f"({a}) U ({b})"),
                "GU": ("ltl", f"G (({a}) -> (({a}) U ({b})))"),
            }[shape]
        )
    period = draw(st.sampled_from([None, None, 10_000_000]))
    return machines, props, period


def _write(root: Path, machines: list[dict]) -> list[Path]:  # type: ignore[type-arg]
    out = []
    for m in machines:
        extra = "inputs:\n  x:\n    type: bool\n" if m["input"] else ""
        out.append(write_machine(root, m["name"], m["states"], m["code"], variables="v: int = 0\n", yaml_extra=extra))
    return out


def spin_verdicts(model: str, folder: Path, count: int) -> list[str | None]:
    """SPIN's verdict for each property p0..p{count-1} written as an ltl claim (None for those
    the export writes as a comment); reachable claims are read the other way round."""
    (folder / "model.pml").write_text(model)
    subprocess.run([SPIN, "-a", "model.pml"], cwd=folder, check=True, capture_output=True, timeout=120)
    subprocess.run(
        [GCC, "-O0", "-w", "-DNOREDUCE", "-DVECTORSZ=4096", "-o", "pan", "pan.c"],
        cwd=folder,
        check=True,
        capture_output=True,
        timeout=300,
    )
    out: list[str | None] = []
    for p in range(count):
        if f"ltl p{p} " not in model:
            out.append(None)
            continue
        run = subprocess.run(
            ["./pan", "-a", "-m1000000", "-N", f"p{p}"], cwd=folder, capture_output=True, text=True, timeout=300
        )
        errors = int(re.search(r"errors: (\d+)", run.stdout).group(1))  # type: ignore[union-attr]
        violated = errors > 0
        reachable = f"p{p} reachable" in model.split(f"ltl p{p} ")[0].rsplit("/* llfsm:", 1)[1]
        out.append(("holds" if violated else "fails") if reachable else ("fails" if violated else "holds"))
    return out


@needs_spin
@settings(max_examples=20, deadline=None, derandomize=True, database=None, suppress_health_check=list(HealthCheck))
@given(arrangements())
def test_spin_gives_llfsm_s_verdict_on_random_arrangements(case) -> None:  # type: ignore[no-untyped-def]
    machines, props, period = case
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        paths = _write(root, machines)
        loaded = load_arrangement([str(p) for p in paths])
        v = verify(loaded, [PropertySource(k, t) for k, t in props], Options(period=period), keep_graph=True)
        assert v.partial is None and v.error is None
        ours = [o.verdict for o in v.outcomes]
        theirs = spin_verdicts(promela(v), root, len(props))
        for p, (mine, spin) in enumerate(zip(ours, theirs, strict=True)):
            assert spin is None or mine == spin, (p, props[p], mine, spin, v.configurations)
        assert any(t is not None for t in theirs)


@needs_spin
def test_spin_agrees_on_the_seed_verification_and_a_failing_property(tmp_path: Path) -> None:
    loaded = load_arrangement(
        [str(MACHINES / "ros2_turtle_suspend_resume.machine"), str(MACHINES / "ros2_blind_turtle_bot.machine")]
    )
    props = [
        PropertySource("never", 'suspended(ros2_blind_turtle_bot) and published("/turtle1/cmd_vel")'),
        PropertySource(
            "leads_to", 'state(ros2_turtle_suspend_resume) == "SUSPEND_BOT", suspended(ros2_blind_turtle_bot)'
        ),
        PropertySource("eventually", "finished(ros2_blind_turtle_bot)"),
    ]
    v = verify(loaded, props, Options(interrupt=True, period=10_000_000), keep_graph=True)
    assert [o.verdict for o in v.outcomes] == ["holds", "holds", "fails"]
    assert spin_verdicts(promela(v), tmp_path, 3) == ["holds", "holds", "fails"]


# -- SMV ---------------------------------------------------------------------------------------------------


_SMV_TOKEN = re.compile(r"\s*(?:(--[^\n]*)|(\d+)|([A-Za-z_][A-Za-z0-9_]*)|(:=|->|\.\.|[{}();:,=!&|\[\]]))")


def parse_smv(text: str) -> dict[str, object]:
    """A grammar check of what `--export smv` writes (the NuSMV 2.x subset it uses): raises
    AssertionError at the first token out of place; returns what it read."""
    toks: list[str] = []
    pos = 0
    while pos < len(text):
        m = _SMV_TOKEN.match(text, pos)
        assert m is not None, f"bad character at {text[pos : pos + 20]!r}"
        pos = m.end()
        if m.group(1) is None and m.group(0).strip():
            toks.append(m.group(0).strip())
        if m.end() == len(text.rstrip()) and not text[pos:].strip():
            break
    it = iter(toks)
    cur = [next(it, None)]

    def take(expected: str | None = None) -> str:
        t = cur[0]
        assert t is not None, f"ran out, expected {expected}"
        assert expected is None or t == expected, f"expected {expected!r}, got {t!r}"
        cur[0] = next(it, None)
        return t

    def ident() -> str:
        t = take()
        assert re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", t), t
        return t

    def number() -> int:
        t = take()
        assert t.isdigit(), t
        return int(t)

    unary = {"!", "G", "F", "X", "AG", "AF", "AX", "EG", "EF", "EX"}

    def expr() -> None:
        implication()

    def implication() -> None:
        disjunction()
        if cur[0] == "->":
            take()
            implication()

    def disjunction() -> None:
        conjunction()
        while cur[0] == "|":
            take()
            conjunction()

    def conjunction() -> None:
        until()
        while cur[0] == "&":
            take()
            until()

    def until() -> None:
        prefix()
        if cur[0] == "U":
            take()
            until()

    def prefix() -> None:
        t = cur[0]
        if t in unary:
            take()
            prefix()
        elif t in ("A", "E"):  # A [p U q]: the U is read by until() inside the brackets
            take()
            take("[")
            expr()
            take("]")
        elif t == "(":
            take()
            expr()
            take(")")
        elif t in ("TRUE", "FALSE"):
            take()
        else:
            v = ident()
            if cur[0] == "in":
                assert v == "s"
                take()
                take("{")
                number()
                while cur[0] == ",":
                    take()
                    number()
                take("}")

    take("MODULE")
    take("main")
    take("VAR")
    assert ident() == "s"
    take(":")
    lo = number()
    take("..")
    hi = number()
    take(";")
    take("ASSIGN")
    take("init")
    take("(")
    take("s")
    take(")")
    take(":=")
    assert number() == 0
    take(";")
    take("next")
    take("(")
    take("s")
    take(")")
    take(":=")
    take("case")
    cases = 0
    while cur[0] == "s":
        take("s")
        take("=")
        src = number()
        take(":")
        if cur[0] == "{":
            take()
            targets = [number()]
            while cur[0] == ",":
                take()
                targets.append(number())
            take("}")
        else:
            targets = [number()]
        assert lo <= src <= hi and all(lo <= t <= hi for t in targets)
        take(";")
        cases += 1
    take("TRUE")
    take(":")
    take("s")
    take(";")
    take("esac")
    take(";")
    defines = []
    if cur[0] == "DEFINE":
        take()
        while cur[0] is not None and cur[0] not in ("FAIRNESS", "LTLSPEC", "CTLSPEC"):
            defines.append(ident())
            take(":=")
            expr()
            take(";")
    fairness = 0
    specs = []
    while cur[0] is not None:
        kind = take()
        if kind == "FAIRNESS":
            ident()
            take(";")
            fairness += 1
            continue
        assert kind in ("LTLSPEC", "CTLSPEC"), kind
        take("NAME")
        specs.append((kind, ident()))
        take(":=")
        expr()
        take(";")
    return {"states": hi + 1, "cases": cases, "defines": defines, "fairness": fairness, "specs": specs}


def test_smv_export_is_nusmv_input(tmp_path: Path) -> None:
    loaded = load_arrangement(
        [str(MACHINES / "ros2_turtle_suspend_resume.machine"), str(MACHINES / "ros2_blind_turtle_bot.machine")]
    )
    props = [
        PropertySource("never", 'suspended(ros2_blind_turtle_bot) and published("/turtle1/cmd_vel")'),
        PropertySource(
            "ltl", 'G (state(ros2_turtle_suspend_resume) == "SUSPEND_BOT" -> X !finished(ros2_blind_turtle_bot))'
        ),
        PropertySource("ctl", "AG EF !suspended(ros2_blind_turtle_bot)"),
        PropertySource(
            "ctl", 'A[!finished(ros2_turtle_suspend_resume) U state(ros2_turtle_suspend_resume) == "RESUME"]'
        ),
        PropertySource("reachable", 'state(ros2_blind_turtle_bot) == "TURN_RIGHT"'),
    ]
    v = verify(loaded, props, Options(period=100_000_000), keep_graph=True)
    text = smv(v)
    got = parse_smv(text)
    assert got["states"] == v.configurations == got["cases"]
    assert got["fairness"] == 0  # with --period time always passes: no fairness needed
    abstract = verify(
        load_arrangement([str(MACHINES / "wall_follower.machine")]),
        [PropertySource("ltl", 'G F published("/turtle1/cmd_vel")')],
        Options(),
        keep_graph=True,
    )
    assert parse_smv(smv(abstract))["fairness"] == 1  # one fairness set per machine: its time passes
    assert got["specs"] == [
        ("LTLSPEC", "p0"),
        ("LTLSPEC", "p1"),
        ("CTLSPEC", "p2"),
        ("CTLSPEC", "p3"),
        ("CTLSPEC", "p4"),
    ]
    nusmv = shutil.which("NuSMV") or shutil.which("nusmv")
    if nusmv is None:
        return  # the grammar check is the test here; NuSMV itself where it is installed
    (tmp_path / "m.smv").write_text(text)
    run = subprocess.run([nusmv, "m.smv"], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    found = re.findall(r"-- specification .* is (true|false)", run.stdout)
    assert [("holds" if f == "true" else "fails") for f in found] == [o.verdict for o in v.outcomes]


def test_the_command_writes_each_export_and_dot_draws_the_structure(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "a", {"INITIAL": [("END", "True")], "END": None})
    r = llfsm(
        "verify",
        m,
        "--property",
        "eventually: finished(a)",
        "--export",
        "dot",
        tmp_path / "a.dot",
        "--export",
        "promela",
        tmp_path / "a.pml",
        "--export",
        "smv",
        tmp_path / "a.smv",
    )
    assert r.status == 0, r.stderr
    dot = (tmp_path / "a.dot").read_text()
    assert dot.startswith("digraph explored {")
    assert 'c0 [label="#0\\na: INITIAL", peripheries=2];' in dot
    assert "c2 -> c2;" in dot and "a: END (finished)" in dot
    assert "ltl p0 {" in (tmp_path / "a.pml").read_text()
    assert parse_smv((tmp_path / "a.smv").read_text())["specs"] == [("LTLSPEC", "p0")]
