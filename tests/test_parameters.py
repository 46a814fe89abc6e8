"""Parameters (SPEC §12): rclpy's API and reasons, the parameter services every node serves,
`llfsm run -p` / `--params-file`, and machine variables as parameters, set between ringlets.
In process, under the sim clock; over DDS and against rclpy in test_parameters_dds.py."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from helpers import MACHINES, llfsm, run_sim, write_machine

from llfsm import ros
from llfsm.msgs.rcl_interfaces.msg import (
    FloatingPointRange,
    IntegerRange,
    ParameterDescriptor,
    ParameterEvent,
    ParameterType,
    SetParametersResult,
)
from llfsm.msgs.rcl_interfaces.srv import DescribeParameters, GetParameters, ListParameters, SetParameters
from llfsm.ros.bus import Bus
from llfsm.ros.parameter_files import ParameterTextError, node_pattern, parse_param, read_params_file
from llfsm.ros.parameters import (
    InvalidParameterTypeException,
    InvalidParameterValueException,
    Parameter,
    ParameterAlreadyDeclaredException,
    ParameterImmutableException,
    ParameterNotDeclaredException,
    ParameterUninitializedException,
)
from llfsm.session import RunOptions, Session, UsageError

# -- rclpy's API ------------------------------------------------------------------------------------


def test_a_declared_parameter_keeps_its_type_and_a_set_of_another_is_refused_with_rclpys_reason(bus: Bus) -> None:
    n = ros.Node("tuned")
    p = n.declare_parameter("gain", 1.5)
    assert (p.name, p.type_, p.value) == ("gain", Parameter.Type.DOUBLE, 1.5)
    [ok] = n.set_parameters([Parameter("gain", value=2.0)])
    assert ok.successful and n.get_parameter("gain").value == 2.0
    [refused] = n.set_parameters([Parameter("gain", value=3)])
    # rclpy formats the Parameter.Type enums with Python's own IntEnum format: '3' and '2'
    assert (refused.successful, refused.reason) == (False, "Wrong parameter type, expected '3' got '2'")
    assert n.get_parameter("gain").value == 2.0


def test_descriptors_read_only_ranges_and_steps_refuse_as_rclpy_does(bus: Bus) -> None:
    n = ros.Node("described")
    n.declare_parameter("ro", "fixed", ParameterDescriptor(read_only=True))
    n.declare_parameter("i", 4, ParameterDescriptor(integer_range=[IntegerRange(from_value=0, to_value=10, step=2)]))
    n.declare_parameter(
        "d", 0.5, ParameterDescriptor(floating_point_range=[FloatingPointRange(from_value=0.0, to_value=1.0)])
    )
    reasons = [
        r.reason
        for r in n.set_parameters(
            [
                Parameter("ro", value="other"),
                Parameter("i", value=11),
                Parameter("i", value=3),
                Parameter("d", value=1.5),
                Parameter("i", value=10),
            ]
        )
    ]
    assert reasons == [
        "Trying to set a read-only parameter: ro.",
        "Parameter i out of range. Min: 0, Max: 10, value: 11",
        "The parameter value for i is not a valid step. Min: 0, max: 10, value: 3, step: 2",
        "Parameter d out of range Min: 0.0, Max: 1.0, value: 1.5",
        "",  # the edge of a range is always in it
    ]
    with pytest.raises(ParameterImmutableException):
        n.undeclare_parameter("ro")


def test_rclpys_exceptions(bus: Bus) -> None:
    n = ros.Node("strict")
    n.declare_parameter("x", 1)
    with pytest.raises(ParameterAlreadyDeclaredException, match=r"Parameter\(s\) already declared: \['x'\]"):
        n.declare_parameter("x", 2)
    with pytest.raises(ParameterNotDeclaredException, match="Invalid access to undeclared parameter"):
        n.get_parameter("y")
    with pytest.raises(ParameterNotDeclaredException):
        n.set_parameters([Parameter("y", value=1)])
    n.declare_parameter("later", Parameter.Type.STRING)
    with pytest.raises(ParameterUninitializedException):
        n.get_parameter("later")
    with pytest.raises(ValueError, match="do not agree"):
        Parameter("z", Parameter.Type.INTEGER, "text")
    with pytest.raises(TypeError, match="not a list of one of the allowed types"):
        Parameter("z", value=[1, "a"])


def test_an_on_set_callback_may_refuse_and_the_last_added_is_asked_first(bus: Bus) -> None:
    n = ros.Node("guarded")
    n.declare_parameter("speed", 1.0)
    asked: list[str] = []

    def cap(params: list[Parameter]) -> SetParametersResult:
        asked.append("cap")
        fast = [p for p in params if p.name == "speed" and p.value > 5.0]
        return SetParametersResult(successful=not fast, reason="too fast" if fast else "")

    def log(params: list[Parameter]) -> SetParametersResult:
        asked.append("log")
        return SetParametersResult(successful=True)

    n.add_on_set_parameters_callback(cap)
    n.add_on_set_parameters_callback(log)
    seen: list[float] = []
    n.add_post_set_parameters_callback(lambda params: seen.extend(p.value for p in params))
    assert n.set_parameters([Parameter("speed", value=9.0)])[0].reason == "too fast"
    assert n.set_parameters([Parameter("speed", value=2.0)])[0].successful
    assert asked == ["log", "cap", "log", "cap"] and seen == [2.0] and n.get_parameter("speed").value == 2.0


def test_set_parameters_atomically_sets_all_or_none(bus: Bus) -> None:
    n = ros.Node("atomic")
    n.declare_parameter("a", 1)
    n.declare_parameter("b", "x", ParameterDescriptor(read_only=True))
    r = n.set_parameters_atomically([Parameter("a", value=2), Parameter("b", value="y")])
    assert not r.successful and n.get_parameter("a").value == 1
    assert n.set_parameters_atomically([Parameter("a", value=3)]).successful and n.get_parameter("a").value == 3


def test_declare_parameters_and_list_with_prefixes_and_depth(bus: Bus) -> None:
    n = ros.Node("nested")
    n.declare_parameters("pid", [("kp", 1.0), ("ki", 0.1), ("limits.max", 5.0)])
    n.declare_parameter("rate", 10)
    assert sorted(n.list_parameters([], 0).names) == ["pid.ki", "pid.kp", "pid.limits.max", "rate"]
    assert sorted(n.list_parameters(["pid"], 1).names) == ["pid.ki", "pid.kp"]
    assert sorted(n.list_parameters([], 1).names) == ["rate"]
    assert sorted(n.list_parameters([], 0).prefixes) == ["pid", "pid.limits"]
    assert set(n.get_parameters_by_prefix("pid")) == {"kp", "ki", "limits.max"}


# -- the parameter services and /parameter_events, in process --------------------------------------


def _call(bus: Bus, node: ros.Node, srv: type, name: str, request: object) -> object:
    future = node.create_client(srv, name).call_async(request)
    assert bus.spin_until(future, 1_000_000_000) is ros.FutureReturnCode.SUCCESS
    return future.result()


def test_every_node_serves_its_parameters_and_publishes_events(bus: Bus) -> None:
    bus.init()
    events = ros.Node("watcher").create_subscription(ParameterEvent, "/parameter_events", None, 10)
    server = ros.Node("server", namespace="robot")
    server.declare_parameter("gain", 1.5, ParameterDescriptor(description="the gain"))
    me = ros.Node("caller")
    got = _call(bus, me, GetParameters, "/robot/server/get_parameters", GetParameters.Request(names=["gain"]))
    assert [(v.type, v.double_value) for v in got.values] == [(ParameterType.PARAMETER_DOUBLE, 1.5)]
    listed = _call(bus, me, ListParameters, "/robot/server/list_parameters", ListParameters.Request())
    assert listed.result.names == ["gain"]
    described = _call(
        bus, me, DescribeParameters, "/robot/server/describe_parameters", DescribeParameters.Request(names=["gain"])
    )
    assert [(d.name, d.type, d.description) for d in described.descriptors] == [("gain", 3, "the gain")]
    wrong = Parameter("gain", value=2).to_parameter_msg()
    right = Parameter("gain", value=2.5).to_parameter_msg()
    unknown = Parameter("nope", value=1).to_parameter_msg()
    res = _call(
        bus,
        me,
        SetParameters,
        "/robot/server/set_parameters",
        SetParameters.Request(parameters=[wrong, right, unknown]),
    )
    assert [(r.successful, r.reason) for r in res.results] == [
        (False, "Wrong parameter type, expected '3' got '2'"),
        (True, ""),
        (False, "Invalid access to undeclared parameter(s): ['nope']"),
    ]
    assert server.get_parameter("gain").value == 2.5
    # one event for the declare (a new parameter), one for the set that succeeded
    bus.spin_some()
    assert events.count == 2
    last = events.latest
    assert last is not None and last.node == "/robot/server"
    assert [(p.name, p.value.double_value) for p in last.changed_parameters] == [("gain", 2.5)]


def test_a_value_of_no_parameter_type_from_a_peer_is_refused_not_raised(bus: Bus) -> None:
    bus.init()
    ros.Node("server").declare_parameter("x", 1)
    bad = Parameter("x", value=1).to_parameter_msg()
    bad.value.type = 200  # a peer may send anything
    res = _call(bus, ros.Node("c"), SetParameters, "/server/set_parameters", SetParameters.Request(parameters=[bad]))
    assert not res.results[0].successful and "unknown parameter type 200" in res.results[0].reason


# -- -p and --params-file -----------------------------------------------------------------------------


def test_p_values_are_typed_as_rcl_types_them() -> None:
    assert parse_param("gain:=2") == (None, "gain", 2)
    assert parse_param("/llfsm/m:gain:=2.0") == ("/llfsm/m", "gain", 2.0)
    assert [parse_param(f"x:={t}")[2] for t in ("1e3", "true", "yes", "'7'", "0x10", "[1, 2]", "abc")] == [
        1000.0,
        True,
        True,
        "7",
        16,
        [1, 2],
        "abc",
    ]
    for bad in ("x", "x:=", ":=1", "x:=[1, a]"):
        with pytest.raises(ParameterTextError):
            parse_param(bad)


def test_a_params_file_with_wildcards_and_namespaces(tmp_path: Path) -> None:
    f = tmp_path / "p.yaml"
    f.write_text(
        "/**:\n  ros__parameters:\n    rate: 5\n"
        "robots:\n  driver:\n    ros__parameters:\n      pid: {kp: 1.0, ki: 0.5}\n      names: [a, b]\n"
        "/llfsm/*:\n  ros__parameters:\n    gain: 2.5\n"
    )
    entries = read_params_file(f)
    assert [k for k, _ in entries] == ["/**", "robots/driver", "/llfsm/*"]
    assert entries[1][1] == {"pid.kp": (1.0, f"{f}:7"), "pid.ki": (0.5, f"{f}:7"), "names": (["a", "b"], f"{f}:8")}
    assert node_pattern("/**").fullmatch("/a/b/c") and node_pattern("robots/driver").fullmatch("/robots/driver")
    assert node_pattern("/llfsm/*").fullmatch("/llfsm/m") and not node_pattern("/llfsm/*").fullmatch("/llfsm/a/b")
    assert node_pattern("/**/driver").fullmatch("/robots/driver") and node_pattern("/**/driver").fullmatch("/driver")


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("a: [\n", "p.yaml:2: not YAML"),
        ("- 1\n", "p.yaml:1: a params file must be a mapping"),
        ("n:\n  ros__parameters:\n    x: [1, 2.0]\n", "p.yaml:3: parameter x: a list must hold values of one type"),
        ("n:\n  ros__parameters:\n    x:\n", "p.yaml:3: parameter x has no value"),
        ("n:\n  params:\n    x: 1\n", "p.yaml:3: x: expected a node's `ros__parameters:`"),
        ("", "p.yaml:1: the file holds no parameters"),
        ("n:\n  ros__parameters:\n    x: []\n", "p.yaml:3: parameter x: an empty list"),
    ],
)
def test_a_bad_params_file_is_one_line_with_file_and_line(tmp_path: Path, text: str, message: str) -> None:
    f = tmp_path / "p.yaml"
    f.write_text(text)
    with pytest.raises(ParameterTextError) as e:
        read_params_file(f)
    assert str(e.value).startswith(f"{tmp_path}/{message}")


def test_overrides_reach_turtlesim_in_order_files_then_p_then_node_specific_p(tmp_path: Path) -> None:
    f = tmp_path / "p.yaml"
    f.write_text(
        "/**:\n  ros__parameters:\n    background_r: 1\n    background_g: 2\n    background_b: 3\n"
        "turtlesim:\n  ros__parameters:\n    background_g: 20\n"
    )
    options = RunOptions(
        clock="sim",
        duration=20_000_000,
        nodes=("turtlesim",),
        params_files=(str(f),),
        params=("turtlesim:background_b:=33", "background_b:=30"),
    )
    session = Session(options, say=lambda _: None)
    assert session.run().status == 0
    assert session.world is not None and session.world.background == (1, 20, 33)


def test_an_override_a_node_refuses_stops_the_run_before_it_starts_naming_where_it_was_written(tmp_path: Path) -> None:
    f = tmp_path / "p.yaml"
    f.write_text("turtlesim:\n  ros__parameters:\n    background_r: 300\n")
    r = run_sim("--node", "turtlesim", "--params-file", f, "--duration", "1s")
    assert r.status == 2
    assert r.stderr.splitlines()[-1] == (
        f"llfsm: {f}:3: /turtlesim refused it: Invalid parameter value (300) for parameter. Reason: Parameter "
        "background_r out of range. Min: 0, Max: 255, value: 300: background_r"
    )
    r = run_sim("--node", "turtlesim", "-p", "background_r:=1.5", "--duration", "1s")
    assert r.status == 2 and "Traceback" not in r.stderr
    assert r.stderr.splitlines()[-1].startswith("llfsm: -p background_r:=1.5: /turtlesim refused it: Trying to set")
    r = run_sim("--node", "turtlesim", "--params-file", tmp_path / "missing.yaml", "--duration", "1s")
    assert r.status == 2 and "missing.yaml: cannot read" in r.stderr and "Traceback" not in r.stderr


def test_the_old_param_spelling_still_works() -> None:
    options = RunOptions(clock="sim", duration=20_000_000, nodes=("turtlesim",), params=("turtlesim:background_r:=10",))
    session = Session(options, say=lambda _: None)
    assert session.run().status == 0 and session.world is not None and session.world.background == (10, 86, 255)
    with pytest.raises(UsageError, match="expected"):
        Session(options.replace(params=("nonsense",)), say=lambda _: None).run()


# -- machine variables as parameters ------------------------------------------------------------------

GAINER_YAML = "parameters: [gain, names]\n"


def _gainer(root: Path, *, self_set: bool = False) -> Path:
    """A machine that publishes its `gain` at the start and end of each ringlet of RUN; with
    `self_set`, it sets its own parameter in the middle of a ringlet (and spins for the answer)."""
    middle = (
        "req = SetParameters.Request(parameters=[Parameter('gain', value=9.0).to_parameter_msg()])\n"
        "ros.spin_until_future_complete(node, setter.call_async(req), timeout_sec=1.0)\n"
        if self_set
        else ""
    )
    return write_machine(
        root,
        "gainer",
        {"INITIAL": [("RUN", "True")], "RUN": [("END", "after_ms(30)")], "END": None},
        {
            "INITIAL_OnEntry": "ros.init()\nnode = ros.Node('gain_node')\n"
            "pub = node.create_publisher(Float64, 'gain', 100)\n"
            "setter = node.create_client(SetParameters, '/llfsm/gainer/set_parameters')\n",
            "RUN_Internal": f"pub.publish(Float64(data=gain))\n{middle}pub.publish(Float64(data=gain))\n",
        },
        variables="gain: float = 1\nnames: list[str] = ['a']\nnode: ros.Node\npub: ros.Publisher\nsetter: ros.Client\n",
        includes="from llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import Float64\n"
        "from llfsm.msgs.rcl_interfaces.srv import SetParameters\nfrom llfsm.ros import Parameter\n",
        yaml_extra=GAINER_YAML,
    )


def _gains(stdout: str) -> list[float]:
    return [d["data"] for d in yaml.safe_load_all(stdout) if d]


def test_an_override_sets_a_machines_variable_before_its_first_ringlet(tmp_path: Path) -> None:
    m = _gainer(tmp_path)
    assert set(_gains(run_sim(m, "--echo", "/gain", "--duration", "10ms").stdout)) == {1.0}
    r = run_sim(m, "--echo", "/gain", "--duration", "10ms", "-p", "/llfsm/gainer:gain:=2.5")
    assert r.status == 0 and set(_gains(r.stdout)) == {2.5}
    f = tmp_path / "p.yaml"
    f.write_text("/llfsm/gainer:\n  ros__parameters:\n    gain: 4.0\n")
    assert set(_gains(run_sim(m, "--echo", "/gain", "--duration", "10ms", "--params-file", f).stdout)) == {4.0}
    r = run_sim(m, "--duration", "10ms", "-p", "gainer:gain:=true")
    assert r.status == 2 and "Traceback" not in r.stderr
    assert (
        "-p gainer:gain:=true: /llfsm/gainer refused it: Trying to set parameter 'gain' to 'True' of type 'BOOL'"
        in r.stderr
    )


def test_a_set_through_the_parameter_service_takes_effect_at_the_next_ringlet(
    tmp_path: Path,
) -> None:
    m = _gainer(tmp_path, self_set=True)
    r = run_sim(m, "--echo", "/gain", "--duration", "10ms")
    assert r.status == 0, r.stderr
    gains = _gains(r.stdout)
    # each ringlet publishes twice: the set answered in the middle of the first changes nothing
    # until the next ringlet, which sees the new value from its start
    assert gains[:4] == [1.0, 1.0, 9.0, 9.0]
    assert all(a == b for a, b in zip(gains[::2], gains[1::2], strict=True))


def test_machine_parameters_are_typed_by_their_annotations(tmp_path: Path, bus: Bus) -> None:
    from llfsm.ros.control import attach
    from llfsm.runtime import Arrangement
    from llfsm.targets import load

    cls = load(str(_gainer(tmp_path)))
    arr = Arrangement([cls], context=bus.ctx)
    bus.init()
    graph = attach(arr, bus)
    node = graph.nodes[0]
    assert node.get_fully_qualified_name() == "/llfsm/gainer"
    gain, names = node.get_parameters(["gain", "names"])
    assert (gain.type_, gain.value) == (Parameter.Type.DOUBLE, 1.0)  # `gain: float = 1`: a double
    assert (names.type_, names.value) == (Parameter.Type.STRING_ARRAY, ["a"])
    assert (
        node.set_parameters([Parameter("gain", value="fast")])[0].reason == "Wrong parameter type, expected '3' got '4'"
    )
    assert node.set_parameters([Parameter("names", value=["b", "c"])])[0].successful
    machine = arr.machines[0]
    assert machine.names == ["a"]  # not yet: at the start of its next ringlet
    arr.run(duration_ns=2_000_000)
    assert machine.names == ["b", "c"]
    machine.gain = 7.0  # the machine's own code changed it: a get shows it
    assert node.get_parameter("gain").value == 7.0


def test_a_machine_that_declares_parameters_is_on_the_graph_without_calling_ros_init(tmp_path: Path) -> None:
    """Issue 27, item 1: its variables are parameters of /llfsm/M (SPEC 12) even when its code never
    touches the bus."""
    m = write_machine(
        tmp_path,
        "tuned",
        {"RUN": [("RUN", "after_ms(100)")]},
        {"RUN_OnEntry": "print('gain', gain)"},
        variables="gain: float = 1.0\n",
        yaml_extra="parameters: [gain]\n",
    )
    r = run_sim(m, "--introspect", "--duration", "150ms")
    assert r.status == 0, r.stderr
    assert "nodes:\n  /llfsm/tuned\n" in r.stderr
    assert "  /llfsm/tuned/set_parameters [rcl_interfaces/srv/SetParameters]" in r.stderr


def test_check_validates_the_parameters_list(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "tuned",
        {"INITIAL": [("END", "True")], "END": None},
        {"INITIAL_Variables": "local: int = 0\n"},
        variables="gain: float = 1.0\nnode: object = None\n",
        yaml_extra="parameters: [gain, gian, node, gain, local]\n",
    )
    r = llfsm("check", m)
    assert r.status == 1
    lines = [line.split(": ", 1)[1] for line in r.stdout.splitlines() if "machine.yaml" in line]
    assert lines == [
        "LF060 error: parameter gian is not a machine variable of Variables.py (did you mean 'gain'?)",
        "LF061 error: parameter node is annotated `object` (Variables.py:2); a parameter is one of: bool, int, "
        "float, str, list[bool], list[int], list[float], list[str]",
        "LF062 error: parameter gain is listed twice",
        "LF060 error: parameter local is not a machine variable of Variables.py (it is a variable of state "
        "INITIAL; only machine variables can be parameters)",
    ]
    assert "machine.yaml:1:" in r.stdout.splitlines()[0]
    r = llfsm("run", "--clock", "sim", m)
    assert r.status == 2 and "LF060" in r.stderr


def test_turtle_follower_exposes_its_gains() -> None:
    r = llfsm("check", MACHINES / "turtle_follower.machine")
    assert r.status == 0
    text = (MACHINES / "turtle_follower.machine" / "machine.yaml").read_text()
    assert "parameters: [k_linear, k_angular, max_linear, max_angular, tolerance]" in text


def test_turtlesim_repaints_when_its_background_is_set(tmp_path: Path) -> None:
    """background_r/g/b are real parameters: set through the service, the picture changes."""
    options = RunOptions(clock="sim", duration=20_000_000, nodes=("turtlesim",))
    session = Session(options, say=lambda _: None)
    session.run()
    node = next(n for n in session.bus.nodes if n.get_name() == "turtlesim")  # type: ignore[union-attr]
    assert [r.successful for r in node.set_parameters([Parameter("background_g", value=0)])] == [True]
    assert session.world is not None and session.world.background == (69, 0, 255)
    refused = node.set_parameters([Parameter("background_g", value=256)])[0]
    assert refused.reason == "Parameter background_g out of range. Min: 0, Max: 255, value: 256"


def test_an_override_of_the_wrong_type_raises_rclpys_exception_at_declare_time(bus: Bus) -> None:
    bus.parameters[(None, "x")] = "text"
    bus.parameters[(None, "y")] = 20
    n = ros.Node("declarer")
    with pytest.raises(InvalidParameterTypeException) as e:
        n.declare_parameter("x", 1)
    assert str(e.value) == "Trying to set parameter 'x' to 'text' of type 'STRING', expecting type 'INTEGER': x"
    with pytest.raises(InvalidParameterValueException, match=r"Reason: Parameter y out of range"):
        n.declare_parameter("y", 1, ParameterDescriptor(integer_range=[IntegerRange(from_value=0, to_value=10)]))
    assert n.declare_parameter("x", 1, ignore_override=True).value == 1
