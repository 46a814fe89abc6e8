"""The format of SPEC 13: guards inline in machine.yaml beside guard files (check at machine.yaml's
line and column, build, run, errors, verify, graph, the schema), the `# -> TARGET` guard comment,
layout.yaml (checked, never built), and `llfsm new machine --states`."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import jsonschema
import pytest
import yaml
from helpers import llfsm, run_sim, write_machine

from llfsm.lang.check import check_machine
from llfsm.verify.explorer import Options
from llfsm.verify.judge import verify
from llfsm.verify.load import PropertySource, load_arrangement

COUNTER = """\
states:
  - name: COUNT
    transitions:
      - to: END
        guard: n >= 3          # done
      - {to: COUNT, guard: "True"}
  - name: END
"""


def counter(root: Path, text: str = COUNTER) -> Path:
    m = root / "c.machine"
    m.mkdir(parents=True)
    (m / "machine.yaml").write_text(text)
    (m / "Variables.py").write_text("n: int = 0\n")
    (m / "State_COUNT_OnEntry.py").write_text("n += 1\nprint(f'n = {n}')\n")
    return m


def codes(m: Path) -> list[tuple[str, str, int, int]]:
    return [(d.code, Path(d.file).name, d.line, d.column) for d in check_machine(m).diagnostics]


def test_inline_guards_check_build_and_run_as_files_do(tmp_path: Path) -> None:
    m = counter(tmp_path)
    assert codes(m) == []
    r = run_sim(m)
    assert r.status == 0 and r.stdout == "n = 1\nn = 2\nn = 3\n"
    built = llfsm("build", m, "-o", tmp_path / "out")
    assert built.status == 0
    source = (tmp_path / "out" / "c.py").read_text()
    assert "    # machine.yaml:5\n    if self.n >= 3:\n" in source  # the pointer names machine.yaml's line
    assert "'machine.yaml', 5)," in source  # and so does the source map a run's errors are reported through


def test_problems_in_inline_guards_are_at_their_place_in_machine_yaml(tmp_path: Path) -> None:
    text = COUNTER.replace("guard: n >= 3 ", "guard: m >= 3 ").replace('guard: "True"', 'guard: "n +"')
    assert codes(counter(tmp_path, text)) == [
        ("LF040", "machine.yaml", 5, 16),  # `m`: column of the name in machine.yaml
        ("LF030", "machine.yaml", 6, 32),  # the syntax error: the end of the text, before the quote
    ]
    block = COUNTER.replace("guard: n >= 3          # done", "guard: |\n          (n >= 3 and\n            k)")
    assert codes(counter(tmp_path / "b", block)) == [("LF040", "machine.yaml", 7, 13)]
    assert codes(counter(tmp_path / "t", COUNTER.replace("guard: n >= 3 ", "guard: n, 3   "))) == [
        ("LF024", "machine.yaml", 5, 16)
    ]


def test_a_guard_in_both_places_or_in_neither_is_an_error(tmp_path: Path) -> None:
    m = counter(tmp_path)
    (m / "State_COUNT_Transition_0.expr").write_text("n > 5\n")
    got = check_machine(m).diagnostics
    assert [(d.code, Path(d.file).name, d.line, d.column) for d in got] == [("LF070", "machine.yaml", 5, 16)]
    assert "State_COUNT_Transition_0.expr" in got[0].message
    m = counter(tmp_path / "n", COUNTER.replace('      - {to: COUNT, guard: "True"}', "      - to: COUNT"))
    got = check_machine(m).diagnostics
    assert [(d.code, d.line) for d in got] == [("LF023", 6)]
    assert "State_COUNT_Transition_1.expr" in got[0].message and "guard: EXPR" in got[0].message
    assert codes(counter(tmp_path / "e", COUNTER.replace('guard: "True"', 'guard: ""'))) == [
        ("LF004", "machine.yaml", 6, 28)
    ]


def test_an_error_in_an_inline_guard_at_run_time_names_machine_yaml(tmp_path: Path) -> None:
    m = counter(tmp_path, COUNTER.replace("guard: n >= 3 ", "guard: 1 / (n - 2) > 9"))
    r = run_sim(m)
    assert r.status != 0
    assert f"{m}/machine.yaml:5: error: ZeroDivisionError: division by zero (machine c, state COUNT, guard)" in r.stderr
    assert "    guard: 1 / (n - 2) > 9" in r.stderr


def test_verify_explores_a_machine_with_inline_guards_as_one_with_files(tmp_path: Path) -> None:
    inline = counter(tmp_path / "inline")
    files = write_machine(
        tmp_path / "files",
        "c",
        {"COUNT": [("END", "n >= 3"), ("COUNT", "True")], "END": None},
        {"COUNT_OnEntry": "n += 1"},
        variables="n: int = 0\n",
    )
    results = []
    for m in (inline, files):
        loaded = load_arrangement([str(m)])
        r = verify(
            loaded, [PropertySource("always", "c.n <= 3"), PropertySource("eventually", "finished(c)")], Options()
        )
        results.append(((r.configurations, r.steps), [o.verdict for o in r.outcomes]))
    assert results[0] == results[1] and results[0][1] == ["holds", "holds"]


def test_the_guard_comment_is_checked_and_not_drawn(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "g", {"A": [("B", "# -> B\nafter_ms(5)"), ("C", "# -> B\nTrue")], "B": None, "C": None})
    assert codes(m) == [("LF071", "State_A_Transition_1.expr", 1, 6)]
    r = llfsm("graph", m)
    assert "    A --> B : 0. after_ms(5)\n    A --> C : 1. True\n" in r.stdout
    assert llfsm("check", m).status == 0 and llfsm("check", "--strict", m).status == 1


def test_the_schema_takes_inline_guards(tmp_path: Path) -> None:
    schema = json.loads(llfsm("schema").stdout)
    jsonschema.validate(yaml.safe_load(COUNTER), schema)
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(yaml.safe_load(COUNTER.replace("to: END", "ot: END")), schema)


def test_layout_yaml_is_checked_and_never_changes_a_build(tmp_path: Path) -> None:
    m = counter(tmp_path)
    assert llfsm("build", m, "-o", tmp_path / "a").status == 0
    (m / "layout.yaml").write_text(
        "states:\n  COUNT: {x: 10, y: 20}\n  GONE: {x: 1, y: 2}\nlabels:\n  COUNT:\n    4: {x: 1, y: 1}\n"
    )
    assert codes(m) == [("LF072", "layout.yaml", 3, 3), ("LF072", "layout.yaml", 6, 5)]
    assert llfsm("build", m, "-o", tmp_path / "b").status == 0
    assert (tmp_path / "a" / "c.py").read_bytes() == (tmp_path / "b" / "c.py").read_bytes()
    for text, where in (
        ("states: [COUNT]\n", (1, 9)),
        ("states:\n  COUNT: {x: 1}\n", (2, 10)),
        ("states:\n  COUNT: {x: 1, y: '2'}\n", (2, 10)),
        ("states:\n  COUNT: {x: 1, y: [}\n", (2, 21)),
        ("sizes: 3\n", (1, 1)),
    ):
        (m / "layout.yaml").write_text(text)
        got = codes(m)
        assert [g[:2] for g in got] == [("LF073", "layout.yaml")] and got[0][2:] == where, (text, got)
        assert llfsm("build", m, "-o", tmp_path / "c").status == 1  # an error of check stops a build


def test_new_machine_with_states_is_a_chain(tmp_path: Path) -> None:
    r = llfsm("new", "machine", "walk", "--dir", tmp_path, "--states", "START,MIDDLE,STOP")
    assert r.status == 0
    m = tmp_path / "walk.machine"
    assert (
        "  - name: START\n    transitions: [MIDDLE]\n  - name: MIDDLE\n    transitions: [STOP]\n  - name: STOP\n"
        in (m / "machine.yaml").read_text()
    )
    assert (m / "State_MIDDLE_Transition_0.expr").read_text() == "# -> STOP\nafter_ms(100)\n"
    assert codes(m) == []
    r = run_sim(m, "-v")
    assert [line.split(" - ")[-1] for line in r.stderr.splitlines()] == ["START", "MIDDLE", "STOP"]
    for bad in ("A,A", "A,../b", "A,class", ""):
        assert llfsm("new", "machine", "x", "--dir", tmp_path, "--states", bad).status != 0
        assert not (tmp_path / "x.machine").exists()
    shutil.rmtree(m)


def test_descriptions_show_guards_as_written_without_their_comment(tmp_path: Path) -> None:
    from llfsm.diagram.description import of_machine, validate
    from llfsm.ros.control import description
    from llfsm.targets import load

    m = counter(tmp_path)
    (m / "machine.yaml").write_text(COUNTER.replace('      - {to: COUNT, guard: "True"}', "      - COUNT"))
    (m / "State_COUNT_Transition_1.expr").write_text("# -> COUNT\nafter_ms(5)\n")
    model = check_machine(m).machine
    assert model is not None
    drawn = validate(of_machine(model))  # the editor's and `llfsm graph`'s, from the directory
    published = description(load(str(m)))  # what a run publishes on /llfsm/c/description
    for desc in (drawn, published):
        assert [(t["target"], t["guard"]) for t in desc["states"][0]["transitions"]] == [
            ("END", "n >= 3"),
            ("COUNT", "after_ms(5)"),
        ]
