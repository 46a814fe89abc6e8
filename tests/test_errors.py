"""Exceptions in machine code: exit 1 and one report naming the user's file, line and text."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from helpers import REPO, llfsm_process, run_sim, write_machine

BOOM = "x = 1\ny = x - 1\nz = x / y  # boom\n"


@pytest.mark.parametrize(
    ("key", "section", "state"),
    [
        ("A_OnEntry", "OnEntry", "A"),
        ("A_Internal", "Internal", "A"),
        ("A_OnExit", "OnExit", "A"),
        ("END_OnEntry", "OnEntry", "END"),
    ],
)
def test_exception_in_a_section_names_machine_state_section_file_line_and_text(
    tmp_path: Path, key: str, section: str, state: str
) -> None:
    guard = "after_ms(2)"
    m = write_machine(tmp_path, "faulty", {"A": [("END", guard)], "END": None}, {key: BOOM})
    r = run_sim(m)
    assert r.status == 1
    first, second = r.stderr.splitlines()[-2:]
    assert first == (
        f"{m}/State_{key}.py:3: error: ZeroDivisionError: division by zero (machine faulty, state {state}, {section})"
    )
    assert second.strip() == "z = x / y  # boom"


def test_exception_in_a_guard(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "faulty",
        {"A": [("END", "False"), ("END", "missing['key']")], "END": None},
        variables="missing: dict = {}\n",
    )
    r = run_sim(m)
    assert r.status == 1
    assert (
        f"{m}/State_A_Transition_1.expr:1: error: KeyError: 'key' (machine faulty, state A, Transition 1)" in r.stderr
    )
    assert "missing['key']" in r.stderr


def test_exception_in_a_multiline_guard_points_at_its_line(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "faulty", {"A": [("END", "(True and  # first\n 1 / 0)")], "END": None})
    r = run_sim(m)
    assert f"{m}/State_A_Transition_0.expr:2: error: ZeroDivisionError" in r.stderr


def test_exception_in_onsuspend_and_onresume(tmp_path: Path) -> None:
    for sec in ("OnSuspend", "OnResume"):
        m = write_machine(
            tmp_path / sec,
            "faulty",
            {"A": [("END", "False")], "END": None},
            {"A_OnEntry": "suspend_self() if n == 0 else None\nn += 1", f"A_{sec}": "raise RuntimeError('nope')"},
            variables="n: int = 0\n",
        )
        boss = write_machine(
            tmp_path / sec,
            "boss",
            {"W": [("R", "after_ms(3)")], "R": [("END", "True")], "END": None},
            {"R_OnEntry": "resume('faulty')"},
        )
        r = run_sim(m, boss)
        assert r.status == 1, sec
        assert f"State_A_{sec}.py:1: error: RuntimeError: nope (machine faulty, state A, {sec})" in r.stderr


def test_exception_in_a_variable_initialiser(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "faulty", {"A": None}, variables="# counts\nok: int = 1\nbad: int = ok // 0\n")
    r = run_sim(m)
    assert r.status == 1
    assert (
        f"{m}/Variables.py:3: error: ZeroDivisionError: integer division or modulo by zero (machine faulty, Variables)"
        in r.stderr
    )


def test_an_include_that_fails_to_import(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "faulty", {"A": None}, includes="import os\nimport no_such_module_here\n")
    r = run_sim(m)
    assert r.status == 1
    assert f"{m}/Includes.py:2: error: ModuleNotFoundError: No module named 'no_such_module_here'" in r.stderr


def test_unknown_machine_name_is_a_clear_runtime_error(tmp_path: Path) -> None:
    for call in ("is_suspended('ghost')", "is_running('ghost')", "state_name_of('ghost')", "suspend('ghost')"):
        m = write_machine(tmp_path / call[:5], "asker", {"A": [("END", call)], "END": None})
        r = run_sim(m)
        assert r.status == 1
        assert "no machine named 'ghost' is loaded (loaded: asker)" in r.stderr


def test_no_traceback_and_exit_1_from_the_real_command(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "faulty", {"A": None}, {"A_OnEntry": BOOM})
    r = llfsm_process("run", "--clock", "sim", m)
    assert r.status == 1
    assert "Traceback" not in r.stderr
    assert len(r.stderr.splitlines()) == 2


def test_bad_arguments_exit_2(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "fine", {"A": None})
    for args in (["--duration", "soon"], ["--clock", "moon"], ["--period", "0"], ["--nope"]):
        r = llfsm_process("run", m, *args)
        assert r.status == 2, args
        assert "Traceback" not in r.stderr
    r = llfsm_process("run", tmp_path / "missing.machine")
    assert r.status == 2 and "no such machine" in r.stderr
    r = llfsm_process("run", m, m)
    assert r.status == 2 and "loaded twice" in r.stderr


def test_invalid_machine_exits_2_with_diagnostics(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "broken", {"A": [("NOWHERE", "True")]})
    r = llfsm_process("run", "--clock", "sim", m)
    assert r.status == 2
    assert "LF020" in r.stderr and "nothing was run" in r.stderr


def _spawn(args: list[str]) -> subprocess.Popen[str]:
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    return subprocess.Popen(
        [sys.executable, "-m", "llfsm", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        cwd=REPO,
    )


def test_sigint_grace_then_stop_and_second_sigint_stops_at_once(tmp_path: Path) -> None:
    # a machine that never ends by itself and prints once it is running
    m = write_machine(tmp_path, "forever", {"A": [("A", "after_ms(20)")]}, {"A_OnEntry": "print('tick', flush=True)"})
    p = _spawn(["run", str(m), "--grace", "300ms"])
    assert p.stdout is not None
    assert p.stdout.readline().strip() == "tick"
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=20)
    assert p.returncode == 130 and "Traceback" not in err
    assert err.startswith("llfsm: interrupted; machines have 0.3 s of run time to finish")
    assert out.count("tick") >= 10  # rounds went on for the grace time (~300 ms at a tick per 21 ms)

    p = _spawn(["run", str(m), "--grace", "60s"])
    assert p.stdout is not None and p.stdout.readline()
    assert p.stderr is not None
    p.send_signal(signal.SIGINT)
    assert "interrupt again to stop now" in p.stderr.readline()
    p.send_signal(signal.SIGINT)
    p.communicate(timeout=20)
    assert p.returncode == 130


def test_sigterm_behaves_like_sigint(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "forever", {"A": [("A", "after_ms(20)")]}, {"A_OnEntry": "print('tick', flush=True)"})
    p = _spawn(["run", str(m), "--grace", "100ms"])
    assert p.stdout is not None and p.stdout.readline()
    p.send_signal(signal.SIGTERM)
    _out, err = p.communicate(timeout=20)
    assert p.returncode == 143 and "Traceback" not in err


def test_machines_see_the_interrupt_and_finish_within_the_grace_time(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "polite",
        {"A": [("END", "current().interrupted")], "END": None},
        {"A_OnEntry": "print('running', flush=True)", "END_OnEntry": "print('bye')"},
        includes="from llfsm.runtime import current\n",
    )
    p = _spawn(["run", str(m)])
    assert p.stdout is not None and p.stdout.readline()
    p.send_signal(signal.SIGINT)
    out, _err = p.communicate(timeout=20)
    assert p.returncode == 0 and out.strip() == "bye"


def test_a_run_whose_machines_left_ends_0_though_its_closing_outlasted_the_stop_timer(tmp_path: Path) -> None:
    """Sixty DDS runs sent SIGINT at once on two cores (issue 28 item 9): a run's machines reach
    END, then destroying their nodes while a hundred peers leave takes longer than the stop
    timer allows, and the timer stops the run between rounds.  Its machines all left in time, so
    it ends 0, as it would have (a machine still running makes it 130, as before:
    tests/test_hardening_run.py's long wait between rounds)."""
    from llfsm.runtime import Arrangement, RunContext, SimClock
    from llfsm.runtime.errors import RunStopped
    from llfsm.targets import load

    cls = load(str(write_machine(tmp_path, "leaver", {"A": [("END", "True")], "END": None})))
    ctx = RunContext(SimClock())
    arr = Arrangement([cls], context=ctx)

    def closing_outlasts_the_timer() -> None:  # what signals_handled's timer raises, between rounds
        ctx.wake = 0
        if arr.machines[0]._finished:
            arr.interrupt(signal.SIGINT)
            raise RunStopped(signal.SIGINT, "stopped by SIGINT", in_machine_code=False)

    ctx.between_rounds.append(closing_outlasts_the_timer)
    result = arr.run(duration_ns=10_000_000_000)
    assert (result.reason, result.status) == ("finished", 0)


def test_stdout_closed_early_ends_quietly(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "chatty", {"A": [("A", "True")]}, {"A_OnEntry": "print('line ' * 20)"})
    ping = REPO / "machines" / "ros2_ping_pong.machine"
    llfsm_cmd = f"{sys.executable} -m llfsm"
    for cmd, first in (
        (f"{llfsm_cmd} run --clock sim --duration 20s {m} | head -1", "line"),
        (f"{llfsm_cmd} run --clock sim --duration 60s --echo /pingpong {ping} 2>/dev/null | head -1", "data:"),
        (f"{llfsm_cmd} run --clock sim --duration 20s -v {m} 2>&1 >/dev/null | head -1", "m  0"),
    ):
        proc = subprocess.run(
            ["bash", "-c", cmd + '; echo "status ${PIPESTATUS[0]}" >&2'],
            capture_output=True,
            text=True,
            timeout=60,
            cwd=REPO,
        )
        assert proc.stdout.startswith(first), cmd
        assert proc.stderr == "status 0\n", (cmd, proc.stderr)


def test_error_event_in_the_trace_uses_the_same_id_key(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "faulty", {"A": None}, {"A_OnEntry": BOOM})
    tr = tmp_path / "t.jsonl"
    run_sim(m, "--trace", tr)
    last = json.loads(tr.read_text().splitlines()[-1])
    assert last["event"] == "error" and last["id"] == 0 and "machine_id" not in last
    assert last["file"].endswith("State_A_OnEntry.py") and last["line"] == 3


def test_a_built_module_moved_with_its_machine_names_the_moved_files(tmp_path: Path) -> None:
    """The module names its machine folder relative to its own: a project (machines and build
    folder) moved or checked out elsewhere reports errors against the files where they are now."""
    from llfsm.compiler.build import build_machine

    old = tmp_path / "old"
    m = write_machine(old / "machines", "faulty", {"A": None}, {"A_OnEntry": BOOM})
    assert build_machine(m, old / "build").status == "compiled"
    new = tmp_path / "new" / "place"
    shutil.copytree(old, new)
    shutil.rmtree(old)
    r = run_sim(new / "build" / "faulty.py")
    assert r.status == 1
    assert f"{new}/machines/faulty.machine/State_A_OnEntry.py:3: error: ZeroDivisionError" in r.stderr
    assert r.stderr.splitlines()[-1].strip() == "z = x / y  # boom"


def test_a_module_installed_by_a_package_names_the_machine_installed_beside_it(tmp_path: Path) -> None:
    """colcon installs share/PKG/llfsm/NAME.py and share/PKG/machine/NAME.machine; the module's
    path from the build folder does not lead to the machine from there, the folder beside does."""
    from llfsm.compiler.build import build_machine

    m = write_machine(tmp_path / "ws" / "src" / "pkg" / "machine", "faulty", {"A": None}, {"A_OnEntry": BOOM})
    assert build_machine(m, tmp_path / "ws" / "build" / "pkg" / "llfsm").status == "compiled"
    share = tmp_path / "ws" / "install" / "pkg" / "share" / "pkg"
    (share / "llfsm").mkdir(parents=True)
    shutil.copy(tmp_path / "ws" / "build" / "pkg" / "llfsm" / "faulty.py", share / "llfsm")
    shutil.copytree(m, share / "machine" / "faulty.machine")
    r = run_sim(share / "llfsm" / "faulty.py")
    assert r.status == 1
    assert f"{share}/machine/faulty.machine/State_A_OnEntry.py:3: error: ZeroDivisionError" in r.stderr
