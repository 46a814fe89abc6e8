"""What the tests share: writing machine directories from a compact description, running the
command in-process or as a process, the C parts' skip rules, and the checks of generated modules
that more than one test module makes.  Test modules import from here (`from helpers import ...`),
never from conftest.py (which holds only fixtures and hooks) nor from one another; other helper
modules beside this one: strategies.py (hypothesis), samples.py (shipped message classes and
samples of them), dds_netns.py (the private network namespace of the DDS tests), clfsm_writer.py
(clfsm machine directories, for the tests of `llfsm import`).
"""

from __future__ import annotations

import ast
import contextlib
import errno
import functools
import io
import json
import os
import subprocess
import sys
import sysconfig
import tokenize
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner

from llfsm.cli import cli
from llfsm.runtime.generated import SOURCE_MAP
from llfsm.templating import CODING_LINE

REPO = Path(__file__).resolve().parent.parent
MACHINES = REPO / "machines"

# -- machines and runs ----------------------------------------------------------------------------


@contextlib.contextmanager
def disk_full_at(nth: int) -> Iterator[None]:
    """Inside it, the disk fills up as llfsm.edit writes the `nth` file of a change (counted
    from 1; those before it are written): how every writer of machine directories is tested
    against a full disk (llfsm.edit stages each file beside its place, then renames them all)."""
    from llfsm.edit import change

    real, calls = change._stage, []

    def staged(*args: Any) -> str:
        calls.append(args)
        if len(calls) == nth:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(*args)

    change._stage = staged  # restored below, whatever happens
    try:
        yield
    finally:
        change._stage = real


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


def turning_machine(root: Path) -> Path:
    """`w`: FORWARD until its input wall_close (bound to /turtle1/wall_close) holds, then TURN,
    counting its turns, back to FORWARD once clear and 150 ms have passed: the machine of the
    counterexample tests (a counterexample of `never: w.turns == 2 and state(w) == "TURN"`)."""
    return write_machine(
        root,
        "w",
        {
            "INITIAL": [("FORWARD", "True")],
            "FORWARD": [("TURN", "wall_close")],
            "TURN": [("FORWARD", "not wall_close and after_ms(150)")],
        },
        {"TURN_OnEntry": "turns += 1"},
        variables="turns: int = 0\n",
        yaml_extra=(
            "inputs:\n  wall_close:\n    type: bool\n    topic: /turtle1/wall_close\n"
            "    msg: std_msgs/msg/Bool\n    field: data\n"
        ),
    )


def driver(root: Path) -> Path:
    """A machine that publishes a Twist on /turtle1/cmd_vel and a String on /chat every 100 ms
    of run time (more than 100 ms after entering DRIVE: entries at 1 ms, 103 ms, 205 ms...):
    what the recording tests record."""
    return write_machine(
        root,
        "driver",
        {"INITIAL": [("DRIVE", "True")], "DRIVE": [("DRIVE", "after_ms(100)")]},
        {
            "INITIAL_OnEntry": (
                "ros.init()\nnode = ros.Node('driver')\n"
                "pub = node.create_publisher(Twist, '/turtle1/cmd_vel', 10)\n"
                "chat = node.create_publisher(String, '/chat', 10)\n"
            ),
            "DRIVE_OnEntry": (
                "n += 1\nt = Twist()\nt.linear.x = 1.0 + n % 3\nt.angular.z = 0.5 * (n % 5 - 2)\npub.publish(t)\n"
                "s = String()\ns.data = f'step {n}'\nchat.publish(s)\n"
            ),
        },
        variables="n: int = 0\npub: ros.Publisher\nchat: ros.Publisher\nnode: ros.Node\n",
        includes=(
            "from llfsm import ros\nfrom llfsm.msgs.geometry_msgs.msg import Twist\n"
            "from llfsm.msgs.std_msgs.msg import String\n"
        ),
    )


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


def on_pty(argv: list[str], timeout: float = 120, columns: int = 200, **kw: object) -> tuple[int, str, str]:
    """(status, stdout, what the terminal showed) of a command whose stderr is a terminal
    `columns` wide (a pseudo-terminal, as in a user's shell): what llfsm.progress draws there."""
    import fcntl
    import pty
    import select
    import struct
    import termios
    import time

    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, columns, 0, 0))
    p = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=slave, stdin=subprocess.DEVNULL, **kw)  # type: ignore[call-overload]
    os.close(slave)
    chunks = []
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        ready, _, _ = select.select([master], [], [], 0.2)
        if ready:
            try:
                data = os.read(master, 4096)
            except OSError:  # EIO: every holder of the terminal has gone
                break
            if not data:
                break
            chunks.append(data)
        elif p.poll() is not None:
            break
    os.close(master)
    out = p.stdout.read().decode() if p.stdout else ""
    p.wait(timeout=30)
    return p.returncode, out, b"".join(chunks).decode(errors="replace")


# -- the C parts ----------------------------------------------------------------------------------

#: The C parts (the recorder's tap, turtlesim's painter) are left out on purpose in two cases:
#: LLFSM_NO_C=1 (the run of the suite that tests the Python code they stand in for) and
#: free-threaded CPython (setup.py does not build them there).
C_DISABLED = os.environ.get("LLFSM_NO_C", "") not in ("", "0")
FREE_THREADED = bool(sysconfig.get_config_var("Py_GIL_DISABLED"))
C_OFF = C_DISABLED or FREE_THREADED
#: With LLFSM_REQUIRE_C=1 (`make test` sets it) a C part that was not built is a failure, not a
#: skip: the numbers docs/recording.md gives assume them, and CI measures what the docs claim.
REQUIRE_C = os.environ.get("LLFSM_REQUIRE_C", "") not in ("", "0")


def skip_unless_built(built: bool, what: str) -> pytest.MarkDecorator:
    """Skip, saying why, a test of a C part (`what`: "the C tap (llfsm/bag/_tap.c)") that is not
    there; under LLFSM_REQUIRE_C=1 an unbuilt one is not skipped, so that the test fails."""
    if C_OFF:
        why = f"{what} is off on purpose (LLFSM_NO_C, or free-threaded CPython)"
    else:
        why = f"{what} is not built: no C compiler, or not CPython with the GIL (LLFSM_REQUIRE_C=1 makes this fail)"
    return pytest.mark.skipif(not built and (C_OFF or not REQUIRE_C), reason=why)


# -- generated modules and SARIF ------------------------------------------------------------------


def header_ok(source: str) -> None:
    """The first lines of a generated module are comments, one line each, ASCII, with the fixed
    coding line second."""
    lines = source.split("\n")
    assert lines[0].startswith("# Generated by llfsm")
    assert lines[1] == CODING_LINE
    enc, _ = tokenize.detect_encoding(io.BytesIO(source.encode("utf-8")).readline)
    assert enc in ("utf-8", "utf-8-sig")
    header = []
    for line in lines:
        if not line.startswith("#"):
            break
        header.append(line)
    assert all(h.isascii() and h.isprintable() for h in header), header
    toks = list(tokenize.generate_tokens(io.StringIO(source).readline))
    comments = [t for t in toks if t.type == tokenize.COMMENT and t.start[0] <= len(header)]
    assert [c.start[0] for c in comments] == list(range(1, len(header) + 1))
    assert all(c.start[0] == c.end[0] for c in comments)


def only_expected_statements(tree: ast.Module) -> None:
    """A machine module holds its docstring, imports (the runtime's and those of Includes.py,
    which check allows to hold nothing else), functions and the class, and its source map:
    any other statement at module level got in from somewhere else."""
    for i, stmt in enumerate(tree.body):
        if i == 0 and isinstance(stmt, ast.Expr) and isinstance(stmt.value, ast.Constant):
            continue
        if isinstance(stmt, ast.Import | ast.ImportFrom):
            continue
        if isinstance(stmt, ast.FunctionDef | ast.ClassDef):
            continue
        if isinstance(stmt, ast.Assign) and [getattr(t, "id", "") for t in stmt.targets] == [SOURCE_MAP]:
            continue
        raise AssertionError(f"unexpected statement at line {stmt.lineno}: {ast.unparse(stmt)[:80]}")
    assert isinstance(tree.body[-1], ast.Assign)


@functools.cache
def sarif_validator() -> object:
    """A validator of SARIF 2.1.0 (tests/data/sarif-schema-2.1.0.json, draft 4) that checks formats."""
    jsonschema = pytest.importorskip("jsonschema")
    schema = json.loads((Path(__file__).parent / "data" / "sarif-schema-2.1.0.json").read_text(encoding="utf-8"))
    # the schema is draft 4; FormatChecker() knows `uri-reference` (rfc3986-validator)
    checker = jsonschema.FormatChecker()
    assert not checker.conforms("a b#c#d", "uri-reference"), "uri-reference is not checked: install the extras"
    return jsonschema.Draft4Validator(schema, format_checker=checker)


def strings_in(value: object) -> list[str]:
    """Every string in a JSON value, keys included."""
    if isinstance(value, str):
        return [value]
    if isinstance(value, dict):
        return [s for k, v in value.items() for s in (*strings_in(k), *strings_in(v))]
    if isinstance(value, list):
        return [s for v in value for s in strings_in(v)]
    return []
