"""SPEC 16: properties judged while a run goes on (`--monitor`, `--monitor-property`,
`--on-violation`), under the sim clock."""

from __future__ import annotations

from pathlib import Path

from click.testing import CliRunner
from helpers import MACHINES, llfsm, write_machine

from llfsm.cli import cli

PING = MACHINES / "ros2_ping_pong.machine"


def run(*args: object):  # type: ignore[no-untyped-def]
    return llfsm("run", "--clock", "sim", *args)


def test_a_safety_property_violated_is_one_line_and_the_run_goes_on() -> None:
    r = run("--duration", "3s", PING, "--monitor-property", "never: ros2_ping_pong.count >= 2")
    assert r.status == 0
    line = next(x for x in r.stderr.splitlines() if "violated" in x)
    assert line.startswith("llfsm: monitor: never: ros2_ping_pong.count >= 2 violated at 2.508 s, ringlet 2509:")
    assert "ros2_ping_pong WAIT_AND_COUNT" in line and "ros2_ping_pong.count=2" in line


def test_stop_ends_the_run_with_status_4_and_log_does_not() -> None:
    r = run(
        "--duration", "3s", PING, "--monitor-property", "never: ros2_ping_pong.count >= 2", "--on-violation", "stop"
    )
    assert r.status == 4
    assert "The count is 2" not in r.stdout + r.stderr
    r = run(
        "--duration", "3s", PING, "--monitor-property", "always: ros2_ping_pong.count < 9", "--on-violation", "stop"
    )
    assert r.status == 0 and "violated" not in r.stderr


def test_pause_pauses_the_run_where_the_property_is_violated() -> None:
    args = [
        "run",
        "--clock",
        "sim",
        "--duration",
        "4s",
        str(PING),
        "--monitor-property",
        "never: ros2_ping_pong.count >= 2",
    ]
    res = CliRunner().invoke(cli, [*args, "--on-violation", "pause"], input="p ros2_ping_pong.count\nc\n")
    assert res.exit_code == 0
    assert (
        "paused after ros2_ping_pong's ringlet (2.508 s): monitor: never: ros2_ping_pong.count >= 2 violated"
        in res.stderr
    )
    assert "(llfsm) 2\n" in res.stderr  # read at the prompt, where it was violated
    assert "The count is 2" in res.stderr  # then it went on


def test_ctl_is_refused_with_the_reason() -> None:
    r = run("--duration", "1s", PING, "--monitor-property", 'ctl: AG EF state(ros2_ping_pong) == "PUBLISH"')
    assert r.status == 2 and "a run is one path" in r.stderr


def test_ltl_reachable_and_eventually_at_the_end() -> None:
    r = run(
        "--duration", "3s", PING,
        "--monitor-property", 'ltl: G F published("/pingpong")',
        "--monitor-property", 'reachable: state(ros2_ping_pong) == "PUBLISH"',
        "--monitor-property", "eventually: finished(ros2_ping_pong)",
        "--monitor-property", 'ltl: F state(ros2_ping_pong) == "PUBLISH"',
        "--monitor-property", 'ltl: G state(ros2_ping_pong) == "INITIAL"',
    )  # fmt: skip
    assert r.status == 0
    err = r.stderr
    assert 'ltl: G F published("/pingpong"): pending at the end' in err
    assert 'reachable: state(ros2_ping_pong) == "PUBLISH": held at some boundary' in err
    assert "eventually: finished(ros2_ping_pong): not seen in this run" in err
    assert 'ltl: F state(ros2_ping_pong) == "PUBLISH": satisfied' in err
    assert 'ltl: G state(ros2_ping_pong) == "INITIAL" violated at 1.001 s' in err


def _deadline(tmp_path: Path, within: str) -> Path:
    m = write_machine(tmp_path, "d", {"A": [("B", "after(1)")], "B": None})
    f = tmp_path / "d.verify.yaml"
    f.write_text(
        f'machines: [{m}]\nproperties:\n  - leads_to: [state(d) == "A", state(d) == "B"]\n    within: {within}\n'
    )
    return f


def test_a_deadline_met_exactly_holds_and_one_period_less_is_violated(tmp_path: Path) -> None:
    f = _deadline(tmp_path, "1001ms")  # A from 0, B at 1.001 s (the first 1 ms round past a second)
    r = run("--period", "1ms", "--monitor", f, tmp_path / "d.machine")
    assert r.status == 0 and "violated" not in r.stderr, r.stderr
    f = _deadline(tmp_path, "1s")
    r = run("--period", "1ms", "--monitor", f, tmp_path / "d.machine")
    assert "violated at 1.001 s" in r.stderr and "within the deadline" in r.stderr
