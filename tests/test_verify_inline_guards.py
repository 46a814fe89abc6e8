"""verify and the monitor with inline guards (`{to: T, guard: EXPR}` in machine.yaml,
SPEC 13): explored as guard files are, refused at their place in machine.yaml, judged where
they can change."""

from __future__ import annotations

from pathlib import Path

from helpers import llfsm

MACHINE = """\
states:
  - name: WAIT
    transitions:
      - {to: GO, guard: "n >= 2 and coin > 0.5"}
      - {to: WAIT, guard: after_ms(10)}
  - name: GO
"""


def _machine(root: Path, coin: str) -> Path:
    m = root / "c.machine"
    m.mkdir(parents=True)
    (m / "machine.yaml").write_text(MACHINE)
    (m / "Variables.py").write_text("n: int = 0\ncoin: float = 0.0\n")
    (m / "State_WAIT_OnEntry.py").write_text(f"n += 1\ncoin = {coin}\n")
    return m


def test_verify_explores_and_refuses_inline_guards_at_their_line(tmp_path: Path) -> None:
    m = _machine(tmp_path / "ok", "0.75")
    r = llfsm("verify", m, "--property", 'never: state(c) == "GO"', "--property", "always: c.n <= 2")
    assert r.status == 1, r.stdout + r.stderr
    assert 'never: state(c) == "GO": fails' in r.stdout and "always: c.n <= 2: holds" in r.stdout
    # a read of the world inside an inline guard is refused at machine.yaml's line, as a file's is
    bad = _machine(tmp_path / "bad", "0.75")
    (bad / "machine.yaml").write_text(MACHINE.replace("coin > 0.5", "random.random() > 0.5"))
    (bad / "Includes.py").write_text("import random\n")
    r = llfsm("verify", bad)
    assert r.status == 2
    assert f"{bad}/machine.yaml:4:" in r.stdout and "random" in r.stdout


def test_the_monitor_judges_a_machine_with_inline_guards(tmp_path: Path) -> None:
    m = _machine(tmp_path, "0.75")
    r = llfsm("run", "--clock", "sim", m, "--monitor-property", 'never: state(c) == "GO"', "--on-violation", "stop")
    assert r.status == 4
    assert 'never: state(c) == "GO" violated at 0.012 s, ringlet 13: c GO' in r.stderr, r.stderr
