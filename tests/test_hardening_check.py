"""Hardening of the front end (issue 12): reader, check, compiler and output formats.

Each test class stands for a class of defect, with several members of it, so that a fix of
one example cannot pass for a fix of the class.
"""

from __future__ import annotations

import ast
import gc
import io
import json
import os
import re
import signal
import subprocess
import sys
import time
import tokenize
import urllib.parse
from collections.abc import Callable
from pathlib import Path

import pytest
from helpers import header_ok, llfsm, only_expected_statements, run_sim, sarif_validator, strings_in, write_machine

from llfsm.compiler.build import build_machine
from llfsm.lang.check import check_machine

#: Folder names that try to change what a generated file means: a line break that would
#: start code, encoding declarations (PEP 263 reads lines 1-2), quotes, backslashes, bytes
#: that are not UTF-8, control characters, Unicode line separators.
HOSTILE_FOLDERS = [
    "a\nraise SystemExit(7)\n#",
    "x\rprint(1)",
    "coding=utf_7",
    "# -*- coding: latin-1 -*-",
    "vim: set fileencoding=utf_7 :",
    'q\'"""quote',
    "back\\slash\\",
    os.fsdecode(b"caf\xe9\xff"),
    "tab\there\x1b[31m",
    "line\u2028sep\x85next",
    "#%?:& space",
]


def _hostile_dir(root: Path, name: str) -> Path:
    d = root / name
    try:
        d.mkdir(parents=True)
    except (OSError, UnicodeEncodeError) as e:  # pragma: no cover - a file system refusing the name
        pytest.skip(f"the file system refuses {name!r}: {e}")
    return d


class TestHeadersCarryNoCode:
    """Item 3 of issue 12: nothing from a user's path reaches lines 1-2, every header escapes."""

    @pytest.mark.parametrize("folder", HOSTILE_FOLDERS)
    def test_machine_module(self, tmp_path: Path, folder: str) -> None:
        root = _hostile_dir(tmp_path, folder)
        m = write_machine(root, "m", {"A": [("END", "True")], "END": None})
        out = build_machine(m, tmp_path / "out")
        assert out.status == "compiled", out.diagnostics
        source = out.module.read_text(encoding="utf-8")
        header_ok(source)
        only_expected_statements(ast.parse(source))
        # the path is still there, escaped, and the run-time can read it back
        from llfsm.runtime.generated import source_dir_of

        mod = out.module
        assert source_dir_of(str(mod)) == os.path.abspath(m)

    @pytest.mark.parametrize("folder", HOSTILE_FOLDERS)
    def test_interface_module(self, tmp_path: Path, folder: str) -> None:
        from llfsm.idl.package import build_package

        pkg = _hostile_dir(tmp_path, folder) / "my_pkg"
        (pkg / "msg").mkdir(parents=True)
        (pkg / "msg" / "Thing.msg").write_text("int32 value\n")
        out = tmp_path / "out"
        build_package(pkg, out, "f" * 16)
        for rel in ("__init__.py", "msg/__init__.py"):
            source = (out / rel).read_text(encoding="utf-8")
            header_ok(source)
            tree = ast.parse(source)
            assert not any(isinstance(s, ast.Raise) for s in ast.walk(tree))
            assert not any(isinstance(s, ast.Call) and getattr(s.func, "id", "") == "print" for s in ast.walk(tree))

    def test_names_with_a_trailing_newline_are_refused(self, tmp_path: Path) -> None:
        """`$` matches before a final newline: every name rule must end at the end (\\Z)."""
        from llfsm.idl.spec import FIELD_NAME, PACKAGE_NAME, TYPE_NAME
        from llfsm.lang.model import is_valid_name
        from llfsm.scaffold import ScaffoldError, check_package_name

        assert not is_valid_name("count\n")
        for rx, good in ((PACKAGE_NAME, "my_pkg"), (TYPE_NAME, "Thing"), (FIELD_NAME, "value")):
            assert rx.match(good) and not rx.match(good + "\n")
        with pytest.raises(ScaffoldError):
            check_package_name("my_pkg\n")
        d = tmp_path / "x"
        d.mkdir()
        (d / "machine.yaml").write_text('states:\n  - name: "A\\n"\n    transitions: ["B\\n"]\n  - name: B\n')
        codes = {x.code for x in check_machine(d).diagnostics}
        assert "LF011" in codes


def _ratio(make: Callable[[int], Callable[[], object]], n: int, factor: int = 4) -> float:
    """time(factor * n) / time(n), each the best of three, interleaved: a linear cost gives
    about `factor`, a quadratic one `factor` squared.  Never an absolute time."""
    small, big = make(n), make(factor * n)
    ts: list[float] = []
    tb: list[float] = []
    small()  # warm: imports and caches are not what is measured
    for _ in range(3):
        for f, out in ((small, ts), (big, tb)):
            gc.collect()
            gc.disable()  # the cyclic collector's passes grow with the heap: not the code's cost
            try:
                t0 = time.perf_counter()
                f()
                out.append(time.perf_counter() - t0)
            finally:
                gc.enable()
    return min(tb) / max(min(ts), 1e-6)


class TestLinearWork:
    """Item 4 of issue 12: every per-diagnostic, per-node, per-file cost is linear overall."""

    def _many_problems(self, tmp_path: Path, n: int) -> Path:
        # one undefined name per line (a diagnostic each), on lines with non-ASCII text
        code = "".join(f"é = 1; print(undefined_{i}); x_{i} = 1\n" for i in range(n))
        return write_machine(tmp_path / str(n), "m", {"A": [("END", "True")], "END": None}, {"A_OnEntry": code})

    def test_the_file_is_split_once_however_many_diagnostics(self, tmp_path: Path, monkeypatch) -> None:
        import llfsm.lang.positions as rw

        calls = []
        real = rw.source_lines
        monkeypatch.setattr(rw, "source_lines", lambda text: calls.append(len(text)) or real(text))
        rw.line_index.cache_clear()
        m = self._many_problems(tmp_path, 500)
        diags = check_machine(m).diagnostics
        assert len([d for d in diags if "undefined_" in d.message]) == 500
        assert len(calls) <= 3, len(calls)  # the section, and perhaps the guard: not once per diagnostic

    def test_check_time_grows_linearly_with_the_diagnostics(self, tmp_path: Path) -> None:
        def make(n: int) -> Callable[[], object]:
            m = self._many_problems(tmp_path, n)
            return lambda: check_machine(m)

        assert _ratio(make, 1000) < 10

    def test_check_time_grows_linearly_with_states_and_variables(self, tmp_path: Path) -> None:
        """States x machine variables, check and build: a name map per state used to copy every
        variable, and each variable's text was cut out of a fresh split of the whole file."""

        def make(n: int) -> Callable[[], object]:
            states: dict[str, list[tuple[str, str]] | None] = {f"S{i}": [(f"S{i + 1}", "True")] for i in range(n)}
            states[f"S{n}"] = None
            variables = "".join(f"v{i}: int = {i}\n" for i in range(n))
            m = write_machine(tmp_path / f"sv{n}", "m", states, variables=variables)
            return lambda: build_machine(m, tmp_path / f"out{n}", force=True)

        assert _ratio(make, 300) < 10

    @pytest.mark.parametrize("where", ["guard", "section"])
    def test_a_huge_f_string_is_refused_before_parsing(self, tmp_path: Path, where: str) -> None:
        def make(n: int) -> Callable[[], object]:
            fstring = 'f"' + "{x}" * n + '"'
            guard, code = (f"{fstring} != ''", {}) if where == "guard" else ("True", {"A_OnEntry": f"s = {fstring}\n"})
            m = write_machine(tmp_path / f"f{n}", "m", {"A": [("END", guard)], "END": None}, code)

            def run() -> None:
                diags = check_machine(m).diagnostics
                assert [d.code for d in diags if d.code == "LF039"] == ["LF039"], diags

            return run

        assert _ratio(make, 20_000) < 10

    @pytest.mark.parametrize("bracket", ["()", "[]", "{}"])
    def test_deeply_nested_brackets_stay_linear_and_too_deep_is_refused(self, tmp_path: Path, bracket: str) -> None:
        """CPython refuses more than 200 nested brackets at once; below that, parsing (even
        with a syntax error at the end, which makes it parse twice) is linear in the file."""
        o, c = bracket

        def make(n: int) -> Callable[[], object]:
            line = f"x = {o * 190}1{c * 190}\n" if o != "{" else f"x = {'{1:' * 95}1{'}' * 95}\n"
            m = write_machine(
                tmp_path / f"b{n}", "m", {"A": [("END", "True")], "END": None}, {"A_OnEntry": line * n + "x +\n"}
            )
            return lambda: check_machine(m)

        assert _ratio(make, 30) < 10
        deep = write_machine(
            tmp_path / "deep", "m", {"A": [("END", o * 300 + "1" + c * 300)], "END": None}, {"A_OnEntry": "x = 1\n"}
        )
        assert [d.code for d in check_machine(deep).diagnostics] == ["LF030"]

    def test_a_small_f_string_is_fine(self, tmp_path: Path) -> None:
        m = write_machine(tmp_path, "m", {"A": [("END", 'f"{1}{2}{3}" != ""')], "END": None})
        assert check_machine(m).ok

    def test_jobs_are_bounded_by_the_usable_cores(self, tmp_path: Path, monkeypatch) -> None:
        import concurrent.futures

        from llfsm.lang.check import diagnose, usable_cores

        seen: list[int] = []
        real = concurrent.futures.ProcessPoolExecutor

        def recording(max_workers: int, **kw: object) -> object:
            seen.append(max_workers)
            return real(max_workers=max_workers, **kw)

        monkeypatch.setattr(concurrent.futures, "ProcessPoolExecutor", recording)
        for i in range(4):
            write_machine(tmp_path, f"m{i}", {"A": [("END", "True")], "END": None})
        count, diags = diagnose([tmp_path], jobs=10_000)
        assert count == 4 and diags == []
        assert all(w <= usable_cores() for w in seen), seen

    @pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
    def test_workers_die_with_their_parent(self, tmp_path: Path) -> None:
        """kill -9 of `llfsm check -j 2` leaves no worker behind."""
        code = "".join(f"x_{i} = {i} + {i}\n" for i in range(3000))
        for i in range(120):
            write_machine(tmp_path, f"m{i}", {"A": [("END", "True")], "END": None}, {"A_OnEntry": code})
        proc = subprocess.Popen(
            [sys.executable, "-m", "llfsm", "check", "-q", "-j", "2", str(tmp_path)],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        try:
            workers: set[int] = set()
            deadline = time.monotonic() + 30
            while not workers and time.monotonic() < deadline and proc.poll() is None:
                workers = _children(proc.pid)
                time.sleep(0.02)
            assert workers, "no worker seen"
            os.kill(proc.pid, signal.SIGKILL)
            proc.wait(timeout=10)
            deadline = time.monotonic() + 10
            while time.monotonic() < deadline and any(_alive(w) for w in workers):
                time.sleep(0.05)
            assert not any(_alive(w) for w in workers)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait(timeout=10)


def _children(pid: int) -> set[int]:
    out = set()
    for task in Path(f"/proc/{pid}/task").glob("*"):
        try:
            out.update(int(c) for c in (task / "children").read_text().split())
        except OSError:
            pass
    return out


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


class TestOneRuleForLinkedMachines:
    """Item 5 of issue 12: a machine directory linked from outside is refused by every entry point."""

    @pytest.fixture
    def linked(self, tmp_path: Path) -> Path:
        secret = write_machine(tmp_path / "secret", "stolen", {"A": [("END", "True")], "END": None})
        (secret / "State_A_OnEntry.py").write_text("print('SECRET')\n")
        repo = tmp_path / "repo"
        repo.mkdir()
        (repo / "evil.machine").symlink_to(secret)
        (repo / "inside").mkdir()
        write_machine(repo / "inside", "fine", {"A": [("END", "True")], "END": None})
        (repo / "alias.machine").symlink_to("inside/fine.machine")  # stays in its folder: fine
        return repo

    def test_check_by_search_and_by_name(self, linked: Path) -> None:
        for args in ([linked], [linked / "evil.machine"], sorted(linked.glob("*.machine"))):
            r = llfsm("check", *args)
            assert r.status == 1, args
            assert "LF037" in r.stdout and "SECRET" not in r.stdout
            assert r.stdout.count("LF037") == 1

    def test_a_link_inside_its_folder_is_read(self, linked: Path) -> None:
        r = llfsm("check", linked / "alias.machine")
        assert r.status == 0, r.stdout

    @pytest.mark.parametrize("explicit", [True, False])
    def test_build(self, linked: Path, tmp_path: Path, explicit: bool) -> None:
        r = llfsm("build", "-o", tmp_path / "out", linked / "evil.machine" if explicit else linked)
        assert r.status == 1
        assert "LF037" in r.stderr
        assert not (tmp_path / "out" / "evil.py").exists()

    def test_run(self, linked: Path) -> None:
        r = run_sim(linked / "evil.machine", "--duration", "10ms")
        assert r.status == 2
        assert "LF037" in r.stderr and "SECRET" not in r.stdout

    def test_graph(self, linked: Path) -> None:
        r = llfsm("graph", linked / "evil.machine")
        assert r.status == 1
        assert "LF037" in r.stderr and "A" not in r.stdout


def _run_entry(tmp_path: Path, code: str, variables: str = "count: int = 3\n") -> list[str]:
    """Run a machine whose INITIAL OnEntry is `code` (sim clock); its printed lines."""
    m = write_machine(tmp_path, "m", {"A": [("END", "True")], "END": None}, {"A_OnEntry": code}, variables=variables)
    checked = check_machine(m)
    assert checked.ok, checked.diagnostics
    r = run_sim(m, "--duration", "20ms")
    assert r.status == 0, r.stderr
    return r.lines


class TestRewriteFollowsPythonScoping:
    """Item 6 of issue 12: the rewrite of bare names follows Python's scopes exactly."""

    def test_class_body_names_are_not_seen_by_methods(self, tmp_path: Path) -> None:
        code = (
            "class Box:\n"
            "    count = 10\n"
            "    seen = count\n"
            "    firsts = [k for k in range(count)]\n"  # the first iterable: in the class scope
            "    doubled = [count * k for k in range(2)]\n"  # the rest: not in the class scope
            "    def get(this):\n"
            "        return count\n"
            "    grab = lambda this: count\n"
            "print(Box().get(), Box().grab(), Box.seen, len(Box.firsts), Box.doubled)\n"
        )
        assert _run_entry(tmp_path, code) == ["3 3 10 10 [0, 3]"]

    def test_nested_classes(self, tmp_path: Path) -> None:
        code = (
            "def make():\n"
            "    class Outer:\n"
            "        count = 1\n"
            "        class Inner:\n"
            "            value = count\n"  # Inner's body does not see Outer's names
            "    return Outer.Inner.value\n"
            "print(make())\n"
        )
        assert _run_entry(tmp_path, code) == ["3"]

    def test_comprehension_variables(self, tmp_path: Path) -> None:
        code = (
            "a = [count for count in range(2)]\n"
            "b = {count: count for count in 'x'}\n"
            "c = [count + y for y in range(2) for count in range(y, y + 1)]\n"
            "d = [[count for _ in range(1)] for count in range(2)]\n"
            "print(a, b, c, d, count)\n"
        )
        assert _run_entry(tmp_path, code) == ["[0, 1] {'x': 'x'} [0, 2] [[0], [1]] 3"]

    def test_lambda_parameters(self, tmp_path: Path) -> None:
        code = (
            "f = lambda count: count * 2\n"
            "g = lambda: count\n"
            "h = lambda x, *count, **kw: count\n"
            "k = lambda x=count: x\n"  # a default is evaluated where the lambda stands
            "print(f(5), g(), h(1, 2), k())\n"
        )
        assert _run_entry(tmp_path, code) == ["10 3 (2,) 3"]

    def test_nested_functions(self, tmp_path: Path) -> None:
        code = (
            "def g(count):\n"
            "    def h():\n"
            "        return count\n"  # g's parameter, through the closure
            "    return h()\n"
            "def k():\n"
            "    count = 7\n"  # the machine variable, as documented (no `nonlocal` needed)
            "def j(*, count=count):\n"
            "    return count\n"
            "k()\n"
            "print(g(4), count, j(), j(count=1))\n"
        )
        assert _run_entry(tmp_path, code) == ["4 7 3 1"]

    def test_self_documenting_f_strings(self, tmp_path: Path) -> None:
        code = (
            "print(f'{count=}')\n"
            "print(f'{count = }')\n"
            "print(f'{count=:>4}|')\n"
            "print(f'{count=!s}')\n"
            "print(f'{ (count) + 1 =}')\n"
            'print(f"{count=} and {count}")\n'
            "print(f'{ {count: 1}[count]=}')\n"
            "print(f'{count==3}')\n"
        )
        assert _run_entry(tmp_path, code) == [
            "count=3",
            "count = 3",
            "count=   3|",
            "count=3",
            " (count) + 1 =4",
            "count=3 and 3",
            " {count: 1}[count]=1",
            "True",
        ]

    def test_self_documenting_f_string_in_a_guard(self, tmp_path: Path) -> None:
        m = write_machine(
            tmp_path,
            "m",
            {"A": [("END", "print(f'{count=}') or True")], "END": None},
            variables="count: int = 5\n",
        )
        r = run_sim(m, "--duration", "20ms")
        assert r.status == 0, r.stderr
        assert r.lines == ["count=5"]

    def test_walrus_in_a_comprehension_binds_in_the_enclosing_function(self, tmp_path: Path) -> None:
        code = (
            "vals = [(last := v) for v in range(3)]\n"
            "f = lambda count: [(count := v) for v in range(3)] and count\n"
            "print(last, f(0), count)\n"
        )
        assert _run_entry(tmp_path, code) == ["2 2 3"]

    @pytest.mark.parametrize(
        "code",
        [
            "vals = [(count := v) for v in range(3)]\n",
            "def f():\n    return [(count := v) for v in range(3)]\n",
            "vals = [[(count := v) for v in range(2)] for w in range(2)]\n",
        ],
    )
    def test_walrus_binding_a_machine_variable_is_refused(self, tmp_path: Path, code: str) -> None:
        m = write_machine(
            tmp_path, "m", {"A": [("END", "True")], "END": None}, {"A_OnEntry": code}, variables="count: int = 3\n"
        )
        assert "LF038" in {d.code for d in check_machine(m).diagnostics}

    def test_a_parameter_named_self_does_not_hide_the_machine(self, tmp_path: Path) -> None:
        """`def get(self): return count` reads the machine's count (issue 18: it was refused as
        LF013, "name the parameter `this`"); the compiled code reaches the machine through an
        alias there.  tests/test_nested_scopes.py has the other cases."""
        code = (
            "class Box:\n    def get(self):\n        return count\n"
            "f = lambda self: [count for _ in range(1)]\n"
            "print(Box().get(), f(None))\n"
        )
        assert _run_entry(tmp_path, code) == ["3 [3]"]

    def test_a_parameter_named_self_is_fine_otherwise(self, tmp_path: Path) -> None:
        code = "class Box:\n    def __str__(self):\n        return 'box'\nprint(Box(), count)\n"
        assert _run_entry(tmp_path, code) == ["box 3"]


class TestOutputFormatsForAnyFileName:
    """SARIF and JSON output of issue 12: valid for any file name."""

    @pytest.fixture
    def hostile(self, tmp_path: Path) -> list[Path]:
        out = []
        for i, folder in enumerate(HOSTILE_FOLDERS):
            root = _hostile_dir(tmp_path / f"h{i}", folder)
            # a machine with an error and a warning: a diagnostic in each file it names
            out.append(write_machine(root, "m", {"A": [("ENDD", "True")], "END": None, "LOST": None}))
        return out

    @pytest.mark.parametrize("relative", [False, True])
    def test_sarif_is_valid_against_the_schema(
        self, hostile: list[Path], tmp_path: Path, monkeypatch, relative: bool
    ) -> None:
        validator = sarif_validator()
        if relative:
            monkeypatch.chdir(tmp_path)
            args = [os.path.relpath(m, tmp_path) for m in hostile]
        else:
            args = [str(m) for m in hostile]
        r = llfsm("check", "--format", "sarif", *args)
        assert r.status == 1
        doc = json.loads(r.stdout)
        errors = sorted(validator.iter_errors(doc), key=str)
        assert not errors, errors[0]
        results = doc["runs"][0]["results"]
        assert len(results) >= 2 * len(hostile)
        for s in strings_in(doc):
            s.encode("utf-8")  # no lone surrogate anywhere
        uris = [loc["physicalLocation"]["artifactLocation"]["uri"] for res in results for loc in res["locations"]]
        for uri in uris:
            assert uri.startswith("file:///") != relative
            assert not any(c in uri for c in " #?") and uri.isascii()
        # each URI gives back the bytes of the file it names
        named = {os.fsencode(os.path.join(str(m), "machine.yaml")) for m in hostile}
        decoded = set()
        for uri in uris:
            raw = urllib.parse.unquote_to_bytes(uri.removeprefix("file://"))
            decoded.add(raw if not relative else os.fsencode(os.path.join(str(tmp_path), os.fsdecode(raw))))
        assert named <= decoded

    def test_json_has_no_lone_surrogates(self, hostile: list[Path]) -> None:
        r = llfsm("check", "--format", "json", *hostile)
        assert r.status == 1
        doc = json.loads(r.stdout)
        assert len({d["file"] for d in doc}) >= len(hostile)
        for s in strings_in(doc):
            s.encode("utf-8")
        assert any("\\xe9\\xff" in d["file"] for d in doc)  # the bytes, spelled out

    @pytest.mark.parametrize("fmt", ["text", "github"])
    def test_line_formats_keep_one_line_per_diagnostic(self, hostile: list[Path], fmt: str) -> None:
        r = llfsm("check", "--format", fmt, *hostile)
        count = len(json.loads(llfsm("check", "--format", "json", *hostile).stdout))
        assert len(r.stdout.splitlines()) == count
        r.stdout.encode("utf-8")


class TestClearMessages:
    """'Should be a clear message' of issue 12, the front end's share."""

    def test_a_name_check_accepts_is_a_name_build_can_write(self, tmp_path: Path) -> None:
        from llfsm.lang.model import MAX_MACHINE_NAME

        ok = write_machine(tmp_path, "m" * MAX_MACHINE_NAME, {"A": [("END", "True")], "END": None})
        r = llfsm("build", "-q", "-o", tmp_path / "out", ok)
        assert r.status == 0, r.stderr
        long = write_machine(tmp_path, "n" * (255 - len(".machine")), {"A": [("END", "True")], "END": None})
        r = llfsm("check", long)
        assert r.status == 1 and "LF014" in r.stdout
        r = llfsm("build", "-q", "-o", tmp_path / "out", long)
        assert r.status == 1 and "LF014" in r.stderr and "Traceback" not in r.stderr

    @pytest.mark.parametrize("targets", ["[~, END]", "[END, ~]", "[~]", "\n      -\n      - END"])
    def test_a_missing_transition_target_is_reported(self, tmp_path: Path, targets: str) -> None:
        d = tmp_path / "m.machine"
        d.mkdir()
        (d / "machine.yaml").write_text(f"states:\n  - name: A\n    transitions: {targets}\n  - name: END\n")
        (d / "State_A_Transition_0.expr").write_text("after(1)\n")
        (d / "State_A_Transition_1.expr").write_text("after(2)\n")
        diags = check_machine(d).diagnostics
        assert [x.code for x in diags] == ["LF004"], diags
        assert "has no target" in diags[0].message


class TestNewcomerYaml:
    """The newcomer's rough edges in machine.yaml: one typo, one diagnostic, with a suggestion."""

    def _machine(self, tmp_path: Path, yaml_text: str) -> Path:
        d = tmp_path / "m.machine"
        d.mkdir()
        (d / "machine.yaml").write_text(yaml_text)
        for s, n in (("INITIAL", 2), ("WAIT", 1)):
            for i in range(n):
                (d / f"State_{s}_Transition_{i}.expr").write_text(f"after({i + 1})\n")
        return d

    def test_a_misspelt_target_gets_one_diagnostic_with_a_suggestion(self, tmp_path: Path) -> None:
        d = self._machine(
            tmp_path,
            "states:\n  - name: INITIAL\n    transitions: [WAIT, ENDD]\n"
            "  - name: WAIT\n    transitions: [END]\n  - name: END\n",
        )
        diags = check_machine(d).diagnostics
        assert [x.code for x in diags] == ["LF020"], diags
        assert "did you mean 'END'?" in diags[0].message

    def test_a_misspelt_key_gets_one_diagnostic(self, tmp_path: Path) -> None:
        d = self._machine(
            tmp_path,
            "states:\n  - name: INITIAL\n    transition: [WAIT, END]\n"
            "  - name: WAIT\n    transitions: [END]\n  - name: END\n",
        )
        diags = check_machine(d).diagnostics
        assert [x.code for x in diags] == ["LF004"], diags

    def test_a_misspelt_initial_state(self, tmp_path: Path) -> None:
        d = self._machine(
            tmp_path,
            "initial: INITAL\nstates:\n  - name: INITIAL\n    transitions: [WAIT, END]\n"
            "  - name: WAIT\n    transitions: [END]\n  - name: END\n",
        )
        diags = check_machine(d).diagnostics
        assert [x.code for x in diags] == ["LF021"], diags
        assert "did you mean 'INITIAL'?" in diags[0].message

    def test_an_unrelated_unreachable_state_is_still_reported(self, tmp_path: Path) -> None:
        d = self._machine(
            tmp_path,
            "states:\n  - name: INITIAL\n    transitions: [END, ENDD]\n"
            "  - name: WAIT\n    transitions: [END]\n  - name: END\n",
        )
        assert sorted(x.code for x in check_machine(d).diagnostics) == ["LF020", "LF102"]

    def test_suggestions_stay_linear(self, tmp_path: Path) -> None:
        def make(n: int) -> Callable[[], object]:
            d = tmp_path / f"s{n}.machine"
            d.mkdir()
            states = "".join(f"  - name: S{i}\n    transitions: [T{i}]\n" for i in range(n))
            (d / "machine.yaml").write_text("states:\n" + states)
            for i in range(n):
                (d / f"State_S{i}_Transition_0.expr").write_text("True\n")
            return lambda: check_machine(d)

        assert _ratio(make, 1000) < 10


def _codes_of(tmp_path: Path, code: dict[str, str], guard: str = "True", **kw: str) -> list[tuple[str, str, int]]:
    m = write_machine(tmp_path, "m", {"A": [("END", guard)], "END": None}, code, **kw)
    return sorted((d.code, Path(d.file).name, d.line) for d in check_machine(m).diagnostics)


class TestUndeclaredNames:
    """The newcomer's commonest mistake is an error at check time, with the fix in its message."""

    def test_a_local_of_on_entry_read_in_a_guard(self, tmp_path: Path) -> None:
        m = write_machine(tmp_path, "m", {"A": [("END", "started")], "END": None}, {"A_OnEntry": "started = True\n"})
        diags = check_machine(m).diagnostics
        assert [(d.code, Path(d.file).name) for d in diags] == [("LF040", "State_A_Transition_0.expr")]
        assert "State_A_OnEntry.py" in diags[0].message and "Variables.py" in diags[0].message
        assert llfsm("check", m).status == 1
        # and what the message says to do makes it pass and run
        (m / "Variables.py").write_text("started: bool = False\n")
        assert check_machine(m).ok
        assert run_sim(m, "--duration", "10ms").status == 0

    def test_a_local_of_another_section(self, tmp_path: Path) -> None:
        got = _codes_of(tmp_path, {"A_OnEntry": "n = 1\n", "A_OnExit": "print(n)\n"})
        assert got == [("LF040", "State_A_OnExit.py", 1)]

    def test_read_before_assigned(self, tmp_path: Path) -> None:
        got = _codes_of(tmp_path, {"A_OnEntry": "print(total)\ntotal = 0\nx += 1\n"})
        assert got == [("LF040", "State_A_OnEntry.py", 1), ("LF040", "State_A_OnEntry.py", 3)]

    @pytest.mark.parametrize(
        "code",
        [
            "total = 0\nprint(total)\n",
            "for i in range(3):\n    if i:\n        print(prev)\n    prev = i\n",
            "n = 0\nwhile n < 3:\n    if n:\n        print(last)\n    last = n\n    n += 1\n",
            "def f():\n    return later\nlater = 1\nprint(f())\n",
            "import math\nprint(math.pi)\n",
            "try:\n    import json as j\nexcept ImportError:\n    j = None\nprint(j)\n",
            "try:\n    1 / 0\nexcept ZeroDivisionError as e:\n    print(e)\n",
            "print([v for v in range(2)], {k: k for k in 'ab'})\n",
            "vals = [(last := v) for v in range(3)]\nprint(last)\n",
            "with open(__file__) as fh:\n    pass\nprint(fh.closed)\n",
            "x = 1\ndel x\n",
            "for a, (b, c) in [(1, (2, 3))]:\n    print(a, b, c)\n",
            "class K:\n    y = 1\n    z = y + 1\nprint(K.z)\n",
            "count = count + 1\nprint(after_ms(1), count)\n",
            "f = lambda a, *r, k=1, **kw: (a, r, k, kw)\nprint(f(1))\n",
            "match [1, 2]:\n    case [a, *rest]:\n        print(a, rest)\n",
        ],
    )
    def test_correct_code_passes_and_runs(self, tmp_path: Path, code: str) -> None:
        m = write_machine(
            tmp_path,
            "m",
            {"A": [("END", "True")], "END": None},
            {"A_OnEntry": code},
            variables="count: int = 0\n",
        )
        checked = check_machine(m)
        assert checked.ok, checked.diagnostics
        r = run_sim(m, "--duration", "10ms")
        assert r.status == 0, r.stderr

    @pytest.mark.parametrize(
        ("code", "name"),
        [
            ("print([v for v in range(2)], v)\n", "v"),
            ("class K:\n    y = 1\n    def m(this):\n        return y\nK().m()\n", "y"),
            ("x: int\nprint(x)\n", "x"),
            ("f = lambda a: a + b\nf(1)\n", "b"),
            ("del nothere\n", "nothere"),
            ("g = [k for k in range(k)]\n", "k"),
        ],
    )
    def test_wrong_code_is_an_error(self, tmp_path: Path, code: str, name: str) -> None:
        m = write_machine(tmp_path, "m", {"A": [("END", "True")], "END": None}, {"A_OnEntry": code})
        diags = check_machine(m).diagnostics
        assert [d.code for d in diags] == ["LF040"], diags
        assert repr(name) in diags[0].message
        # and check is right: the run fails
        assert run_sim(m, "--duration", "10ms").status != 0

    def test_suggestions_and_other_languages(self, tmp_path: Path) -> None:
        m = write_machine(
            tmp_path,
            "m",
            {"A": [("END", "conut > 1 or true")], "END": None},
            variables="count: int = 0\n",
        )
        msgs = {d.message.split("'")[1]: d.message for d in check_machine(m).diagnostics if d.code == "LF040"}
        assert "did you mean 'count'?" in msgs["conut"]
        assert "`True`" in msgs["true"]

    def test_a_star_import_makes_it_a_warning(self, tmp_path: Path) -> None:
        got = _codes_of(tmp_path, {"A_OnEntry": "print(pi)\n"}, includes="from math import *\n")
        assert got == [("LF105", "State_A_OnEntry.py", 1)]


class TestOtherLanguagesHabits:
    """C++ (clfsm) and rclpy habits get the llfsm spelling, not just "invalid syntax"."""

    @pytest.mark.parametrize(
        ("line", "spelling"),
        [
            ("count++", "count += 1"),
            ("count--", "count -= 1"),
            ("ok = a && b", "`and`"),
            ("ok = a || b", "`or`"),
            ("if !done:\n    pass", "`not x`"),
            ("int x = 0;", "`x = 0`"),
            ("if (a) {\n}", "colon and indentation"),
            ("// a comment", "`#`"),
        ],
    )
    def test_cpp_syntax_gets_a_hint(self, tmp_path: Path, line: str, spelling: str) -> None:
        m = write_machine(
            tmp_path, "m", {"A": [("END", "True")], "END": None}, {"A_OnEntry": line}, variables="count: int = 0\n"
        )
        diags = check_machine(m).diagnostics
        assert [d.code for d in diags] == ["LF030"], diags
        assert spelling in diags[0].message

    def test_a_guard_with_cpp_operators(self, tmp_path: Path) -> None:
        m = write_machine(tmp_path, "m", {"A": [("END", "after(1) && !false")], "END": None})
        diags = check_machine(m).diagnostics
        assert [d.code for d in diags] == ["LF030"] and "`and`" in diags[0].message

    def test_a_trailing_semicolon_is_a_warning(self, tmp_path: Path) -> None:
        got = _codes_of(tmp_path, {"A_OnEntry": "x = 1;\ny = 2; z = 3\nprint(x, y, z);  # done\n"})
        assert got == [("LF108", "State_A_OnEntry.py", 1), ("LF108", "State_A_OnEntry.py", 3)]

    @pytest.mark.parametrize(
        ("where", "text", "spelling"),
        [
            ("Includes.py", "import rclpy\n", "from llfsm import ros"),
            ("Includes.py", "from std_msgs.msg import String\n", "from llfsm.msgs.std_msgs.msg import String"),
            ("Includes.py", "import geometry_msgs.msg\n", "import llfsm.msgs.geometry_msgs.msg"),
            ("Includes.py", "from rclpy.qos import qos_profile_sensor_data\n", "ros.qos_profile_sensor_data"),
            ("Includes.py", "from rclpy.qos import QoSPresetProfiles\n", "ros.QoSProfile(depth=10)"),
            ("Includes.py", "from rclpy.node import Node\n", "from llfsm import ros"),
            ("State_A_OnEntry.py", "from turtlesim.srv import Spawn\n", "from llfsm.msgs.turtlesim.srv import Spawn"),
        ],
    )
    def test_rclpy_habits_get_the_llfsm_spelling(self, tmp_path: Path, where: str, text: str, spelling: str) -> None:
        m = write_machine(tmp_path, "m", {"A": [("END", "True")], "END": None}, {where: text})
        diags = [d for d in check_machine(m).diagnostics if d.code == "LF041"]
        assert len(diags) == 1 and spelling in diags[0].message, diags

    def test_to_msg_and_qos_presets(self, tmp_path: Path) -> None:
        ROS_HABITS = "\n".join(
            ["node = ros.Node('n')", "stamp = node.get_clock().now().to_msg()", "q = qos_profile_sensor_data", ""]
        )
        m = write_machine(
            tmp_path,
            "m",
            {"A": [("END", "True")], "END": None},
            {"A_OnEntry": ROS_HABITS},
            includes="from llfsm import ros\n",
        )
        diags = check_machine(m).diagnostics
        assert {(d.code, d.line) for d in diags} == {("LF041", 2), ("LF040", 3)}
        assert "seconds_nanoseconds" in next(d.message for d in diags if d.code == "LF041")
        assert "`ros.qos_profile_sensor_data`" in next(d.message for d in diags if d.code == "LF040")

    def test_llfsm_spellings_and_helper_modules_pass(self, tmp_path: Path) -> None:
        m = write_machine(
            tmp_path,
            "m",
            {"A": [("END", "True")], "END": None},
            {"A_OnEntry": "s, ns = node.get_clock().now().seconds_nanoseconds()\nprint(helpers, String)\n"},
            includes="from llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import String\nimport helpers\n",
            variables="node: ros.Node = ros.Node('n')\n",
        )
        assert check_machine(m).ok, check_machine(m).diagnostics


DOC = Path(__file__).resolve().parent.parent / "docs" / "machine-format.md"
_DOC_BLOCK = re.compile(
    r"(<!-- generated: the module of machines/counter\.machine.*?-->\n```python\n)(.*?)(```\n)", re.S
)


def _normalised(module: str) -> str:
    """A built module with what depends on the build (version, fingerprint, folder) spelled out."""
    module = re.sub(r"^# Generated by llfsm \S+:", "# Generated by llfsm X.Y.Z:", module, count=1, flags=re.M)
    module = re.sub(
        r"^# Fingerprint: \w*$", "# Fingerprint: <hash of the machine's files and the compiler>", module, flags=re.M
    )
    module = re.sub(r"^# Source: .*$", "# Source: /home/me/project/machines/counter.machine", module, flags=re.M)
    return re.sub(r"^(\s*SOURCE_DIR = ).*$", r"\1'/home/me/project/machines/counter.machine'", module, flags=re.M)


class TestGeneratedModulesInTheDocs:
    """Item 8: docs/machine-format.md shows the real module; modules are relocatable."""

    def test_the_doc_shows_what_build_writes(self, tmp_path: Path) -> None:
        from helpers import MACHINES

        out = build_machine(MACHINES / "counter.machine", tmp_path)
        assert out.status == "compiled"
        built = _normalised(out.module.read_text(encoding="utf-8"))
        doc = DOC.read_text(encoding="utf-8")
        m = _DOC_BLOCK.search(doc)
        assert m is not None, "the generated block of docs/machine-format.md is missing"
        if os.environ.get("LLFSM_UPDATE_DOCS") == "1":
            DOC.write_text(doc[: m.start(2)] + built + doc[m.end(2) :], encoding="utf-8")
            return
        assert m.group(2) == built, "docs/machine-format.md is stale: run LLFSM_UPDATE_DOCS=1 pytest -k the_doc_shows"

    def test_a_module_runs_from_elsewhere_and_names_the_users_file(self, tmp_path: Path) -> None:
        m = write_machine(
            tmp_path / "src",
            "m",
            {"A": [("END", "after_ms(2)")], "END": None},
            {"A_OnEntry": "print('hello')\n", "END_OnEntry": "x = 1\nprint(1 // 0)\n"},
        )
        out = build_machine(m, tmp_path / "build")
        text = out.module.read_text(encoding="utf-8")
        assert str(tmp_path / "build") not in text  # no path of the build inside
        moved = tmp_path / "elsewhere" / "deep" / "m.py"
        moved.parent.mkdir(parents=True)
        out.module.rename(moved)
        (tmp_path / "build").rmdir()
        r = run_sim(moved, "--duration", "50ms")
        assert r.status == 1
        assert r.lines == ["hello"]
        assert "State_END_OnEntry.py:2" in r.stderr and "ZeroDivisionError" in r.stderr


@pytest.mark.parametrize("folder", HOSTILE_FOLDERS)
def test_hostile_folders_through_every_command(tmp_path: Path, folder: str) -> None:
    """Item 9: check (every format), build, run and graph on a machine in a hostile folder."""
    root = _hostile_dir(tmp_path, folder)
    m = write_machine(root, "m", {"A": [("END", "after_ms(1)")], "END": None}, {"A_OnEntry": "print('hi')\n"})
    for fmt in ("text", "json", "github", "sarif"):
        r = llfsm("check", "--format", fmt, "-q", m)
        assert r.status == 0 and "Traceback" not in r.stderr, (fmt, r.stderr)
        r.stdout.encode("utf-8")
    r = llfsm("build", "-q", "-o", tmp_path / "out", m)
    assert r.status == 0, r.stderr
    header_ok((tmp_path / "out" / "m.py").read_text(encoding="utf-8"))
    r = run_sim(m, "--duration", "10ms")
    assert r.status == 0 and r.lines == ["hi"], r.stderr
    for fmt in ("mermaid", "dot"):
        r = llfsm("graph", "--format", fmt, m)
        assert r.status == 0 and "A" in r.stdout, r.stderr


@pytest.mark.parametrize(
    "text", ["coding=utf_7 +AGEAYQ-", "a\nraise SystemExit(7)", 'q\'"""\\', "# -*- coding: latin-1 -*-"]
)
def test_package_scaffold_python_files_carry_no_user_text_in_lines_1_and_2(tmp_path: Path, text: str) -> None:
    """Item 3 for the package templates: setup.py and the test file begin with llfsm's own text."""
    from llfsm.scaffold import ScaffoldError, create_package

    reference = tmp_path / "ref"
    reference.mkdir()
    create_package(reference, "pkg", machines=["m"])
    target = tmp_path / "hostile"
    target.mkdir()
    try:
        create_package(target, "pkg", machines=["m"], description=text, maintainer_name=text)
    except ScaffoldError:
        return  # refused with a message: nothing of it reaches a file
    for rel in ("setup.py", "test/test_llfsm_check.py"):
        got = (target / "pkg" / rel).read_text(encoding="utf-8")
        want = (reference / "pkg" / rel).read_text(encoding="utf-8")
        assert got.split("\n")[:2] == want.split("\n")[:2]
        enc, _ = tokenize.detect_encoding(io.BytesIO(got.encode("utf-8")).readline)
        assert enc == "utf-8"
        kinds = [type(s).__name__ for s in ast.parse(got).body]
        assert kinds == [type(s).__name__ for s in ast.parse(want).body]


def test_a_helper_package_beside_the_machine_is_not_a_ros_habit(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path, "m", {"A": [("END", "True")], "END": None}, includes="from tools.msg import helper\nimport helpers\n"
    )
    (tmp_path / "tools").mkdir()
    (tmp_path / "tools" / "msg.py").write_text("helper = 1\n")
    (tmp_path / "helpers.py").write_text("")
    assert check_machine(m).ok, check_machine(m).diagnostics
    (tmp_path / "tools" / "msg.py").unlink()
    (tmp_path / "tools").rmdir()
    assert [d.code for d in check_machine(m).diagnostics] == ["LF041"]
