"""Hardening of the run time, the caches and the command line (issue 12): runs that must stop,
caches that must not be trusted, and failures that must be one clear line, not a traceback or a
silent success.  Signal tests cross processes, so they (only they) wait in real time, briefly
and under timeouts."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import REPO, write_machine

PY = sys.executable


def _spawn(args: list[str], cwd: Path = REPO, **env: str) -> subprocess.Popen[str]:
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


def _finish(p: subprocess.Popen[str], timeout: float = 20) -> tuple[str, str]:
    try:
        return p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        p.kill()
        p.communicate()
        raise


# -- 1. a run that cannot be stopped -------------------------------------------------------------

STUCK = {
    # section code, the line (of State_A_OnEntry.py) where it is stopped
    "loop": ("print('go', flush=True)\nwhile True:\n    pass\n", 2, "while True:"),
    "sleep": ("print('go', flush=True)\ntime.sleep(600)\n", 2, "time.sleep(600)"),
}
SIGNALS = {"SIGINT": (signal.SIGINT, 130), "SIGTERM": (signal.SIGTERM, 143), "SIGHUP": (signal.SIGHUP, 129)}


def _stuck_machine(root: Path, kind: str) -> Path:
    code, _line, _text = STUCK[kind]
    return write_machine(root, kind, {"A": [("A", "True")]}, {"A_OnEntry": code}, includes="import time\n")


@pytest.mark.parametrize("signame", list(SIGNALS))
@pytest.mark.parametrize("kind", list(STUCK))
def test_second_signal_stops_a_looping_or_blocking_section_at_once(tmp_path: Path, kind: str, signame: str) -> None:
    signum, status = SIGNALS[signame]
    m = _stuck_machine(tmp_path, kind)
    p = _spawn(["run", str(m), "--grace", "60s"], cwd=tmp_path)
    _wait_for_go(p)
    p.send_signal(signum)
    time.sleep(0.2)  # two separate signals, not one coalesced pending signal
    p.send_signal(signum)
    _out, err = _finish(p, timeout=10)  # the grace is 60 s: only the second signal can end it this soon
    assert p.returncode == status, err
    _code, line, text = STUCK[kind]
    first = err.strip().splitlines()[0]
    where = f"(machine {kind}, state A, OnEntry)"
    assert first == f"{kind}.machine/State_A_OnEntry.py:{line}: stopped by a second {signame} {where}"
    assert text in err and "Traceback" not in err


@pytest.mark.parametrize("kind", list(STUCK))
def test_first_signal_stops_a_stuck_section_once_the_grace_has_passed_in_real_time(tmp_path: Path, kind: str) -> None:
    m = _stuck_machine(tmp_path, kind)
    p = _spawn(["run", str(m), "--grace", "200ms"], cwd=tmp_path)
    _wait_for_go(p)
    p.send_signal(signal.SIGTERM)
    _out, err = _finish(p, timeout=10)
    assert p.returncode == 143, err
    _code, line, _text = STUCK[kind]
    assert err.startswith(f"{kind}.machine/State_A_OnEntry.py:{line}: stopped by SIGTERM: still running"), err
    assert "(machine " + kind + ", state A, OnEntry)" in err


def test_grace_is_bounded_in_real_time_under_a_fast_sim_clock(tmp_path: Path) -> None:
    """--period 1ns: a second of run time would be a billion rounds."""
    m = write_machine(tmp_path, "idle", {"A": [("A", "False")]}, {"A_OnEntry": "print('go', flush=True)"})
    p = _spawn(["run", "--clock", "sim", "--period", "1ns", "--grace", "300ms", str(m)], cwd=tmp_path)
    _wait_for_go(p)
    p.send_signal(signal.SIGTERM)
    _out, err = _finish(p, timeout=15)
    assert p.returncode == 143, err
    assert "interrupted; machines have 0.3 s" in err and "Traceback" not in err


def test_sighup_ends_a_run_like_sigterm_flushing_the_trace_and_writing_the_image(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "ticker",
        {"A": [("A", "after_ms(5)")]},
        {"A_OnEntry": "if not started:\n    print('go', flush=True)\nstarted = True"},
        variables="started: bool = False\n",
    )
    trace, image = tmp_path / "t.jsonl", tmp_path / "pic.png"
    p = _spawn(["run", str(m), "--node", "turtlesim", "--trace", str(trace), "--image", str(image)], cwd=tmp_path)
    _wait_for_go(p)
    p.send_signal(signal.SIGHUP)
    _out, err = _finish(p, timeout=15)
    assert p.returncode == 129, err
    lines = trace.read_text().splitlines()
    assert lines and all(json.loads(line) for line in lines)  # complete lines, flushed
    assert image.read_bytes().startswith(b"\x89PNG")
