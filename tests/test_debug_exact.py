"""The debugger's exactness (SPEC 14, docs/debug.md): under the sim clock, a run paused, stepped,
stopped at breakpoints and continued gives the same standard output, `--trace` and bag, byte for
byte, as the same run never paused; and its prompt, driven through standard input as a script
would drive it."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner
from helpers import MACHINES, Run

from llfsm.cli import cli

BOT = "ros2_blind_turtle_bot"
BOSS = "ros2_turtle_suspend_resume"


def run_with_input(args: list[str], text: str | None = None) -> Run:
    """`llfsm run ARGS` in process, standard input fed with `text` (the prompt's commands)."""
    res = CliRunner().invoke(cli, ["run", *args], input=text, catch_exceptions=False)
    return Run(res.exit_code, res.stdout, res.stderr)


def _outputs(tmp_path: Path, name: str, args: list[str], commands: str | None) -> tuple[Run, bytes, bytes]:
    """The run, its trace and its bag (the same bag name in each folder: the name is in the bag)."""
    folder = tmp_path / name
    folder.mkdir()
    trace, bag = folder / "t.jsonl", folder / "bag"
    r = run_with_input(["--clock", "sim", *args, "--trace", str(trace), "--record", str(bag)], commands)
    mcap = next(bag.glob("*.mcap")).read_bytes()
    return r, trace.read_bytes(), mcap + (bag / "metadata.yaml").read_bytes().replace(str(folder).encode(), b"")


def _same_run(tmp_path: Path, args: list[str], commands: str) -> Run:
    plain, plain_trace, plain_bag = _outputs(tmp_path, "plain", args, None)
    debugged, trace, bag = _outputs(tmp_path, "debugged", [*args, "--paused"], commands)
    assert plain.status == debugged.status == 0, debugged.stderr
    assert debugged.stdout == plain.stdout
    assert trace == plain_trace
    assert bag == plain_bag
    assert "(llfsm) " in debugged.stderr and "(llfsm) " not in debugged.stdout
    return debugged


def test_the_how_to_pair_paused_stepped_and_continued_is_the_same_run(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv("RCUTILS_LOGGING_USE_STDOUT", "1")  # the nodes' and machines' log lines on stdout too
    args = [str(MACHINES / f"{BOSS}.machine"), str(MACHINES / f"{BOT}.machine"), "--node", "turtlesim"]
    args += ["--duration", "6s"]
    commands = "\n".join(
        [
            "s",  # the controller's first ringlet
            "s",  # the bot's
            "n",  # a whole round
            f'b state({BOT}) == "TURN_RIGHT"',
            "c",
            "w",
            f"p {BOT}",
            "s",
            "n",
            "cl",
            f'b fired({BOSS}, "RESUME", 1)',
            "c",
            "hist 2",
            "cl",
            "c",
        ]
    )
    r = _same_run(tmp_path, args, commands + "\n")
    err = r.stderr
    assert "paused before the first round (0.000 s): --paused" in err
    assert f'break 1: state({BOT}) == "TURN_RIGHT"' in err
    assert f"> {BOT}: TURN_RIGHT" in err  # `w` marks the machine whose ringlet the pause follows
    assert f'break 2: fired({BOSS}, "RESUME", 1)' in err
    assert "no history is kept: run with --history N" in err  # `hist` without --history


def test_a_machine_with_an_input_paused_at_a_breakpoint_is_the_same_run(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv("RCUTILS_LOGGING_USE_STDOUT", "1")
    args = [str(MACHINES / "wall_follower.machine"), "--node", "turtlesim", "--node", "wall_sensor"]
    args += ["--duration", "12s", "--echo", "/turtle1/wall_close", "--history", "100"]
    commands = "\n".join(
        [
            "b wall_follower.wall_close",  # pauses where the sensor's input turns true
            "c",
            "p wall_follower.wall_close",
            "hist 3",
            "s",
            "c",  # the next time it turns true
            "cl",
            "c",
        ]
    )
    r = _same_run(tmp_path, args, commands + "\n")
    assert r.stderr.count("break 1: wall_follower.wall_close") == 2
    assert "(llfsm) True\n" in r.stderr  # p: the input as the machine holds it at the pause
    assert "wall_close: False -> True" in r.stderr  # hist: the ringlet that took the new value


def test_the_prompt_reads_sets_and_refuses_in_one_line(tmp_path: Path) -> None:
    counter = MACHINES / "counter.machine"
    commands = "\n".join(
        [
            "p counter",
            "set counter.count = 3",
            "set counter.count = hello",
            "set counter.nope = 1",
            "set counter.limit = 2.5",
            'b state(counter) == "NOPE"',
            "b counter.count == 4",
            "c",
            "p counter.count * 10",
            "w",
            "frobnicate",
            "c",
        ]
    )
    r = run_with_input([str(counter), "--clock", "sim", "--paused"], commands + "\n")
    assert r.status == 0
    out = r.stdout.splitlines()
    assert out[0] == "counter starts, counting to 5"
    assert "count = 4 at state COUNT" in out and "count = 2 at state COUNT" not in out  # set to 3 while paused
    err = r.stderr
    assert "  state: INITIAL\n" in err and "    count: 0\n" in err  # p counter, as YAML
    assert "counter.count = 3" in err
    assert "*** counter.count is int: 'hello' is a string, not an int" in err
    assert "*** counter has no variable or input nope; it has: count, limit" in err
    assert "*** counter.limit is int: 2.5 is a float, not an int" in err
    assert '*** break: `state(counter) == "NOPE"`: counter has no state NOPE' in err
    assert "break 1: counter.count == 4" in err
    assert "(llfsm) 40\n" in err
    assert "*** unknown command 'frobnicate' (h for help)" in err


def test_end_of_input_lets_the_run_finish(tmp_path: Path) -> None:
    r = run_with_input([str(MACHINES / "counter.machine"), "--clock", "sim", "--break", "counter.count == 2"], "")
    assert r.status == 0
    assert "done" in r.stdout.splitlines()
    assert "end of the debugger's input: the run goes on without breakpoints" in r.stderr


@pytest.mark.parametrize(
    ("expr", "message"),
    [
        ('state(counter) = "COUNT"', "--break 'state(counter) = \"COUNT\"': not an expression"),
        ('state(countr) == "COUNT"', "no machine named countr (did you mean counter?)"),
        ("counter.cuont > 1", "counter has no variable or input cuont (did you mean counter.count?)"),
        ('fired(counter, "COUNT", 7)', "state COUNT of counter has transitions 0 to 1, not 7"),
    ],
)
def test_a_bad_break_is_refused_before_the_run_starts(expr: str, message: str) -> None:
    r = run_with_input([str(MACHINES / "counter.machine"), "--clock", "sim", "--break", expr])
    assert r.status == 2
    assert r.stdout == ""  # nothing ran
    assert message in r.stderr and r.stderr.count("\n") == 1, r.stderr


def test_the_trace_records_what_changed_and_the_diagrams(tmp_path: Path) -> None:
    trace = tmp_path / "t.jsonl"
    r = run_with_input([str(MACHINES / "counter.machine"), "--clock", "sim", "--trace", str(trace)])
    assert r.status == 0
    events = [json.loads(line) for line in trace.read_text().splitlines()]
    first = events[0]
    assert first["event"] == "machine" and first["variables"] == {"count": 0, "limit": 5}
    assert [s["name"] for s in first["description"]["states"]][:3] == ["INITIAL", "COUNT", "END"]
    changes = [e["changed"] for e in events if e["event"] == "variables"]
    assert changes == [{"count": [n, n + 1]} for n in range(5)]


def test_on_a_terminal_the_prompt_completes_names_with_readline() -> None:
    import os
    import pty
    import select
    import sys
    import time

    pid, fd = pty.fork()
    if pid == 0:  # the child: a run on the terminal
        os.execv(
            sys.executable,
            [sys.executable, "-m", "llfsm", "run", "--clock", "sim", str(MACHINES / "counter.machine"), "--paused"],
        )
    out = b""

    def read(until: bytes, timeout: float = 20) -> None:
        nonlocal out
        end = time.monotonic() + timeout
        while until not in out and time.monotonic() < end:
            if select.select([fd], [], [], 0.1)[0]:
                try:
                    out += os.read(fd, 4096)
                except OSError:
                    return

    try:
        read(b"(llfsm) ")
        os.write(fd, b"p coun\t.co\t\n")  # tab: counter, then counter.count
        read(b"ter.count\r\n0\r\n(llfsm) ")  # the next prompt: typed before it, the terminal echoes
        os.write(fd, b"c\n")
        read(b"done")
    finally:
        os.waitpid(pid, 0)
    # typed `coun`, `.co` and tabs: readline completed the rest, and `p` printed the count
    assert b"ter.count\r\n0\r\n(llfsm) " in out and b"done" in out
