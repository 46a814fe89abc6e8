"""Hints of `llfsm check` that must point at the real mistake (issue 22, items 7 and 8).

Each hint is tested by doing what it says: the suggested line is written into the machine,
and the check must then pass (a hint that leads to another error is a wrong hint).
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest
from helpers import write_machine

from llfsm.lang.check import check_machine
from llfsm.lang.diagnostics import Diagnostic


def _machine(tmp_path: Path, **files: str) -> Path:
    code = {k: v for k, v in files.items() if k not in ("variables", "includes")}
    return write_machine(
        tmp_path,
        "m",
        {"A": [("END", "True")], "END": None},
        code,
        variables=files.get("variables"),
        includes=files.get("includes"),
    )


def _diags(m: Path) -> list[Diagnostic]:
    return check_machine(m).diagnostics


def _suggested(message: str) -> list[str]:
    return re.findall(r"`([^`]+)`", message)


class TestCppCommentsAfterCode:
    """`printf("..."); // comment`: the problem is `//`, whatever the line holds before it."""

    @pytest.mark.parametrize(
        "line",
        [
            'print("hello"); // say hello',
            'print("count++"); // a string that holds ++',
            'print("a -- b"); // and --',
            "x = 1 ; // one",
            'print("x")  // no semicolon',
        ],
    )
    def test_the_hint_is_about_the_comment(self, tmp_path: Path, line: str) -> None:
        diags = _diags(_machine(tmp_path, A_OnEntry=line + "\n"))
        assert [d.code for d in diags] == ["LF030"], diags
        msg = diags[0].message
        assert "`#`" in msg and "`//`" in msg, msg
        assert "++" not in msg and "`--`" not in msg and "not x" not in msg, msg

    def test_the_fixed_line_passes(self, tmp_path: Path) -> None:
        m = _machine(tmp_path, A_OnEntry='print("hello")  # say hello\n')
        assert check_machine(m).ok, _diags(m)

    def test_floor_division_is_not_a_comment(self, tmp_path: Path) -> None:
        m = _machine(tmp_path, A_OnEntry="x = 7 // 2\nprint(x)\n")
        assert check_machine(m).ok, _diags(m)

    def test_an_increment_still_gets_its_own_hint(self, tmp_path: Path) -> None:
        diags = _diags(_machine(tmp_path, A_OnEntry="count++\n", variables="count: int = 0\n"))
        assert [d.code for d in diags] == ["LF030"] and "count += 1" in diags[0].message


class TestCppDeclarations:
    """`int count = 0;` in Variables.py: the hint is the line Variables.py takes."""

    @pytest.mark.parametrize(
        ("line", "expected"),
        [
            ("int count = 0;", "count: int = 0"),
            ("double speed = 1.5;", "speed: float = 1.5"),
            ("float gain = 0.5f;", "gain: float = 0.5"),
            ("bool done = false;", "done: bool = False"),
            ('std::string name = "turtle1";', 'name: str = "turtle1"'),
            ("unsigned int n;", "n: int = 0"),
            ("const int LIMIT = 10;", "LIMIT: int = 10"),
        ],
    )
    def test_in_variables_py_the_hint_is_an_annotated_assignment(
        self, tmp_path: Path, line: str, expected: str
    ) -> None:
        diags = _diags(_machine(tmp_path, variables=line + "\n"))
        assert [d.code for d in diags] == ["LF030"], diags
        assert f"`{expected}`" in diags[0].message, diags[0].message
        assert "write `" + expected.split(":")[0] + " = " not in diags[0].message  # the advice LF032 refused
        # doing what the hint says gives a machine that passes
        fixed = _machine(tmp_path / "fixed", variables=expected + "\n")
        assert check_machine(fixed).ok, _diags(fixed)

    def test_in_a_state_variables_file_too(self, tmp_path: Path) -> None:
        diags = _diags(_machine(tmp_path, **{"State_A_Variables.py": "int tries = 3;\n"}))
        assert [d.code for d in diags] == ["LF030"] and "`tries: int = 3`" in diags[0].message

    def test_in_a_section_the_hint_is_a_plain_assignment(self, tmp_path: Path) -> None:
        diags = _diags(_machine(tmp_path, A_OnEntry="int x = 0;\nprint(x)\n"))
        assert [d.code for d in diags] == ["LF030"]
        msg = diags[0].message
        assert "`x = 0`" in msg and "Variables.py" in msg and "`x: int = 0`" in msg, msg


class TestCFunctions:
    """A C function that is not defined gets its Python spelling, not a variable to declare."""

    @pytest.mark.parametrize(
        ("code", "spelling"),
        [
            ('printf("hello %d", 1)', "print"),
            ('puts("hello")', "print"),
            ('x = strlen("abc")\nprint(x)', "len"),
            ("x = fabs(-1.0)\nprint(x)", "abs"),
            ("x = sqrt(2.0)\nprint(x)", "math.sqrt"),
        ],
    )
    def test_the_python_function_is_suggested(self, tmp_path: Path, code: str, spelling: str) -> None:
        diags = [d for d in _diags(_machine(tmp_path, A_OnEntry=code + "\n")) if d.code == "LF040"]
        assert len(diags) == 1, diags
        assert f"`{spelling}" in diags[0].message, diags[0].message
        assert "Variables.py" not in diags[0].message, diags[0].message

    def test_an_unknown_function_is_not_declared_as_an_int(self, tmp_path: Path) -> None:
        diags = [d for d in _diags(_machine(tmp_path, A_OnEntry="frobnicate(3)\n")) if d.code == "LF040"]
        assert len(diags) == 1
        assert "frobnicate: int = 0" not in diags[0].message and "Includes.py" in diags[0].message

    def test_a_variable_read_still_gets_the_declaration(self, tmp_path: Path) -> None:
        diags = [d for d in _diags(_machine(tmp_path, A_OnEntry="print(total)\n")) if d.code == "LF040"]
        assert len(diags) == 1 and "`total: int = 0`" in diags[0].message


class TestInterfaceTypesWithoutTheirImport:
    """Issue 27, item 7: a message class used without its import was told to be declared as
    `TurtlePosition: int = 0` in Variables.py; its hint is the import line."""

    @pytest.mark.parametrize(
        ("code", "variables"),
        [
            ("req = TurtlePosition.Request()\nprint(req)\n", None),
            ("msg.linear.x = 2.0\n", "msg: Twist = Twist()\n"),
            ("print(Twist)\n", None),  # read, not called
        ],
    )
    def test_the_hint_is_the_import_line_and_following_it_checks_clean(
        self, tmp_path: Path, code: str, variables: str | None
    ) -> None:
        m = _machine(tmp_path, A_OnEntry=code, variables=variables)
        diags = [d for d in _diags(m) if d.code == "LF040"]
        assert len(diags) == 1, diags
        assert "Variables.py" not in diags[0].message and "it is an interface type" in diags[0].message
        [line] = [s for s in _suggested(diags[0].message) if s.startswith("from llfsm.msgs.")]
        (m / "Includes.py").write_text(line + "\n")
        assert _diags(m) == []

    def test_a_name_two_packages_define_gets_both_lines(self, tmp_path: Path) -> None:
        diags = _diags(_machine(tmp_path, A_OnEntry="p = Pose()\nprint(p)\n"))
        assert _suggested(diags[0].message)[-2:] == [
            "from llfsm.msgs.geometry_msgs.msg import Pose",
            "from llfsm.msgs.turtlesim.msg import Pose",
        ]

    def test_a_type_of_a_users_package_beside_the_machine(self, tmp_path: Path) -> None:
        (tmp_path / "my_msgs" / "srv").mkdir(parents=True)
        (tmp_path / "my_msgs" / "srv" / "Ping.srv").write_text("---\nbool ok\n")
        diags = _diags(_machine(tmp_path, A_OnEntry="req = Ping.Request()\nprint(req)\n"))
        assert _suggested(diags[0].message)[-1] == "from llfsm.msgs.my_msgs.srv import Ping"


class TestMessageImports:
    """An import of a name the message module lacks fails at run time: it is an error of check."""

    def test_a_misspelt_shipped_message(self, tmp_path: Path) -> None:
        m = _machine(tmp_path, includes="from llfsm import ros\nfrom llfsm.msgs.geometry_msgs.msg import Twists\n")
        diags = _diags(m)
        assert [(d.code, Path(d.file).name, d.line) for d in diags] == [("LF042", "Includes.py", 2)], diags
        assert "Twists" in diags[0].message and "'Twist'" in diags[0].message
        assert diags[0].severity == "error"

    @pytest.mark.parametrize(
        "line",
        [
            "from llfsm.msgs.geometry_msgs.msg import Twist, Pose\n",
            "from llfsm.msgs.std_srvs.srv import Trigger, Trigger_Request\n",
            "from llfsm.msgs.turtlesim.srv import Spawn as S\n",
            "import llfsm.msgs.geometry_msgs.msg\n",
            "from llfsm.msgs import std_msgs\n",
            "from llfsm.msgs.std_msgs import msg\n",
        ],
    )
    def test_real_names_pass(self, tmp_path: Path, line: str) -> None:
        m = _machine(tmp_path, includes=line)
        assert check_machine(m).ok, _diags(m)

    def test_the_wrong_kind(self, tmp_path: Path) -> None:
        diags = _diags(_machine(tmp_path, includes="from llfsm.msgs.std_srvs.msg import Trigger\n"))
        assert [d.code for d in diags] == ["LF042"] and "std_srvs/srv/Trigger" in diags[0].message

    def test_a_misspelt_kind_names_the_kinds_and_where_the_type_is(self, tmp_path: Path) -> None:
        diags = _diags(_machine(tmp_path, includes="from llfsm.msgs.turtlesim.actoin import RotateAbsolute\n"))
        assert [d.code for d in diags] == ["LF042"]
        assert diags[0].message.endswith(
            "turtlesim has msg, srv and action, not 'actoin': turtlesim/action/RotateAbsolute is an action"
        ), diags[0].message

    def test_in_a_section_too(self, tmp_path: Path) -> None:
        diags = _diags(_machine(tmp_path, A_OnEntry="from llfsm.msgs.std_msgs.msg import Strin\nprint(Strin)\n"))
        assert [(d.code, d.line) for d in diags] == [("LF042", 1)] and "'String'" in diags[0].message

    def test_a_users_package_beside_the_machine(self, tmp_path: Path) -> None:
        pkg = tmp_path / "my_msgs" / "msg"
        pkg.mkdir(parents=True)
        (pkg / "Note.msg").write_text("string text\n")
        ok = _machine(tmp_path, includes="from llfsm.msgs.my_msgs.msg import Note\n")
        assert check_machine(ok).ok, _diags(ok)
        (ok / "Includes.py").write_text("from llfsm.msgs.my_msgs.msg import Notes\n")
        diags = _diags(ok)
        assert [d.code for d in diags] == ["LF042"] and "'Note'" in diags[0].message
        assert "my_msgs/msg" in diags[0].message

    def test_an_unknown_package_is_a_warning_that_says_where_llfsm_looked(self, tmp_path: Path) -> None:
        diags = _diags(_machine(tmp_path, includes="from llfsm.msgs.geometry_msg.msg import Twist\n"))
        assert [d.code for d in diags] == ["LF109"], diags
        msg = diags[0].message
        assert "'geometry_msgs'" in msg and "LLFSM_INTERFACE_PATH" in msg and "AMENT_PREFIX_PATH" in msg

    def test_check_reads_definitions_without_importing_messages(self, tmp_path: Path) -> None:
        m = _machine(tmp_path, includes="from llfsm.msgs.geometry_msgs.msg import Twists\n")
        code = (
            "import sys\n"
            "from llfsm.lang.check import check_machine\n"
            f"print([d.code for d in check_machine({str(m)!r}).diagnostics])\n"
            "print(sorted(m for m in sys.modules if m.startswith(('llfsm.msgs', 'llfsm.idl'))))\n"
        )
        proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
        assert proc.stdout.splitlines() == ["['LF042']", "[]"], proc.stderr


class TestHelperInsideTheMachineFolder:
    """A helper module inside NAME.machine/ is never imported: check says where it must go."""

    def test_an_import_of_a_helper_inside_the_machine_folder(self, tmp_path: Path) -> None:
        m = _machine(tmp_path, includes="import helpers\n", A_OnEntry="print(helpers.greet())\n")
        (m / "helpers.py").write_text("def greet():\n    return 'hi'\n")
        diags = _diags(m)
        assert [(d.code, Path(d.file).name, d.line) for d in diags] == [("LF043", "Includes.py", 1)], diags
        assert "m.machine/helpers.py" in diags[0].message and str(tmp_path) not in diags[0].message.split("to ")[0]
        # moving it where the message says makes the machine pass
        (m / "helpers.py").rename(tmp_path / "helpers.py")
        assert check_machine(m).ok, _diags(m)

    def test_a_package_inside_the_machine_folder(self, tmp_path: Path) -> None:
        m = _machine(tmp_path, A_OnEntry="from tools.geo import heading\nprint(heading)\n")
        (m / "tools").mkdir()
        (m / "tools" / "__init__.py").write_text("")
        (m / "tools" / "geo.py").write_text("heading = 1\n")
        diags = _diags(m)
        assert [(d.code, d.line) for d in diags] == [("LF043", 1)], diags

    def test_a_helper_beside_the_machine_passes(self, tmp_path: Path) -> None:
        m = _machine(tmp_path, includes="import helpers\n")
        (tmp_path / "helpers.py").write_text("X = 1\n")
        assert check_machine(m).ok, _diags(m)
