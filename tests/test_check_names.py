"""Names `check` now knows from text alone (issue 27, items 5 and 6): the machines a
`suspend("M")` may name (LF050, across the machines checked together) and the fields of a
message type (LF051, from the definitions, never imported)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from helpers import MACHINES, llfsm, write_machine

from llfsm.lang.check import check_machine

TWIST = "from llfsm.msgs.geometry_msgs.msg import Twist\n"


def _lines(stdout: str, code: str) -> list[str]:
    return [line for line in stdout.splitlines() if f" {code} " in line]


# -- LF050: a machine name that none of the machines checked together has ----------------------


def _boss(root: Path, code: str) -> Path:
    return write_machine(root, "boss", {"A": [("END", "after_ms(10)")], "END": None}, {"A_OnEntry": code})


def test_a_misspelt_machine_name_is_a_warning_with_did_you_mean(tmp_path: Path) -> None:
    write_machine(tmp_path, "wall_bot", {"A": [("A", "after_ms(1)")]})
    _boss(tmp_path, "suspend('WallBot')\nresume('wall_bot')\nif is_running(\"wallbot\"):\n    restart('boss')\n")
    r = llfsm("check", tmp_path)
    assert r.status == 0, r.stdout  # a warning
    assert _lines(r.stdout, "LF050") == [
        f"{tmp_path}/boss.machine/State_A_OnEntry.py:1:9: LF050 warning: no machine 'WallBot' among the machines "
        "checked and beside them (boss, wall_bot) (did you mean 'wall_bot'?): naming a machine that is not "
        "loaded fails when the line runs",
        f"{tmp_path}/boss.machine/State_A_OnEntry.py:3:15: LF050 warning: no machine 'wallbot' among the machines "
        "checked and beside them (boss, wall_bot) (did you mean 'wall_bot'?): naming a machine that is not "
        "loaded fails when the line runs",
    ]
    assert llfsm("check", "--strict", tmp_path).status == 1  # an error under --strict
    parallel = llfsm("check", "-j", "2", tmp_path / "boss.machine", tmp_path / "wall_bot.machine")
    assert _lines(parallel.stdout, "LF050") == _lines(r.stdout, "LF050")  # worker processes say the same


def test_one_machine_alone_and_names_that_are_not_literals_are_not_judged(tmp_path: Path) -> None:
    boss = _boss(tmp_path / "a", "suspend('WallBot')\nsuspend(machine_name())\n")
    assert llfsm("check", "--strict", boss).status == 0  # what runs beside it is unknown
    write_machine(tmp_path / "b", "other", {"A": [("A", "after_ms(1)")]})
    r = llfsm("check", boss, tmp_path / "b")
    assert [line.split(": LF050")[0] for line in _lines(r.stdout, "LF050")] == [
        f"{tmp_path}/a/boss.machine/State_A_OnEntry.py:1:9"
    ]


def test_a_machine_beside_the_ones_given_counts(tmp_path: Path) -> None:
    """pre-commit passes only the machines a commit changed."""
    write_machine(tmp_path, "wall_bot", {"A": [("A", "after_ms(1)")]})
    write_machine(tmp_path, "other", {"A": [("A", "after_ms(1)")]})
    boss = _boss(tmp_path, "suspend('wall_bot')\n")
    assert llfsm("check", "--strict", boss / "State_A_OnEntry.py", tmp_path / "other.machine").status == 0


def test_the_shipped_machines_name_each_other_correctly() -> None:
    assert _lines(llfsm("check", MACHINES).stdout, "LF050") == []


# -- LF051: a field the message type does not have ----------------------------------------------


def _codes(m: Path) -> list[tuple[str, str, int, int, str]]:
    return [(d.code, Path(d.file).name, d.line, d.column, d.message) for d in check_machine(m).diagnostics]


def test_a_misspelt_field_of_an_annotated_variable_is_an_error_with_did_you_mean(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "driver",
        {"A": [("A", "after_ms(100) and msg.linear.X > 0")]},
        {"A_OnEntry": "msg.linear.X = 2.0\nmsg.angular.z = 1.0\nmsg.lineer.x = 0.5\n"},
        variables="msg: Twist = Twist()\n",
        includes=TWIST,
    )
    vector3 = "geometry_msgs/msg/Vector3 has no field 'X' (did you mean 'x'?); its fields: x, y, z"
    assert _codes(m) == [
        ("LF051", "State_A_OnEntry.py", 1, 12, f"`msg.linear.X`: {vector3}"),
        (
            "LF051",
            "State_A_OnEntry.py",
            3,
            5,
            "`msg.lineer`: geometry_msgs/msg/Twist has no field 'lineer' (did you mean 'linear'?); "
            "its fields: linear, angular",
        ),
        ("LF051", "State_A_Transition_0.expr", 1, 30, f"`msg.linear.X`: {vector3}"),
    ]
    r = llfsm("run", "--clock", "sim", m, "--duration", "1ms")
    assert r.status == 2 and "LF051" in r.stderr  # found before the machine runs, not as an AttributeError


def test_services_state_variables_and_a_sections_own_messages(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "caller",
        {"A": [("END", "True")], "END": None},
        {
            "A_Variables": "pose: Pose | None = None\n",
            "A_OnEntry": (
                "req.nme = 'x'\nreq.x = 1.0\nresp: TurtlePosition.Response = TurtlePosition.Response()\n"
                "print(resp.thetaa, pose.theta, pose.thetta)\nmessage = String()\nmessage.dat = 'hi'\n"
                "print(message.data.upper(), Pose.__name__)\n"
            ),
        },
        variables="req: Spawn.Request = Spawn.Request()\n",
        includes="from llfsm.msgs.turtlesim.srv import Spawn\nfrom llfsm.msgs.turtlesim.msg import Pose\n"
        "from llfsm.msgs.turtle_sensor_interface.srv import TurtlePosition\n"
        "from llfsm.msgs.std_msgs.msg import String\n",
    )
    assert [(c, line, msg.split(":")[0]) for c, _f, line, _col, msg in _codes(m)] == [
        ("LF051", 1, "`req.nme`"),
        ("LF051", 4, "`resp.thetaa`"),
        ("LF051", 4, "`pose.thetta`"),
        ("LF051", 6, "`message.dat`"),
    ]


def test_what_is_not_known_to_be_a_message_is_left_alone(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "free",
        {"A": [("END", "True")], "END": None},
        {
            "A_OnEntry": (
                "f = lambda msg: msg.anything\n"
                "print([msg.whatever for msg in [1]])\n"
                "local = Twist()\nlocal = 3\nprint(local.real)\n"  # bound twice: it may hold anything
                "print(msg.to_dict(), msg.get_fields_and_field_types(), msg._copy())\n"
                "print(other.foo, status.STATUS_SUCCEEDED, status.goal_info.stamp.sec)\n"
            )
        },
        variables="msg: Twist = Twist()\nother: int = 0\nstatus: GoalStatus = GoalStatus()\n",
        includes=TWIST + "from llfsm.msgs.action_msgs.msg import GoalStatus\n",
    )
    assert _codes(m) == []


def test_fields_come_from_the_definitions_never_from_an_import(tmp_path: Path) -> None:
    """A user's package beside the machine is read as text; the check imports no message module."""
    (tmp_path / "my_msgs" / "msg").mkdir(parents=True)
    (tmp_path / "my_msgs" / "msg" / "Gain.msg").write_text("float64 value\ngeometry_msgs/Vector3 axis\n")
    m = write_machine(
        tmp_path,
        "tuned",
        {"A": [("END", "True")], "END": None},
        {"A_OnEntry": "g.valeu = 1.0\ng.axis.X = 2.0\n"},
        variables="g: Gain = Gain()\n",
        includes="from llfsm.msgs.my_msgs.msg import Gain\n",
    )
    code = (
        "import sys\nfrom llfsm.lang.check import check_machine\n"
        f"print(sorted(d.message.split(':')[0] for d in check_machine({str(m)!r}).diagnostics))\n"
        "print(any(n.startswith('llfsm.msgs.') and n.count('.') > 2 and not n.split('.')[2].startswith('_') "
        "for n in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out == "['`g.axis.X`', '`g.valeu`']\nFalse\n"
