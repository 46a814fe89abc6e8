"""Progress on a terminal (issue 22, item 9): long silent work shows what it does while stderr
is a terminal, and writes nothing of the kind to a pipe or a file (CI logs, tests).

The terminal is a real pseudo-terminal: the command runs in a process of its own with its
stderr on the pty, as in a user's shell.
"""

from __future__ import annotations

import io
import subprocess
import sys
import textwrap
import time
from pathlib import Path

from helpers import MACHINES, REPO, on_pty

from llfsm.progress import Status, seconds

# A native build whose compile is replaced by a slow stand-in: what the terminal shows while
# mypyc works is the subject, not mypyc (tests/test_native.py compiles for real).
FAKE_NATIVE = textwrap.dedent(
    """
    import sys, time
    from pathlib import Path
    import llfsm.compiler.native as native

    def slow(modules, root, say=None):
        say("compiling 1 machine(s) and the runtime with mypyc")
        time.sleep(1.6)
        return native.NativeBuild(Path(root), {str(m): None for m in modules}, [])

    native.available = lambda: None
    native.native_build = slow
    from llfsm.cli import main
    sys.argv = ["llfsm", *sys.argv[1:]]
    main()
    """
)


def test_a_native_build_says_what_it_compiles_on_a_terminal(tmp_path: Path) -> None:
    argv = [
        sys.executable,
        "-c",
        FAKE_NATIVE,
        "build",
        "--native",
        str(MACHINES / "counter.machine"),
        "-o",
        str(tmp_path),
    ]
    status, _out, shown = on_pty(argv, cwd=REPO)
    assert status == 0, shown
    assert "native: compiling 1 machine(s) and the runtime with mypyc... 1 s" in shown, shown
    assert "\r\x1b[K" in shown  # rewritten in place, then cleared
    assert "native: 0 of 1 machines compiled" in shown.split("\r\x1b[K")[-1]  # the last word starts on a clean line


def test_nothing_of_it_in_a_pipe(tmp_path: Path) -> None:
    argv = [
        sys.executable,
        "-c",
        FAKE_NATIVE,
        "build",
        "--native",
        str(MACHINES / "counter.machine"),
        "-o",
        str(tmp_path),
    ]
    r = subprocess.run(argv, capture_output=True, text=True, cwd=REPO, timeout=120)
    assert r.returncode == 0, r.stderr
    assert "compiling" not in r.stderr and "\r" not in r.stderr and "\x1b" not in r.stderr


class FakeTerminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_the_status_line_is_cut_to_the_terminal_and_lines_go_above_it(monkeypatch) -> None:
    monkeypatch.setenv("COLUMNS", "20")
    monkeypatch.delenv("TERM", raising=False)
    term = FakeTerminal()
    s = Status(term)
    s.show("recording 12 topics to a very long folder name", now=True)
    s.print("llfsm: a warning")
    s.clear()
    assert term.getvalue() == ("\r\x1b[Krecording 12 topic…\r\x1b[Kllfsm: a warning\nrecording 12 topic…\r\x1b[K")


def test_a_dumb_terminal_or_a_file_gets_nothing(monkeypatch) -> None:
    monkeypatch.setenv("TERM", "dumb")
    term = FakeTerminal()
    s = Status(term)
    with s.ticking(lambda t: "busy"):
        time.sleep(0.05)
    s.print("a line of the command's own")
    assert term.getvalue() == "a line of the command's own\n"


def test_long_work_that_asks_for_a_log_writes_its_line_there_now_and_then(monkeypatch) -> None:
    """`llfsm verify` in CI: off a terminal, a plain line once the work has run 2 s, then every
    10 s; on a terminal the same calls draw the status line each time."""
    monkeypatch.setenv("COLUMNS", "80")
    monkeypatch.delenv("TERM", raising=False)
    log = io.StringIO()
    s = Status(log, log_after=2.0, log_every=10.0)
    for t in (0.5, 1.9, 2.0, 3.0, 11.9, 12.0, 13.0, 22.5):
        s.progress(f"at {t}", t)
    s.clear()
    assert log.getvalue() == "at 2.0\nat 12.0\nat 22.5\n"
    quiet = io.StringIO()
    Status(quiet).progress("work that asked for no log", 60.0)
    assert quiet.getvalue() == ""
    term = FakeTerminal()
    s = Status(term, log_after=2.0)
    s.progress("at 0.5", 0.5)
    s.progress("at 1.5", 1.5)
    s.clear()
    assert term.getvalue() == "\r\x1b[Kat 0.5\r\x1b[Kat 1.5\r\x1b[K"


def test_seconds() -> None:
    assert [seconds(x) for x in (0.4, 7.9, 125)] == ["0 s", "7 s", "2 min 05 s"]
