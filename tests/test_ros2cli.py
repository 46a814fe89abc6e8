"""The ros2-style verbs, offline: `interface show`, TYPE resolution, VALUES, usage errors.

Everything here runs without DDS: what a user gets wrong (a type, VALUES, a field, a name) is
found before the domain is joined, with one line and exit status 2.  The verbs over DDS are
tested across processes in tests/test_ros2cli_dds.py.
"""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from helpers import llfsm, llfsm_process

from llfsm.msgs import to_yaml
from llfsm.msgs._yaml import ValuesError, from_yaml
from llfsm.msgs.geometry_msgs.msg import PoseStamped, Twist
from llfsm.msgs.std_msgs.msg import Float64MultiArray, String
from llfsm.msgs.turtlesim.srv import Spawn
from llfsm.ros2cli import CliError
from llfsm.ros2cli.interface import known_types, show
from llfsm.ros2cli.lookup import message_class, service_class
from llfsm.ros2cli.topic.echo import format_message
from llfsm.ros2cli.topic.hz import RateMeter, rate_table

# -- interface show --------------------------------------------------------------------------------

TWIST = """\
# This expresses velocity in free space broken into its linear and angular parts.

Vector3  linear
\tfloat64 x
\tfloat64 y
\tfloat64 z
Vector3  angular
\tfloat64 x
\tfloat64 y
\tfloat64 z
"""


def test_interface_show_prints_the_definition_with_nested_types_tab_indented() -> None:
    r = llfsm("interface", "show", "geometry_msgs/msg/Twist")
    assert r.status == 0
    assert r.stdout == TWIST


def test_interface_show_expands_nested_types_without_their_comments() -> None:
    text = show("geometry_msgs/msg/PoseStamped")
    lines = text.splitlines()
    assert lines[0] == "# A Pose with reference coordinate frame and timestamp"
    i = lines.index("std_msgs/Header header")
    assert lines[i + 1 : i + 5] == [
        "\tbuiltin_interfaces/Time stamp",
        "\t\tint32 sec",
        "\t\tuint32 nanosec",
        "\tstring frame_id",
    ]
    assert not any(line.startswith("\t#") for line in lines)  # nested comments are left out
    assert "\t\tfloat64 w 1" in lines  # Quaternion's default, as written


def test_interface_show_service_keeps_the_separator_and_trailing_comments() -> None:
    assert show("turtlesim/srv/Spawn") == (
        "float32 x\nfloat32 y\nfloat32 theta\n"
        "string name # Optional.  A unique name will be created and returned if this is empty\n"
        "---\nstring name\n"
    )


def test_interface_show_no_comments_and_all_comments() -> None:
    r = llfsm("interface", "show", "std_msgs/msg/Header", "--no-comments")
    assert r.stdout == "builtin_interfaces/Time stamp\n\tint32 sec\n\tuint32 nanosec\nstring frame_id\n"
    r = llfsm("interface", "show", "std_msgs/msg/Header", "--all-comments")
    assert "\t# The seconds component, valid over all int32 values." in r.stdout.splitlines()


def test_interface_show_accepts_pkg_name_and_reads_stdin() -> None:
    assert show("turtlesim/Pose") == show("turtlesim/msg/Pose")
    assert show("turtlesim/Spawn") == show("turtlesim/srv/Spawn")
    r = llfsm_process("interface", "show", "-", input="geometry_msgs/msg/Twist\n", timeout=60)
    assert (r.status, r.stdout) == (0, TWIST)


def test_interface_show_finds_a_users_package_in_the_working_directory(tmp_path: Path) -> None:
    (tmp_path / "my_pkg" / "msg").mkdir(parents=True)
    (tmp_path / "my_pkg" / "msg" / "Reading.msg").write_text(
        "# one reading\nstd_msgs/Header header\nfloat64[] values\n"
    )
    r = llfsm_process("interface", "show", "my_pkg/msg/Reading", cwd=tmp_path, timeout=60)
    assert r.status == 0, r.stderr
    assert r.stdout.splitlines()[:3] == ["# one reading", "std_msgs/Header header", "\tbuiltin_interfaces/Time stamp"]
    assert r.stdout.splitlines()[-1] == "float64[] values"


def test_interface_show_of_a_broken_user_definition_names_file_and_line(tmp_path: Path) -> None:
    (tmp_path / "bad_pkg" / "msg").mkdir(parents=True)
    (tmp_path / "bad_pkg" / "msg" / "Oops.msg").write_text("float64 x\nfloat64 X\n")
    r = llfsm_process("interface", "show", "bad_pkg/msg/Oops", cwd=tmp_path, timeout=60)
    assert r.status == 2
    assert len(r.stderr.splitlines()) == 1
    assert "Oops.msg:2:" in r.stderr


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["turtlesim/srv/Spaw"], "did you mean 'turtlesim/srv/Spawn'?"),
        (["geometry_msgs/msg/Twst"], "did you mean 'geometry_msgs/msg/Twist'?"),
        (["no_such_pkg/msg/Thing"], "unknown message type 'no_such_pkg/msg/Thing'"),
        (["Twist"], "expected pkg/msg/Name"),
        (["std_msgs/msg/String", "--all-comments", "--no-comments"], "exclude each other"),
    ],
)
def test_interface_show_bad_type_is_one_line_exit_2(args: list[str], needle: str) -> None:
    r = llfsm("interface", "show", *args)
    assert r.status == 2
    assert r.stdout == ""
    assert len(r.stderr.splitlines()) == 1 and needle in r.stderr


def _shown_fields(lines: list[str]) -> list[str]:
    """The field names of the top-level lines of `interface show --no-comments` (not constants)."""
    names = []
    for line in lines:
        if line.startswith("\t"):
            continue
        name = line.split()[1]
        if "=" not in name and not line.split(name, 1)[1].lstrip().startswith("="):  # `int8 A   = 0` is a constant
            names.append(name)
    return names


def test_every_known_type_has_a_definition_that_agrees_with_its_class() -> None:
    """Each shipped definition shows and imports, with the fields the generated class has."""
    msgs, srvs = known_types("msg"), known_types("srv")
    assert "geometry_msgs/msg/Twist" in msgs and "std_msgs/msg/String" in msgs and "turtlesim/srv/Spawn" in srvs
    for t in msgs:
        cls = message_class(t)
        assert t == cls._TYPE
        assert _shown_fields(show(t, comments="none").splitlines()) == [f for f, _ in cls._FIELDS], t
    for t in srvs:
        srv = service_class(t)
        lines = show(t, comments="none").splitlines()
        cut = lines.index("---")
        assert _shown_fields(lines[:cut]) == [f for f, _ in srv.Request._FIELDS], t
        assert _shown_fields(lines[cut + 1 :]) == [f for f, _ in srv.Response._FIELDS], t


# -- TYPE resolution -------------------------------------------------------------------------------


def test_types_resolve_in_both_spellings() -> None:
    assert message_class("geometry_msgs/msg/Twist") is Twist
    assert message_class("geometry_msgs/Twist") is Twist
    assert service_class("turtlesim/srv/Spawn") is Spawn
    assert service_class("turtlesim/Spawn") is Spawn


@pytest.mark.parametrize(
    ("call", "text", "needle"),
    [
        (message_class, "turtlesim/srv/Spawn", "is a service type"),
        (service_class, "geometry_msgs/msg/Twist", "is a message type"),
        (message_class, "geometry_msgs/msg/twist", "expected pkg/msg/Name"),
        (message_class, "geometry_msgs/msg/Pos", "did you mean 'geometry_msgs/msg/Pose'?"),
        (message_class, "_yaml/msg/Thing", "expected pkg/msg/Name"),  # never llfsm.msgs' own modules
        (message_class, "std_srvs/msg/Trigger", "('std_srvs/srv/Trigger' is a service type)"),
        (service_class, "std_msgs/String", "('std_msgs/msg/String' is a message type)"),
    ],
)
def test_bad_types_are_usage_errors(call: object, text: str, needle: str) -> None:
    with pytest.raises(CliError) as e:
        call(text)  # type: ignore[operator]
    assert e.value.status == 2 and needle in e.value.message


# -- VALUES ----------------------------------------------------------------------------------------


def test_values_fill_nested_fields_as_ros2_takes_them() -> None:
    msg, stamps = from_yaml(Twist, "{linear: {x: 2.0}, angular: {z: 1}}")
    assert (msg.linear.x, msg.angular.z, msg.linear.y) == (2.0, 1.0, 0.0)
    assert stamps == []
    assert from_yaml(String, "data: hello world")[0].data == "hello world"
    assert from_yaml(String, "data: 42")[0].data == "42"  # rosidl writes str(value)
    assert from_yaml(Twist, "")[0] == Twist()
    assert from_yaml(Float64MultiArray, "{data: [1, 2.5]}")[0].data == [1.0, 2.5]


def test_values_header_auto_is_stamped_at_each_send() -> None:
    msg, stamps = from_yaml(PoseStamped, "{header: auto, pose: {position: {x: 1.0}}}")
    assert len(stamps) == 1
    stamps[0](12, 34)
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec, msg.pose.position.x) == (12, 34, 1.0)


@pytest.mark.parametrize(
    ("cls", "text", "needle"),
    [
        (Twist, "{linar: {x: 2.0}}", "geometry_msgs/msg/Twist has no field 'linar'; did you mean 'linear'?"),
        (Twist, "{linear: {x: fast}}", "linear.x: The 'x' field of geometry_msgs/msg/Vector3 must be of type 'float'"),
        (Twist, "{linear: {x: 2.0}", "not valid YAML"),
        (Twist, "{linear: " + "[" * 5000 + "]" * 5000 + "}", "nests deeper than any message"),
        (Twist, "linear:\n" + "".join(" " * i + "- \n" for i in range(1, 3000)), "nests deeper than any message"),
        (Twist, "{linear: 3}", "linear: geometry_msgs/msg/Vector3 takes a mapping of its fields, not 3"),
        (Twist, "[1, 2]", "must be a YAML mapping"),
        (Spawn.Request, "{x: true}", "must be of type 'float'"),
        (Float64MultiArray, "{data: 3}", "must be a list"),
    ],
)
def test_bad_values_raise_one_clear_line(cls: type, text: str, needle: str) -> None:
    with pytest.raises(ValuesError) as e:
        from_yaml(cls, text)
    assert needle in str(e.value)
    assert "\n" not in str(e.value)


@pytest.mark.parametrize(
    "args",
    [
        ["topic", "pub", "/turtle1/cmd_vel", "geometry_msgs/msg/Twist", "{linear: {x: fast}}"],
        ["topic", "pub", "/turtle1/cmd_vel", "geometry_msgs/msg/Twist", "{linear: {x: 2.0}"],
        ["topic", "pub", "/turtle1/cmd_vel", "geometry_msgs/msg/Twst", "{linear: {x: 2.0}}"],
        ["topic", "pub", "/turtle1/cmd_vel", "turtlesim/srv/Spawn"],
        ["topic", "pub", "bad name", "std_msgs/msg/String"],
        ["topic", "echo", "/pingpong", "std_msgs/msg/Strin"],
        ["topic", "echo", "/pingpong", "std_msgs/msg/String", "--field", "dat"],
        ["service", "call", "/spawn", "turtlesim/srv/Spawn", "{x: two}"],
        ["service", "call", "/spawn", "turtlesim/srv/Spwan", "{x: 2.0}"],
        ["topic", "pub", "/x", "std_msgs/msg/String", "--once", "--times", "3"],
    ],
)
def test_verbs_reject_bad_input_with_one_line_and_exit_2(args: list[str]) -> None:
    """Checked before the domain is joined: no DDS needed, no traceback, nothing on stdout."""
    r = llfsm(*args)
    assert r.status == 2, r.stderr
    assert r.stdout == ""
    assert len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert r.stderr.startswith("llfsm: ")


def test_help_of_each_verb() -> None:
    for args in (["topic"], ["topic", "pub"], ["topic", "echo"], ["service", "call"], ["node", "list"], ["interface"]):
        r = llfsm(*args, "--help")
        assert r.status == 0 and r.stdout.startswith("Usage: ") and " ".join(args) in r.stdout, args
    assert "--times" in llfsm("topic", "pub", "--help").stdout
    assert "--show-types" in llfsm("topic", "list", "--help").stdout


# -- what echo and hz print ------------------------------------------------------------------------


def test_echo_format_is_message_to_yaml_then_dashes() -> None:
    msg = Twist()
    msg.linear.x = 2.0
    text = format_message(msg, [], 128)
    assert text.endswith("\n---\n")
    assert yaml.safe_load(text[: -len("---\n")]) == msg.to_dict()
    assert text == to_yaml(msg) + "---\n"
    assert format_message(msg, ["linear", "x"], 128) == "2.0\n---\n"  # a primitive field: its Python value
    assert format_message(msg, ["linear"], 128) == "x: 2.0\ny: 0.0\nz: 0.0\n---\n"


def test_echo_truncates_long_arrays_and_strings_as_ros2() -> None:
    arr = Float64MultiArray(data=[float(i) for i in range(200)])
    shown = yaml.safe_load(format_message(arr, [], 128)[: -len("---\n")])
    assert shown["data"][:2] == [0.0, 1.0] and len(shown["data"]) == 129 and shown["data"][-1] == "..."
    full = yaml.safe_load(format_message(arr, [], None)[: -len("---\n")])
    assert len(full["data"]) == 200
    s = yaml.safe_load(format_message(String(data="x" * 300), [], 128)[: -len("---\n")])
    assert s["data"] == "x" * 128 + "..."
    no_arr = format_message(arr, [], 128, no_arr=True)
    assert "data" not in yaml.safe_load(no_arr[: -len("---\n")])


def test_hz_statistics_match_ros2_topic_hz_format() -> None:
    meter = RateMeter(window=10000)
    assert meter.report() is None
    for t in (0, 100_000_000, 200_000_000, 350_000_000):
        meter.tick(t)
    text = meter.report()
    assert text is not None
    assert text == "average rate: 8.571\n\tmin: 0.100s max: 0.150s std dev: 0.02357s window: 3\n"
    assert meter.report() is None  # nothing new since


def test_hz_window_keeps_the_last_gaps() -> None:
    meter = RateMeter(window=2)
    for t in (0, 1_000_000_000, 1_500_000_000, 1_750_000_000):
        meter.tick(t)
    assert meter.report().endswith("window: 2\n")  # type: ignore[union-attr]
    assert meter.report() is None


def test_hz_of_several_topics_is_ros2s_table() -> None:
    slow, fast = RateMeter(), RateMeter()
    for t in (0, 100_000_000, 200_000_000):
        slow.tick(t)
    for t in (0, 16_000_000, 32_000_000, 48_000_000):
        fast.tick(t)
    assert rate_table({"/turtle1/pose": fast, "/chatter": slow}) == (
        "    topic        rate    min_delta   max_delta   std_dev   window\n"
        "=================================================================\n"
        "/turtle1/pose   62.500   0.016       0.016       0.00000   3     \n"
        "/chatter        10.000   0.100       0.100       0.00000   2     \n\n"
    )
    assert rate_table({"/turtle1/pose": fast, "/chatter": slow}) is None  # nothing new since
