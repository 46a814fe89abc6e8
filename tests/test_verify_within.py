"""SPEC 16: `within: DURATION` on leads_to, verified exactly under --period, refused in abstract
time; the exports say they do not carry it; and the hint at the state limit in exact time."""

from __future__ import annotations

from pathlib import Path

from helpers import MACHINES, llfsm, write_machine


def _file(tmp_path: Path, within: str, period: str | None = "100ms") -> Path:
    m = write_machine(tmp_path, "d", {"A": [("B", "after(1)")], "B": [("A", "True")]})
    f = tmp_path / "d.verify.yaml"
    f.write_text(
        f"machines: [{m}]\n"
        + (f"period: {period}\n" if period else "")
        + f'properties:\n  - leads_to: [state(d) == "A", state(d) == "B"]\n    within: {within}\n'
    )
    return f


def test_a_deadline_met_exactly_holds_and_one_period_less_fails(tmp_path: Path) -> None:
    # A is current from the round its transition fires; after(1) counts from its OnEntry, a round
    # later, and fires one period past the second: B comes 1.2 s after A at the latest
    r = llfsm("verify", _file(tmp_path, "1200ms"))
    assert r.status == 0, r.stdout + r.stderr
    r = llfsm("verify", _file(tmp_path, "1100ms"))
    assert r.status == 1
    assert "fails" in r.stdout and "counterexample" in r.stdout


def test_a_deadline_in_abstract_time_is_refused_with_the_reason(tmp_path: Path) -> None:
    r = llfsm("verify", _file(tmp_path, "1s", period=None))
    assert r.status == 2
    assert "needs exact time (--period P" in r.stderr


def test_the_exports_say_they_do_not_carry_a_deadline(tmp_path: Path) -> None:
    f = _file(tmp_path, "1200ms")
    r = llfsm("verify", f, "--export", "smv", tmp_path / "d.smv", "--export", "promela", tmp_path / "d.pml", "-q")
    assert r.status == 0
    assert "deadline (within), which this export does not carry" in (tmp_path / "d.smv").read_text()
    assert "deadline (within), which this export does not carry" in (tmp_path / "d.pml").read_text()


def test_within_on_another_kind_is_one_line(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "e", {"A": None})
    f = tmp_path / "e.verify.yaml"
    f.write_text(f'machines: [{m}]\nperiod: 1ms\nproperties:\n  - always: state(e) == "A"\n    within: 1s\n')
    r = llfsm("verify", f)
    assert r.status == 2 and "`within:` is a deadline for leads_to" in r.stderr


def test_exact_time_at_the_state_limit_says_waiting_grew_and_suggests_a_period() -> None:
    r = llfsm(
        "verify", MACHINES / "ros2_blind_turtle_bot.machine", "--period", "1ms", "--max-states", "500",
        "--property", "always: True",
    )  # fmt: skip
    assert r.status == 3
    assert "waiting is what grew" in r.stdout
    assert "ros2_blind_turtle_bot INITIAL 1,000" in r.stdout
    assert "--period 1s keeps every after* threshold exact" in r.stdout
