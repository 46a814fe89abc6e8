"""Inputs (SPEC 11): declared in machine.yaml, checked, compiled, and read at run time as a
snapshot at the start of each ringlet, from the newest message on a topic when bound."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from helpers import MACHINES, llfsm, run_sim, write_machine

from llfsm.lang.check import check_machine

BOOL_INPUT = """inputs:
  wall_close:
    type: bool
    topic: /wall_close
    msg: std_msgs/msg/Bool
    field: data
"""

PUB_INCLUDES = "from llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import Bool\n"


def codes(path: Path) -> list[tuple[str, str, int]]:
    return sorted((d.code, Path(d.file).name, d.line) for d in check_machine(path).diagnostics)


def publisher(root: Path, after_ms: int = 3) -> Path:
    """A machine that publishes Bool(data=True) on /wall_close once, `after_ms` after it starts."""
    return write_machine(
        root,
        "pub",
        {"INITIAL": [("ON", f"after_ms({after_ms})")], "ON": [("END", "True")], "END": None},
        {
            "INITIAL_OnEntry": 'ros.init()\nnode = ros.Node("pub")\np = node.create_publisher(Bool, "/wall_close", 10)',
            "ON_OnEntry": "p.publish(Bool(data=True))",
        },
        variables="p: ros.Publisher\nnode: ros.Node\n",
        includes=PUB_INCLUDES,
    )


def reader(root: Path) -> Path:
    """A machine that waits for its input wall_close, printing it at each ringlet."""
    return write_machine(
        root,
        "rd",
        {"WAIT": [("SEEN", "wall_close")], "SEEN": None},
        {"WAIT_Internal": 'print("wait", wall_close)', "SEEN_OnEntry": 'print("seen", wall_close)'},
        yaml_extra=BOOL_INPUT,
    )


# -- check ------------------------------------------------------------------------------------------


def test_assigning_an_input_is_an_error_where_the_name_is_the_machines(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "m",
        {"A": [("END", "wall_close")], "END": None},
        {
            "A_OnEntry": "wall_close = True\nf = lambda wall_close: wall_close\n",
            "A_Internal": "del wall_close\n",
            "A_OnExit": "x = [wall_close for wall_close in (1, 2)]\nwall_close.real = 1\n",
        },
        yaml_extra=BOOL_INPUT,
    )
    assert codes(m) == [
        ("LF046", "State_A_Internal.py", 1),
        ("LF046", "State_A_OnEntry.py", 1),
        ("LF046", "State_A_OnExit.py", 2),
    ]


def test_augmented_assignment_of_an_input_is_refused_and_reading_one_is_fine(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "m",
        {"A": [("END", "speed > 1.0")], "END": None},
        {"A_OnEntry": "speed += 1\n", "A_Internal": "print(speed * 2)\n"},
        yaml_extra="inputs:\n  speed:\n    type: float\n    domain: [0, 2.5]\n",
    )
    assert codes(m) == [("LF046", "State_A_OnEntry.py", 1)]


def test_input_names_values_and_bindings_are_checked(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "m",
        {"A": [("END", "True")], "END": None},
        variables="count: int = 0\n",
        yaml_extra="""inputs:
  count:
    type: int
  after:
    type: bool
  speed:
    type: float
    default: "fast"
  mode:
    type: int
    domain: [1, 2.5]
  twice:
    type: str
    domain: [a, a]
  kind:
    type: complex
  pose_x:
    type: int
    topic: /turtle1/pose
    msg: turtlesim/msg/Pose
    field: x
  typo:
    type: bool
    topic: /b
    msg: std_msgs/msg/Bool
    field: dat
  unknown:
    type: bool
    topic: /b
    msg: nowhere_msgs/msg/Bool
    field: data
  half:
    type: bool
    topic: /b
  nested:
    type: float
    topic: /cmd_vel
    msg: geometry_msgs/msg/Twist
    field: linear.x
""",
    )
    got = check_machine(m).diagnostics
    by_code = sorted((d.code, d.line) for d in got)
    assert by_code == [
        ("LF047", 2),  # count: a machine variable
        ("LF047", 4),  # after: a macro
        ("LF048", 8),  # default "fast" for a float
        ("LF048", 11),  # 2.5 for an int
        ("LF048", 14),  # a listed twice
        ("LF048", 16),  # type complex
        ("LF049", 21),  # a float32 field for an int input
        ("LF049", 26),  # no field dat
        ("LF049", 30),  # no package nowhere_msgs
        ("LF049", 34),  # topic without msg and field
    ]
    messages = " ".join(d.message for d in got)
    assert "std_msgs/msg/Bool has no field 'dat' (its fields: data)" in messages
    assert "is a float32, which an int input cannot hold" in messages
    assert "add msg, field" in messages


def test_an_input_in_the_interface_search_path_is_checked_from_its_msg_file(tmp_path: Path, monkeypatch) -> None:
    pkg = tmp_path / "ifaces" / "sensor_msgs_x" / "msg"
    pkg.mkdir(parents=True)
    (pkg / "Range.msg").write_text("# a distance\nfloat32 range\nbool valid\n")
    monkeypatch.setenv("LLFSM_INTERFACE_PATH", str(tmp_path / "ifaces"))
    yaml = "inputs:\n  near:\n    type: float\n    topic: /range\n    msg: sensor_msgs_x/msg/Range\n    field: {}\n"
    ok = write_machine(tmp_path / "a", "m", {"A": None}, yaml_extra=yaml.format("range"))
    bad = write_machine(tmp_path / "b", "m", {"A": None}, yaml_extra=yaml.format("distance"))
    assert codes(ok) == []
    assert codes(bad) == [("LF049", "machine.yaml", 6)]


# -- build --------------------------------------------------------------------------------------------


def test_the_class_lists_its_inputs_and_a_machine_without_has_no_trace_of_them(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "m",
        {"A": [("END", "wall_close or mode == 2")], "END": None},
        yaml_extra=BOOL_INPUT + "  mode:\n    type: float\n    default: 1\n    domain: [1, 2]\n",
    )
    plain = write_machine(tmp_path, "p", {"A": [("END", "True")], "END": None})
    assert llfsm("build", m, plain, "-o", tmp_path / "out").status == 0
    text = (tmp_path / "out" / "m.py").read_text()
    assert "('wall_close', 'bool', False, (False, True), '/wall_close', 'std_msgs/msg/Bool', 'data')," in text
    assert "('mode', 'float', 1.0, (1.0, 2.0), None, None, None)," in text
    assert "__slots__ = ('wall_close', 'mode')" in text
    assert "if self.wall_close or self.mode == 2:" in text
    assert "INPUTS" not in (tmp_path / "out" / "p.py").read_text()


# -- run ------------------------------------------------------------------------------------------------


def test_a_bound_input_takes_the_newest_message_at_the_start_of_each_ringlet(tmp_path: Path) -> None:
    pub, rd = publisher(tmp_path), reader(tmp_path)
    # pub's after_ms(3) holds at 4 ms: ON's OnEntry publishes in round 5, before rd's ringlet of
    # that round, whose guard sees it (rd's Internal ran in rounds 0-4)
    first = run_sim(pub, rd)
    assert first.status == 0, first.stderr
    assert first.lines == ["wait False"] * 5 + ["seen True"]
    # rd first: the message comes after rd's ringlet of round 5, so rd sees it one round later
    second = run_sim(rd, pub)
    assert second.lines == ["wait False"] * 6 + ["seen True"]


def test_an_input_never_changes_during_a_ringlet_even_when_the_machine_publishes_it(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "self_feed",
        {"A": [("B", "after_ms(1)")], "B": [("END", "after_ms(1)")], "END": None},
        {
            "A_OnEntry": 'ros.init()\nnode = ros.Node("n")\np = node.create_publisher(Bool, "/wall_close", 10)',
            "B_OnEntry": 'print("before", wall_close)\np.publish(Bool(data=True))\nprint("after", wall_close)',
            "B_Internal": 'print("internal", wall_close)',
        },
        variables="p: ros.Publisher\nnode: ros.Node\n",
        includes=PUB_INCLUDES,
        yaml_extra=BOOL_INPUT,
    )
    r = run_sim(m)
    assert r.status == 0, r.stderr
    # Internal runs in the entry ringlet too (the guard waits): still the ringlet's snapshot;
    # the next ringlet takes the new value
    assert r.lines == ["before False", "after False", "internal False", "internal True"]


def test_an_unbound_input_keeps_its_default(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "m",
        {"A": [("END", "after_ms(2)")], "END": None},
        {"A_Internal": "print(mode, type(mode).__name__)"},
        yaml_extra="inputs:\n  mode:\n    type: float\n    default: 3\n    domain: [1, 3]\n",
    )
    r = run_sim(m)
    assert r.lines == ["3.0 float"] * 3


def test_a_binding_that_clashes_with_the_topics_type_is_one_line_naming_machine_yaml(tmp_path: Path) -> None:
    pub = write_machine(
        tmp_path,
        "pub",
        {"A": None},
        {"A_OnEntry": 'ros.init()\nnode = ros.Node("pub")\np = node.create_publisher(Bool, "/wall_close", 10)'},
        includes=PUB_INCLUDES,
    )
    rd = write_machine(
        tmp_path,
        "rd",
        {"A": None},
        yaml_extra=BOOL_INPUT.replace("wall_close:", "n:").replace("bool", "int").replace("Bool", "Int32"),
    )
    # the reader binds first, with Int32; pub's Bool publisher then fails in its own code
    r = run_sim(rd, pub)
    assert r.status == 1
    assert "State_A_OnEntry.py:3" in r.stderr and "Traceback" not in r.stderr
    # two machines binding one topic with two types: the session refuses before the first round
    rd2 = write_machine(
        tmp_path,
        "rd2",
        {"A": None},
        yaml_extra=BOOL_INPUT.replace("wall_close:", "b:"),
    )
    r = run_sim(rd, rd2)
    assert r.status == 2
    assert "rd2.machine/machine.yaml: input b (topic /wall_close)" in r.stderr
    assert "Traceback" not in r.stderr


def test_remaps_apply_to_a_bound_inputs_topic(tmp_path: Path) -> None:
    pub, rd = publisher(tmp_path), reader(tmp_path)
    r = run_sim(pub, rd, "--remap", "/wall_close:=/elsewhere", "--duration", "20ms")
    # both the publisher and the input's reader are remapped: the message still arrives
    assert r.lines[-1] == "seen True"


def test_the_description_the_graph_and_the_schema_show_inputs(tmp_path: Path) -> None:
    from llfsm.diagram.description import validate
    from llfsm.ros.control import description
    from llfsm.targets import load

    rd = reader(tmp_path)
    desc = description(load(str(rd)))
    assert desc["inputs"] == [
        {
            "name": "wall_close",
            "type": "bool",
            "default": False,
            "domain": [False, True],
            "topic": "/wall_close",
            "msg": "std_msgs/msg/Bool",
            "field": "data",
        }
    ]
    assert validate(json.loads(json.dumps(desc)))["inputs"][0]["topic"] == "/wall_close"
    mermaid = llfsm("graph", rd).stdout
    assert "%% input wall_close: bool <- /wall_close (std_msgs/msg/Bool data)" in mermaid
    dot = llfsm("graph", rd, "--format", "dot").stdout
    assert "__inputs [shape=note" in dot
    schema = json.loads(llfsm("schema").stdout)
    assert set(schema["$defs"]["YamlInput"]["properties"]) == {"type", "default", "domain", "topic", "msg", "field"}


def test_the_wall_follower_follows_turtlesim_s_walls_on_its_sensor_input(tmp_path: Path) -> None:
    trace = tmp_path / "t.jsonl"
    r = run_sim(
        "--node", "turtlesim", "--node", "wall_sensor", MACHINES / "wall_follower.machine",
        "--duration", "40s", "--trace", trace, "--echo", "/turtle1/pose",
    )  # fmt: skip
    assert r.status == 0, r.stderr
    assert "I hit the wall" not in r.stderr
    events = [json.loads(line) for line in trace.read_text().splitlines()]
    turns = [e for e in events if e["event"] == "entry" and e["state"] == "TURN"]
    assert len(turns) >= 3, "the sensor never made it turn"
    xs = [float(line.split()[1]) for line in r.stdout.splitlines() if line.startswith("x: ")]
    assert max(xs) > 9.0 and min(xs) < 2.0, "it did not go round the arena"


def test_the_web_view_lists_a_machine_s_inputs() -> None:
    import asyncio

    aiohttp = pytest.importorskip("aiohttp")
    from llfsm import ros
    from llfsm.ros.control import enable
    from llfsm.runtime import Arrangement, RunContext, SimClock
    from llfsm.runtime.context import activate
    from llfsm.targets import load
    from llfsm.web.server import WebServer
    from llfsm.web.source import RunSource

    ctx = RunContext(SimClock())
    prev = activate(ctx)
    try:
        arr = Arrangement([load(str(MACHINES / "wall_follower.machine"))], context=ctx)
        ros.init()
        enable(ctx)
        srv = WebServer(RunSource(arr, ros.bus_of()), "127.0.0.1", 0)
        srv.start()
    finally:
        activate(prev)

    async def hello() -> dict:  # type: ignore[type-arg]
        async with aiohttp.ClientSession() as s, s.ws_connect(f"ws://127.0.0.1:{srv.port}/ws") as ws:
            return json.loads((await ws.receive()).data)  # type: ignore[no-any-return]

    try:
        first = asyncio.run(hello())
    finally:
        srv.stop()
    assert first["type"] == "hello"
    assert first["machines"][0]["inputs"] == ["wall_close: bool <- /turtle1/wall_close (std_msgs/msg/Bool data)"]


def test_a_message_between_rounds_is_the_next_ringlet_s_snapshot(tmp_path: Path) -> None:
    # a timer publishes between rounds (the bus's hook, where no ringlet runs, so the value goes
    # into the machine at once: llfsm.runtime.inputs); each ringlet sees the newest value
    # published before it, as with a machine publishing during a round
    m = write_machine(
        tmp_path,
        "timed",
        {"A": [("B", "after_ms(1)")], "B": [("END", "n >= 6")], "END": None},
        {
            "A_OnEntry": (
                'ros.init()\nnode = ros.Node("n")\np = node.create_publisher(Bool, "/wall_close", 10)\n'
                "t = node.create_timer(0.002, lambda: p.publish(Bool(data=not wall_close)))"
            ),
            "B_Internal": "print(node.get_clock().now().nanoseconds // 1_000_000, wall_close)\nn += 1",
        },
        variables="p: ros.Publisher\nnode: ros.Node\nt: ros.Timer\nn: int = 0\n",
        includes=PUB_INCLUDES,
        yaml_extra=BOOL_INPUT,
    )
    r = run_sim(m)
    assert r.status == 0, r.stderr
    # B's ringlets run at 3..8 ms; the timer flips the value at 2, 4, 6 and 8 ms, before the round
    assert r.lines == ["3 True", "4 False", "5 False", "6 True", "7 True", "8 False"], r.lines
