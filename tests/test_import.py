"""`llfsm import` (SPEC 15): clfsm machine directories in, llfsm machine directories out, with
the structure exact, the code translated where it is clear, and nothing executed or written
outside -o.  The clfsm machines are written by tests/clfsm_writer.py (ours, not MiPal's)."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from clfsm_writer import HOW_TO, ClfsmState, write_clfsm
from helpers import MACHINES, disk_full_at, llfsm, run_sim

from llfsm.importer import cxx

pytest.importorskip("tree_sitter_cpp")

TRACE = re.compile(r"^m +\d+ s +\d+ - ", re.M)


@pytest.fixture(scope="module")
def how_to(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The how-to's four machines in clfsm's form (tests/clfsm_writer.py)."""
    root = tmp_path_factory.mktemp("clfsm")
    for make in HOW_TO:
        make(root)
    return root


def import_(*args: str | os.PathLike[str]) -> tuple[int, str, str]:
    r = llfsm("import", *args)
    return r.status, r.stdout, r.stderr


def states_of(machine: Path) -> dict[str, object]:
    return yaml.safe_load((machine / "machine.yaml").read_text())  # type: ignore[no-any-return]


def files_under(root: Path) -> set[str]:
    return {str(p.relative_to(root)) for p in root.rglob("*")}


# -- the how-to's four machines -----------------------------------------------------------------


def test_the_how_to_machines_in_clfsm_form_check_clean_and_trace_as_the_shipped_ones(
    how_to: Path, tmp_path: Path
) -> None:
    status, out, _ = import_(how_to, "-o", tmp_path)
    assert status == 0, out
    assert out.strip().endswith("imported 4 of 4 machine(s): 136 of 136 code lines translated (100%)")
    r = llfsm("check", "--strict", tmp_path)
    assert r.status == 0, r.stdout
    runs = [
        (["ros2_ping_pong"], ["--duration", "6s", "--echo", "/pingpong"]),
        (["ros2_blind_turtle_bot"], ["--node", "turtlesim", "--duration", "5s"]),
        (["ros2_wall_turtle_bot"], ["--node", "turtlesim", "--node", "turtle_sensor_poster", "--duration", "40s"]),
        (["ros2_turtle_suspend_resume", "ros2_blind_turtle_bot"], ["--node", "turtlesim", "--duration", "12s"]),
    ]
    for names, options in runs:
        shipped = run_sim("-v", *[MACHINES / f"{n}.machine" for n in names], *options)
        imported = run_sim("-v", *[tmp_path / f"{n}.machine" for n in names], *options)
        assert shipped.status == imported.status == 0, imported.stderr
        assert len(TRACE.findall(shipped.stderr)) >= 4
        assert imported.stderr == shipped.stderr  # the -v trace, and every log line
        assert imported.stdout == shipped.stdout


def test_the_wall_bot_translates_line_for_line(how_to: Path, tmp_path: Path) -> None:
    import_(how_to / "ros2_wall_turtle_bot.machine", "-o", tmp_path)
    m = tmp_path / "ros2_wall_turtle_bot.machine"
    assert (m / "State_STOP_OnEntry.py").read_text() == (
        "msg.linear.x = 0.0\nmsg.angular.z = 0.0\npublisher_.publish(msg)\nrequest = TurtlePosition.Request()\n"
        "result = client_.call_async(request)\nI_wait = ros.spin_until_future_complete(node, result)\n"
    )
    assert (m / "State_STOP_Transition_1.expr").read_text() == "# -> TEST\nI_wait == ros.FutureReturnCode.SUCCESS\n"
    assert (
        m / "State_TEST_OnEntry.py"
    ).read_text() == "position_x = result.result().x\nposition_y = result.result().y\n"
    assert (m / "Includes.py").read_text() == (
        "from llfsm import ros\nfrom llfsm.msgs.geometry_msgs.msg import Twist\n"
        "from llfsm.msgs.turtle_sensor_interface.srv import TurtlePosition\n"
    )
    assert "msg: Twist = Twist()\n" in (m / "Variables.py").read_text()
    assert "position_x: float = 0.0\n" in (m / "Variables.py").read_text()


# -- structure, exactly ----------------------------------------------------------------------------


def test_structure_is_exact_pseudo_state_suspend_in_the_middle_six_transitions(tmp_path: Path) -> None:
    six = [("E", "after(6)"), ("A", "after(1)"), ("SUSPENDED", "false"), ("C", "x > 3"), ("A", "x == 2"), ("D", "true")]
    src = write_clfsm(
        tmp_path / "src",
        "Corners",
        [
            ClfsmState("InitialPseudoState", [("A", "true")]),
            ClfsmState("A", [("C", "after_ms(10)")], {"OnEntry": "x = x + 1;"}),
            ClfsmState("SUSPENDED"),
            ClfsmState("C", six),
            ClfsmState("D", [("C", "true")]),
            ClfsmState("E"),
        ],
        variables="int\tx;\t///< a counter\n",
        suspended="SUSPENDED",
        states_newline=True,
    )
    status, out, _ = import_(src, "-o", tmp_path / "out")
    assert status == 0, out
    m = tmp_path / "out" / "Corners.machine"
    doc = states_of(m)
    assert "initial" not in doc  # InitialPseudoState is first, and initial, as in clfsm
    assert doc["suspended"] == "SUSPENDED"
    assert [s["name"] for s in doc["states"]] == ["InitialPseudoState", "A", "SUSPENDED", "C", "D", "E"]
    c = doc["states"][3]
    assert c["transitions"] == [t for t, _ in six]
    for i, (target, _guard) in enumerate(six):
        text = (m / f"State_C_Transition_{i}.expr").read_text()
        assert text.startswith(f"# -> {target}\n"), text
    assert (m / "State_C_Transition_5.expr").read_text() == "# -> D\nTrue\n"
    assert (m / "State_C_Transition_3.expr").read_text() == "# -> C\nx > 3\n"
    assert (m / "Variables.py").read_text() == "x: int = 0  # a counter\n"
    assert llfsm("check", m).status == 0  # a warning only: transition 2 is `false`
    trace = run_sim("-v", m, "--duration", "50ms")
    assert "s  0 - Corners              - InitialPseudoState" in trace.stderr
    assert "s  1 - Corners              - A" in trace.stderr  # the index is clfsm's


def test_initial_state_from_the_mm_and_old_machines_without_suspend_sections(tmp_path: Path) -> None:
    src = write_clfsm(
        tmp_path / "src",
        "Old",
        [ClfsmState("A", [("B", "true")]), ClfsmState("B", [("A", "true")], {"OnEntry": "n++;"}), ClfsmState("C")],
        variables="unsigned int\tn;\t///<\n",
        initial="B",
        suspend_sections=False,
        layout=False,
    )
    assert not list(src.glob("*OnSuspend*"))
    status, _, _ = import_(src, "-o", tmp_path / "out")
    m = tmp_path / "out" / "Old.machine"
    assert status == 0
    doc = states_of(m)
    assert doc["initial"] == "B" and "suspended" not in doc
    assert (m / "State_B_OnEntry.py").read_text() == "n += 1\n"
    assert not (m / "layout.yaml").exists()
    assert llfsm("check", m).status == 0


def test_layout_plist_positions_go_to_layout_yaml_and_a_broken_plist_costs_only_them(tmp_path: Path) -> None:
    src = write_clfsm(tmp_path / "src", "Drawn", [ClfsmState("A", [("B", "true")]), ClfsmState("B")])
    status, _, _ = import_(src, "-o", tmp_path / "out")
    assert status == 0
    layout = yaml.safe_load((tmp_path / "out" / "Drawn.machine" / "layout.yaml").read_text())
    assert layout == {"states": {"A": {"x": 100, "y": 100}, "B": {"x": 350, "y": 100}}}
    (src / "Layout.plist").write_bytes(b"<?xml version='1.0'?><plist><dict><key>States</key>")
    status, out, _ = import_(src, "-o", tmp_path / "out2")
    assert status == 0
    assert "note: Layout.plist not read" in out
    assert not (tmp_path / "out2" / "Drawn.machine" / "layout.yaml").exists()


def test_glue_and_appledouble_files_are_ignored_and_orphans_said(tmp_path: Path) -> None:
    src = write_clfsm(tmp_path / "src", "Glue", [ClfsmState("A", [("A", "after(1)")])])
    (src / "._State_A_OnEntry.mm").write_bytes(b"\x00\x05\x16\x07 Mac OS X        \x00\x02\xff")
    (src / "._States").write_bytes(b"\x00\x05\x16\x07")
    (src / "State_Gone_OnEntry.mm").write_text("x = 1;\n")
    status, out, _ = import_(src, "-o", tmp_path / "out")
    assert status == 0, out
    assert "note: ignored: State_Gone_OnEntry.mm" in out
    assert "._" not in out
    assert sorted(files_under(tmp_path / "out" / "Glue.machine")) == [
        "State_A_Transition_0.expr", "layout.yaml", "machine.yaml"]  # fmt: skip


def test_a_missing_guard_file_is_left_for_a_person_and_a_missing_header_stops_that_machine(tmp_path: Path) -> None:
    src = write_clfsm(tmp_path / "src", "NoGuard", [ClfsmState("A", [("B", "true"), ("A", "false")]), ClfsmState("B")])
    (src / "State_A_Transition_1.expr").unlink()
    other = write_clfsm(tmp_path / "src", "NoHeader", [ClfsmState("A", [("A", "true")])])
    (other / "State_A.h").unlink()
    status, out, _ = import_(tmp_path / "src", "-o", tmp_path / "out")
    assert status == 1  # NoHeader could not be read; NoGuard is written all the same
    assert "not imported: " in out and "NoHeader.machine/State_A.h: missing" in out
    assert not (tmp_path / "out" / "NoHeader.machine").exists()
    guard = tmp_path / "out" / "NoGuard.machine" / "State_A_Transition_1.expr"
    assert guard.read_text() == (
        "# -> A\n# UNTRANSLATED (State_A_Transition_1.expr is missing in the clfsm machine):\nFalse\n"
    )
    r = llfsm("check", tmp_path / "out" / "NoGuard.machine")
    assert r.status == 1 and "State_A_Transition_1.expr:2:1: LF080 error" in r.stdout


# -- names ---------------------------------------------------------------------------------------


def test_odd_names_are_changed_said_and_followed_by_the_suspend_family(tmp_path: Path) -> None:
    write_clfsm(tmp_path / "src", "2-fast", [ClfsmState("Go-Left", [("class", "after(1)")]), ClfsmState("class")])
    write_clfsm(
        tmp_path / "src",
        "boss",
        [ClfsmState("S", [("T", 'is_suspended("2-fast") && state_name_of("2-fast") != "x"')],
                    {"OnEntry": 'suspend("2-fast");\nresume("elsewhere");'}), ClfsmState("T")],
    )  # fmt: skip
    status, out, _ = import_(tmp_path / "src", "-o", tmp_path / "out")
    assert status == 0, out
    assert 'renamed 2-fast to _2_fast (an llfsm name); suspend("...") calls follow' in out
    assert "state Go-Left renamed Go_Left" in out and "state class renamed class_" in out
    fast = tmp_path / "out" / "_2_fast.machine"
    assert [s["name"] for s in states_of(fast)["states"]] == ["Go_Left", "class_"]
    assert (fast / "State_Go_Left_Transition_0.expr").read_text() == "# -> class_\nafter(1)\n"
    boss = tmp_path / "out" / "boss.machine"
    assert (boss / "State_S_OnEntry.py").read_text() == 'suspend("_2_fast")\nresume("elsewhere")\n'
    assert (boss / "State_S_Transition_0.expr").read_text() == (
        '# -> T\nis_suspended("_2_fast") and state_name_of("_2_fast") != "x"\n'
    )
    assert llfsm("check", fast, boss).status == 0


# -- hostile directories ---------------------------------------------------------------------------


def _replace_by_link(path: Path, target: str) -> None:
    path.unlink()
    path.symlink_to(target)


@pytest.mark.parametrize(
    ("spoil", "message"),
    [
        (lambda d: (d / "States").write_text("A\n../../evil\n"), "cannot name a file"),
        (lambda d: (d / "States").write_text("A\nA\n"), "listed twice"),
        (lambda d: (d / "State_A_OnEntry.mm").write_bytes(b"x = 1;\x00\x01"), "a binary file"),
        (lambda d: (d / "State_A_OnEntry.mm").write_bytes(b"x = '\xe9';"), "not UTF-8 text"),
        (lambda d: (d / "State_A_OnEntry.mm").write_bytes(b"//" + b"x" * (1 << 20)), "more than the"),
        (lambda d: _replace_by_link(d / "State_A_OnEntry.mm", "/etc/passwd"), "a symlink; llfsm import follows none"),
        (lambda d: (d / "State_A.h").write_text("Transition_0(int toState = 7)"), "targets state 7; there are 1"),
        (lambda d: (d / "States").unlink(), "no States file: not a clfsm machine directory"),
    ],
    ids=["dotdot-state", "twice", "binary", "latin1", "huge", "symlink", "bad-target", "no-States"],
)
def test_hostile_directories_get_one_clear_line_and_nothing_is_written(tmp_path: Path, spoil, message: str) -> None:  # type: ignore[no-untyped-def]
    src = write_clfsm(tmp_path / "src", "Bad", [ClfsmState("A", [("A", "true")])])
    good = write_clfsm(tmp_path / "src", "Good", [ClfsmState("A", [("A", "true")])])
    spoil(src)
    before = files_under(tmp_path)
    status, out, err = import_(src, good, "-o", tmp_path / "out")
    assert status == 1, out
    assert message in out and "Traceback" not in out + err
    assert (tmp_path / "out" / "Good.machine" / "machine.yaml").exists()
    after = files_under(tmp_path) - before
    assert all(p.startswith("out/Good.machine") or p in ("out", "out/Good.machine") for p in after), after


def test_a_machine_directory_linked_from_elsewhere_is_refused(tmp_path: Path) -> None:
    real = write_clfsm(tmp_path / "elsewhere", "Real", [ClfsmState("A")])
    (tmp_path / "src").mkdir()
    (tmp_path / "src" / "Linked.machine").symlink_to(real)
    status, out, _ = import_(tmp_path / "src" / "Linked.machine", "-o", tmp_path / "out")
    assert status == 1 and "symlink" in out
    assert not list((tmp_path / "out").iterdir())


def test_output_into_an_existing_machine_needs_force_and_never_replaces_other_folders(tmp_path: Path) -> None:
    src = write_clfsm(tmp_path / "src", "M", [ClfsmState("A", [("A", "after(1)")])])
    out = tmp_path / "out"
    assert import_(src, "-o", out)[0] == 0
    (out / "M.machine" / "State_A_OnEntry.py").write_text("print('mine')\n")
    status, text, _ = import_(src, "-o", out)
    assert status == 1 and "M.machine exists (--force replaces it)" in text
    assert (out / "M.machine" / "State_A_OnEntry.py").exists()
    assert import_(src, "-o", out, "--force")[0] == 0
    assert not (out / "M.machine" / "State_A_OnEntry.py").exists()
    assert sorted(p.name for p in out.iterdir()) == ["M.machine"]  # no temporary folder left
    (out / "M.machine" / "machine.yaml").unlink()  # now a folder that is not an llfsm machine
    status, text, _ = import_(src, "-o", out, "--force")
    assert status == 1 and "is not an llfsm machine: not replaced" in text


def test_usage_errors_exit_2(tmp_path: Path) -> None:
    assert import_(tmp_path / "nowhere")[0] == 2
    src = write_clfsm(tmp_path / "src", "M", [ClfsmState("A")])
    (tmp_path / "file").write_text("x")
    r = llfsm("import", src, "-o", tmp_path / "file")
    assert r.status == 2 and "not a folder" in r.stderr
    r = llfsm("import", src, "-o", tmp_path / "x.machine")
    assert r.status == 2 and "name the folder" in r.stderr


def test_without_tree_sitter_the_command_says_what_to_install(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    src = write_clfsm(tmp_path / "src", "M", [ClfsmState("A")])
    monkeypatch.setattr(cxx, "_PARSER", None)
    monkeypatch.setitem(sys.modules, "tree_sitter", None)
    r = llfsm("import", src, "-o", tmp_path / "out")
    assert r.status == 2
    assert "pip install 'llfsm[import]'" in r.stderr


def test_json_report_lists_each_statement_left_at_both_ends(tmp_path: Path) -> None:
    src = write_clfsm(
        tmp_path / "src",
        "Left",
        [ClfsmState("A", [("A", "control_machine_at_index(1, CLStatus) == CLSuspend")],
                    {"OnEntry": "int n = 3;\nunlink(\"/tmp/x\");\nexit(EXIT_FAILURE);\nn++;"})],
    )  # fmt: skip
    status, out, _ = import_(src, "-o", tmp_path / "out", "--format", "json")
    assert status == 0
    [report] = json.loads(out)
    assert report["machine"] == "Left" and report["error"] is None
    assert report["lines"] == {"code": 6, "translated": 4, "left": 2}  # the include is a line too
    assert [(x["file"], x["line"], x["source"], x["source_line"]) for x in report["left"]] == [
        ("State_A_OnEntry.py", 3, "State_A_OnEntry.mm", 3),
        ("State_A_Transition_0.expr", 2, "State_A_Transition_0.expr", 1),
    ]
    assert "load index" in report["left"][1]["reason"]
    r = llfsm("check", tmp_path / "out")
    assert r.status == 1
    assert [line.split(": LF080")[0].split("/")[-1] for line in r.stdout.splitlines()] == [
        "State_A_OnEntry.py:3:1", "State_A_Transition_0.expr:2:1"]  # fmt: skip
    assert llfsm("build", tmp_path / "out" / "Left.machine", "-o", tmp_path / "built").status == 1


def test_check_build_and_run_never_load_the_importer_or_its_parser(how_to: Path, tmp_path: Path) -> None:
    import_(how_to / "ros2_ping_pong.machine", "-o", tmp_path)
    m = tmp_path / "ros2_ping_pong.machine"
    for argv in (["check", m], ["build", m, "-o", tmp_path / "b"], ["run", "--clock", "sim", m, "--duration", "1s"]):
        probe = (
            "import atexit, sys\n"
            "atexit.register(lambda: sys.stderr.write('LOADED %s\\n' % sorted(m for m in sys.modules"
            " if m.startswith(('tree_sitter', 'llfsm.importer')))))\n"
            "from llfsm.__main__ import main\n"
            f"sys.argv = ['llfsm', *{[str(a) for a in argv]!r}]\n"
            "main()\n"
        )
        r = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
        assert "LOADED []" in r.stderr, (argv, r.stderr)


def test_a_failure_midway_leaves_no_half_written_machine_and_keeps_the_old_one(tmp_path: Path) -> None:
    src = write_clfsm(tmp_path / "src", "M", [ClfsmState("A", [("B", "true")], {"OnEntry": "x = 1;"}), ClfsmState("B")])
    out = tmp_path / "out"
    with disk_full_at(3):  # llfsm.edit writes the machine (SPEC 13)
        status, text, _ = import_(src, "-o", out)
    assert status == 1 and "M.machine/" in text and "cannot write: No space left on device; nothing was changed" in text
    assert list(out.iterdir()) == []  # neither a machine nor a temporary folder
    assert import_(src, "-o", out)[0] == 0
    before = {p.name: p.read_bytes() for p in (out / "M.machine").iterdir()}
    more = [ClfsmState("A", [("B", "true")], {"OnEntry": "x = 2;"}), ClfsmState("B", [("C", "true")]), ClfsmState("C")]
    write_clfsm(tmp_path / "src", "M", more)  # files to write again: an unchanged file is not written
    with disk_full_at(3):
        status, text, _ = import_(src, "-o", out, "--force")
    assert status == 1
    assert {p.name: p.read_bytes() for p in (out / "M.machine").iterdir()} == before
    assert sorted(p.name for p in out.iterdir()) == ["M.machine"]
