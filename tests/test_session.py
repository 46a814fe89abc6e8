"""The run session (llfsm.session) driven without a subprocess: options in, a typed session that
opens what the options ask for, typed errors instead of an exit, and everything closed after."""

from __future__ import annotations

from pathlib import Path

import pytest
from helpers import MACHINES, write_machine

from llfsm.cli.run_args import RUN_OPTIONS, TARGETS, parse, run_options
from llfsm.runtime import RunContext
from llfsm.session import FIELDS, MachineFailed, RunOptions, Session, SessionError, UsageError

SIM = {"clock": "sim"}


def test_the_options_are_the_table_of_llfsm_run() -> None:
    assert (TARGETS, *(o.dest for o in RUN_OPTIONS)) == FIELDS


def test_the_defaults_are_those_of_a_run_with_no_option(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("LLFSM_TRANSPORT", raising=False)
    assert run_options([]) == RunOptions()
    keywords = parse(["a.machine", "--clock", "sim", "--node", "turtlesim"])
    assert keywords is not None
    assert RunOptions(**keywords) == RunOptions(("a.machine",), clock="sim", nodes=("turtlesim",))
    assert run_options(["--help"]) is None


def test_options_are_frozen_and_replaced_as_a_copy() -> None:
    o = RunOptions(("a.machine",))
    with pytest.raises(AttributeError):
        o.clock = "sim"  # type: ignore[misc]
    p = o.replace(clock="sim")
    assert (o.clock, p.clock, p.targets) == ("wall", "sim", ("a.machine",))
    assert p != o and hash(p) == hash(RunOptions(("a.machine",), clock="sim"))
    assert "clock='sim'" in repr(p)


def test_usage_errors_are_raised_not_exits() -> None:
    with pytest.raises(UsageError) as e:
        Session(RunOptions(("x.machine",), period=0))
    assert (e.value.message, e.value.status) == ("--period must be greater than 0", 2)
    with pytest.raises(UsageError, match="nothing to run"):
        Session(RunOptions())
    with pytest.raises(UsageError, match="--clock sim cannot be used with --transport dds"):
        Session(RunOptions(("x.machine",), clock="sim", transport="dds"))


def test_a_machine_with_errors_is_reported_with_its_diagnostics(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "broken", {"INITIAL": [("END", "true and")], "END": None})
    with pytest.raises(UsageError) as e:
        Session(RunOptions((str(m),), **SIM)).run()
    assert e.value.message == f"{m}: the machine has errors; nothing was run"
    assert "error" in e.value.details and e.value.details.endswith("\n")


def test_an_initial_value_that_raises_is_a_machine_error(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "init", {"INITIAL": None}, variables="x: int = 1 // 0\n")
    with pytest.raises(MachineFailed) as e:
        Session(RunOptions((str(m),), **SIM)).run()
    assert e.value.status == 1 and "ZeroDivisionError" in e.value.details
    assert e.value.report.section == "Variables"


def test_a_plain_run_opens_nothing_beside_its_machines(capsys: pytest.CaptureFixture[str]) -> None:
    session = Session(RunOptions((str(MACHINES / "counter.machine"),), **SIM))
    outcome = session.run()
    assert (outcome.result.reason, outcome.status, outcome.failed_outputs, outcome.graph) == ("finished", 0, [], None)
    assert session.bus is None and session.transport is None and session.bags is None and session.nodes == {}
    assert session.arrangement is not None and session.ctx is session.arrangement.ctx
    assert session.ctx.bus is None and session.ctx.arrangement is session.arrangement
    assert "done" in capsys.readouterr().out


def test_nodes_bus_and_world_are_typed_attributes_of_the_session(tmp_path: Path) -> None:
    said: list[str] = []
    options = RunOptions(
        clock="sim", duration=50_000_000, nodes=("turtlesim",), params=("turtlesim:background_r:=10",), introspect=True
    )
    session = Session(options, say=said.append)
    outcome = session.run()
    assert outcome.status == 0 and outcome.result.reason == "duration"
    assert session.bus is not None and session.ctx is not None and session.ctx.bus is session.bus
    assert list(session.nodes) == ["turtlesim"] and session.world is not None
    assert session.parameters == {("turtlesim", "background_r"): 10}
    assert outcome.graph is not None and "/turtle1/pose" in outcome.graph["topics"]


def test_a_node_that_cannot_start_is_a_usage_error_and_the_bag_is_still_closed(tmp_path: Path) -> None:
    pytest.importorskip("mcap")
    options = RunOptions(
        (str(MACHINES / "counter.machine"),), clock="sim", nodes=("nonesuch",), record=str(tmp_path / "bag")
    )
    session = Session(options)
    with pytest.raises(SessionError) as e:
        session.run()
    assert e.value.status == 2 and e.value.message.startswith("--node nonesuch: no such node")
    assert (tmp_path / "bag" / "metadata.yaml").exists()


def test_the_run_context_has_no_untyped_slots() -> None:
    assert not hasattr(RunContext(), "extras")
