"""A section stuck in a C call that holds the GIL (issue 18, "Stopping"): no Python signal handler
can run, so only the run's watchdog process can end it, with the usual report of where it was.
The tests cross processes, so they wait in real time, under generous timeouts; the only timing
they assert is that the run ends well within those timeouts."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from helpers import REPO, write_machine

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc to find the watchdog")

PY = sys.executable
STUCK_LINE = "sum(range(10**14))"  # hours of work inside one C call that never lets go of the GIL
SIGNALS = {"SIGINT": signal.SIGINT, "SIGTERM": signal.SIGTERM}


def _spawn(args: list[str], cwd: Path, **env: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [PY, "-m", "llfsm", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=dict(os.environ, PYTHONUNBUFFERED="1", **env),
        cwd=cwd,
    )


def _wait_for_go(p: subprocess.Popen[str]) -> None:
    assert p.stdout is not None
    assert p.stdout.readline().strip() == "go", "the machine did not start"


def _finish(p: subprocess.Popen[str], timeout: float) -> tuple[str, str]:
    try:
        return p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        _kill_tree(p.pid)
        p.communicate()
        raise


def _children(pid: int) -> list[int]:
    """The processes whose parent is `pid` (the run's watchdog, here)."""
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            stat = Path(f"/proc/{entry}/stat").read_text()
        except OSError:
            continue
        fields = stat.rsplit(")", 1)[1].split()  # after "(comm)": state, ppid, ...
        if int(fields[1]) == pid:
            found.append(int(entry))
    return found


def _alive(pid: int) -> bool:
    """Whether a process exists and is not a zombie (an orphan's zombie waits for its reaper)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"


def _gone_soon(pids: list[int], timeout: float = 5.0) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if not any(_alive(p) for p in pids):
            return True
        time.sleep(0.05)
    return False


def _kill_tree(pid: int) -> None:
    for child in _children(pid):
        try:
            os.kill(child, signal.SIGKILL)
        except ProcessLookupError:
            pass
    try:
        os.kill(pid, signal.SIGKILL)
    except ProcessLookupError:
        pass


def _stuck_machine(root: Path) -> Path:
    return write_machine(
        root, "stuck", {"A": [("A", "True")]}, {"A_OnEntry": f"print('go', flush=True)\n{STUCK_LINE}\n"}
    )


def _watchdog_of(p: subprocess.Popen[str]) -> list[int]:
    """The run's watchdog: a child of the run process that exists while machines run."""
    end = time.monotonic() + 5
    while time.monotonic() < end:
        kids = _children(p.pid)
        if kids:
            return kids
        time.sleep(0.02)
    return []


@pytest.mark.parametrize("signame", list(SIGNALS))
def test_a_second_signal_after_the_grace_ends_a_section_stuck_in_c(tmp_path: Path, signame: str) -> None:
    signum = SIGNALS[signame]
    m = _stuck_machine(tmp_path)
    p = _spawn(["run", "--grace", "300ms", str(m)], cwd=tmp_path)
    try:
        _wait_for_go(p)
        watchdog = _watchdog_of(p)
        p.send_signal(signum)
        time.sleep(0.6)  # past the grace time (a signal is a message, not a measurement)
        p.send_signal(signum)
        _out, err = _finish(p, timeout=20)  # the section alone would run for hours
    finally:
        _kill_tree(p.pid)
    assert p.returncode == -signal.SIGKILL, err  # the shell's 137: see docs/semantics.md
    lines = err.splitlines()
    report = [i for i, line in enumerate(lines) if line.startswith("stuck.machine/State_A_OnEntry.py:2: ")]
    assert report, err
    head = lines[report[0]]
    assert head.endswith("(machine stuck, state A, OnEntry)"), err
    assert signame in head, err
    assert lines[report[0] + 1].strip() == STUCK_LINE, err
    assert "Traceback" not in err and 'File "' not in err and "Thread 0x" not in err, err
    assert watchdog and _gone_soon(watchdog), "the watchdog outlived the run"


def test_a_single_signal_ends_a_section_stuck_in_c_soon_after_the_grace(tmp_path: Path) -> None:
    """`kill` once: as for a section that loops in Python (docs/semantics.md), the run ends half a
    second of real time after the grace time, now also when the section is inside a C call."""
    m = _stuck_machine(tmp_path)
    p = _spawn(["run", "--grace", "200ms", str(m)], cwd=tmp_path)
    try:
        _wait_for_go(p)
        watchdog = _watchdog_of(p)
        p.send_signal(signal.SIGTERM)
        _out, err = _finish(p, timeout=20)
    finally:
        _kill_tree(p.pid)
    assert p.returncode == -signal.SIGKILL, err
    assert "stuck.machine/State_A_OnEntry.py:2: " in err and "SIGTERM" in err, err
    assert "(machine stuck, state A, OnEntry)" in err and STUCK_LINE in err, err
    assert "Traceback" not in err, err
    assert watchdog and _gone_soon(watchdog), "the watchdog outlived the run"


def _run_waiter(tmp_path: Path, **env: str) -> tuple[int | None, str, str, list[int]]:
    """A run of a machine that waits for a file `stop`, with its watchdog found while it runs,
    then stopped: (exit status, stdout, stderr, the watchdog's process)."""
    m = write_machine(
        tmp_path,
        "waiter",
        {"A": [("END", "os.path.exists('stop')")], "END": None},
        {"A_OnEntry": "print('go', flush=True)", "END_OnEntry": "print('done')"},
        includes="import os\n",
    )
    p = _spawn(["run", str(m)], cwd=tmp_path, **env)
    try:
        _wait_for_go(p)
        watchdog = _watchdog_of(p)
        assert watchdog, "no watchdog while machines run"
        (tmp_path / "stop").write_text("")
        out, err = _finish(p, timeout=20)
    finally:
        _kill_tree(p.pid)
    return p.returncode, out, err, watchdog


def test_a_normal_run_has_a_silent_watchdog_that_ends_with_it(tmp_path: Path) -> None:
    status, out, err, watchdog = _run_waiter(tmp_path)
    assert status == 0, err
    assert (out, err) == ("done\n", "")
    assert _gone_soon(watchdog), "the watchdog outlived the run"


def test_a_normal_ctrl_c_prints_nothing_extra_and_leaves_no_watchdog(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "polite",
        {"A": [("END", "current().interrupted")], "END": None},
        {"A_OnEntry": "print('go', flush=True)", "END_OnEntry": "print('bye')"},
        includes="from llfsm.runtime import current\n",
    )
    p = _spawn(["run", str(m)], cwd=tmp_path)
    try:
        _wait_for_go(p)
        watchdog = _watchdog_of(p)
        assert watchdog, "no watchdog while machines run"
        p.send_signal(signal.SIGINT)
        out, err = _finish(p, timeout=20)
    finally:
        _kill_tree(p.pid)
    assert p.returncode == 0, err
    assert out == "bye\n"
    assert err == "llfsm: interrupted; machines have 1 s of run time to finish (interrupt again to stop now)\n"
    assert _gone_soon(watchdog), "the watchdog outlived the run"


def test_a_second_ctrl_c_in_python_code_is_still_handled_by_the_run_itself(tmp_path: Path) -> None:
    """A section looping in Python: the run's own handler stops it (status 130, not a kill), so
    the watchdog, which sees the same signals, must stand back."""
    m = write_machine(
        tmp_path, "loop", {"A": [("A", "True")]}, {"A_OnEntry": "print('go', flush=True)\nwhile True:\n    pass\n"}
    )
    p = _spawn(["run", "--grace", "200ms", str(m)], cwd=tmp_path)
    try:
        _wait_for_go(p)
        watchdog = _watchdog_of(p)
        p.send_signal(signal.SIGINT)
        time.sleep(0.3)
        p.send_signal(signal.SIGINT)
        _out, err = _finish(p, timeout=20)
    finally:
        _kill_tree(p.pid)
    assert p.returncode == 130, err
    assert err.splitlines()[-2:] == [
        "loop.machine/State_A_OnEntry.py:2: stopped by a second SIGINT (machine loop, state A, OnEntry)",
        "    while True:",
    ], err
    assert _gone_soon(watchdog), "the watchdog outlived the run"


def test_a_run_and_its_watchdog_write_nothing_into_the_installed_package(tmp_path: Path) -> None:
    """With PYTHONDONTWRITEBYTECODE=1 (or a read-only install), `llfsm run` leaves the package as
    it found it: so does its watchdog, whose interpreter (`python -I`) does not read that
    variable and would otherwise cache its bytecode beside the installed runtime."""
    import shutil

    root = tmp_path / "site"
    shutil.copytree(REPO / "llfsm", root / "llfsm", ignore=shutil.ignore_patterns("__pycache__"))
    before = set((root / "llfsm").rglob("*"))
    status, _out, err, watchdog = _run_waiter(tmp_path, PYTHONDONTWRITEBYTECODE="1", PYTHONPATH=str(root))
    assert status == 0, err
    assert _gone_soon(watchdog), "the watchdog outlived the run"
    new = sorted(str(p.relative_to(root)) for p in set((root / "llfsm").rglob("*")) - before)
    assert not new, f"written into the package: {new}"
