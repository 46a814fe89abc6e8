"""Machine variables inside the functions, lambdas, comprehensions and classes of machine code
(issue 18, "A machine's own classes").

A bare name that is a machine (or state) variable means that variable in every scope of a
section, whatever the parameters of the scopes around it are called: `def get(self): return
count` in a class defined in OnEntry reads the machine's `count`, and `self` stays the
instance's own.  A parameter, a comprehension variable or a class attribute of the same name
hides the variable in its own scope, as Python's scoping says.  Each case is checked (`llfsm
check` accepts it) and run under the sim clock, where the printed values show what each name
meant.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from helpers import llfsm, run_sim, write_machine

from llfsm.lang.check import check_machine

ONE_STATE = {"A": [("END", "True")], "END": None}


def _codes(m: Path) -> list[str]:
    return [d.code for d in check_machine(m).diagnostics]


def _run(m: Path, *args: str) -> list[str]:
    """Check the machine (no diagnostic at all), run it under the sim clock; its printed lines."""
    checked = check_machine(m)
    assert checked.diagnostics == [], checked.diagnostics
    r = run_sim(m, "--duration", "50ms", *args)
    assert r.status == 0, r.stderr
    return r.lines


def _entry(tmp_path: Path, code: str, variables: str = "count: int = 3\n", **files: str) -> list[str]:
    """Run a machine whose state A has `code` as OnEntry and goes to END; its printed lines."""
    m = write_machine(tmp_path, "m", ONE_STATE, {"A_OnEntry": code, **files}, variables=variables)
    return _run(m)


# -- methods whose first parameter is `self` ------------------------------------------------------


def test_a_method_with_self_reads_a_machine_variable(tmp_path: Path) -> None:
    code = "class Box:\n    def get(self):\n        return count\nprint(Box().get())\n"
    assert _entry(tmp_path, code) == ["3"]


def test_a_method_with_self_assigns_machine_variables(tmp_path: Path) -> None:
    """`count += 1` in a method assigns the machine variable, as a bare name does anywhere in a
    section: a name a section assigns is the machine's if it is declared, else a local."""
    code = (
        "class Counter:\n"
        "    def bump(self, by):\n"
        "        count += by\n"
        "        label = f'bumped by {by}'\n"
        "        total = count * 10\n"  # not declared: a local of bump
        "        return total\n"
        "c = Counter()\n"
        "print(c.bump(2), c.bump(1), count, label)\n"
    )
    assert _entry(tmp_path, code, "count: int = 3\nlabel: str = ''\n") == ["50 60 6 bumped by 1"]


def test_self_is_the_instance_and_its_attributes_are_its_own(tmp_path: Path) -> None:
    """`self.count` is the instance's attribute; the bare `count` is the machine's."""
    code = (
        "class Box:\n"
        "    def __init__(self, k):\n"
        "        self.count = count * k\n"
        "        self.k = k\n"
        "    def both(self):\n"
        "        return self.count, count, self.k\n"
        "    def __repr__(self):\n"
        "        return f'Box({self.k})'\n"
        "b = Box(10)\n"
        "count = 4\n"
        "print(b.both(), b, [Box(2)])\n"
    )
    assert _entry(tmp_path, code) == ["(30, 4, 10) Box(10) [Box(2)]"]


def test_methods_see_machine_variables_when_called_later_from_another_state(tmp_path: Path) -> None:
    """An instance kept in a machine variable keeps reaching the machine: its methods run in
    other states' sections (a callback works the same way)."""
    m = write_machine(
        tmp_path,
        "m",
        {"A": [("B", "True")], "B": [("END", "count >= 5")], "END": None},
        {
            "A_OnEntry": (
                "class Ticker:\n    def tick(self):\n        count += 1\n        return count\nticker = Ticker()\n"
            ),
            "B_Internal": "print('tick', ticker.tick())\n",
            "END_OnEntry": "print('end', count)\n",
        },
        variables="count: int = 2\nticker: object\n",
    )
    assert _run(m) == ["tick 3", "tick 4", "tick 5", "end 5"]


def test_super_class_methods_and_static_methods(tmp_path: Path) -> None:
    code = (
        "class Base:\n"
        "    def __init__(self):\n"
        "        self.v = count\n"
        "class Child(Base):\n"
        "    def __init__(self):\n"
        "        super().__init__()\n"
        "        self.w = count + 1\n"
        "    @classmethod\n"
        "    def make(cls):\n"
        "        return cls()\n"
        "    @staticmethod\n"
        "    def plus(self):\n"  # a static method whose parameter happens to be called self
        "        return self + count\n"
        "    @property\n"
        "    def twice(self):\n"
        "        return count * 2\n"
        "c = Child.make()\n"
        "print(c.v, c.w, Child.plus(10), c.twice)\n"
    )
    assert _entry(tmp_path, code) == ["3 4 13 6"]


def test_a_default_value_of_a_method_is_evaluated_where_the_def_stands(tmp_path: Path) -> None:
    code = "class Box:\n    def get(self, k=count):\n        return k, count\ncount = 7\nprint(Box().get())\n"
    assert _entry(tmp_path, code) == ["(3, 7)"]


# -- other nested scopes whose `self` is the user's ----------------------------------------------------


def test_nested_functions_and_lambdas_with_a_self_parameter(tmp_path: Path) -> None:
    code = (
        "def f(self, k):\n"
        "    return self + count + k\n"
        "g = lambda self: self * count\n"
        "def outer(self):\n"
        "    def inner():\n"
        "        return self + count\n"  # inner's `self` is outer's parameter
        "    return inner() + (lambda: count)()\n"
        "print(f(10, 100), g(2), outer(1))\n"
    )
    assert _entry(tmp_path, code) == ["113 6 7"]


def test_a_function_whose_local_is_called_self(tmp_path: Path) -> None:
    code = "def f():\n    self = 10\n    return self + count\nprint(f())\n"
    assert _entry(tmp_path, code) == ["13"]


def test_comprehensions_binding_self(tmp_path: Path) -> None:
    code = (
        "a = [self + count for self in range(2)]\n"
        "b = {self: count for self in 'xy'}\n"
        "c = [[self * count for _ in range(1)] for self in range(2)]\n"
        "class Box:\n"
        "    def get(self):\n"
        "        return [self.k + count for _ in range(2)], {self.k: count}\n"
        "    k = 1\n"
        "print(a, b, c, Box().get())\n"
    )
    assert _entry(tmp_path, code) == ["[3, 4] {'x': 3, 'y': 3} [[0], [3]] ([4, 4], {1: 3})"]


def test_a_class_body_that_binds_self(tmp_path: Path) -> None:
    code = "class Box:\n    self = 5\n    seen = self + count\nprint(Box.seen, Box.self)\n"
    assert _entry(tmp_path, code) == ["8 5"]


def test_a_guard_with_a_lambda_whose_parameter_is_self(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "m",
        {"A": [("END", "(lambda self: self + count > 4)(2)")], "END": None},
        {"A_OnEntry": "print('A', count)\n", "END_OnEntry": "print('END', count)\n"},
        variables="count: int = 3\n",
    )
    assert _run(m) == ["A 3", "END 3"]


# -- hiding: the innermost binding wins, as in Python ----------------------------------------------


def test_a_parameter_named_like_a_machine_variable_hides_it(tmp_path: Path) -> None:
    code = (
        "class Box:\n"
        "    def set(self, count):\n"
        "        self.count = count\n"
        "        return count\n"
        "    def get(self):\n"
        "        return self.count, count\n"
        "b = Box()\n"
        "print(b.set(9), b.get(), (lambda self, count: count)(0, 8), count)\n"
    )
    assert _entry(tmp_path, code) == ["9 (9, 3) 8 3"]


def test_a_class_attribute_named_like_a_machine_variable(tmp_path: Path) -> None:
    """In the class body, `count` is the class attribute; in its methods (which do not see the
    class body, as in Python) it is the machine variable again."""
    code = (
        "class Box:\n"
        "    count = 10\n"
        "    doubled = count * 2\n"
        "    def get(self):\n"
        "        return self.count, count, Box.count\n"
        "print(Box.doubled, Box().get(), count)\n"
    )
    assert _entry(tmp_path, code) == ["20 (10, 3, 10) 3"]


# -- state variables, every kind of section, initialisers ---------------------------------------------


def test_state_variables_in_methods(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "m",
        {"PING": [("END", "visits == 3"), ("PING", "True")], "END": None},
        {
            "PING_Variables": "visits: int = 0\n",
            "PING_OnEntry": (
                "class Visit:\n"
                "    def add(self):\n"
                "        visits += 1\n"
                "        total += visits\n"
                "        return self\n"
                "    def show(self):\n"
                "        return f'visit {visits} total {total}'\n"
                "print(Visit().add().show())\n"
            ),
        },
        variables="total: int = 0\n",
    )
    assert _run(m) == ["visit 1 total 1", "visit 2 total 3", "visit 3 total 6"]


def test_every_section_kind(tmp_path: Path) -> None:
    """OnEntry, Internal, OnExit, OnSuspend and OnResume, and a section compiled into a method
    of its own (B's OnEntry binds a local `math` while its guard reads the module `math`)."""
    method = "class H:\n    def go(self, tag):\n        count += 1\n        print(tag, count)\nH().go({tag!r})\n"
    m = write_machine(
        tmp_path,
        "m",
        {"A": [("B", "after_ms(2)")], "B": [("END", "resumed and math.pi > 3")], "END": None},
        {
            "A_OnEntry": method.format(tag="entry"),
            "A_Internal": method.format(tag="internal"),
            "A_OnExit": method.format(tag="exit"),
            "B_OnEntry": "math = 1\n" + method.format(tag="entry B") + "if not resumed:\n    suspend_self()\n",
            "B_OnSuspend": method.format(tag="suspend"),
            "B_OnResume": "resumed = True\n" + method.format(tag="resume"),
            "SUSPENDED_OnEntry": "resume(machine_name())\n",
        },
        variables="count: int = 0\nresumed: bool = False\n",
        includes="import math\n",
    )
    assert _run(m) == [
        "entry 1",
        "internal 2",
        "internal 3",
        "internal 4",
        "exit 5",
        "entry B 6",
        "suspend 7",
        "resume 8",
        "entry B 9",
    ]
    r = llfsm("build", m, "-o", tmp_path / "out")
    assert r.status == 0, r.stderr
    assert "    def on_entry_B(self) -> None:\n        _llfsm_machine = self" in (tmp_path / "out" / "m.py").read_text()


def test_variable_initialisers(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "m",
        ONE_STATE,
        {"A_OnEntry": "count = 5\nprint(get(None), make().twice())\n"},
        variables=(
            "count: int = 3\n"
            "get: object = lambda self: count + 1\n"
            "make: object = lambda: type('T', (), {'twice': lambda self: count * 2})()\n"
        ),
    )
    assert _run(m) == ["6 10"]


# -- what stays an error ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "code",
    [
        "class Box:\n    def get(self):\n        global count\n        count = 1\n",
        "class Box:\n    def get(self):\n        def inner():\n            nonlocal self\n            self = 1\n",
    ],
)
def test_global_and_nonlocal_are_still_errors(tmp_path: Path, code: str) -> None:
    m = write_machine(tmp_path, "m", ONE_STATE, {"A_OnEntry": code}, variables="count: int = 3\n")
    assert _codes(m) == ["LF034"]


@pytest.mark.parametrize(
    "code",
    [
        "self = 3\n",
        "print(self)\n",
        "def f():\n    return self\n",  # nothing the user wrote binds it: it would be the machine
        # a class body's names are not seen in its methods
        "class Box:\n    self = 1\n    def get(this):\n        return self\n",
        "x = [(self := 1) for _ in range(2)]\n",  # := binds in the section's own scope
    ],
)
def test_the_machines_own_self_is_still_reserved(tmp_path: Path, code: str) -> None:
    m = write_machine(tmp_path, "m", ONE_STATE, {"A_OnEntry": code}, variables="count: int = 3\n")
    diags = check_machine(m).diagnostics
    assert [d.code for d in diags] == ["LF013"], diags
    assert "`self`" in diags[0].message and "this" not in diags[0].message


def test_check_never_runs_the_classes_it_reads(tmp_path: Path) -> None:
    marker = tmp_path / "ran"
    code = f"class Box:\n    open({str(marker)!r}, 'w')\n    def get(self):\n        return count\n"
    m = write_machine(tmp_path, "m", ONE_STATE, {"A_OnEntry": code}, variables="count: int = 3\n")
    assert _codes(m) == []
    assert not marker.exists()


# -- the generated module ---------------------------------------------------------------------------


def test_the_module_names_the_machine_plainly_and_only_where_self_is_taken(tmp_path: Path) -> None:
    """Where the user's `self` hides the machine's, the module reaches the machine through one
    alias bound before the block, with a comment saying why; elsewhere nothing changes."""
    code = "class Box:\n    def get(self):\n        return count\nprint(Box().get(), count)\n"
    m = write_machine(tmp_path, "m", ONE_STATE, {"A_OnEntry": code}, variables="count: int = 3\n")
    r = llfsm("build", m, "-o", tmp_path / "out")
    assert r.status == 0, r.stderr
    text = (tmp_path / "out" / "m.py").read_text()
    assert "        return _llfsm_machine.count\n" in text
    assert "print(Box().get(), self.count)\n" in text
    assert text.count("_llfsm_machine = self") == 1
    plain = write_machine(tmp_path / "p", "m", ONE_STATE, {"A_OnEntry": "print(count)\n"}, variables="count: int = 3\n")
    assert llfsm("build", plain, "-o", tmp_path / "p" / "out").status == 0
    assert "_llfsm_machine" not in (tmp_path / "p" / "out" / "m.py").read_text()


def test_an_error_in_a_method_points_at_the_users_line(tmp_path: Path) -> None:
    code = "class Box:\n    def get(self):\n        return count / 0\nprint(Box().get())\n"
    m = write_machine(tmp_path, "m", ONE_STATE, {"A_OnEntry": code}, variables="count: int = 3\n")
    r = run_sim(m, "--duration", "20ms")
    assert r.status == 1
    assert "State_A_OnEntry.py:3: error: ZeroDivisionError" in r.stderr, r.stderr
    assert "return count / 0" in r.stderr, r.stderr
