"""Fuzzing (issue 5): `llfsm check` runs on untrusted pull requests, and arrangements run for
hours beside real robots, so no input may crash, hang or mislead them.

Properties, over machines from tests/strategies.py:
- `check_machine` never raises, whatever the directory holds, and every output format renders;
- its output is deterministic: the same twice, and the same for a copy at another path
  (modulo that path);
- a machine that checks with no error builds, imports, and runs 1,000 simulated rounds with no
  llfsm-internal error: the run ends normally, or with an error report that names a file of the
  machine directory and a line in it (generated code may divide by zero: that is the user's);
- the generated module is valid Python that imports only `llfsm.runtime` and the user's includes.

Two budgets: a small, derandomised one in `make test` (about 20 s), and a large one behind the
`slow` marker (`make fuzz`), random so that each run explores new machines (a failure is kept
in .hypothesis/ and replayed first next time).  The examples each property tried are counted
in TRIED and printed when the session ends; `--hypothesis-show-statistics` adds hypothesis'
own statistics and the events below (how runs ended, which mutations and rules were hit).
"""

from __future__ import annotations

import ast
import atexit
import gc
import json
import os
import sys
import sysconfig
import tempfile
import time
from collections import Counter
from collections.abc import Iterator
from pathlib import Path

import pytest
from helpers import header_ok, llfsm, only_expected_statements, sarif_validator, strings_in, write_machine
from hypothesis import HealthCheck, event, given, settings
from strategies import (
    MachineSpec,
    Mutation,
    apply_mutation,
    arrangements,
    copy_case,
    hostile_folder_names,
    machine_specs,
    mutated_machines,
    write_spec,
)

from llfsm.compiler.build import build_machine
from llfsm.lang.check import check_machine, check_paths
from llfsm.lang.diagnostics import FORMATS, format_text, render
from llfsm.runtime import Arrangement, ErrorReport, Machine, SimClock, report_for
from llfsm.targets import MachineLoadError, load_class

ROUNDS = 1000
_QUIET = list(HealthCheck)  # slow examples and big data are the point here
SMALL = settings(max_examples=60, deadline=None, derandomize=True, database=None, suppress_health_check=_QUIET)
SMALL_MUTATED = settings(SMALL, max_examples=150)
LARGE = settings(max_examples=2000, deadline=None, suppress_health_check=_QUIET)
LARGE_MUTATED = settings(LARGE, max_examples=3000)
SMALL_ARRANGEMENTS = settings(SMALL, max_examples=20)
SMALL_HOSTILE = settings(SMALL, max_examples=20)
LARGE_ARRANGEMENTS = settings(LARGE, max_examples=1000)

#: Examples tried per property in this session, printed to stderr when the session ends.
TRIED: Counter[str] = Counter()


@atexit.register
def _report() -> None:
    if TRIED:
        sys.stderr.write("fuzz examples tried: " + ", ".join(f"{k}={v}" for k, v in sorted(TRIED.items())) + "\n")


# -- helpers -------------------------------------------------------------------------------------


def _diagnostics(case: Path, path: Path) -> list[tuple[str, str, int, int, str]]:
    """Everything `llfsm check` says about `path` and about the folder `case` holding it."""
    checked = check_machine(path)
    for fmt in FORMATS:
        render(checked.diagnostics, fmt, "0")  # every format renders whatever the input
    found = [d for r in check_paths([case]) for d in r.diagnostics]
    return [(d.code, d.file, d.line, d.column, d.message) for d in checked.diagnostics + found]


def _moved(diags: list[tuple[str, str, int, int, str]], old: Path, new: Path) -> list[tuple[str, str, int, int, str]]:
    return [(c, f.replace(str(old), str(new)), ln, col, m.replace(str(old), str(new))) for c, f, ln, col, m in diags]


def _user_imports(machine: Path) -> set[str]:
    """Modules the machine's own files import: Includes.py, and the sections of a mutated
    machine (generated sections never import).  Its compiled module may import these."""
    out: set[str] = set()
    for f in machine.iterdir():
        if f.suffix in (".py", ".expr") and f.is_file() and not f.is_symlink():
            try:
                out |= _imports(f.read_bytes().decode("utf-8-sig"))
            except (SyntaxError, ValueError):
                pass
    return out


def _imports(source: str) -> set[str]:
    out = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            out.add("." * node.level + (node.module or ""))
    return out


def _points_at_user_file(rep: ErrorReport | None, machines: list[Path], what: str) -> None:
    """An error report must name a file of a machine directory and a line that exists."""
    assert rep is not None, f"{what}: an exception with no frame in the machine's code (an llfsm bug)"
    assert rep.file and rep.line, f"{what}: a report that names no file or line: {rep}"
    path = Path(rep.file) if os.path.isabs(rep.file) else Path.cwd() / rep.file
    assert path.parent.resolve() in {m.resolve() for m in machines}, f"{what}: {rep.file} is in no machine"
    lines = path.read_text(encoding="utf-8-sig").splitlines()
    assert 1 <= rep.line <= len(lines), f"{what}: {rep.file} has no line {rep.line}"
    event(f"{what} error: {rep.exception.split(':')[0]}")


def build_and_import(machine: Path, out: Path) -> type[Machine] | None:
    """Build a machine that checks clean, verify its module, and import it (None: importing
    raised in the user's includes, and the report says where)."""
    outcome = build_machine(machine, out)
    assert outcome.status == "compiled", format_text(outcome.diagnostics)
    assert outcome.module is not None
    source = outcome.module.read_text(encoding="utf-8")
    compile(source, str(outcome.module), "exec", dont_inherit=True)
    extra = _imports(source) - {"llfsm.runtime"} - _user_imports(machine)
    assert not extra, f"the generated module imports {sorted(extra)}"
    try:
        return load_class(outcome.module)
    except MachineLoadError as e:  # `import no_such_module` in Includes.py: the user's
        _points_at_user_file(e.report, [machine], "import")
        return None


def runs(classes: list[type[Machine]], machines: list[Path]) -> str:
    """Load and run an arrangement for ROUNDS simulated rounds; returns how the run ended."""
    try:
        try:
            arr = Arrangement(classes, clock=SimClock())
        except Exception as exc:  # a variable initialiser raised: the user's code
            _points_at_user_file(report_for(exc), machines, "loading")
            return "load error"
        result = arr.run(duration_ns=ROUNDS * 1_000_000)  # an exception escaping here is a bug
        assert result.reason in ("finished", "suspended", "duration", "error"), result
        if result.error is not None:
            _points_at_user_file(result.error, machines, "run")
        else:
            assert result.reason != "error"
        return result.reason
    finally:
        for cls in classes:
            sys.modules.pop(cls.__module__, None)


def builds_imports_and_runs(machine: Path, out: Path) -> str:
    cls = build_and_import(machine, out)
    return runs([cls], [machine]) if cls is not None else "import error"


# -- the properties ------------------------------------------------------------------------------


def valid_machine_property(spec: MachineSpec) -> None:
    TRIED["valid"] += 1
    with tempfile.TemporaryDirectory() as tmp:
        machine = write_spec(spec, Path(tmp) / "src")
        checked = check_machine(machine)
        assert checked.ok, format_text(checked.errors)
        event(f"ended: {builds_imports_and_runs(machine, Path(tmp) / 'out')}")


def mutated_machine_property(spec: MachineSpec, muts: list[Mutation]) -> None:
    TRIED["mutated"] += 1
    with tempfile.TemporaryDirectory() as tmp:
        case = Path(tmp) / "a"
        machine = write_spec(spec, case)
        for mut in muts:
            machine = apply_mutation(case, machine, spec, mut)
            event(f"mutation: {mut[0]}")
        first = _diagnostics(case, machine)
        assert _diagnostics(case, machine) == first, "check is not deterministic"
        other = Path(tmp) / "elsewhere" / "b"
        other.parent.mkdir()
        copy_case(case, other)
        moved = other / machine.relative_to(case)
        assert _diagnostics(other, moved) == _moved(first, case, other), "check depends on the path"
        for code in sorted({d[0] for d in first}):
            event(f"diagnostic: {code}")
        if machine.name.endswith(".machine") and check_machine(machine).ok:
            TRIED["mutated, still valid"] += 1
            event(f"ended: {builds_imports_and_runs(machine, Path(tmp) / 'out')}")


def arrangement_property(specs: list[MachineSpec]) -> None:
    TRIED["arrangement"] += 1
    with tempfile.TemporaryDirectory() as tmp:
        machines = [write_spec(spec, Path(tmp) / "src") for spec in specs]
        for machine in machines:
            checked = check_machine(machine)
            assert checked.ok, format_text(checked.errors)
        classes = [build_and_import(machine, Path(tmp) / "out") for machine in machines]
        assert all(classes)  # the includes of generated machines always import
        event(f"ended: {runs([c for c in classes if c is not None], machines)}")


@SMALL
@given(machine_specs())
def test_valid_machines_check_clean_build_import_and_run(spec: MachineSpec) -> None:
    valid_machine_property(spec)


@SMALL_MUTATED
@given(mutated_machines())
def test_check_never_raises_and_is_deterministic_on_mutated_machines(case: tuple[MachineSpec, list[Mutation]]) -> None:
    mutated_machine_property(*case)


@SMALL_ARRANGEMENTS
@given(arrangements())
def test_machines_that_name_each_other_run_together(specs: list[MachineSpec]) -> None:
    arrangement_property(specs)


@pytest.mark.slow
@LARGE_ARRANGEMENTS
@given(arrangements())
def test_arrangements_at_volume(specs: list[MachineSpec]) -> None:
    arrangement_property(specs)


@pytest.mark.slow
@LARGE
@given(machine_specs())
def test_valid_machines_at_volume(spec: MachineSpec) -> None:
    valid_machine_property(spec)


@pytest.mark.slow
@LARGE_MUTATED
@given(mutated_machines())
def test_mutated_machines_at_volume(case: tuple[MachineSpec, list[Mutation]]) -> None:
    mutated_machine_property(*case)


# -- bugs the fuzzing found, kept as plain regression tests --------------------------------------

OK_STATES = {"A": [("END", "after_ms(2)")], "END": None}


def _codes(machine: Path) -> list[str]:
    return sorted(d.code for d in check_machine(machine).diagnostics)


def _run(machine: Path, out: Path) -> str:
    return builds_imports_and_runs(machine, out)


@pytest.mark.parametrize("depth", [300, 1000, 100_000])
def test_deeply_nested_code_is_refused_not_a_recursion_error(tmp_path: Path, depth: int) -> None:
    """`1+1+...+1` parses into a tree as deep as it is long; the compiler's tree walks recurse,
    so a few hundred levels used to raise RecursionError out of check and build."""
    variables = "count: int = 0\n"
    m = write_machine(tmp_path, "m", OK_STATES, {"A_OnEntry": "x = " + "1+" * depth + "1\nimport count\n"}, variables)
    assert _codes(m) == ["LF030"]
    assert build_machine(m, tmp_path / "out").status == "failed"


def test_ordinary_nesting_is_fine(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "m", OK_STATES, {"A_OnEntry": "x = " + "1+" * 150 + "1\n"})
    assert _codes(m) == []
    assert _run(m, tmp_path / "out") == "finished"


@pytest.mark.parametrize(
    ("text", "ending"),
    [
        (b"n = 1\rif n:\r    n += 1\r", "cr"),
        (b"n = 1\r\nif n:\r\n    n += 1\r\n", "crlf"),
        ("s = 'a\u2028b'  # \x0c \x1c \x85\nn = len(s)\nn += 1\n".encode(), "line separators in strings"),
    ],
)
def test_every_line_ending_python_accepts_builds_as_it_checks(tmp_path: Path, text: bytes, ending: str) -> None:
    """ast counts \\r, \\r\\n and \\n as line ends; the compiler split lines with
    str.splitlines (which also splits on \\x0c, \\x1c, \\x85, U+2028...) or with \\n only,
    so these machines checked clean and then failed to build, or built the wrong code."""
    m = write_machine(tmp_path, "m", OK_STATES, variables="n: int = 0\n")
    (m / "State_A_OnEntry.py").write_bytes(text)
    assert _codes(m) == [], ending
    assert _run(m, tmp_path / "out") == "finished"


def test_a_form_feed_in_indentation_is_refused(tmp_path: Path) -> None:
    """CPython resets the indentation count at a form feed: re-indented into a method, the line
    would leave the method (and run at import)."""
    m = write_machine(tmp_path, "m", OK_STATES)
    (m / "State_A_OnEntry.py").write_text("x = 1\n\f    print(x)\n\f\n")
    diags = check_machine(m).diagnostics
    assert [(d.code, d.line) for d in diags] == [("LF030", 2)]
    (m / "State_A_OnEntry.py").write_text("x = 1\n\f\ny = 2 \f+ 1\n")  # a page break on its own line
    assert _codes(m) == []


@pytest.mark.parametrize("guard", ["1, 2", "*[1], 2", "True;", "x > 1 ; # two"])
def test_guards_that_cannot_be_an_if_condition_are_refused(tmp_path: Path, guard: str) -> None:
    m = write_machine(tmp_path, "m", {"A": [("END", guard)], "END": None}, variables="x: int = 0\n")
    assert _codes(m) == ["LF024"]


@pytest.mark.parametrize(
    "code",
    [
        "x = 1\nbreak\n",
        "continue\n",
        "from math import *\n",
        "def f(a, a):\n    pass\n",
        "class K:\n    return 1\n",
        "class K:\n    yield 1\n",
        "f = lambda: (await x)\n",
        "".join("    " * i + f"for i{i} in range(1):\n" for i in range(21)) + "    " * 21 + "pass\n",
        "".join("    " * i + f"with open(f{i}):\n" for i in range(21)) + "    " * 21 + "pass\n",
        "try:\n    pass\nexcept:\n    pass\nexcept ValueError:\n    pass\n",
        "print(a=1, a=2)\n",
        "__debug__ = 1\n",
        "x.__debug__ = 1\n",
        "print(__debug__=1)\n",
        "del __debug__\n",
        "import math as __debug__\n",
        "*a, *b = [1, 2]\n",
        "*a = [1]\n",
        "from __future__ import annotations\n",
        "y = [x async for x in range(3)]\n",
    ],
)
def test_what_only_the_compiler_refuses_is_a_check_error(tmp_path: Path, code: str) -> None:
    """These parse, so `check` passed them, and then `build` failed to compile the module."""
    m = write_machine(tmp_path, "m", OK_STATES, {"A_OnEntry": code})
    assert "LF030" in _codes(m)


def _stdlib_statements(limit: int | None) -> Iterator[tuple[str, ast.Module]]:
    """Every statement of the standard library's modules (the first `limit` files), each as
    the code of a section: a large corpus of real Python the generators would never write."""
    files = sorted(Path(sysconfig.get_paths()["stdlib"]).glob("*.py"))[:limit]
    for f in files:
        try:
            tree = ast.parse(f.read_bytes())
        except (SyntaxError, ValueError):
            continue
        for node in ast.walk(tree):
            if isinstance(node, ast.stmt):
                yield f"{f.name}:{node.lineno}", ast.Module(body=[node], type_ignores=[])


def _plain_but_refused(limit: int | None) -> tuple[int, list[str]]:
    from llfsm.lang.check.scan import compile_error as _compile_error
    from llfsm.lang.check.scan import scan_code as _scan

    plain, refused = 0, []
    for where, module in _stdlib_statements(limit):
        if _scan(module, {}).plain and "__debug__" not in ast.unparse(module):
            plain += 1
            if _compile_error(module, guard=False) is not None:
                refused.append(where)
    return plain, refused


def test_plain_code_that_check_does_not_compile_compiles() -> None:
    """`check` skips the bytecode compile of code made only of plain statements and
    expressions: every such statement of the standard library must compile in a method."""
    plain, refused = _plain_but_refused(40)
    assert plain > 5000 and refused == []


@pytest.mark.slow
def test_plain_code_that_check_does_not_compile_compiles_whole_stdlib() -> None:
    plain, refused = _plain_but_refused(None)
    assert plain > 40_000 and refused == []


def test_code_is_compiled_where_the_module_puts_it(tmp_path: Path) -> None:
    """Sections, guards and initialisers are compiled as parts of a method: what is fine there
    (a top-level `return` is LF036, not a compile error; a comprehension; a lambda) passes."""
    m = write_machine(
        tmp_path,
        "m",
        {"A": [("END", "[i for i in range(2)] and (lambda: x)()")], "END": None},
        {"A_OnEntry": "for i in range(2):\n    if i:\n        break\n    continue\nf = lambda: (yield)\n"},
        variables="x: object = [i for i in range(2)]\n",
    )
    assert _codes(m) == []
    assert _run(m, tmp_path / "out") == "finished"


@pytest.mark.parametrize("include", ["import os as Machine", "from os import path as super", "import os as frozenset"])
def test_includes_cannot_rebind_what_the_compiled_module_uses(tmp_path: Path, include: str) -> None:
    """The module's class derives from `Machine` and calls `super()`: rebinding either made the
    module fail to import, with an error report naming no file of the machine."""
    m = write_machine(tmp_path, "m", OK_STATES, includes=include + "\n")
    assert _codes(m) == ["LF013"]


def test_variable_initialisers_cannot_rebind_self(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "m", OK_STATES, variables="x: int = (self := 3)\ny: int = 2\n")
    assert _codes(m) == ["LF013"]


def test_state_variables_cannot_share_an_attribute(tmp_path: Path) -> None:
    """`c` of state `A__B` and `B__c` of state `A` are both stored as `A__B__c`; `x` of state
    `ringlet` is stored as `ringlet__x`, the ringlet method of state `_x`."""
    m = write_machine(
        tmp_path,
        "m",
        {"A__B": [("A", "True")], "A": [("END", "True")], "END": None},
        {"A__B_Variables": "c: int = 1\n", "A_Variables": "B__c: int = 2\n"},
    )
    assert _codes(m) == ["LF013"]
    m = write_machine(
        tmp_path / "r",
        "m",
        {"ringlet": [("_x", "True")], "_x": [("END", "True")], "END": None},
        {"ringlet_Variables": "x: int = 1\n"},
    )
    assert _codes(m) == ["LF013"]


def test_private_variable_names_are_refused(tmp_path: Path) -> None:
    """`self.__x` is mangled with the name of the class it appears in: inside a class a section
    defines, it named another attribute."""
    m = write_machine(tmp_path, "m", OK_STATES, variables="__x: int = 0\n")
    assert _codes(m) == ["LF013"]
    m = write_machine(tmp_path / "s", "m", {"__A": [("END", "True")], "END": None}, {"__A_Variables": "x: int = 0\n"})
    assert _codes(m) == ["LF013"]


def test_huge_transition_lists_are_checked_in_linear_time(tmp_path: Path) -> None:
    """A 1 MiB machine.yaml holds about 300,000 transitions.  Looking for the diagnostics of
    each missing guard file scanned every diagnostic so far: hours of CPU for one file, and
    a quarter of an hour for this one.  Ten times the transitions must cost about ten times
    the work, not a hundred: the two sizes are timed side by side and only their ratio is
    compared, in CPU time (the process's, not the wall's: another process on a loaded machine
    takes the wall, not this one's CPU), the fastest of repeated runs."""

    def seconds(count: int) -> float:
        m = write_machine(tmp_path / str(count), "m", OK_STATES)
        (m / "machine.yaml").write_text("states:\n  - name: A\n    transitions: [" + ", ".join(["A"] * count) + "]\n")
        for f in m.glob("*.expr"):
            f.unlink()
        # `llfsm check` runs in a fresh process: the objects this test process gathered from the
        # tests before it are set aside from the collector (the check's own are collected as in
        # `llfsm check`).  Late in `make test`, on a quiet machine, the process's CPU time once
        # read 2.1 s for 20,000 transitions where the check alone takes 0.4 s.
        gc.collect()
        gc.freeze()
        try:
            start = time.thread_time()
            codes = Counter(d.code for d in check_machine(m).diagnostics)
            spent = time.thread_time() - start
        finally:
            gc.unfreeze()
        assert codes == {"LF023": count}
        return spent

    small = min(seconds(2_000) for _ in range(3))
    large = min(seconds(20_000) for _ in range(2))
    assert large / small < 40, f"2,000 transitions: {small:.3f} s, 20,000: {large:.3f} s (CPU)"


def test_a_true_guard_warns_about_the_later_transitions_once(tmp_path: Path) -> None:
    """Each of n constant-true guards used to warn about every later transition: n²/2 warnings."""
    n = 400
    m = write_machine(tmp_path, "m", {"A": [("A", "True")] * n})
    assert Counter(d.code for d in check_machine(m).diagnostics) == {"LF104": n - 1}


# -- bugs the fuzzing found in the compiler and the runtime (fixed) -----------------------------------


def test_status_macros_work_in_variable_initialisers(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "m", {"A": None}, variables="up: bool = is_running('m')\n")
    outcome = build_machine(m, tmp_path / "out")
    assert outcome.module is not None
    cls = load_class(outcome.module)
    assert Arrangement([cls], clock=SimClock()).machines[0].up is True  # type: ignore[attr-defined]


def test_starting_in_the_suspend_state_runs_its_on_entry_once(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "m",
        {"A": None, "P": [("A", "True")]},
        {"P_OnEntry": "entries += 1\n"},
        variables="entries: int = 0\n",
        yaml_extra="initial: P\nsuspended: P",
    )
    outcome = build_machine(m, tmp_path / "out")
    assert outcome.module is not None
    arr = Arrangement([load_class(outcome.module)], clock=SimClock())
    arr.run(duration_ns=10_000_000)
    assert arr.machines[0].entries == 1  # type: ignore[attr-defined]


def test_error_reports_name_the_real_file_in_a_folder_with_any_name(tmp_path: Path) -> None:
    m = write_machine(tmp_path / 'café "q"', "m", {"A": None}, {"A_OnEntry": "x = 1 / 0\n"})
    outcome = build_machine(m, tmp_path / "out")
    assert outcome.module is not None
    result = Arrangement([load_class(outcome.module)], clock=SimClock()).run(duration_ns=5_000_000)
    assert result.error is not None and result.error.file is not None
    assert Path(result.error.file).resolve() == (m / "State_A_OnEntry.py").resolve()


def test_a_value_error_in_an_initialiser_is_reported_against_its_line(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "m", {"A": None}, variables="x: int = int('nope')\n")
    r = llfsm("run", "--clock", "sim", m)
    assert r.status == 1 and "Variables.py:1" in r.stderr


def test_a_star_import_cannot_break_the_module(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    (tmp_path / "shadowing.py").write_text("Machine = None\nsuper = None\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    m = write_machine(tmp_path, "m", {"A": None}, includes="from shadowing import *\n", variables="x: int = 1\n")
    assert _codes(m) == []
    assert _run(m, tmp_path / "out") == "finished"


def _run_in_process(tmp_path: Path, machine: Path) -> object:
    outcome = build_machine(machine, tmp_path / "out")
    assert outcome.module is not None, format_text(outcome.diagnostics)
    return Arrangement([load_class(outcome.module)], clock=SimClock()).run(duration_ns=5_000_000)


def test_an_exception_that_cannot_be_printed_is_still_reported(tmp_path: Path) -> None:
    code = "class E(Exception):\n    def __str__(self):\n        raise ValueError('no')\n\n\nraise E()\n"
    m = write_machine(tmp_path, "m", {"A": None}, {"A_OnEntry": code})
    result = _run_in_process(tmp_path, m)
    assert result.error is not None and result.error.line == 6  # type: ignore[attr-defined]


def test_a_base_exception_from_machine_code_is_reported(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "m",
        {"A": None},
        {"A_OnEntry": "raise CancelledError()\n"},
        includes="from asyncio import CancelledError\n",
    )
    result = _run_in_process(tmp_path, m)
    assert result.error is not None and result.error.line == 1  # type: ignore[attr-defined]


# -- hostile paths (issue 12): every entry point and output format ------------------------------


def hostile_path_property(spec: MachineSpec, folder: str) -> None:
    """A valid machine under a hostile folder: check is clean and every format is valid, the
    module's header carries no code, the machine builds, runs and draws; a broken copy beside
    it gets diagnostics that every format renders validly for the same folder."""
    from llfsm.diagram.dot import dot
    from llfsm.diagram.mermaid import mermaid

    TRIED["hostile path"] += 1
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp) / folder
        try:
            root.mkdir()
        except OSError:
            event("folder refused by the file system")
            return
        machine = write_spec(spec, root)
        checked = check_machine(machine)
        assert checked.ok, format_text(checked.errors)
        broken = write_spec(spec, root, dirname=f"{spec.name}_broken.machine")
        (broken / "machine.yaml").write_text("states:\n  - name: A\n    transitions: [ENDD]\n  - name: B\n")
        diags = [d for r in check_paths([root]) for d in r.diagnostics]
        assert diags, "the broken copy has problems"
        for fmt in FORMATS:
            text = render(diags, fmt, "0")
            text.encode("utf-8")  # no lone surrogate in any format
            if fmt in ("text", "github"):
                assert len(text.splitlines()) == len(diags)
        sarif = json.loads(render(diags, "sarif", "0"))
        errors = list(sarif_validator().iter_errors(sarif))
        assert not errors, errors[0]
        for s in strings_in(json.loads(render(diags, "json", "0"))):
            s.encode("utf-8")
        out = Path(tmp) / "out"
        cls = build_and_import(machine, out)
        source = (out / f"{spec.name}.py").read_text(encoding="utf-8")
        header_ok(source)
        only_expected_statements(ast.parse(source))
        if cls is not None:
            event(f"ended: {runs([cls], [machine])}")
        assert checked.machine is not None
        for drawing in (mermaid(checked.machine), dot(checked.machine)):
            drawing.encode("utf-8")


@SMALL_HOSTILE
@given(machine_specs(), hostile_folder_names())
def test_hostile_paths_through_check_build_run_graph_and_every_format(spec: MachineSpec, folder: str) -> None:
    hostile_path_property(spec, folder)


@pytest.mark.slow
@LARGE
@given(machine_specs(), hostile_folder_names())
def test_hostile_paths_at_volume(spec: MachineSpec, folder: str) -> None:
    hostile_path_property(spec, folder)
