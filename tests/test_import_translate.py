"""The C/C++ translator of `llfsm import`: what it writes for each construct, that what it
writes is Python, and that what it cannot carry over is kept, marked, with the reason."""

from __future__ import annotations

import pytest

pytest.importorskip("tree_sitter_cpp")

from llfsm.importer.kinds import Imports
from llfsm.importer.statements import Translation, python_name, translate_guard, translate_section
from llfsm.importer.terms import Scope

VARIABLES = {
    "count": ("count", "int"),
    "ratio": ("ratio", "float"),
    "ok": ("ok", "bool"),
    "name": ("name", "str"),
    "node": ("node", "ros:Node"),
    "pub": ("pub", "ros:Publisher"),
    "msg": ("msg", "msg:Twist"),
    "fut": ("fut", "ros:Future"),
    "wb": ("wb", None),  # a variable whose type was left untranslated
    "values": ("values", "list:int"),
}


def section(source: str, machines: dict[str, str] | None = None) -> tuple[Translation, Imports]:
    imports = Imports()
    t = translate_section(source, Scope(imports, dict(VARIABLES), machines or {}))
    compile("\n".join(t.lines) + "\n", "<translated>", "exec")  # Python, never run
    return t, imports


def lines(source: str) -> list[str]:
    return section(source)[0].lines


def guard(source: str) -> str:
    t = translate_guard(source, Scope(Imports(), dict(VARIABLES)))
    compile("\n".join(t.lines) + "\n", "<guard>", "eval")
    return "\n".join(t.lines)


@pytest.mark.parametrize(
    ("cpp", "python"),
    [
        ("count++;", ["count += 1"]),
        ("--count;", ["count -= 1"]),
        ("count = count / 2;", ["count = int(count / 2)"]),  # C divides integers towards zero
        ("ratio = count / 2.0;", ["ratio = count / 2.0"]),
        ("count /= 3;", ["count = int(count / 3)"]),
        ("ratio = fmod(ratio, 2) + ratio % 1.5;", ["ratio = math.fmod(ratio, 2) + math.fmod(ratio, 1.5)"]),
        ("ok = !ok == false;", ["ok = (not ok) == False"]),
        ("ok = count < 3 == ok;", ["ok = (count < 3) == ok"]),  # Python would chain
        ("ok = count > 1 && (ratio < 2 || !ok);", ["ok = count > 1 and (ratio < 2 or not ok)"]),
        ("count = ok ? 1 : 2;", ["count = 1 if ok else 2"]),
        (
            "count = (int)ratio + static_cast<int>(ratio) + int(ratio);",
            ["count = int(ratio) + int(ratio) + int(ratio)"],
        ),
        ("count = 0644 + 0x1F + 10UL;", ["count = 0o644 + 0x1F + 10"]),
        ("ratio = 1.5f + .5 + 2.;", ["ratio = 1.5 + 0.5 + 2.0"]),
        ('name = "a\\tb" "c";', ['name = "a\\tbc"']),
        ("name = 'x';", ['name = "x"']),
        ("int n = 3, m;", ["n = 3", "m = 0"]),
        ("double d; bool b; std::string s;", ["d = 0.0", "b = False", 's = ""']),
        ("int count = 1;", ["count_ = 1"]),  # a local never writes the machine variable
        ("int a[3];", ["a = [0] * 3"]),
        ("int a[] = {1, 2};", None),
        ("values[1] = 2;", ["values[1] = 2"]),
        ("auto t = geometry_msgs::msg::Twist();", ["t = Twist()"]),
        ("geometry_msgs::msg::Twist t = msg;", ["t = copy.deepcopy(msg)"]),  # C++ copies a message
        ('printf("%d items\\n", count);', ['print("%d items\\n" % (count,), end="")']),
        ('cout << "n = " << count << endl;', ['print(f"n = {count}")']),
        ('cout << ok << " " << ratio << "\\n";', ['print(f"{ok:d} {ratio:g}")']),  # 1/0 and %g, as C++
        ('cerr << "oops";', ['print("oops", end="", file=sys.stderr)']),
        ('std::stringstream ss; ss << count << "!"; name = ss.str();', ['ss = ""', 'ss += f"{count}!"', "name = ss"]),
        ("name = std::to_string(count) + name;", ["name = str(count) + name"]),
        ("count = name.length() + strlen(name.c_str());", ["count = len(name) + len(name)"]),
        (
            "if (ok) count = 1; else if (ratio > 2) count = 2; else { count = 3; }",
            ["if ok:", "    count = 1", "elif ratio > 2:", "    count = 2", "else:", "    count = 3"],
        ),
        ("for (int i = 0; i < 10; i++) count += i;", ["for i in range(10):", "    count += i"]),
        ("for (int i = 10; i >= 0; i -= 2) { count += i; }", ["for i in range(10, 0 - 1, -2):", "    count += i"]),
        ("for (int i = 0; i < 4; i++) { i++; }", ["i = 0", "while i < 4:", "    i += 1", "    i += 1"]),
        (
            "while (count < 3) { count++; if (ok) break; }",
            ["while count < 3:", "    count += 1", "    if ok:", "        break"],
        ),
        (
            "do { count--; } while (count > 0);",
            ["while True:", "    count -= 1", "    if not (count > 0):", "        break"],
        ),
        ("{ using namespace std; count = 1; }", ["count = 1"]),
        ("static int visits = 0; visits++;", ["visits += 1"]),
        (
            "// a comment\ncount = 1; // why\n/* block\n * two */",
            ["# a comment", "count = 1  # why", "# block", "# two"],
        ),
        ('suspend("Other"); resume_at(machine_index());', ['suspend("Other")', "resume(machine_name())"]),
        ("pub->publish(msg);", ["pub.publish(msg)"]),
        ("msg.linear.x = -2.0;", ["msg.linear.x = -2.0"]),
        ('RCLCPP_WARN(node->get_logger(), "low: %f", ratio);', ['node.get_logger().warning("low: %f" % (ratio,))']),
        ("ratio = fut.get()->x;", ["ratio = fut.result().x"]),
        ('unlink("/tmp/f");', ['with contextlib.suppress(OSError): os.unlink("/tmp/f")']),
        ('int f = open("/tmp/f", O_CREAT, 0644);', ['f = os.open("/tmp/f", os.O_CREAT, 0o644)']),
        ('char buf[8]; strcpy(buf, "x");', ['buf = ""', 'buf = "x"']),  # a C string buffer
    ],
)
def test_constructs(cpp: str, python: list[str] | None) -> None:
    t, _ = section(cpp)
    if python is None:
        assert t.left, t.lines
    else:
        assert t.lines == python
        assert not t.left


def test_a_static_local_becomes_a_state_variable() -> None:
    t, _ = section("static int visits = 0;\nvisits++;")
    assert [(s.name, s.annotation, s.initial, s.line) for s in t.statics] == [("visits", "int", "0", 1)]


def test_imports_follow_what_the_code_uses() -> None:
    _, imports = section("cerr << sqrt(ratio) << M_PI;\nauto r = std::make_shared<turtlesim::srv::Spawn::Request>();")
    assert imports.lines() == ["import math", "import sys", "from llfsm.msgs.turtlesim.srv import Spawn"]


@pytest.mark.parametrize(
    ("cpp", "why"),
    [
        ("wb.set(3);", "wb is of a type left untranslated"),
        ("unknown_call(3);", "unknown_call is not a function llfsm knows"),
        ("exit(EXIT_SUCCESS);", "exit ends clfsm's whole process"),
        ("return;", "a section of an llfsm machine runs to its end"),
        ("int *p = &count;", "the type int *"),
        ("switch (count) { case 1: break; }", "switch statement"),
        ("[obj message];", "C++ the parser cannot read"),
        ("suspend_at(1);", "llfsm addresses machines by name, not by load index"),
        ("name = name + count;", "+ of a string and a number"),
        ("count = a = 2;", "an assignment inside an expression"),
        ("#ifdef X\ncount = 1;\n#endif", "preproc ifdef"),
    ],
)
def test_what_is_not_translated_is_kept_marked_with_why(cpp: str, why: str) -> None:
    t, _ = section(cpp)
    assert t.left and why in t.left[0][1], t.left
    assert t.lines[0].startswith("# UNTRANSLATED (")
    assert why in t.lines[0]
    assert t.left_lines == len(cpp.strip().split("\n"))


def test_a_statement_left_inside_a_block_keeps_the_block() -> None:
    t, _ = section("if (ok) {\n  unknown_call();\n} else {\n  count = 1;\n  exit(1);\n}")
    assert t.lines == [
        "if ok:",
        "    # UNTRANSLATED (unknown_call is not a function llfsm knows): unknown_call();",
        "    pass",
        "else:",
        "    count = 1",
        "    # UNTRANSLATED (exit ends clfsm's whole process; an llfsm machine ends by reaching an accepting state): "
        "exit(1);",
    ]
    assert [line for line, _ in t.left] == [2, 5]
    assert t.code == 5  # a line holding only `}` is no line of code


def test_a_brace_too_many_never_loses_code() -> None:
    t, _ = section("}\ncount = 1;")
    assert t.left_lines == t.code == 1 and all(line.startswith("# UNTRANSLATED") for line in t.lines)


@pytest.mark.parametrize(
    ("cpp", "python"),
    [
        ("after_ms(500)", "after_ms(500)"),
        ("(count == 2)", "count == 2"),
        ("!rclcpp::ok()", "not ros.ok()"),
        ("true", "True"),
        ("timeout(1500)", "after_us(1500)"),  # CLMacros: microseconds in the state
        ("suspend_self() != CLError", "suspend_self() is None"),  # llfsm's control macros return None
        ('status("m") == CLSuspend', 'is_suspended("m")'),
        ("count > 1 && // more\n ok", "# more\ncount > 1 and ok"),
        ("count = 2", "# UNTRANSLATED (assignment expression): count = 2\nFalse"),
        ("ok); evil(", "# UNTRANSLATED (not one C++ expression the parser can read): ok); evil(\nFalse"),
    ],
)
def test_guards(cpp: str, python: str) -> None:
    assert guard(cpp) == python


def test_the_suspend_family_follows_renamed_machines() -> None:
    t, _ = section('suspend("2-fast"); if (is_running("2-fast")) count = 1;', {"2-fast": "_2_fast"})
    assert t.lines == ['suspend("_2_fast")', 'if is_running("_2_fast"):', "    count = 1"]


def test_deep_nesting_is_refused_not_a_crash() -> None:
    deep = "(" * 3000 + "count" + ")" * 3000
    assert "nested deeper than" in guard(deep)
    t, _ = section(f"count = {deep};\nok = true;")
    assert t.lines[-1] == "ok = True" and "nested deeper than" in t.left[0][1]
    t, _ = section("if (ok) {" * 400 + "count = 1;" + "}" * 400)
    assert t.left and t.left_lines == t.code


def test_names_python_or_llfsm_reserve_are_changed() -> None:
    assert [python_name(n) for n in ("lambda", "self", "after_ms", "_llfsm_x", "__init__", "count")] == [
        "lambda_", "self_", "after_ms_", "c_llfsm_x", "c_init", "count"]  # fmt: skip
    assert python_name("count", {"count"}, {"count_": 1}) == "count__"
