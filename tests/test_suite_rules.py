"""The test suite's own rules (docs/architecture.md, "Tests"): test modules share code through
helpers.py and the other helper modules, never through conftest.py or one another, and a C part
that was not built skips its tests, saying why, unless LLFSM_REQUIRE_C=1 (`make test`) asks for
a failure."""

from __future__ import annotations

import ast
from pathlib import Path

import helpers
import pytest

TESTS = Path(__file__).resolve().parent


def _imported_modules(tree: ast.Module) -> list[tuple[int, str]]:
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            out.append((node.lineno, node.module))
    return out


def test_test_modules_import_helpers_not_conftest_nor_each_other() -> None:
    found = []
    files = sorted(p for p in TESTS.rglob("*.py") if "data" not in p.relative_to(TESTS).parts)
    assert len(files) > 40
    for path in files:
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        for line, module in _imported_modules(tree):
            last = module.rsplit(".", 1)[-1]
            if last == "conftest" or last.startswith("test_") or module.startswith("tests."):
                found.append(f"{path.relative_to(TESTS.parent)}:{line}: imports {module}")
    assert not found, "import shared test code from helpers.py (or samples.py, strategies.py):\n" + "\n".join(found)


@pytest.mark.parametrize(
    ("built", "off", "required", "skipped"),
    [
        (True, False, False, False),
        (True, False, True, False),
        (False, False, False, True),  # not built: skipped, saying why
        (False, False, True, False),  # not built under LLFSM_REQUIRE_C=1: runs, and fails
        (False, True, True, True),  # off on purpose (LLFSM_NO_C): skipped whatever is required
    ],
)
def test_a_c_part_that_is_not_built_skips_unless_it_is_required(
    monkeypatch: pytest.MonkeyPatch, built: bool, off: bool, required: bool, skipped: bool
) -> None:
    monkeypatch.setattr(helpers, "C_OFF", off)
    monkeypatch.setattr(helpers, "REQUIRE_C", required)
    mark = helpers.skip_unless_built(built, "the C tap (llfsm/bag/_tap.c)").mark
    assert mark.name == "skipif"
    assert mark.args == (skipped,)
    reason = mark.kwargs["reason"]
    assert "llfsm/bag/_tap.c" in reason
    assert ("off on purpose" in reason) == off


@pytest.mark.parametrize(
    ("marks", "slow_ones"),
    [
        (["-m", "not dds and not browser"], False),  # the quick run of docs/architecture.md
        (["-m", "slow"], True),  # make fuzz
    ],
)
def test_slow_tests_run_only_when_the_mark_expression_names_them(marks: list[str], slow_ones: bool) -> None:
    """A `-m` on the command line replaces the one of pyproject.toml's addopts: the quick run
    must still leave the slow tests out (tests/test_fuzz.py has both kinds)."""
    import subprocess
    import sys

    cmd = [sys.executable, "-m", "pytest", "--collect-only", "-q", "-p", "no:cacheprovider", *marks, "test_fuzz.py"]
    r = subprocess.run(cmd, cwd=TESTS, capture_output=True, text=True, timeout=300, check=False)
    collected = [line for line in r.stdout.splitlines() if "::" in line]
    assert r.returncode == 0 and collected, r.stdout + r.stderr
    slow = [line for line in collected if line.split("::")[1].split("[")[0] in _SLOW_FUZZ]
    assert bool(slow) == slow_ones and (slow_ones or len(collected) > 5), collected


#: The slow tests of tests/test_fuzz.py, read from its source (not by importing it).
_SLOW_FUZZ = {
    node.name
    for node in ast.parse((TESTS / "test_fuzz.py").read_text(encoding="utf-8")).body
    if isinstance(node, ast.FunctionDef)
    and any(ast.unparse(d).startswith("pytest.mark.slow") for d in node.decorator_list)
}
