"""What a params file, a `-p` or a `param set` VALUE can cost (SPEC §18, issue 28 items 5 and 6):
no YAML anchors or aliases, no nesting without end, wildcard keys matched part by part (no
backtracking however long the node names), integers outside int64 refused naming where they
came from, and `param dump` writing whatever names a node answers (`a` beside `a.b`)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml
from dds_netns import NetNamespace, finish
from helpers import llfsm, llfsm_process, run_sim, write_machine
from hypothesis import given, settings
from hypothesis import strategies as st

from llfsm.ros.parameter_files import (
    INT64_MAX,
    INT64_MIN,
    ParameterTextError,
    dump,
    guess_value,
    node_pattern,
    parse_param,
    read_params_file,
)

OUTSIDE = f"is outside the 64-bit integers a parameter holds ({INT64_MIN} to {INT64_MAX})"
#: A billion-laughs params file of 1 kB: nine levels of nine aliases.
BOMB = (
    "a0: &a0 [x, x, x, x, x, x, x, x, x]\n"
    + "".join(f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 9)}]\n" for i in range(1, 9))
    + "/**:\n  ros__parameters:\n    p: *a8\n"
)


def test_anchors_and_aliases_are_refused_before_anything_is_built(tmp_path: Path) -> None:
    f = tmp_path / "bomb.yaml"
    f.write_text(BOMB)
    assert len(BOMB) < 1200
    with pytest.raises(ParameterTextError, match=rf"^{re.escape(str(f))}:1: anchors and aliases are not allowed"):
        read_params_file(f)
    r = run_sim("--node", "turtlesim", "--params-file", f, "--duration", "1s")
    assert r.status == 2 and r.stderr.strip().splitlines() == [
        f"llfsm: {f}:1: anchors and aliases are not allowed in a params file"
    ]


def test_nesting_without_end_is_refused(tmp_path: Path) -> None:
    f = tmp_path / "deep.yaml"
    f.write_text("n:\n  ros__parameters:\n    x: " + "[" * 200 + "]" * 200 + "\n")
    with pytest.raises(ParameterTextError, match=r"deep.yaml:3: nested deeper than 64 levels"):
        read_params_file(f)


# -- wildcard keys ------------------------------------------------------------------------------------


def _regex(key: str) -> re.Pattern[str]:
    """rcl's wildcards as a regular expression (what llfsm used; backtracks without end on
    hostile keys): the reference the part-by-part matcher must agree with on small cases."""
    full = key if key.startswith("/") else "/" + key
    parts = full[1:].split("/")
    return re.compile(
        "".join("(?:/[^/]+)*" if p == "**" else "/" + "[^/]*".join(map(re.escape, p.split("*"))) for p in parts)
    )


_PART = st.sampled_from(["a", "b", "ab", "ba", "aab", ""])
_KEY_PART = st.sampled_from(["a", "b", "*", "a*", "*b", "a*b", "*a*", "**"])


@settings(deadline=None, max_examples=150)
@given(st.lists(_KEY_PART, min_size=1, max_size=5), st.lists(_PART.filter(bool), min_size=1, max_size=5))
def test_wildcards_match_as_the_regular_expression_did(key_parts: list[str], name_parts: list[str]) -> None:
    key, name = "/" + "/".join(key_parts), "/" + "/".join(name_parts)
    assert bool(node_pattern(key).fullmatch(name)) == bool(_regex(key).fullmatch(name)), (key, name)


def test_examples_of_wildcards() -> None:
    assert node_pattern("/**").fullmatch("/a/b/c") and node_pattern("/**").fullmatch("/a")
    assert node_pattern("/**/driver_*").fullmatch("/robots/r1/driver_left")
    assert not node_pattern("/**/driver_*").fullmatch("/robots/driver/left")
    assert node_pattern("robots/*/driver").fullmatch("/robots/r1/driver")
    assert not node_pattern("robots/*/driver").fullmatch("/robots/driver")
    assert node_pattern("/**/**/x").fullmatch("/x") and node_pattern("/a/**/b/**/c").fullmatch("/a/q/b/c")


def test_hostile_keys_against_long_names_end(tmp_path: Path) -> None:
    """`/**/*a*a...*b` against a node named a...a, `/**/**/...` against many namespaces: a
    regular expression backtracks through every way to split the name (C(60, 30) ways); the
    parts are matched once each.  A run whose node has such a name starts, and its variable
    keeps its value; a key that does name it still sets it."""
    name = "a" * 60
    starred = "/**/" + "*a" * 30 + "*b"
    assert not node_pattern(starred).fullmatch(f"/llfsm/{name}")
    assert not node_pattern("/**" * 40 + "/b").fullmatch("/a" * 200)
    machine = write_machine(
        tmp_path,
        name,
        {"INITIAL": [("END", "True")], "END": None},
        {"INITIAL_OnEntry": "print('x =', x)"},
        variables="x: int = 1\n",
        yaml_extra="parameters: [x]",
    )
    f = tmp_path / "p.yaml"
    f.write_text(f"{starred}:\n  ros__parameters:\n    x: 2\n/**/{name[:30]}*:\n  ros__parameters:\n    x: 3\n")
    r = llfsm_process("run", "--clock", "sim", machine, "--params-file", f, timeout=120)
    assert r.status == 0 and r.stdout == "x = 3\n", r.stderr


# -- integers outside int64 ------------------------------------------------------------------------------


@pytest.mark.parametrize("number", [str(INT64_MAX + 1), str(INT64_MIN - 1), "0x" + "f" * 17, "1" + "0" * 5000])
def test_an_integer_outside_int64_is_a_usage_error_naming_where_it_came_from(tmp_path: Path, number: str) -> None:
    f = tmp_path / "p.yaml"
    f.write_text(f"turtlesim:\n  ros__parameters:\n    background_r: {number}\n")
    r = run_sim("--node", "turtlesim", "--params-file", f, "--duration", "1s")
    assert r.status == 2 and "Traceback" not in r.stderr
    [line] = r.stderr.strip().splitlines()
    assert line.startswith(f"llfsm: {f}:3: parameter background_r: ") and line.endswith(OUTSIDE)
    r = run_sim("--node", "turtlesim", "-p", f"turtlesim:background_r:={number}", "--duration", "1s")
    assert r.status == 2
    [line] = r.stderr.strip().splitlines()
    assert line.startswith("llfsm: -p 'turtlesim:background_r:=") and line.endswith(OUTSIDE)
    r = llfsm("param", "set", "/turtlesim", "background_r", "--", number)  # refused before joining the domain
    assert r.status == 2
    [line] = r.stderr.strip().splitlines()
    assert line.startswith("llfsm: param set background_r VALUE: ") and line.endswith(OUTSIDE)
    r = llfsm("param", "set", "/turtlesim", "gains", f"[1, {number}]")
    assert r.status == 2 and r.stderr.strip().endswith(OUTSIDE)


def test_the_edges_of_int64_are_values() -> None:
    assert parse_param(f"x:={INT64_MAX}")[2] == INT64_MAX and guess_value(str(INT64_MIN)) == INT64_MIN
    assert guess_value(f"[{INT64_MIN}, {INT64_MAX}]") == [INT64_MIN, INT64_MAX]
    assert guess_value("1.0e+400") == float("inf")  # a double, as rclpy reads it
    assert guess_value("2020-13-45") == "2020-13-45"  # no date: text (PyYAML raised ValueError)


# -- param dump ------------------------------------------------------------------------------------------------


def test_dump_writes_every_name_a_node_answers_and_reads_back(tmp_path: Path) -> None:
    values = {
        "a": 1,
        "a.b": 2,
        "a.c.d": [1.5, 2.5],
        "k.l": "yes",
        "k.m.n": True,
        ".lead": 1,
        "trail.": 2,
        "twice..dotted": 3,
        ".".join(["p"] * 120): "deep",
    }
    text = dump("/dotted", values)
    assert "    a: 1\n    a.b: 2\n    a.c.d:\n" in text and "    k:\n      l: 'yes'\n" in text
    f = tmp_path / "dump.yaml"
    f.write_text(text)
    [(key, read)] = read_params_file(f)
    assert key == "/dotted" and {name: value for name, (value, _) in read.items()} == values


#: An llfsm node over DDS whose parameters are `a` and `a.b` (rclpy allows both).
DOTTED_NODE = """
import time
from llfsm import ros
from llfsm.ros.transports import make
from llfsm.runtime import RunContext, WallClock
from llfsm.runtime.context import activate
ctx = RunContext(WallClock())
ctx.transport = make("dds")
activate(ctx)
ros.init()
node = ros.Node("dotted")
node.declare_parameter("a", 1)
node.declare_parameter("a.b", 2.5)
deadline = time.monotonic() + 60
while time.monotonic() < deadline:
    node._bus.spin_once(50_000_000)
"""


@pytest.mark.dds
def test_param_dump_of_a_beside_a_b_over_dds(netns: NetNamespace) -> None:
    netns.python(DOTTED_NODE)
    status, out, err = finish(netns.llfsm("param", "dump", "/dotted", "--timeout", "30"), 60)
    assert status == 0, err
    assert yaml.safe_load(out) == {"/dotted": {"ros__parameters": {"a": 1, "a.b": 2.5}}}
