"""Security (issue 5): what a hostile machine directory, or an interrupted or racing build, can do.

- Nothing from machine files becomes code in the generated module except the user's own code:
  names are refused unless they are plain identifiers; descriptions, annotations and
  initialisers stay inside the string, docstring or statement they belong to.
- Paths stay put: a symlink out of the machine directory is refused (every file, and a
  machine directory found by searching), and a machine name cannot make `llfsm build` write
  outside its output folder.
- YAML is composed, never constructed: python tags are never executed; anchors are refused.
- Builds are atomic: racing builds and interrupted builds leave the old module or the new one,
  never half of one, and no temporary file.
"""

from __future__ import annotations

import ast
import os
import random
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from helpers import llfsm, llfsm_process, write_machine
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from strategies import _yaml_string

from llfsm.compiler.build import build_machine
from llfsm.lang.check import check_machine, check_paths
from llfsm.lang.reader import MAX_FILE_BYTES
from llfsm.runtime import Arrangement, RunResult, SimClock
from llfsm.runtime.machine import Machine
from llfsm.targets import load_class

OK = {"A": [("END", "after_ms(2)")], "END": None}


def payload(marker: Path) -> str:
    """Python that leaves a trace if it ever runs."""
    return f"__import__('pathlib').Path({str(marker)!r}).touch()"


def build_load_run(machine: Path, out: Path, rounds: int = 50) -> tuple[Machine, RunResult]:
    outcome = build_machine(machine, out)
    assert outcome.status == "compiled", [d.message for d in outcome.diagnostics]
    assert outcome.module is not None
    cls = load_class(outcome.module)
    arr = Arrangement([cls], clock=SimClock())
    result = arr.run(duration_ns=rounds * 1_000_000)
    return arr.machines[0], result


def refused(machine: Path, *codes: str) -> list[str]:
    """The error codes `check` gives; a refused machine also builds to nothing."""
    found = [d.code for d in check_machine(machine).errors]
    assert found, "expected the machine to be refused"
    assert set(codes) <= set(found), found
    out = machine.parent / "out-refused"
    assert build_machine(machine, out).status == "failed"
    assert not out.exists() or not any(out.iterdir())
    return found


# -- names ---------------------------------------------------------------------------------------

HOSTILE_NAMES = [
    'A"""\nimport os\n"""',
    "A'); __import__('os').system('echo x'); ('",
    "A\nB",
    "A # comment",
    "A):\n        pass\n    def evil(self",
    "A\\",
    "ﬁle",  # NFKC-normalises to `file`: a Python identifier, not an llfsm name
    "Ａ",  # full-width: a Python identifier, not ASCII
    "A\u200b",
    "A.B",
    "A-B",
    "1A",
    "class",
    "None",
    "",
    "x" * 10_000,
]
#: Not a hostile name but one no file can carry (a file name is at most 255 bytes): refused because
#: its transition's guard file cannot exist.
TOO_LONG = HOSTILE_NAMES[-1]


@pytest.mark.parametrize("name", HOSTILE_NAMES)
def test_hostile_state_names_are_refused(tmp_path: Path, name: str) -> None:
    m = write_machine(tmp_path, "m", OK)
    (m / "machine.yaml").write_text(
        f"states:\n  - name: {_yaml_string(name)}\n    transitions: [A]\n  - name: A\n", encoding="utf-8"
    )
    refused(m, "LF023" if name == TOO_LONG else "LF011")  # missing-guard; invalid-state-name


@pytest.mark.parametrize("name", HOSTILE_NAMES)
@pytest.mark.parametrize("key", ["initial", "suspended", "target"])
def test_hostile_names_in_initial_suspended_and_targets_are_refused(tmp_path: Path, name: str, key: str) -> None:
    if key == "initial" and not name:
        pytest.skip("an empty `initial:` means the default, as documented")
    m = write_machine(tmp_path, "m", OK)
    text = (m / "machine.yaml").read_text()
    if key == "target":
        text = text.replace("transitions: [END]", f"transitions: [{_yaml_string(name)}]")
    else:
        text = f"{key}: {_yaml_string(name)}\n{text}"
    (m / "machine.yaml").write_text(text, encoding="utf-8")
    refused(m, {"initial": "LF021", "suspended": "LF022", "target": "LF020"}[key])  # unknown-initial|suspended|target


@pytest.mark.parametrize("dirname", ['m"""x', "m'x", "m x", "m\nx", "m\\x", "m;x", "ｍ", "class"])
def test_hostile_machine_directory_names_are_refused(tmp_path: Path, dirname: str) -> None:
    m = write_machine(tmp_path, dirname, OK)
    refused(m, "LF010")


@pytest.mark.parametrize(
    "name",
    ["__class__", "__dict__", "__slots__", "__init__", "__x", "self", "_llfsm_state", "NAME", "ENTER", "_arr"],
)
def test_hostile_variable_names_are_refused(tmp_path: Path, name: str) -> None:
    m = write_machine(tmp_path, "m", OK, variables=f"{name}: int = 0\n")
    refused(m, "LF013")
    s = write_machine(tmp_path / "s", "m", OK, {"A_Variables": f"{name}: int = 0\n"})
    refused(s, "LF013")


DESCRIPTIONS = st.one_of(
    st.text(),
    st.sampled_from(['"""', "'''", '\\"""', "\\", '"', 'x"""\nimport os\n"""', "\x00\x1b[2J", "\u2028\u2029\x85"]),
    st.lists(st.sampled_from(['"', "'", "\\", "\n", "\r", "#", "{{", "}}", "{%", "%}", "x", "\t", "\x00"])).map(
        "".join
    ),
)


@settings(max_examples=40, deadline=None, derandomize=True, database=None, suppress_health_check=list(HealthCheck))
@given(DESCRIPTIONS)
def test_descriptions_never_escape_their_docstrings(description: str) -> None:
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        marker = root / "ran"
        m = write_machine(
            root, "m", {"A": None}, yaml_extra=f"description: {_yaml_string(description + payload(marker))}"
        )
        out = root / "out"
        machine, result = build_load_run(m, out)
        assert result.reason == "finished" and not marker.exists()
        tree = ast.parse((out / "m.py").read_text(encoding="utf-8"))
        # the module holds its docstring, one import, the ringlets, one class and its source map:
        # nothing else got in
        kinds = [type(n).__name__ for n in tree.body]
        assert kinds == ["Expr", "ImportFrom", *["FunctionDef"] * 4, "ClassDef", "Assign"]
        ringlets = [n.name for n in tree.body if isinstance(n, ast.FunctionDef)]
        assert ringlets == ["_llfsm_enter_A", "_llfsm_steady_A", "_llfsm_enter_SUSPENDED", "_llfsm_steady_SUSPENDED"]
        assert [t.id for t in tree.body[-1].targets] == ["_LLFSM_SOURCE_MAP"]  # type: ignore[attr-defined]
        cls = tree.body[-2]
        assert isinstance(cls, ast.ClassDef)
        want = " ".join((description + payload(marker)).split())
        assert ast.get_docstring(cls, clean=False) == want
        assert ast.get_docstring(tree, clean=False) == f"m: {want}"
        assert type(machine).__doc__ == want
        members = {t.id for n in cls.body if isinstance(n, ast.Assign) for t in n.targets if isinstance(t, ast.Name)}
        members |= {n.name for n in cls.body if isinstance(n, ast.FunctionDef)}
        assert members == {
            *("NAME", "STATES", "INITIAL", "SUSPENDED", "ACCEPTING", "SOURCE_DIR", "__slots__"),
            *("DESCRIPTION", "TRANSITIONS"),  # what /llfsm/M/description publishes (a literal, like NAME)
            *("ENTER", "STEADY", "ON_SUSPEND", "ON_RESUME"),
        }
        assert " ".join(type(machine).DESCRIPTION.split()) == want


#: Variables.py files, each with the code `check` refuses it with (None: it is accepted).
VARIABLE_FILES: list[tuple[str, str | None]] = [
    ('x: int = 1  # """ ) ; import os\n', None),
    ('x: "str\\"\\"\\"" = \'"""\'\n', None),
    ('x: str = """\nclass Evil:\n    pass\n"""\n', None),
    ("x: str = '''\n    def ringlet_A(self):\n        PAYLOAD'''\n", None),
    ("x: int = (1 +\n2)\n", None),
    ("x: int = 1 \\\n    + 2\n", None),
    ("x: dict[\n    str, int\n] = {}\n", None),
    ('x: str = "\\\n"\n', None),
    ("x: (lambda: PAYLOAD) = 1\n", None),
    ("x: PAYLOAD = 2\n", None),
    ("x: int = 1 if True else \\\n  2\n", None),
    ('x: str = f"""{1}\n"""\n', None),
    ("x: object = lambda: PAYLOAD\n", None),
    ("x: int = 1; PAYLOAD\n", "LF032"),
    ("x: int = (\n\f1)\n", "LF030"),
    ("x: int = 1\rPAYLOAD\n", "LF032"),
    ("x: int = 1\u2028PAYLOAD\n", "LF030"),
    ("x: int = 1\n\fPAYLOAD\n", "LF030"),
    ("x: int\nPAYLOAD\n", "LF032"),
    ("x: int = (yield)\n", "LF036"),
    ("x: int = (self := 1)\n", "LF013"),
]


@pytest.mark.parametrize(("text", "refused_with"), VARIABLE_FILES)
def test_annotations_and_initialisers_cannot_break_out(tmp_path: Path, text: str, refused_with: str | None) -> None:
    """Either `check` refuses the file (with the rule that says why), or loading the machine sets
    exactly the values Python gives the initialisers, and nothing else runs (annotations are
    never evaluated)."""
    marker = tmp_path / "ran"
    text = text.replace("PAYLOAD", payload(marker))
    m = write_machine(tmp_path, "m", {"A": None}, variables=text)
    if refused_with is not None:
        refused(m, refused_with)
        assert not marker.exists()
        return
    assert check_machine(m).ok
    machine, result = build_load_run(m, tmp_path / "out")
    assert result.reason == "finished"
    assert not marker.exists()
    tree = ast.parse(text.replace("\r", "\n"))
    want = {}
    for stmt in tree.body:
        assert isinstance(stmt, ast.AnnAssign) and isinstance(stmt.target, ast.Name)
        value = None
        if stmt.value is not None:
            value = eval(compile(ast.Expression(stmt.value), "<test>", "eval"), {}, dict(want))
        want[stmt.target.id] = value
    for name, value in want.items():
        got = getattr(machine, name)
        assert got == value or (callable(got) and callable(value)), (name, got, value)
    assert set(machine.__slots__) == set(want)


@pytest.mark.parametrize(
    "guard",
    [
        "x > 2  # ):\n",
        "(x  # \\\n > 2)\n",
        "x > 2 \\\n  and x < 5\n",
        "'):\\n    import os' != ''\n",
        "x if x else (\n  0)\n",
        "[x for x in range(0)]\n",
        "(y := x) > 2\n",
        "lambda: 0\n",
        "not x  # '''\n",
        "x > 2 # comment \\",
        '"""\n):\n""" == "\\n):\\n"\n',  # a string spanning the guard's lines keeps its value
    ],
)
def test_guards_mean_what_python_says(tmp_path: Path, guard: str) -> None:
    """A guard is wrapped into `if (...):` in the module; it must keep the truth value Python
    gives the expression.  Every guard here is one `check` accepts: the wrapping, not `check`,
    is what is tried."""
    m = write_machine(tmp_path, "m", {"A": [("YES", guard), ("NO", "True")], "YES": None, "NO": None})
    (m / "Variables.py").write_text("x: int = 3\n")
    (m / "State_A_Transition_0.expr").write_text(guard)
    assert check_machine(m).ok, [d.message for d in check_machine(m).errors]
    machine, result = build_load_run(m, tmp_path / "out")
    expected = "YES" if eval(guard.strip(), {"x": 3}) else "NO"
    assert result.reason == "finished" and machine.STATES[machine._state] == expected


def test_a_comment_cannot_forge_the_file_of_an_error_report(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "m", {"A": None}, {"A_OnEntry": "# State_B_OnExit.py:50\nx = 1 / 0\n"})
    _machine, result = build_load_run(m, tmp_path / "out")
    assert result.error is not None
    assert (Path(result.error.file or "").name, result.error.line) == ("State_A_OnEntry.py", 2)


def test_check_output_cannot_be_forged_by_file_names(tmp_path: Path) -> None:
    """File names come from the pull request: no escape sequence, line break or undecodable
    byte of theirs reaches the terminal or the CI log raw."""
    m = write_machine(tmp_path, "m", OK)
    for name in ("State_\x1b[2J_OnEntry.py", "State_X\x07_OnExit.py"):
        (m / name).write_text("x = 1\n")
    os.close(os.open(os.fsencode(m) + b"/State_\xff_OnEntry.py", os.O_CREAT | os.O_WRONLY))
    for fmt in ("text", "github"):
        r = llfsm("check", "--format", fmt, m)
        assert r.status == 0
        assert len(r.stdout.splitlines()) == 3
        assert "\\x1b[2J" in r.stdout and "\\x07" in r.stdout and "\\udcff" in r.stdout
        assert not any(ch in r.stdout for ch in "\x1b\x07\udcff")


# -- paths ---------------------------------------------------------------------------------------

FILES = ["machine.yaml", "Includes.py", "Variables.py", "State_A_Variables.py", "State_A_OnEntry.py"]
FILES += ["State_A_OnResume.py", "State_A_Transition_0.expr"]


@pytest.mark.parametrize("fname", FILES)
@pytest.mark.parametrize("how", ["direct", "chain", "absolute", "directory", "parent"])
def test_symlinks_out_of_the_machine_directory_are_refused(tmp_path: Path, fname: str, how: str) -> None:
    outside = tmp_path / "outside"
    outside.mkdir()
    secret = outside / "secret.py"
    secret.write_text("x = (\n")  # if it were read, it would be a syntax error (LF030)
    m = write_machine(tmp_path, "m", OK)
    link = m / fname
    link.unlink(missing_ok=True)
    if how == "direct":
        link.symlink_to(os.path.relpath(secret, m))
    elif how == "chain":  # a link inside, to a link inside, to a file outside
        (m / "hop2").symlink_to(secret)
        (m / "hop1").symlink_to("hop2")
        link.symlink_to("hop1")
    elif how == "absolute":
        link.symlink_to("/etc/passwd")
    elif how == "directory":
        link.symlink_to(outside)
    else:
        link.symlink_to("..")
    diags = check_machine(m).diagnostics
    assert ("LF037", fname) in {(d.code, Path(d.file).name) for d in diags}, diags
    assert not any(d.code == "LF030" for d in diags)
    refused(m, "LF037")


def test_symlink_loops_are_reported_not_raised(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "m", OK)
    (m / "State_A_OnEntry.py").symlink_to("State_A_OnEntry.py")
    (m / "State_A_Transition_0.expr").unlink()
    (m / "State_A_Transition_0.expr").symlink_to("loop_b")
    (m / "loop_b").symlink_to("State_A_Transition_0.expr")
    assert {(d.code, Path(d.file).name) for d in check_machine(m).diagnostics} == {
        ("LF002", "State_A_OnEntry.py"),
        ("LF002", "State_A_Transition_0.expr"),
    }
    loop = tmp_path / "loop.machine"
    loop.symlink_to("loop.machine")
    assert [d.code for d in check_machine(loop).diagnostics] == ["LF001"]


def test_a_machine_directory_linked_from_outside_the_searched_folder_is_refused(tmp_path: Path) -> None:
    secret = write_machine(tmp_path / "secret", "stolen", OK)
    repo = tmp_path / "repo"
    write_machine(repo, "fine", OK)
    (repo / "evil.machine").symlink_to(secret)
    (repo / "alias.machine").symlink_to("fine.machine")  # a link inside the folder is fine
    r = llfsm("check", repo)
    assert r.status == 1
    assert r.stdout == (
        f"{repo}/evil.machine:1:1: LF037 error: evil.machine is a symlink leading out of {repo}; refused\n"
    )


@pytest.mark.parametrize("dirname", ["..machine", "...machine", ".machine", "a..b.machine", "..%2F..machine"])
def test_a_machine_name_cannot_make_build_write_outside_its_output_folder(tmp_path: Path, dirname: str) -> None:
    src = tmp_path / "src"
    m = src / dirname
    m.mkdir(parents=True)
    (m / "machine.yaml").write_text("states:\n  - name: A\n")
    out = tmp_path / "deep" / "out"
    before = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*"))
    outcome = build_machine(m, out)
    assert outcome.status == "failed" and "LF010" in {d.code for d in outcome.diagnostics}
    assert sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*")) == before
    assert llfsm("build", src, "-o", out).status in (1, 2)  # searching skips hidden folders
    assert llfsm("build", m, "-o", out).status == 1
    assert sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*")) == before


# -- yaml ----------------------------------------------------------------------------------------

PYTHON_TAGS = [
    "states: !!python/object/apply:os.system ['PAYLOAD']\n",
    "description: !!python/object/apply:os.system ['PAYLOAD']\nstates:\n  - name: A\n",
    "states:\n  - !!python/object/new:os.system ['PAYLOAD']\n",
    "states:\n  - name: A\n    transitions: !!python/object/apply:os.system ['PAYLOAD']\n",
    "initial: !!python/object/apply:os.system ['PAYLOAD']\nstates:\n  - name: A\n",
    "states:\n  - name: !!python/name:os.system A\n",
    "states:\n  - name: !!python/module:os A\n",
    "states:\n  - name: !evil A\n",
    "!!python/object:__main__.X {states: [{name: A}]}\n",
]


@pytest.mark.parametrize("doc", PYTHON_TAGS)
def test_yaml_python_tags_are_never_executed(tmp_path: Path, doc: str) -> None:
    marker = tmp_path / "ran"
    shell = f"touch {marker}"
    m = write_machine(tmp_path, "m", {"A": None})
    (m / "machine.yaml").write_text(doc.replace("PAYLOAD", shell))
    checked = check_machine(m)
    if checked.ok:  # a tag on a plain scalar: the scalar is read as written, the tag ignored
        machine, result = build_load_run(m, tmp_path / "out")
        assert machine.STATES == ("A", "SUSPENDED") and result.reason == "finished"
        assert "os.system" not in (tmp_path / "out" / "m.py").read_text()
    else:
        # a tagged list of targets is read as a list of targets
        assert {d.code for d in checked.errors} <= {"LF004", "LF020", "LF023"}
    r = llfsm("run", "--clock", "sim", m)
    assert r.status in (0, 2)
    assert not marker.exists()


@pytest.mark.parametrize(
    "doc",
    [
        "states:\n  - &s {name: A}\n",
        "states:\n  - name: &n A\n  - name: B\n    transitions: [*n]\n",
        "base: &b {transitions: []}\nstates:\n  - <<: *b\n    name: A\n",
        "states: &all\n  - name: A\n",
    ],
)
def test_yaml_anchors_are_refused_wherever_they_are(tmp_path: Path, doc: str) -> None:
    m = write_machine(tmp_path, "m", {"A": None})
    (m / "machine.yaml").write_text(doc)
    assert [d.code for d in check_machine(m).diagnostics] == ["LF005"]


def test_the_size_limit_is_exactly_one_mebibyte(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "m", {"A": None})
    head = b"states:\n  - name: A\n"
    (m / "machine.yaml").write_bytes(head + b"#" * (MAX_FILE_BYTES - len(head) - 1) + b"\n")
    assert check_machine(m).diagnostics == []
    (m / "machine.yaml").write_bytes(head + b"#" * (MAX_FILE_BYTES - len(head)) + b"\n")
    assert [d.code for d in check_machine(m).diagnostics] == ["LF002"]


def test_a_fifo_where_a_file_belongs_is_refused_at_once(tmp_path: Path) -> None:
    """Opening a FIFO for reading blocks until a writer comes: `check` must never wait."""
    m = write_machine(tmp_path, "m", OK)
    (m / "machine.yaml").rename(m / "real.yaml")
    os.mkfifo(m / "machine.yaml")
    os.mkfifo(m / "State_A_OnEntry.py")
    code = (
        "from llfsm.lang.check import check_machine\n"
        f"print(sorted(d.code for d in check_machine({str(m)!r}).diagnostics))"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=20)
    assert proc.stdout.strip() == "['LF002']", proc.stderr
    (m / "machine.yaml").unlink()
    (m / "real.yaml").rename(m / "machine.yaml")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=20)
    assert proc.stdout.strip() == "['LF002']", proc.stderr


# -- atomic builds -------------------------------------------------------------------------------


def _many_machines(root: Path, count: int) -> list[Path]:
    """Machines with enough code that writing each takes a moment."""
    body = "".join(f"n = (n + {i}) % 97\n" for i in range(100))
    return [
        write_machine(
            root, f"m{i:02d}", {"A": [("B", "n > 3")], "B": [("A", "after_ms(5)")]}, {"A_OnEntry": body}, "n: int = 0\n"
        )
        for i in range(count)
    ]


def _stray(out: Path) -> list[str]:
    return sorted(p.name for p in out.iterdir() if not (p.suffix == ".py" and not p.name.startswith(".")))


RACER = textwrap.dedent(
    """
    import sys
    from pathlib import Path
    from llfsm.compiler.build import build_machine
    for _ in range(int(sys.argv[3])):
        assert build_machine(Path(sys.argv[1]), Path(sys.argv[2]), force=True).status == "compiled"
    """
)


def test_racing_builds_never_leave_a_half_written_module(tmp_path: Path) -> None:
    """Two builds of the same machine at once (two processes, many times over) while a third
    reads: every read sees a whole module, and the result always imports."""
    (m,) = _many_machines(tmp_path / "src", 1)
    out = tmp_path / "out"
    reference = tmp_path / "ref"
    build_machine(m, reference)
    whole = (reference / "m00.py").read_bytes()
    for rounds in range(3):
        racers = [subprocess.Popen([sys.executable, "-c", RACER, m, out, "15"]) for _ in range(2)]
        racers.append(subprocess.Popen([sys.executable, "-m", "llfsm", "build", "-q", "--force", m, "-o", out]))
        reads = 0
        while any(p.poll() is None for p in racers):
            try:
                data = (out / "m00.py").read_bytes()
            except FileNotFoundError:
                assert rounds == 0  # only before the very first build lands
                continue
            assert data == whole
            reads += 1
        assert all(p.returncode == 0 for p in racers)
        assert reads > 0 and _stray(out) == []
        cls = load_class(out / "m00.py")
        assert Arrangement([cls], clock=SimClock()).run(duration_ns=20_000_000).error is None
        sys.modules.pop(cls.__module__, None)


def _build_process(src: Path, out: Path) -> subprocess.Popen[str]:
    cmd = [sys.executable, "-m", "llfsm", "build", "-q", "--force", str(src), "-o", str(out)]
    return subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True)


def _interrupt_builds(tmp_path: Path, times: int, signum: int) -> tuple[int, int]:
    """Interrupt `llfsm build` of 40 machines at random moments; returns (builds cut short,
    builds cut short after writing some modules but not all)."""
    _many_machines(tmp_path / "src", 40)
    reference = tmp_path / "ref"
    start = time.monotonic()
    _, err = _build_process(tmp_path / "src", reference).communicate(timeout=120)
    whole = time.monotonic() - start  # interrupts land anywhere from start-up to the last write
    assert len(list(reference.iterdir())) == 40, err
    start = time.monotonic()
    subprocess.run([sys.executable, "-c", "pass"], check=True)
    # before its site module is imported, Python itself prints a traceback at a Ctrl-C
    interpreter = 2 * (time.monotonic() - start)
    rng = random.Random(signum)
    cut = midway = 0
    for i in range(times):
        out = tmp_path / f"out{i}"
        proc = _build_process(tmp_path / "src", out)
        # the first interrupt lands early even if the reference build ran on a busier machine
        time.sleep(max(interpreter, rng.uniform(0.1, 0.3 if i == 0 else 0.95) * whole))
        proc.send_signal(signum)
        _, err = proc.communicate(timeout=60)
        assert "Traceback" not in err and "internal error" not in err, err
        written = sorted(out.iterdir()) if out.exists() else []
        assert [p.name for p in written if p.suffix != ".py" or p.name.startswith(".")] == []  # no temp file
        for module in written:
            assert module.read_bytes() == (reference / module.name).read_bytes(), module
        if proc.returncode == 0:
            assert len(written) == 40
        else:
            assert proc.returncode in (130, -signum), err
            cut += 1
            midway += 0 < len(written) < 40
    return cut, midway


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_an_interrupted_build_of_many_machines_leaves_whole_modules_only(tmp_path: Path, signum: int) -> None:
    cut, _midway = _interrupt_builds(tmp_path, 4, signum)
    assert cut > 0  # the build was cut short at least once


FINALIZER = textwrap.dedent(
    """
    import time
    from llfsm.compiler.build import terminated_as_exception

    class Slow:
        def __del__(self):
            print("in finalizer", flush=True)
            time.sleep(1.0)  # the SIGTERM lands here, where an exception can only be printed

    with terminated_as_exception():
        Slow()
        for _ in range(300):
            time.sleep(0.01)
        print("went on building", flush=True)
    """
)


def test_sigterm_landing_in_a_finalizer_still_stops_the_build_without_a_traceback(tmp_path: Path) -> None:
    """A signal handler that raises runs wherever the main thread is, a __del__ included; there
    Python prints "Exception ignored in ..." with a traceback and carries on.  The build must
    still stop, silently, as at any other moment (seen once in the interrupted-build test)."""
    proc = subprocess.Popen(
        [sys.executable, "-c", FINALIZER], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path
    )
    assert proc.stdout is not None and proc.stdout.readline() == "in finalizer\n"
    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=60)
    assert "went on building" not in out
    assert proc.returncode == -signal.SIGTERM
    assert "Traceback" not in err and "Exception ignored" not in err, err


WRITER = textwrap.dedent(
    """
    import sys
    from pathlib import Path
    from llfsm.compiler.build import write_atomic_bytes
    data = b"x" * (32 << 20)
    print("ready", flush=True)
    for _ in range(1000):
        write_atomic_bytes(Path(sys.argv[1]), data)
    """
)


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_signal_in_the_middle_of_a_write_leaves_no_temporary_file(tmp_path: Path, signum: int) -> None:
    """Large writes, so that the signal lands inside one.  SIGTERM's default action kills the
    process on the spot: without the signal held back, its temporary file stayed behind."""
    for attempt in range(5):
        out = tmp_path / f"out{attempt}"
        out.mkdir()
        proc = subprocess.Popen([sys.executable, "-c", WRITER, out / "m.py"], stdout=subprocess.PIPE, cwd=tmp_path)
        assert proc.stdout is not None and proc.stdout.readline() == b"ready\n"
        time.sleep(0.15 + 0.07 * attempt)
        proc.send_signal(signum)
        proc.wait(timeout=60)
        assert proc.returncode in (1, -signum), proc.returncode  # 1: the KeyboardInterrupt traceback
        assert [p.name for p in out.iterdir()] in ([], ["m.py"])
        assert not (out / "m.py").exists() or (out / "m.py").stat().st_size == 32 << 20


@pytest.mark.slow
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_interrupted_builds_at_volume(tmp_path: Path, signum: int) -> None:
    cut, midway = _interrupt_builds(tmp_path, 60, signum)
    assert midway > 10, (cut, midway)  # many interrupts landed while modules were being written


def test_a_deep_folder_tree_cannot_crash_the_search_for_machines(tmp_path: Path) -> None:
    write_machine(tmp_path, "ok", OK)
    deepest = tmp_path
    for _ in range(1100):  # 2,200 characters of path: well within PATH_MAX
        deepest = deepest / "a"
        deepest.mkdir()
    try:
        assert [c.path.name for c in check_paths([tmp_path])] == ["ok.machine"]
    finally:  # shutil.rmtree recurses too: take the tree down from the bottom
        while deepest != tmp_path:
            deepest.rmdir()
            deepest = deepest.parent


def test_running_a_symlink_loop_is_a_usage_error(tmp_path: Path) -> None:
    (tmp_path / "x.machine").symlink_to("x.machine")
    assert llfsm("run", "--clock", "sim", tmp_path / "x.machine").status == 2


def test_an_unwritable_output_is_a_clear_failure(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "m", OK)
    (tmp_path / "out" / "m.py").mkdir(parents=True)
    r = llfsm_process("build", m, "-o", tmp_path / "out")
    assert r.status == 1 and "internal error" not in r.stderr and "m.py" in r.stderr
    assert [p.name for p in (tmp_path / "out").iterdir()] == ["m.py"]  # and no temporary file


CTRL_C_WHILE_IMPORTING = textwrap.dedent(
    """
    import sys

    class CtrlC:  # the Ctrl-C lands while click is being imported
        def find_spec(self, name, path=None, target=None):
            if name == "click":
                raise KeyboardInterrupt
            return None

    sys.meta_path.insert(0, CtrlC())
    sys.argv = ["llfsm", "check", "."]
    from llfsm.__main__ import main
    main()
    """
)


def test_a_ctrl_c_while_the_command_is_still_importing_ends_quietly() -> None:
    """The first tenth of a second of every command imports click, pydantic and jinja2: a
    Ctrl-C there printed a KeyboardInterrupt traceback."""
    proc = subprocess.run([sys.executable, "-c", CTRL_C_WHILE_IMPORTING], capture_output=True, text=True, timeout=60)
    assert (proc.returncode, proc.stdout, proc.stderr) == (130, "", "")
