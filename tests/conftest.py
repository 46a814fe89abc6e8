"""Shared helpers: write machine directories from a compact description and run them."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from click.testing import CliRunner

from llfsm import ros
from llfsm.cli import cli
from llfsm.ros.bus import Bus, bus_of
from llfsm.runtime import RunContext, SimClock
from llfsm.runtime.context import activate

REPO = Path(__file__).resolve().parent.parent
MACHINES = REPO / "machines"


@pytest.fixture(autouse=True)
def _isolated_cache(tmp_path_factory: pytest.TempPathFactory, monkeypatch: pytest.MonkeyPatch) -> None:
    """Every test compiles into its own cache, never into ~/.cache."""
    monkeypatch.setenv("LLFSM_CACHE_DIR", str(tmp_path_factory.mktemp("cache")))


@pytest.fixture
def bus() -> Iterator[Bus]:
    """A fresh run context with a sim clock, active for the test."""
    ctx = RunContext(SimClock())
    prev = activate(ctx)
    ros.init()
    try:
        yield bus_of(ctx)
    finally:
        activate(prev)


def write_machine(
    root: Path,
    name: str,
    states: dict[str, list[tuple[str, str]] | None],
    code: dict[str, str] | None = None,
    variables: str | None = None,
    includes: str | None = None,
    yaml_extra: str = "",
) -> Path:
    """`states` maps each state to its transitions [(target, guard)]; `code` maps file stems
    such as "PUBLISH_OnEntry" (or whole file names) to their text."""
    d = root / f"{name}.machine"
    d.mkdir(parents=True, exist_ok=True)
    lines = [yaml_extra.rstrip()] if yaml_extra else []
    lines.append("states:")
    for s, trans in states.items():
        lines.append(f"  - name: {s}")
        if trans:
            lines.append(f"    transitions: [{', '.join(t for t, _ in trans)}]")
            for i, (_t, guard) in enumerate(trans):
                (d / f"State_{s}_Transition_{i}.expr").write_text(guard + "\n")
    (d / "machine.yaml").write_text("\n".join(lines) + "\n")
    for key, text in (code or {}).items():
        fname = key if "." in key else f"State_{key}.py"
        (d / fname).write_text(text if text.endswith("\n") else text + "\n")
    if variables is not None:
        (d / "Variables.py").write_text(variables)
    if includes is not None:
        (d / "Includes.py").write_text(includes)
    return d


@dataclass
class Run:
    status: int
    stdout: str
    stderr: str

    @property
    def lines(self) -> list[str]:
        return self.stdout.splitlines()


def llfsm(*args: str | os.PathLike[str]) -> Run:
    """Run the CLI in-process (fast); stdout and stderr kept apart.  With LLFSM_TEST_NATIVE=1
    in the environment, `run` goes through a process of its own with --native instead (the
    slow test in test_native.py runs the semantics suite that way)."""
    if os.environ.get("LLFSM_TEST_NATIVE") and args and args[0] == "run":
        return llfsm_process("run", "--native", *args[1:], timeout=900)
    runner = CliRunner()
    res = runner.invoke(cli, [str(a) for a in args], catch_exceptions=False)
    return Run(res.exit_code, res.stdout, res.stderr)


def run_sim(*args: str | os.PathLike[str]) -> Run:
    return llfsm("run", "--clock", "sim", *args)


def llfsm_process(*args: str | os.PathLike[str], timeout: float = 60, **kw: object) -> Run:
    """Run the real `llfsm` entry point in a subprocess (exit codes, signals, no tracebacks)."""
    proc = subprocess.run(
        [sys.executable, "-m", "llfsm", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=timeout,
        **kw,  # type: ignore[arg-type]
    )
    return Run(proc.returncode, proc.stdout, proc.stderr)
