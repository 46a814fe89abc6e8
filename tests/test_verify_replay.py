"""`llfsm verify --counterexample DIR` (SPEC 11): the counterexample's inputs bound to topics as a
rosbag2 bag, which `llfsm run --clock sim --period P --play DIR` replays to the same
configuration."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest
from helpers import MACHINES, llfsm, turning_machine, write_machine

NEVER_TURN = 'never: state(wall_follower) == "TURN"'


def _trace(path: Path) -> list[dict]:  # type: ignore[type-arg]
    return [json.loads(line) for line in path.read_text().splitlines()]


def test_a_counterexample_bag_replays_to_the_same_configuration(tmp_path: Path) -> None:
    # wall_close must be clear in round 1, then close for two rounds, then clear again: the
    # shortest way to see the turtle go FORWARD -> TURN -> FORWARD with a count of 2 turns
    m = turning_machine(tmp_path)
    bag = tmp_path / "cx"
    r = llfsm(
        "verify", m, "--period", "100ms", "--property", 'never: w.turns == 2 and state(w) == "TURN"',
        "--counterexample", bag, "--format", "json",
    )  # fmt: skip
    assert r.status == 1, r.stdout + r.stderr
    steps = json.loads(r.stdout)["properties"][0]["counterexample"]["steps"]
    assert "replay it with: llfsm run --clock sim --period 100ms --play" in r.stderr
    rounds = steps[-1]["round"] + 1
    # the states the counterexample goes through, round by round
    expected = [(s["round"], s["state"]) for s in steps if s["transition"] is not None]
    trace = tmp_path / "t.jsonl"
    run = llfsm(
        "run", "--clock", "sim", "--period", "100ms", "--play", bag, "--duration", f"{rounds * 100}ms",
        "--trace", trace, m,
    )  # fmt: skip
    assert run.status == 0, run.stderr
    events = _trace(trace)
    got = [(e["round"], e["target"]) for e in events if e["event"] == "transition"]
    assert got == expected
    # and TURN's second entry (turns becomes 2) in the counterexample's last round
    entries = [(e["round"], e["state"]) for e in events if e["event"] == "entry" and e["state"] == "TURN"]
    assert len(entries) == 2 and entries[-1] == (rounds - 1, "TURN")
    assert [s["inputs"]["wall_close"] for s in steps].count(True) >= 2


def test_the_wall_follower_counterexample_replays_against_its_sensor_topic(tmp_path: Path) -> None:
    bag = tmp_path / "cx"
    machine = MACHINES / "wall_follower.machine"
    r = llfsm("verify", machine, "--period", "100ms", "--property", NEVER_TURN, "--counterexample", bag)
    assert r.status == 1
    trace = tmp_path / "t.jsonl"
    run = llfsm(
        "run", "--clock", "sim", "--period", "100ms", "--play", bag, "--duration", "200ms", "--trace", trace, machine,
    )  # fmt: skip
    assert run.status == 0, run.stderr
    last = [e for e in _trace(trace) if e["event"] == "transition"][-1]
    assert (last["round"], last["target"]) == (1, "TURN")


def test_the_suggested_replay_shows_the_state_that_breaks_the_property(tmp_path: Path) -> None:
    """Issue 27, item 3: the printed command's `-v` trace ended in FORWARD, a round short of TURN."""
    bag = tmp_path / "cx"
    machine = MACHINES / "wall_follower.machine"
    r = llfsm("verify", machine, "--period", "100ms", "--property", NEVER_TURN, "--counterexample", bag)
    suggested = r.stderr.split("replay it with: llfsm ")[1].splitlines()[0].split()
    assert suggested[suggested.index("--duration") + 1] == "300ms"
    run = llfsm(*suggested, "-v")
    assert run.status == 0, run.stderr
    states = [line.split(" - ")[-1] for line in run.stderr.splitlines() if line.startswith("m  0")]
    assert states == ["INITIAL", "FORWARD", "TURN"]


def test_counterexample_without_the_bag_extra_says_so_before_exploring(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Issue 27, item 2: `make demo` installs no bag extra; verify explored, then ended in an
    internal error with a half-written bag."""
    monkeypatch.setitem(sys.modules, "mcap", None)  # as if not installed: importing it fails
    bag = tmp_path / "cx"
    r = llfsm("verify", MACHINES / "wall_follower.machine", "--period", "100ms", "--property", NEVER_TURN,
              "--counterexample", bag)  # fmt: skip
    assert r.status == 2 and r.stdout == ""  # nothing explored
    assert r.stderr == (
        f"llfsm: --counterexample {bag}: bags need the 'bag' extra (mcap is missing): pip install 'llfsm[bag]'\n"
    )
    assert not bag.exists()


def test_the_report_is_printed_whatever_happens_to_the_bag(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "mcap.writer", None)  # a broken install: mcap is there, its writer is not
    bag = tmp_path / "cx"
    r = llfsm("verify", MACHINES / "wall_follower.machine", "--period", "100ms", "--property", NEVER_TURN,
              "--counterexample", bag)  # fmt: skip
    assert r.status == 1  # the verdict: the property fails
    assert r.stdout.startswith(f"{NEVER_TURN}: fails") and "then: wall_follower TURN" in r.stdout
    assert "llfsm: --counterexample: mcap.writer cannot be imported: pip install 'llfsm[bag]'\n" in r.stderr
    assert not bag.exists()  # no half-written bag
    there = llfsm("verify", MACHINES / "wall_follower.machine", "--period", "100ms", "--property", NEVER_TURN,
                  "--counterexample", tmp_path)  # fmt: skip
    assert there.status == 2 and there.stderr.endswith(f"output folder '{tmp_path}' already exists\n")


def test_what_a_bag_cannot_carry_is_said(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "u",
        {"A": [("B", "mode == 2")], "B": None},
        yaml_extra="inputs:\n  mode:\n    type: int\n    domain: [1, 2]\n    default: 1\n",
    )
    never_b = 'never: state(u) == "B"'
    r = llfsm("verify", m, "--period", "10ms", "--property", never_b, "--counterexample", tmp_path / "cx")
    assert r.status == 1
    assert "input mode of u is bound to no topic, so a run keeps its default 1" in r.stderr
    assert not (tmp_path / "cx").exists()
    r = llfsm("verify", m, "--property", never_b, "--counterexample", tmp_path / "cx")
    assert r.status == 2 and "give --period P" in r.stderr
