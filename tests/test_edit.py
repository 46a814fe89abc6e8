"""llfsm.edit (SPEC 13): the structure operations keep each guard with its transition, keep
machine.yaml's comments and formatting and a machine's guard form, refuse bad requests changing
nothing (the tree hashed), and apply every file or none (a failure injected midway)."""

from __future__ import annotations

import hashlib
import os
import random
import shutil
from pathlib import Path
from typing import Any

import pytest
import yaml
from helpers import MACHINES, disk_full_at, llfsm, write_machine

from llfsm import edit
from llfsm.edit import change as change_module
from llfsm.lang.check import check_machine


def tree_hash(root: Path) -> str:
    """Every name, link and byte below `root`."""
    h = hashlib.sha256()
    for dirpath, dirnames, filenames in sorted(os.walk(root)):
        dirnames.sort()
        for name in sorted(filenames + dirnames):
            p = Path(dirpath) / name
            h.update(str(p.relative_to(root)).encode() + b"\0")
            if p.is_symlink():
                h.update(b"link:" + os.readlink(p).encode())
            elif p.is_file():
                h.update(p.read_bytes())
    return h.hexdigest()


def clean(m: Path) -> list[str]:
    return [f"{d.code} {Path(d.file).name}:{d.line}" for d in check_machine(m).diagnostics]


@pytest.fixture
def bot(tmp_path: Path) -> Path:
    """The how-to's wall bot, whose STOP has three transitions (END, TEST, SERVICE_FAILS)."""
    return Path(shutil.copytree(MACHINES / "ros2_wall_turtle_bot.machine", tmp_path / "ros2_wall_turtle_bot.machine"))


def guard_of(m: Path, state: str, n: int) -> str:
    return (m / f"State_{state}_Transition_{n}.expr").read_text()


def test_a_move_keeps_each_guard_with_its_target(bot: Path) -> None:
    guards = {t: guard_of(bot, "STOP", i).strip() for i, t in enumerate(["END", "TEST", "SERVICE_FAILS"])}
    c = edit.transition_move(bot, "STOP", 2, 0)
    assert set(c.writes) == {"machine.yaml", *(f"State_STOP_Transition_{i}.expr" for i in range(3))}
    edit.apply(c)
    assert "    transitions: [SERVICE_FAILS, END, TEST]\n" in (bot / "machine.yaml").read_text()
    for i, t in enumerate(["SERVICE_FAILS", "END", "TEST"]):
        assert guard_of(bot, "STOP", i) == f"# -> {t}\n{guards[t]}\n"
    assert clean(bot) == []


def test_a_reorder_by_hand_is_a_warning_at_the_guard_file(bot: Path) -> None:
    edit.apply(edit.transition_move(bot, "STOP", 2, 0))  # every guard file now says its target
    text = (bot / "machine.yaml").read_text()
    (bot / "machine.yaml").write_text(text.replace("[SERVICE_FAILS, END, TEST]", "[END, SERVICE_FAILS, TEST]"))
    got = [(d.code, Path(d.file).name, d.line, d.column) for d in check_machine(bot).diagnostics]
    assert got == [
        ("LF071", "State_STOP_Transition_0.expr", 1, 6),
        ("LF071", "State_STOP_Transition_1.expr", 1, 6),
    ]


def test_add_then_remove_renumbers_the_guards_after_it(bot: Path) -> None:
    start = tree_hash(bot)
    c = edit.transition_add(bot, "STOP", "BACK", guard="after(2)", priority=1)
    edit.apply(c)
    assert "[END, BACK, TEST, SERVICE_FAILS]" in (bot / "machine.yaml").read_text()
    assert guard_of(bot, "STOP", 1) == "# -> BACK\nafter(2)\n"
    assert guard_of(bot, "STOP", 3).startswith("# -> SERVICE_FAILS\n")
    assert clean(bot) == []
    edit.apply(edit.transition_remove(bot, "STOP", 1))
    assert "[END, TEST, SERVICE_FAILS]" in (bot / "machine.yaml").read_text()
    assert not (bot / "State_STOP_Transition_3.expr").exists()
    assert clean(bot) == []
    moved = tree_hash(bot)
    with pytest.raises(edit.EditError, match="changed on disk"):  # the undo of a change never applied
        edit.apply(edit.invert(edit.transition_remove(bot, "STOP", 1)))
    assert tree_hash(bot) == moved != start  # (the guards that moved got their `# -> TARGET`)


def test_undo_puts_every_byte_back(bot: Path) -> None:
    start = tree_hash(bot)
    c = edit.state_rename(bot, "STOP", "HALT")
    edit.apply(c)
    assert tree_hash(bot) != start
    edit.apply(edit.invert(c))
    assert tree_hash(bot) == start


def test_rename_moves_files_targets_initial_layout_and_state_name_comparisons(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "r",
        {"WAIT": [("GO", "after_ms(5)"), ("WAIT", 'state_name() != "WAIT"')], "GO": [("WAIT", "True")], "END": None},
        {"WAIT_OnEntry": 'print("WAIT")\nif state_name() == "WAIT":\n    print(1)\n'},
        yaml_extra="initial: WAIT\nsuspended: WAIT",
    )
    (m / "layout.yaml").write_text("# placed by hand\nstates:\n  WAIT: {x: 10, y: 20}\n  GO: {x: 10, y: 90}\n")
    c = edit.state_rename(m, "WAIT", "PAUSE")
    assert c.summary == f"renamed state WAIT to PAUSE ({len(c.writes)} files)"
    edit.apply(c)
    y = (m / "machine.yaml").read_text()
    assert "initial: PAUSE\nsuspended: PAUSE\n" in y and "- name: PAUSE\n    transitions: [GO, PAUSE]" in y
    assert "transitions: [PAUSE]" in y
    assert not list(m.glob("State_WAIT_*"))
    assert (m / "State_PAUSE_OnEntry.py").read_text() == 'print("WAIT")\nif state_name() == "PAUSE":\n    print(1)\n'
    assert guard_of(m, "PAUSE", 1) == '# -> PAUSE\nstate_name() != "PAUSE"\n'
    assert (
        m / "layout.yaml"
    ).read_text() == "# placed by hand\nstates:\n  PAUSE: {x: 10, y: 20}\n  GO: {x: 10, y: 90}\n"
    assert [d for d in clean(m) if d.startswith("LF0")] == []  # (END is unreachable, WAIT suspends)


def test_remove_takes_the_transitions_into_the_state_and_refuses_the_initial(bot: Path) -> None:
    start = tree_hash(bot)
    with pytest.raises(edit.EditError, match="INITIAL is the initial state"):
        edit.state_remove(bot, "INITIAL")
    assert tree_hash(bot) == start
    c = edit.state_remove(bot, "SERVICE_FAILS")
    assert c.summary.startswith("removed state SERVICE_FAILS and 1 transition into it")
    edit.apply(c)
    assert "[END, TEST]" in (bot / "machine.yaml").read_text()
    assert not list(bot.glob("State_SERVICE_FAILS_*"))
    assert clean(bot) == []


HOSTILE = ["..", "a/b", "../../etc", "a\0b", "x" * 300, "état", "class", "", "1abc", "A B", "A\n"]


@pytest.mark.parametrize("name", HOSTILE)
def test_hostile_names_are_refused_before_any_path_is_built(bot: Path, name: str) -> None:
    start = tree_hash(bot)
    for plan in (
        lambda: edit.state_add(bot, name),
        lambda: edit.state_rename(bot, "STOP", name),
        lambda: edit.state_remove(bot, name),
        lambda: edit.transition_add(bot, "STOP", name),
        lambda: edit.transition_add(bot, name, "END"),
        lambda: edit.transition_retarget(bot, "STOP", 0, name),
        lambda: edit.set_initial(bot, name),
    ):
        with pytest.raises(edit.EditError) as e:
            plan()
        assert "\n" not in str(e.value)
    assert tree_hash(bot) == start


def test_clashes_and_bad_indices_are_refused(bot: Path) -> None:
    start = tree_hash(bot)
    for plan, msg in (
        (lambda: edit.state_add(bot, "STOP"), "already has a state STOP"),
        (lambda: edit.state_rename(bot, "STOP", "TEST"), "already has a state TEST"),
        (lambda: edit.state_rename(bot, "NOPE", "X"), "has no state NOPE"),
        (lambda: edit.transition_move(bot, "STOP", 3, 0), "there is no transition 3"),
        (lambda: edit.transition_move(bot, "STOP", 0, 3), "out of range: 0 to 2"),
        (lambda: edit.transition_add(bot, "STOP", "END", priority=9), "out of range: 0 to 3"),
        (lambda: edit.transition_add(bot, "STOP", "END", guard="  "), "cannot be empty"),
        (lambda: edit.write_file(bot, "../x.py", "x"), "refused"),
        (lambda: edit.write_file(bot, "notes.txt", "x"), "not a file of a machine directory"),
        (lambda: edit.write_file(bot, "State_../_OnEntry.py", "x"), "refused"),
        (lambda: edit.set_layout(bot, {"NOPE": (1, 2)}), "has no state NOPE"),
        (lambda: edit.set_layout(bot, {"STOP": (float("nan"), 2)}), "finite"),
    ):
        with pytest.raises(edit.EditError, match=msg):
            plan()
    assert tree_hash(bot) == start


def test_a_failure_midway_leaves_every_byte_as_it_was(bot: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    start = tree_hash(bot)
    c = edit.state_rename(bot, "STOP", "HALT")  # 9 files: written, deleted, machine.yaml
    calls = []
    real = change_module._commit_one

    def failing(tmp: str, path: str) -> None:
        calls.append(path)
        if len(calls) == 3:
            raise OSError(28, "No space left on device", path)
        real(tmp, path)

    monkeypatch.setattr(change_module, "_commit_one", failing)
    with pytest.raises(edit.EditError, match="No space left on device; nothing was changed"):
        edit.apply(c)
    assert len(calls) == 3
    assert tree_hash(bot) == start  # no temporary, no half-renamed state


def test_an_interrupt_midway_also_leaves_the_tree_and_is_raised(bot: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    start = tree_hash(bot)
    c = edit.transition_move(bot, "STOP", 0, 2)
    real, calls = change_module._commit_one, []

    def interrupted(tmp: str, path: str) -> None:
        calls.append(path)
        if len(calls) == 2:
            raise KeyboardInterrupt
        real(tmp, path)

    monkeypatch.setattr(change_module, "_commit_one", interrupted)
    with pytest.raises(KeyboardInterrupt):
        edit.apply(c)
    assert tree_hash(bot) == start


def test_a_file_changed_since_planning_is_named_and_nothing_is_written(bot: Path) -> None:
    c = edit.transition_move(bot, "STOP", 2, 0)
    (bot / "State_STOP_Transition_1.expr").write_text("True\n")
    start = tree_hash(bot)
    with pytest.raises(edit.EditError, match=r"State_STOP_Transition_1\.expr changed on disk"):
        edit.apply(c)
    assert tree_hash(bot) == start


def test_symlinks_are_never_followed(bot: Path, tmp_path: Path) -> None:
    secret = tmp_path / "secret.txt"
    secret.write_text("secret\n")
    (bot / "State_STOP_Transition_1.expr").unlink()
    (bot / "State_STOP_Transition_1.expr").symlink_to(secret)
    start = tree_hash(bot)
    with pytest.raises(edit.EditError, match="is a symlink"):
        edit.transition_move(bot, "STOP", 1, 0)
    with pytest.raises(edit.EditError, match="is a symlink"):
        edit.write_file(bot, "State_STOP_Transition_1.expr", "x")
    link = tmp_path / "elsewhere" / "out.machine"
    link.parent.mkdir()
    link.symlink_to(bot)
    with pytest.raises(edit.EditError, match="leading out of"):
        edit.state_add(link, "NEW")
    assert tree_hash(bot) == start and secret.read_text() == "secret\n"


COMMENTED = """\
# The bot, by hand.
description: A machine with comments.   # what it does
initial: A
states:
  # the first state
  - name: A
    transitions: [B, C]   # B first
  - name: B               # waits
    transitions:
      - to: A
        guard: after_ms(10)     # inline
  - name: C
"""


def test_comments_formatting_and_the_guard_form_are_kept(tmp_path: Path) -> None:
    m = tmp_path / "c.machine"
    m.mkdir()
    (m / "machine.yaml").write_text(COMMENTED)
    (m / "State_A_Transition_0.expr").write_text("True\n")
    (m / "State_A_Transition_1.expr").write_text("False\n")
    edit.apply(edit.transition_add(m, "B", "C", guard="x > 1 and y: 2"))  # B's guards are inline
    edit.apply(edit.transition_add(m, "C", "A"))  # C has none: the machine's form (files)
    assert (m / "machine.yaml").read_text() == COMMENTED.replace(
        "        guard: after_ms(10)     # inline\n",
        "        guard: after_ms(10)     # inline\n      - to: C\n        guard: 'x > 1 and y: 2'\n",
    ).replace("  - name: C\n", "  - name: C\n    transitions: [A]\n")
    assert (m / "State_C_Transition_0.expr").read_text() == "# -> A\nTrue\n"
    assert not (m / "State_B_Transition_1.expr").exists()
    edit.apply(edit.set_guard(m, "B", 1, "count >= 3"))
    assert yaml.safe_load((m / "machine.yaml").read_text())["states"][1]["transitions"][1]["guard"] == "count >= 3"
    edit.apply(edit.transition_move(m, "B", 1, 0))
    text = (m / "machine.yaml").read_text()
    assert "      - to: A\n        guard: after_ms(10)     # inline\n  - name: C\n" in text
    assert yaml.safe_load(text)["states"][1]["transitions"] == [
        {"to": "C", "guard": "count >= 3"},
        {"to": "A", "guard": "after_ms(10)"},
    ]


def test_new_machine_layout_and_write_file(tmp_path: Path) -> None:
    c = edit.new_machine(tmp_path, "ping", ["PING", "PONG", "END"])
    assert c.root == tmp_path and all(v is None for v in c.before.values())
    edit.apply(c)
    m = tmp_path / "ping.machine"
    assert clean(m) == []
    assert (m / "State_PONG_Transition_0.expr").read_text() == "# -> END\nafter_ms(100)\n"
    with pytest.raises(edit.EditError, match="already exists"):
        edit.new_machine(tmp_path, "ping")
    edit.apply(edit.set_layout(m, {"PING": (10, 20.25)}, labels={("PING", 0): (40, 50)}))
    edit.apply(edit.set_layout(m, {"PONG": (10, 90)}))
    assert (m / "layout.yaml").read_text() == (
        "states:\n  PING: {x: 10, y: 20.2}\n  PONG: {x: 10, y: 90}\nlabels:\n  PING:\n    0: {x: 40, y: 50}\n"
    )
    assert clean(m) == []
    edit.apply(edit.transition_add(m, "PING", "END", priority=0))  # the label moves with its transition
    assert "  PING:\n    1: {x: 40, y: 50}\n" in (m / "layout.yaml").read_text()
    (m / "State_PING_Transition_0.expr").unlink()
    c = edit.write_file(m, "State_PING_Transition_0.expr", "after_ms(5)\n")  # a new guard file: its comment first
    assert c.writes == {"State_PING_Transition_0.expr": b"# -> END\nafter_ms(5)\n"}
    edit.apply(edit.write_file(m, "State_PONG_OnEntry.py", "print('pong')\n"))
    assert (m / "State_PONG_OnEntry.py").read_text() == "print('pong')\n"
    assert edit.write_file(m, "State_PONG_OnEntry.py", "print('pong')\n").writes == {}


def test_write_machine_writes_or_replaces_a_whole_machine_all_or_nothing(tmp_path: Path) -> None:
    """What `llfsm import` writes through: a machine directory whole (SPEC 13, issue 31)."""
    files = {f.name: f.read_text() for f in (MACHINES / "ros2_ping_pong.machine").iterdir() if f.is_file()}
    c = edit.write_machine(tmp_path, "pp", files)
    assert c.root == tmp_path and set(c.writes) == {f"pp.machine/{n}" for n in files}
    edit.apply(c)
    m = tmp_path / "pp.machine"
    assert clean(m) == [] and {f.name for f in m.iterdir()} == set(files)
    with pytest.raises(edit.MachineExists, match=r"pp\.machine exists"):
        edit.write_machine(tmp_path, "pp", files)
    (m / "State_PING_OnExit.py").write_text("print('mine')\n")  # a file the new machine does not have
    smaller = {n: t for n, t in files.items() if n != "Includes.py"} | {
        "Variables.py": "count: int = 0\n",
        "State_INITIAL_OnEntry.py": "print('hello')\n",
        "State_PUBLISH_Transition_1.expr": "# -> WAIT_AND_COUNT\nTrue\n",
    }
    start = tree_hash(tmp_path)
    c = edit.write_machine(tmp_path, "pp", smaller, replace=True)
    assert (
        c.writes["pp.machine/State_PING_OnExit.py"] is None
        and c.summary == f"replaced machine pp ({len(smaller)} files)"
    )
    with (
        disk_full_at(2),
        pytest.raises(edit.EditError, match=r"pp\.machine/\S+: cannot write: No space left on device; nothing was"),
    ):
        edit.apply(c)
    assert tree_hash(tmp_path) == start  # the old machine, byte for byte, and nothing beside it
    edit.apply(c)
    assert {f.name for f in m.iterdir()} == set(smaller) and (m / "Variables.py").read_text() == "count: int = 0\n"
    edit.apply(edit.invert(c))
    assert tree_hash(tmp_path) == start  # undone: the old machine back, the file it had too
    assert edit.write_machine(tmp_path, "pp", {n: (m / n).read_text() for n in files if (m / n).exists()}
                              | {"State_PING_OnExit.py": "print('mine')\n"}, replace=True).writes == {}  # fmt: skip


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda m: (m / "machine.yaml").unlink(), "exists and is not an llfsm machine: not replaced"),
        (lambda m: (m / "sub").mkdir(), "sub: not a plain file; .* not replaced"),
        (lambda m: (m / "link.py").symlink_to("/etc/hostname"), "link.py: not a plain file"),
    ],
)
def test_write_machine_replaces_only_an_llfsm_machine_of_plain_files(tmp_path: Path, make: Any, message: str) -> None:
    m = write_machine(tmp_path, "m", {"A": None})
    make(m)
    start = tree_hash(tmp_path)
    with pytest.raises(edit.EditError, match=message):
        edit.write_machine(tmp_path, "m", {"machine.yaml": "states:\n  - name: A\n"}, replace=True)
    assert tree_hash(tmp_path) == start


def test_write_machine_never_writes_outside_its_folder(tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (tmp_path / "elsewhere.machine").mkdir()
    (out / "linked.machine").symlink_to(tmp_path / "elsewhere.machine")
    for name, files, message in [
        ("../x", {"machine.yaml": ""}, "not a valid name"),
        ("ok", {"../machine.yaml": ""}, "refused file name"),
        ("ok", {"notes.txt": ""}, "not a file of a machine directory"),
        ("linked", {"machine.yaml": ""}, "is a symlink: not replaced"),
    ]:
        with pytest.raises(edit.EditError, match=message):
            edit.write_machine(out, name, files, replace=True)
    assert [p.name for p in out.iterdir()] == ["linked.machine"] and not any((tmp_path / "elsewhere.machine").iterdir())


# -- the commands ------------------------------------------------------------------------------------


def test_the_commands_say_what_they_did_and_refuse_in_one_line(bot: Path) -> None:
    r = llfsm("transition", "move", bot, "STOP", "2", "--to-priority", "0")
    assert (r.status, r.stdout) == (0, "moved transition 2 of STOP (to SERVICE_FAILS) to priority 0\n")
    r = llfsm("transition", "add", bot, "TEST", "STOP", "--guard", "after_ms(1)", "--priority", "0", "--inline")
    assert (r.status, r.stdout) == (0, "added transition 0 of TEST to STOP (guard inline)\n")
    assert (
        "    transitions: [{to: STOP, guard: after_ms(1)}, END, STRAIGHT, BACK]\n" in (bot / "machine.yaml").read_text()
    )
    r = llfsm("transition", "retarget", bot, "TEST", "0", "BACK")
    assert r.status == 0 and "{to: BACK, guard: after_ms(1)}" in (bot / "machine.yaml").read_text()
    r = llfsm("state", "add", bot, "WAIT", "--after", "STOP")
    assert r.stdout == "added state WAIT\n"
    assert (
        "  - name: STOP\n    transitions: [SERVICE_FAILS, END, TEST]\n  - name: WAIT\n"
        in (bot / "machine.yaml").read_text()
    )
    assert llfsm("state", "rename", bot, "WAIT", "PAUSE").status == 0
    assert llfsm("state", "remove", bot, "PAUSE").status == 0
    assert llfsm("transition", "remove", bot, "TEST", "0").status == 0
    assert clean(bot) == []
    start = tree_hash(bot)
    for args, message in (
        (("state", "remove", bot, "INITIAL"), "INITIAL is the initial state of ros2_wall_turtle_bot.machine"),
        (("state", "add", bot, "STOP"), "already has a state STOP"),
        (("state", "rename", bot, "STOP", "a/b"), "'a/b' is not a valid name"),
        (("transition", "add", bot, "STOP", "NOWHERE"), "has no state NOWHERE"),
        (("transition", "move", bot, "STOP", "7", "--to-priority", "0"), "there is no transition 7"),
        (("state", "add", bot.parent / "nope.machine", "X"), "no such directory"),
    ):
        r = llfsm(*args)
        assert r.status == 1 and r.stdout == ""
        assert r.stderr.count("\n") == 1 and message in r.stderr, r.stderr
    assert tree_hash(bot) == start


def test_a_mangled_machine_yaml_gets_one_line_never_a_traceback(bot: Path) -> None:
    """(bench-size fuzzing: 400 texts x 11 operations found nothing either)"""
    text = (bot / "machine.yaml").read_text()
    pieces = ["{", "}", "[", "]", ": ", "- ", "\n", "  ", "&a ", "*a", "!!int ", "~", "'", "#", "\0", "é", "to: "]
    rnd = random.Random(29)
    for _ in range(25):
        mangled = list(text)
        for _ in range(rnd.randint(1, 4)):
            at = rnd.randrange(len(mangled))
            if rnd.random() < 0.5:
                mangled.insert(at, rnd.choice(pieces))
            else:
                del mangled[at : at + rnd.randint(1, 10)]
        (bot / "machine.yaml").write_text("".join(mangled))
        start = tree_hash(bot)
        for plan in (
            lambda: edit.state_rename(bot, "STOP", "HALT"),
            lambda: edit.transition_move(bot, "STOP", 1, 0),
            lambda: edit.state_remove(bot, "TEST"),
            lambda: edit.transition_add(bot, "STOP", "END", inline=True),
            lambda: edit.set_layout(bot, {"STOP": (1, 2)}),
        ):
            try:
                plan()  # planned, not applied: a plan writes nothing
            except edit.EditError as e:
                assert "\n" not in str(e)
        assert tree_hash(bot) == start
