"""`llfsm check`: every rule, every format, exit codes, and input built to break it."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from helpers import MACHINES, llfsm, llfsm_process, write_machine

from llfsm.lang.check import check_machine, find_machines
from llfsm.lang.diagnostics import RULES, Diagnostic

OK_STATES = {"INITIAL": [("END", "after_ms(10)")], "END": None}


def codes(path: Path) -> list[tuple[str, str, int, int]]:
    """(code, file name, line, column) of each diagnostic."""
    return [(d.code, Path(d.file).name, d.line, d.column) for d in check_machine(path).diagnostics]


def only(path: Path) -> Diagnostic:
    diags = check_machine(path).diagnostics
    assert len(diags) == 1, diags
    return diags[0]


def test_a_clean_machine_has_no_diagnostics(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "clean", OK_STATES, {"INITIAL_OnEntry": "n += 1"}, variables="n: int = 0\n")
    assert check_machine(m).diagnostics == []


def test_LF001_missing_machine_yaml(tmp_path: Path) -> None:
    (tmp_path / "empty.machine").mkdir()
    assert codes(tmp_path / "empty.machine") == [("LF001", "machine.yaml", 1, 1)]


@pytest.mark.parametrize(
    ("data", "why"),
    [
        (b"\x00\x01\x02binary", "binary"),
        (b"states: \xff\xfe\n", "not UTF-8"),
        (b"x" * (1 << 20 + 1), "larger than"),
    ],
)
def test_LF002_unreadable_files(tmp_path: Path, data: bytes, why: str) -> None:
    m = write_machine(tmp_path, "m", OK_STATES)
    (m / "machine.yaml").write_bytes(data)
    d = only(m)
    assert d.code == "LF002" and why in d.message


def test_LF002_in_a_code_file_too(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "m", OK_STATES)
    (m / "State_INITIAL_OnEntry.py").write_bytes(b"print('ok')\nprint('\xe9')\n")
    d = only(m)
    assert (d.code, Path(d.file).name, d.line) == ("LF002", "State_INITIAL_OnEntry.py", 2)


def test_LF003_yaml_syntax_error_with_position(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "m", OK_STATES)
    (m / "machine.yaml").write_text("states:\n  - name: A\n    transitions: [B\n")
    d = only(m)
    assert d.code == "LF003" and d.line == 4


@pytest.mark.parametrize(
    ("text", "line", "fragment"),
    [
        ("", 1, "empty"),
        ("- a\n- b\n", 1, "must be a mapping"),
        ("description: x\n", 1, "no `states`"),
        ("states: A\n", 1, "non-empty list"),
        ("states: []\n", 1, "non-empty list"),
        ("states:\n  - A\n", 2, "a state must be a mapping"),
        ("states:\n  - name: A\n    transition: [B]\n", 3, "unknown key `transition`"),
        ("states:\n  - name: A\n    transitions: B\n", 3, "must be a list"),
        ("states:\n  - name: [A]\n", 2, "single word"),
        ("states:\n  - transitions: []\n", 2, "needs a `name`"),
        ("states:\n  - name: A\nstates:\n  - name: B\n", 3, "duplicate key"),
        ("initil: A\nstates:\n  - name: A\n", 1, "unknown key `initil`"),
    ],
)
def test_LF004_yaml_structure(tmp_path: Path, text: str, line: int, fragment: str) -> None:
    m = write_machine(tmp_path, "m", OK_STATES)
    (m / "machine.yaml").write_text(text)
    found = [d for d in check_machine(m).diagnostics if d.code == "LF004"]
    assert found, check_machine(m).diagnostics
    assert found[0].line == line and fragment in found[0].message


def test_LF004_deep_yaml_is_refused_without_recursion(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "m", OK_STATES)
    (m / "machine.yaml").write_text("states: " + "[" * 5000 + "]" * 5000 + "\n")
    d = only(m)
    assert d.code == "LF004" and "deeper" in d.message


@pytest.mark.parametrize("loader", ["CSafeLoader", "SafeLoader"])
@pytest.mark.parametrize(
    "text",
    [
        "states: " + "[" * 33 + "]" * 33,
        "states: " + "[" * 1001 + "]" * 1001,  # past libyaml 0.2.6's own cap (PyYAML 6.0.4)
        "states: " + "{a: " * 1200 + "}" * 1200,
        "states:\n" + "".join("  " * i + "- \n" for i in range(1, 40)),
    ],
    ids=["33", "1001", "1200-mappings", "block"],
)
def test_LF004_deep_yaml_whichever_yaml_parser_refuses_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, loader: str, text: str
) -> None:
    import yaml

    from llfsm.lang import reader

    if not hasattr(yaml, loader):
        pytest.skip(f"this PyYAML has no {loader}")
    monkeypatch.setattr(reader, "YAML_LOADER", getattr(yaml, loader))
    m = write_machine(tmp_path, "m", OK_STATES)
    (m / "machine.yaml").write_text(text + "\n")
    d = only(m)
    assert (d.code, d.line, d.message) == ("LF004", d.line, "machine.yaml nests deeper than 32 levels"), d


def test_a_yaml_library_that_refuses_nesting_in_its_own_words_still_gives_LF004(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A later PyYAML may cap nesting where our rescan cannot tell: its wording decides."""
    import yaml

    from llfsm.lang import reader

    class Capped(yaml.SafeLoader):
        def __init__(self, stream: str) -> None:
            super().__init__(stream)
            mark = yaml.Mark("<unicode string>", 0, 0, 7, stream, 7)
            raise yaml.scanner.ScannerError("while increasing flow level", mark, "exceeded maximum nesting depth", mark)

    monkeypatch.setattr(reader, "YAML_LOADER", Capped)
    m = write_machine(tmp_path, "m", OK_STATES)
    d = only(m)
    assert (d.code, d.line, d.column, d.message) == ("LF004", 1, 8, "machine.yaml nests deeper than 32 levels")
    (m / "machine.yaml").write_text("states: [a\n")  # not a limit: plain bad YAML stays LF003
    monkeypatch.setattr(reader, "YAML_LOADER", yaml.SafeLoader)
    assert only(m).code == "LF003"


def test_LF005_alias_bombs_are_refused(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "m", OK_STATES)
    bomb = ["a: &a [x, x, x, x, x, x, x, x, x]"]
    for i, (prev, cur) in enumerate(zip("abcdefgh", "bcdefghi", strict=True)):
        bomb.append(f"{cur}: &{cur} [{', '.join(['*' + prev] * 9)}]")
        assert i < 9
    (m / "machine.yaml").write_text("\n".join(bomb) + "\nstates:\n  - name: A\n")
    d = only(m)
    assert d.code == "LF005" and d.line == 1


def test_LF010_machine_names(tmp_path: Path) -> None:
    for name, ok in (("9lives", False), ("class", False), ("with-dash", False), ("_ok_1", True)):
        d = tmp_path / f"{name}.machine"
        d.mkdir()
        (d / "machine.yaml").write_text("states:\n  - name: A\n")
        got = [c for c, *_ in codes(d)]
        assert (got == []) is ok, (name, got)
        assert ok or got == ["LF010"]
    plain = tmp_path / "plain"
    plain.mkdir()
    (plain / "machine.yaml").write_text("states:\n  - name: A\n")
    assert [c for c, *_ in codes(plain)] == ["LF010"]


def test_LF011_LF012_state_names(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "m", OK_STATES)
    (m / "machine.yaml").write_text("states:\n  - name: A\n  - name: 2B\n  - name: def\n  - name: A\n")
    got = [(c, line) for c, _f, line, _col in codes(m)]
    assert ("LF011", 3) in got and ("LF011", 4) in got and ("LF012", 5) in got


def test_yaml_words_are_names_as_written(tmp_path: Path) -> None:
    # YAML 1.1 would read ON / yes / null as booleans or null; state names are taken as written
    m = write_machine(tmp_path, "m", {"ON": [("yes", "True")], "yes": [("null", "True")], "null": None})
    assert codes(m) == []


def test_LF013_reserved_names(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "m",
        OK_STATES,
        {"INITIAL_OnEntry": "self = 3\nafter_ms = 2\n"},
        variables="state_name: int = 0\n_state: int = 1\nringlet_END: int = 2\n__init__: int = 3\n",
    )
    got = sorted((f, line) for c, f, line, _ in codes(m) if c == "LF013")
    assert got == [
        ("State_INITIAL_OnEntry.py", 1),
        ("State_INITIAL_OnEntry.py", 2),
        ("Variables.py", 1),
        ("Variables.py", 2),
        ("Variables.py", 3),
        ("Variables.py", 4),
    ]


def test_LF020_LF021_LF022_unknown_states_point_at_the_yaml(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "m", OK_STATES)
    (m / "machine.yaml").write_text("initial: START\nsuspended: PAUSE\nstates:\n  - name: A\n    transitions: [B]\n")
    (m / "State_A_Transition_0.expr").write_text("True\n")
    got = codes(m)
    assert ("LF021", "machine.yaml", 1, 10) in got
    assert ("LF022", "machine.yaml", 2, 12) in got
    assert ("LF020", "machine.yaml", 5, 19) in got


def test_LF023_missing_guard(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "m", OK_STATES)
    (m / "State_INITIAL_Transition_0.expr").unlink()
    d = only(m)
    assert (d.code, Path(d.file).name, d.line) == ("LF023", "machine.yaml", 3)
    assert "State_INITIAL_Transition_0.expr" in d.message


@pytest.mark.parametrize("text", ["x = 1", "a\nb", "", "# only a comment", "import os"])
def test_LF024_guard_must_be_one_expression(tmp_path: Path, text: str) -> None:
    m = write_machine(tmp_path, "m", {"INITIAL": [("END", text)], "END": None})
    assert [c for c, *_ in codes(m)] == ["LF024"]


def test_LF030_syntax_errors_have_exact_line_and_column(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "m", OK_STATES, {"INITIAL_OnEntry": "x = 1\ny = (2 +\nprint(x y)\n"})
    d = only(m)
    assert d.code == "LF030" and Path(d.file).name == "State_INITIAL_OnEntry.py"
    assert (d.line, d.column) == (2, 5)
    m = write_machine(tmp_path / "g", "m", {"INITIAL": [("END", "after_ms(10")], "END": None})
    d = only(m)
    assert (d.code, Path(d.file).name, d.line, d.column) == ("LF030", "State_INITIAL_Transition_0.expr", 1, 9)


def test_LF030_column_counts_characters_not_bytes(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "m", OK_STATES, {"INITIAL_OnEntry": "s = 'éé' + )\n"})
    d = only(m)
    assert (d.line, d.column) == (1, 12)


def test_LF031_includes_only_imports(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path, "m", OK_STATES, includes="import os\nx = 1\nfrom __future__ import annotations\nfrom . import y\n"
    )
    assert sorted((c, line) for c, _f, line, _ in codes(m)) == [("LF031", 2), ("LF031", 3), ("LF031", 4)]


def test_LF032_variables_only_annotated_assignments(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "m", OK_STATES, variables="a: int = 1\nb = 2\nprint(a)\nc.d: int = 3\nlater: str\n")
    assert sorted((c, line) for c, _f, line, _ in codes(m)) == [("LF032", 2), ("LF032", 3), ("LF032", 4)]


def test_LF033_state_variable_shadowing_a_machine_variable(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "m",
        OK_STATES,
        {"INITIAL_Variables": "local: int = 0\ncount: int = 1\n"},
        variables="count: int = 0\n",
    )
    assert codes(m) == [("LF033", "State_INITIAL_Variables.py", 2, 1)]


def test_LF034_global_and_nonlocal(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "m",
        OK_STATES,
        {"INITIAL_OnEntry": "global x\ndef f():\n    y = 1\n    def g():\n        nonlocal y\n"},
    )
    assert sorted((c, line) for c, _f, line, _ in codes(m)) == [("LF034", 1), ("LF034", 5)]


def test_LF035_duplicate_variable(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "m", OK_STATES, variables="a: int = 1\na: int = 2\n")
    assert codes(m) == [("LF035", "Variables.py", 2, 1)]


def test_LF036_return_yield_await_at_section_top_level(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "m",
        OK_STATES,
        {"INITIAL_OnEntry": "def ok():\n    return 1\nif True:\n    return\n", "END_OnEntry": "x = yield 1\n"},
    )
    got = sorted((c, f, line) for c, f, line, _ in codes(m))
    assert got == [("LF036", "State_END_OnEntry.py", 1), ("LF036", "State_INITIAL_OnEntry.py", 4)]


def test_LF037_symlinks_out_of_the_machine_directory_are_refused(tmp_path: Path) -> None:
    secret = tmp_path / "secret.txt"
    secret.write_text("print('outside')\n")
    m = write_machine(tmp_path, "m", OK_STATES)
    (m / "State_INITIAL_OnEntry.py").symlink_to(secret)
    assert codes(m) == [("LF037", "State_INITIAL_OnEntry.py", 1, 1)]
    # a symlink inside the directory is fine
    (m / "State_INITIAL_OnEntry.py").unlink()
    (m / "shared.py").write_text("x = 1\n")
    (m / "State_INITIAL_OnEntry.py").symlink_to(m / "shared.py")
    assert codes(m) == []


def test_LF038_machine_variables_cannot_be_bound_by_walrus_import_def(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "m",
        OK_STATES,
        {
            "INITIAL_OnEntry": "if (n := 3):\n    pass\nimport n\ndef n():\n    pass\n"
            "f = lambda n: n + 1\n[n for n in range(3)]\n"
        },
        variables="n: int = 0\n",
    )
    assert sorted((c, line) for c, _f, line, _ in codes(m)) == [("LF038", 1), ("LF038", 3), ("LF038", 4)]


def test_LF101_orphan_files(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "m", OK_STATES, {"GHOST_OnEntry": "x = 1", "State_INITIAL_Transition_7.expr": "True"})
    got = sorted((c, f) for c, f, *_ in codes(m))
    assert got == [("LF101", "State_GHOST_OnEntry.py"), ("LF101", "State_INITIAL_Transition_7.expr")]


def test_LF102_unreachable_state(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "m", {"INITIAL": [("END", "True")], "ISLAND": [("END", "True")], "END": None})
    assert codes(m) == [("LF102", "machine.yaml", 4, 11)]


def test_LF103_LF104_constant_guards(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "m",
        {"INITIAL": [("END", "False"), ("A", "True"), ("END", "x")], "A": None, "END": None},
        variables="x: bool = True\n",
    )
    got = sorted((c, f, line) for c, f, line, _ in codes(m))
    assert got == [("LF103", "State_INITIAL_Transition_0.expr", 1), ("LF104", "machine.yaml", 3)]


def test_LF040_undefined_names_including_another_sections_locals(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "m",
        {"INITIAL": [("END", "ready and tmp > 0")], "END": None},
        {"INITIAL_OnEntry": "tmp = 3\nprint(len(str(tmp)), ros)\n", "INITIAL_Variables": "ready: bool = True\n"},
        includes="import math\n",
    )
    got = sorted((c, f, line, col) for c, f, line, col in codes(m))
    assert got == [("LF040", "State_INITIAL_OnEntry.py", 2, 22), ("LF040", "State_INITIAL_Transition_0.expr", 1, 11)]


def test_every_rule_is_documented() -> None:
    doc = (Path(__file__).resolve().parent.parent / "docs" / "rules.md").read_text()
    for code, rule in RULES.items():
        assert f"### {code} {rule.name}" in doc, code


def test_check_never_runs_user_code(tmp_path: Path) -> None:
    marker = tmp_path / "ran"
    payload = f"open({str(marker)!r}, 'w').write('ran')"
    m = write_machine(
        tmp_path,
        "evil",
        {"INITIAL": [("END", f"{payload} or True")], "END": None},
        {"INITIAL_OnEntry": payload, "INITIAL_Internal": payload, "END_OnExit": payload},
        variables=f"x: int = {payload}\n",
        includes=f"import os; os.system('touch {marker}')\n",
    )
    check_machine(m)
    assert not marker.exists()
    r = llfsm("build", m, "-o", tmp_path / "out")
    assert r.status == 1  # the include is not an import statement only... it is: but `;` joins two
    (m / "Includes.py").write_text("import os\n")
    r = llfsm("build", m, "-o", tmp_path / "out")
    assert r.status == 0, r.stderr
    assert not marker.exists()
    r = llfsm("graph", m)
    assert r.status == 0 and not marker.exists()


def test_find_machines_searches_folders_but_skips_colcon_output(tmp_path: Path) -> None:
    for where in ("src/pkg/machine", "install/pkg/share/pkg/machine", "build/pkg", ".hidden"):
        write_machine(tmp_path / where, "m", OK_STATES)
    found = [p.relative_to(tmp_path).as_posix() for p in find_machines(tmp_path)]
    assert found == ["src/pkg/machine/m.machine"]


# -- the command --------------------------------------------------------------------------


def test_exit_codes(tmp_path: Path) -> None:
    good = write_machine(tmp_path / "good", "good", OK_STATES)
    warn = write_machine(tmp_path / "warn", "warn", {"INITIAL": [("END", "False")], "END": None})
    bad = write_machine(tmp_path / "bad", "bad", {"INITIAL": [("NOPE", "True")]})
    assert llfsm("check", good).status == 0
    assert llfsm("check", warn).status == 0
    assert llfsm("check", "--strict", warn).status == 1
    assert llfsm("check", bad).status == 1
    assert llfsm("check", tmp_path / "nope").status == 2
    empty = tmp_path / "empty"
    empty.mkdir()
    assert llfsm("check", empty).status == 2
    assert llfsm("check", "--format", "xml", good).status == 2
    r = llfsm("check", tmp_path)
    assert r.status == 1 and "checked 3 machine(s): 1 error(s), 1 warning(s)" in r.stderr


def test_text_format_is_file_line_col_code(tmp_path: Path) -> None:
    bad = write_machine(tmp_path, "bad", {"INITIAL": [("NOPE", "True")]})
    r = llfsm("check", bad)
    assert r.stdout == f"{bad}/machine.yaml:3:19: LF020 error: transition 0 of INITIAL goes to unknown state 'NOPE'\n"


def test_json_format(tmp_path: Path) -> None:
    bad = write_machine(tmp_path, "bad", {"INITIAL": [("NOPE", "True")]})
    data = json.loads(llfsm("check", "--format", "json", bad).stdout)
    assert data == [
        {
            "code": "LF020",
            "severity": "error",
            "file": f"{bad}/machine.yaml",
            "line": 3,
            "column": 19,
            "message": "transition 0 of INITIAL goes to unknown state 'NOPE'",
        }
    ]


def test_github_format(tmp_path: Path) -> None:
    bad = write_machine(tmp_path, "bad", {"INITIAL": [("NOPE", "True"), ("INITIAL", "False")]})
    lines = llfsm("check", "--format", "github", bad).stdout.splitlines()
    assert (
        f"::error file={bad}/machine.yaml,line=3,col=19,title=LF020::"
        "transition 0 of INITIAL goes to unknown state 'NOPE'" in lines
    )
    assert any(x.startswith("::warning file=") and "title=LF103" in x for x in lines)


def test_sarif_format(tmp_path: Path) -> None:
    bad = write_machine(tmp_path, "bad", {"INITIAL": [("NOPE", "True"), ("INITIAL", "False")]})
    out = tmp_path / "report.sarif"
    r = llfsm("check", "--format", "sarif", "-o", out, bad)
    assert r.status == 1 and r.stdout == ""
    doc = json.loads(out.read_text())
    assert doc["version"] == "2.1.0"
    run = doc["runs"][0]
    assert run["tool"]["driver"]["name"] == "llfsm"
    rule_ids = [r["id"] for r in run["tool"]["driver"]["rules"]]
    assert rule_ids == ["LF020", "LF103", "LF104"]
    res = next(r for r in run["results"] if r["ruleId"] == "LF020")
    assert res["level"] == "error"
    assert rule_ids[res["ruleIndex"]] == "LF020"
    region = res["locations"][0]["physicalLocation"]["region"]
    assert region == {"startLine": 3, "startColumn": 19}


def test_check_output_is_deterministic(tmp_path: Path) -> None:
    for i in range(3):
        write_machine(tmp_path, f"m{i}", {"INITIAL": [("NOPE", "x")], "ISLAND": None})
    a = llfsm("check", "--format", "json", tmp_path).stdout
    b = llfsm("check", "--format", "json", tmp_path).stdout
    assert a == b and len(json.loads(a)) == 9


def test_hostile_inputs_never_produce_a_traceback(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "m", OK_STATES)
    os.mkfifo(m / "State_INITIAL_OnExit.py.fifo")  # odd files beside the machine are ignored
    (m / "State_INITIAL_Internal.py").write_text("(" * 300 + ")" * 300)
    (m / "State_END_OnEntry.py").write_text("-" * 100_000 + "1\n")
    (m / "State_INITIAL_OnExit.py").mkdir()  # a directory where a file is expected
    r = llfsm_process("check", m)
    assert r.status == 1
    assert "Traceback" not in r.stderr
    assert "LF030" in r.stdout


def test_LF107_code_of_the_suspend_state_that_never_runs(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "m",
        {"INITIAL": [("END", "True")], "END": None, "SUSPENDED": [("INITIAL", "True")]},
        {"SUSPENDED_Internal": "x = 1", "SUSPENDED_OnEntry": "y = 2", "SUSPENDED_OnResume": "z = 3"},
    )
    got = sorted((c, f) for c, f, *_ in codes(m))
    assert got == [("LF107", "State_SUSPENDED_Internal.py"), ("LF107", "machine.yaml")]


def test_parallel_check_gives_the_same_output_in_the_same_order(tmp_path: Path) -> None:
    from llfsm.lang.check import diagnose

    for i in range(12):
        write_machine(tmp_path, f"m{i:02d}", {"INITIAL": [("NOPE" if i % 3 else "END", "x")], "END": None})
    count, one = diagnose([tmp_path], jobs=1)
    count2, two = diagnose([tmp_path], jobs=2)
    assert count == count2 == 12
    assert one == two and len(one) > 8
    r = llfsm("check", "-j", "2", "--format", "json", tmp_path)
    assert [d["file"] for d in json.loads(r.stdout)] == [d.file for d in one]


def test_check_knows_the_attributes_of_llfsms_clock_time() -> None:
    """LF041's hint about `now().to_msg()` rests on a list of what llfsm's clock time has:
    the front end never imports the bus to find out."""
    from llfsm import ros
    from llfsm.lang.check.ros_habits import CLOCK_TIME_ATTRIBUTES

    assert {n for n in dir(ros.Time(0)) if not n.startswith("_")} == CLOCK_TIME_ATTRIBUTES


def test_the_front_end_imports_neither_the_compiler_nor_the_bus() -> None:
    """lang/ sits below compiler/ and above nothing of the bus: checking a machine loads
    neither (nor the messages), so `llfsm check` stays light and the layers point one way."""
    code = (
        "import sys\n"
        "from llfsm.lang.check import check_machine\n"
        f"check_machine({str(MACHINES / 'counter.machine')!r})\n"
        "print(sorted(m for m in sys.modules if m.startswith(('llfsm.compiler', 'llfsm.ros', 'llfsm.msgs'))))\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.stdout.strip() == "[]", proc.stderr


def test_lf080_lines_left_by_llfsm_import_are_errors_at_their_line(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "imported",
        {
            "INITIAL": [("END", "# UNTRANSLATED (why): control_machine_at_index(1, CLStatus) == CLSuspend\nFalse")],
            "END": None,
        },
        {
            "INITIAL_OnEntry": (
                "n = 1\nif n:\n    # UNTRANSLATED (unlink): unlink(f);\n    # UNTRANSLATED: g();\n    pass\n"
            )
        },
        variables="n: int = 0\n# UNTRANSLATED (the type T): T t;\nt: object  # a placeholder\n",
        includes="# a comment that says UNTRANSLATED is fine\n",
    )
    assert codes(m) == [
        ("LF080", "State_INITIAL_OnEntry.py", 3, 5),
        ("LF080", "State_INITIAL_OnEntry.py", 4, 5),
        ("LF080", "State_INITIAL_Transition_0.expr", 1, 1),  # and no LF103 for its stand-in `False`
        ("LF080", "Variables.py", 2, 1),
    ]
    d = next(d for d in check_machine(m).diagnostics if d.line == 3)
    assert d.message == "clfsm code left untranslated (unlink): write `unlink(f);` in Python, then delete this line"
    r = llfsm("build", m, "-o", tmp_path / "out")
    assert r.status == 1
