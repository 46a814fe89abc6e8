"""SPEC 16: the world as a verification file declares it (`environment:`), bounds, the how-to's
four machines verified as written, and refusals at every place of use."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from helpers import MACHINES, llfsm, write_machine

WALL = MACHINES / "ros2_wall_turtle_bot.machine"


def _wall_file(tmp_path: Path, may_fail: bool, props: str) -> Path:
    f = tmp_path / "wall.verify.yaml"
    f.write_text(
        f"machines: [{WALL}]\n"
        "environment:\n  services:\n    /turtle_pose_service:\n"
        "      type: turtle_sensor_interface/srv/TurtlePosition\n"
        "      responses: [{x: 5.5, y: 5.5}, {x: 9.5, y: 5.5}]\n"
        f"      may_fail: {'true' if may_fail else 'false'}\n"
        f"properties:\n{props}"
    )
    return f


@pytest.mark.parametrize("name", ["ping_pong", "blind_turtle_bot", "wall_turtle_bot", "suspend_resume"])
def test_the_shipped_verification_files_hold(name: str) -> None:
    r = llfsm("verify", MACHINES / f"{name}.verify.yaml", "--format", "json")
    assert r.status == 0, r.stdout + r.stderr
    doc = json.loads(r.stdout)
    assert doc["properties"] and all(p["verdict"] == "holds" for p in doc["properties"])


def test_the_wall_bot_is_refused_without_an_environment_and_told_how() -> None:
    r = llfsm("verify", WALL)
    assert r.status == 2
    assert "State_STOP_OnEntry.py:5" in r.stdout and "call_async" in r.stdout
    assert "environment:" in r.stdout


def test_the_wall_bot_with_and_without_may_fail(tmp_path: Path) -> None:
    never_fails = '  - never: state(ros2_wall_turtle_bot) == "SERVICE_FAILS"\n'
    r = llfsm("verify", _wall_file(tmp_path, False, never_fails))
    assert r.status == 0, r.stdout + r.stderr
    r = llfsm("verify", _wall_file(tmp_path, True, never_fails))
    assert r.status == 1
    assert "environment: /turtle_pose_service did not answer (may_fail)" in r.stdout
    assert "I_wait: None -> FutureReturnCode.TIMEOUT" in r.stdout


def test_the_counterexample_names_the_response_chosen(tmp_path: Path) -> None:
    r = llfsm("verify", _wall_file(tmp_path, False, '  - never: state(ros2_wall_turtle_bot) == "BACK"\n'))
    assert r.status == 1
    assert "environment: /turtle_pose_service answered response 1 {x: 9.5, y: 5.5}" in r.stdout
    assert "position_x: 0.0 -> 9.5" in r.stdout


def test_a_declaration_that_names_an_unknown_field_is_one_line(tmp_path: Path) -> None:
    f = tmp_path / "w.verify.yaml"
    f.write_text(
        f"machines: [{WALL}]\nenvironment:\n  services:\n    /turtle_pose_service:\n"
        "      type: turtle_sensor_interface/srv/TurtlePosition\n      responses: [{z: 1.0}]\n"
    )
    r = llfsm("verify", f)
    assert r.status == 2
    assert f"{f}:4: service /turtle_pose_service" in r.stderr and "no field 'z'" in r.stderr


def _reader(tmp_path: Path, push: bool = False) -> Path:
    """A machine reading /bump: PULL (a guard on `sub.latest`), or PUSH (a callback keeping the
    values in `hits`, a guard on them)."""
    name = "pusher" if push else "reader"
    callback, guard = (
        ("lambda msg: hits.add(msg.data)", "True in hits")
        if push
        else ("None", "sub.latest is not None and sub.latest.data")
    )
    return write_machine(
        tmp_path,
        name,
        {"WAIT": [("HIT", guard)], "HIT": None},
        {
            "WAIT_OnEntry": f'ros.init()\nnode = ros.Node("{name}")\n'
            f'sub = node.create_subscription(Bool, "/bump", {callback}, 10)\n'
        },
        variables="node: ros.Node\nsub: ros.Subscription\nhits: set = set()\n",
        includes="from llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import Bool\n",
    )


def test_a_pull_reader_takes_the_topics_values(tmp_path: Path) -> None:
    m = _reader(tmp_path)
    f = tmp_path / "r.verify.yaml"
    f.write_text(
        f"machines: [{m}]\nenvironment:\n  topics:\n    /bump:\n      type: std_msgs/msg/Bool\n"
        "      values: [{data: false}, {data: true}]\n"
        'properties:\n  - never: state(reader) == "HIT"\n'
    )
    r = llfsm("verify", f)
    assert r.status == 1, r.stdout + r.stderr
    assert "environment: /bump: a message {data: True}" in r.stdout
    # without the environment the reader is refused where it reads
    r = llfsm("verify", m)
    assert r.status == 2 and "State_WAIT_Transition_0.expr" in r.stdout


def test_a_bound_stops_a_growing_counter(tmp_path: Path) -> None:
    f = tmp_path / "p.verify.yaml"
    f.write_text(f"machines: [{MACHINES / 'ros2_ping_pong.machine'}]\nbounds:\n  ros2_ping_pong.count: 2\n")
    r = llfsm("verify", f)
    assert r.status == 0, r.stdout + r.stderr
    assert "bounded: ros2_ping_pong.count <= 2" in r.stdout
    f.write_text(f"machines: [{MACHINES / 'ros2_ping_pong.machine'}]\nbounds:\n  ros2_ping_pong.counter: 2\n")
    r = llfsm("verify", f)
    assert r.status == 2 and "bounds: ros2_ping_pong.counter" in r.stderr


def test_a_push_callback_runs_with_the_topics_values(tmp_path: Path) -> None:
    m = _reader(tmp_path, push=True)
    f = tmp_path / "p.verify.yaml"
    f.write_text(
        f"machines: [{m}]\nenvironment:\n  topics:\n    /bump:\n      type: std_msgs/msg/Bool\n"
        "      values: [{data: false}, {data: true}]\n"
        'properties:\n  - never: state(pusher) == "HIT"\n  - reachable: False in pusher.hits\n'
    )
    r = llfsm("verify", f)
    assert r.status == 1, r.stdout + r.stderr
    out = r.stdout
    assert 'never: state(pusher) == "HIT": fails (' in out and "reachable: False in pusher.hits: holds (" in out
    # the callback ran with the value chosen before the ringlet that then took the transition
    assert "environment: /bump: a message {data: True}" in out
    assert "pusher.hits: set() -> {True}" in out  # an empty set as Python prints it ({} is a dict)
    # without the environment the subscription is refused where it is made
    r = llfsm("verify", m)
    assert r.status == 2 and "State_WAIT_OnEntry.py:3" in r.stdout


def _caller(tmp_path: Path) -> Path:
    """A verification file whose machine calls a service of the environment in every way the
    executor orders: a call spun for at once, one behind a callback its own publish queued, one
    cancelled before the spin, one never spun for (answered after the ringlet), with Ctrl-C; and
    after waiting for the service, through a second client of the same name, a call whose
    future has a done callback and a synchronous `call` (three choices in one step)."""
    m = write_machine(
        tmp_path,
        "caller",
        {"INIT": [("ASK", "True")], "ASK": [("ASK", "True")]},
        {
            "INIT_OnEntry": 'ros.init()\nnode = ros.Node("caller")\n'
            'client = node.create_client(TurtlePosition, "/where")\n'
            'client2 = node.create_client(TurtlePosition, "/where")\n'
            'pub = node.create_publisher(Bool, "/ping", 10)\n'
            'sub = node.create_subscription(Bool, "/ping", lambda msg: heard.append(msg.data), 10)\n',
            "ASK_OnEntry": "heard.clear()\n"
            "if count == 1:\n    pub.publish(Bool(data=True))\n"
            "f = client.call_async(TurtlePosition.Request())\n"
            "early = f.done() or f.result() is not None\n"
            "if count == 2:\n    f.cancel()\n"
            "if count != 3:\n    code = str(ros.spin_until_future_complete(node, f))\n"
            "x = f.result().x if f.result() is not None else -1.0\n"
            "seen.clear()\n"
            "if count == 4 and client2.wait_for_service(timeout_sec=1.0) and client2.service_is_ready():\n"
            "    g = client2.call_async(TurtlePosition.Request())\n"
            "    g.add_done_callback(lambda fut: seen.append(fut.result().y))\n"
            "    ros.spin_until_future_complete(node, g, timeout_sec=0.5)\n"
            "    try:\n        x = x + client2.call(TurtlePosition.Request(), timeout_sec=0.5).x\n"
            "    except TimeoutError:\n        x = x - 10.0\n"
            "spun = len(heard)\n"  # the callback ahead of the request ran in the spin
            "count = (count + 1) % 5\n",
        },
        variables="node: ros.Node\nclient: object = None\nclient2: object = None\npub: object = None\n"
        "sub: object = None\nheard: list = []\nseen: list = []\nspun: int = 0\nx: float = 0.0\n"
        "early: bool = False\ncount: int = 0\n"
        "code: str = ''\nf: object = None\n",
        includes="from llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import Bool\n"
        "from llfsm.msgs.turtle_sensor_interface.srv import TurtlePosition\n",
    )
    f = tmp_path / "caller.verify.yaml"
    f.write_text(
        f"machines: [{m}]\ninterrupt: true\nenvironment:\n  services:\n    /where:\n"
        "      type: turtle_sensor_interface/srv/TurtlePosition\n"
        "      responses: [{x: 1.0}, {x: 2.0, y: 3.0}]\n      may_fail: true\n"
        "  topics:\n    /ping:\n      type: std_msgs/msg/Bool\n      values: [{data: false}]\n"
        "properties:\n  - never: caller.x == 2.0 and caller.count == 0\n  - always: not caller.early\n"
    )
    return f


def _by_value(value: object) -> object:
    """A part with each bus handle (its own object in each exploration, compared by identity)
    as what it is, its kind and name, so two explorations' parts compare."""
    from enum import Enum

    from llfsm.verify.values import SCALARS, shown

    if isinstance(value, tuple):
        return tuple(_by_value(v) for v in value)
    if type(value) in SCALARS or isinstance(value, Enum | type | frozenset):
        return value
    return shown(value)


@pytest.mark.parametrize("case", ["services", "push topic", "services in every order"])
def test_with_an_environment_the_specialised_loop_and_the_generic_step_explore_alike(case: str, tmp_path: Path) -> None:
    """The generic step runs each service call through the bus's own executor; the specialised
    loop answers a request next in the queue directly (llfsm.verify.environment, World)."""
    from llfsm.props.file import read_verify_file
    from llfsm.verify.explorer import Options
    from llfsm.verify.judge import verify
    from llfsm.verify.load import load_arrangement
    from llfsm.verify.store import GLOBALS

    if case == "services":
        vf = read_verify_file(_wall_file(tmp_path, True, '  - never: state(ros2_wall_turtle_bot) == "BACK"\n'))
    elif case == "services in every order":
        vf = read_verify_file(_caller(tmp_path))
    else:
        m = _reader(tmp_path, push=True)
        f = tmp_path / "p.verify.yaml"
        f.write_text(
            f"machines: [{m}]\nenvironment:\n  topics:\n    /bump:\n      type: std_msgs/msg/Bool\n"
            "      values: [{data: false}, {data: true}]\n"
            'properties:\n  - eventually: state(pusher) == "HIT"\n'
        )
        vf = read_verify_file(f)
    loaded = load_arrangement(vf.machines, vf.environment)
    shapes = []
    contents = []
    for hash_compact, generic in ((False, False), (False, True), (True, False)):
        options = Options(hash_compact=hash_compact, generic=generic, interrupt=bool(vf.options.get("interrupt")))
        r = verify(loaded, vf.properties, options, keep_graph=True)
        e = r.explorer
        assert r.error is None and r.partial is None
        shapes.append((r.configurations, r.steps, list(e.edges), list(e.edge_choice), list(e.labels), list(e.choice)))
        if not hash_compact and not generic:
            fast = [e.codecs[0].variables_of(e.part(c, 0)) for c in e.configs]
        if not hash_compact:  # what each configuration holds: every variable, the bus's flags, the time
            parts = [[_by_value(e.part(c, k)) for k in range(e.n)] for c in e.configs]
            contents.append(
                [(c[:GLOBALS], e.globals_of(c), e.times_of(c), p) for c, p in zip(e.configs, parts, strict=True)]
            )
    assert shapes[0] == shapes[1] == shapes[2]
    assert contents[0] == contents[1]
    assert shapes[0][0] > 4 and shapes[0][3]
    if case == "services in every order":  # the step of three choices (count 4), each way
        after = {(v["x"], v["seen"]) for v in fast if v["count"] == 0}
        assert (4.0, ("list", 3.0)) in after  # both answered 2.0 (the callback saw y), the call too
        assert (-11.0, ("list",)) in after  # none answered: TIMEOUT, TimeoutError
