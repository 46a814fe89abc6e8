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


def test_seconds() -> None:
    assert [seconds(x) for x in (0.4, 7.9, 125)] == ["0 s", "7 s", "2 min 05 s"]
