"""Message and service classes (llfsm.msgs): rclpy's behaviour, the import hook for users'
interfaces, the committed modules staying in step with their generator, and `--echo` YAML."""

from __future__ import annotations

import importlib
import math
import os
import subprocess
import sys
import textwrap
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType

import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

import llfsm.msgs
from llfsm import interface_path
from llfsm.idl import parser, shipped
from llfsm.idl.package import MSGS_DIR
from llfsm.idl.spec import InterfaceError
from llfsm.msgs import Message, is_message_class, is_service_class, to_yaml
from llfsm.msgs.builtin_interfaces.msg import Time
from llfsm.msgs.geometry_msgs.msg import Point, PoseWithCovariance, Quaternion, Twist, Vector3
from llfsm.msgs.std_msgs.msg import Empty, Float64MultiArray, Header, MultiArrayDimension, String, UInt8MultiArray
from llfsm.msgs.turtle_sensor_interface.srv import TurtlePosition
from llfsm.msgs.turtlesim.msg import Color, Pose
from llfsm.msgs.turtlesim.srv import Spawn

# -- a user's interface package, compiled once through the import hook --------------------------

THING_MSG = """\
# Everything the .msg grammar offers.
uint8 RED=1
int32 BIG = -7  # spaces around = are fine
string GREETING="hi # there"
float64 x 1.5
string name "a"
string<=5 short
int32[3] arr [1, 2, 3]
float64[<=2] few
bool[] flags [true, false]
string[] names ["a, b", 'c']
geometry_msgs/Point p
Point q
Header h
Point[2] pts
"""


def write_pkg(root: Path, name: str, files: dict[str, str]) -> Path:
    for rel, text in files.items():
        p = root / name / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text)
    return root / name


def forget(package: str) -> None:
    for mod in [m for m in sys.modules if m == f"llfsm.msgs.{package}" or m.startswith(f"llfsm.msgs.{package}.")]:
        del sys.modules[mod]


@pytest.fixture(scope="module")
def user_pkg(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[ModuleType, ModuleType, Path]]:
    """llfsm.msgs.llfsm_test_pkg: msg Thing and Point, srv Do."""
    root = tmp_path_factory.mktemp("interfaces")
    write_pkg(
        root,
        "llfsm_test_pkg",
        {
            "msg/Thing.msg": THING_MSG,
            "msg/Point.msg": "float64 x\nfloat64 y\nfloat64 z\n",
            "srv/Do.srv": "Thing thing  # the request\n---\nbool ok\ngeometry_msgs/Twist twist\n",
        },
    )
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("LLFSM_CACHE_DIR", str(tmp_path_factory.mktemp("cache")))
        llfsm.msgs.add_search_path(root)
        try:
            msg = importlib.import_module("llfsm.msgs.llfsm_test_pkg.msg")
            srv = importlib.import_module("llfsm.msgs.llfsm_test_pkg.srv")
            yield msg, srv, root
        finally:
            interface_path._added.remove(str(root))
            forget("llfsm_test_pkg")


# -- rclpy's behaviour ------------------------------------------------------------------------


def test_defaults() -> None:
    t = Twist()
    assert (t.linear.x, t.linear.y, t.angular.z) == (0.0, 0.0, 0.0)
    assert t.linear is not t.angular and Twist().linear is not t.linear
    assert String().data == ""
    assert Pose().theta == 0.0 and Color().r == 0
    h = Header()
    assert h.stamp == Time(sec=0, nanosec=0) and h.frame_id == ""
    assert Quaternion().w == 1.0  # ROS 2's default, absent from rosbags' definitions
    assert Float64MultiArray().data == [] and Float64MultiArray().layout.dim == []
    assert Empty()._FIELDS == ()


def test_keyword_construction_and_nested_assignment() -> None:
    t = Twist(linear=Vector3(x=1, y=2.5))
    assert t.linear.x == 1.0 and type(t.linear.x) is float and t.linear.y == 2.5
    t.linear.x = 2
    assert t.linear.x == 2.0 and type(t.linear.x) is float
    t.angular = Vector3(z=-1.0)
    assert t.angular.z == -1.0
    assert Spawn.Request(x=1, y=2, theta=0.5, name="t2").name == "t2"


def test_unknown_and_positional_arguments_are_type_errors() -> None:
    with pytest.raises(TypeError, match="unexpected keyword argument 'w'"):
        Twist(w=1)
    with pytest.raises(TypeError):
        Vector3(1.0)  # type: ignore[misc]
    with pytest.raises(TypeError):
        Empty(x=1)  # type: ignore[call-arg]


@pytest.mark.parametrize(
    ("obj", "field", "value"),
    [
        (Vector3(), "x", "fast"),
        (Vector3(), "x", True),
        (Vector3(), "x", None),
        (Color(), "r", 1.0),
        (Color(), "r", True),
        (Spawn.Request(), "name", 3),
        (Twist(), "linear", Point()),
        (Twist(), "linear", None),
        (Twist(), "linear", {"x": 1.0}),
        (Header(), "stamp", 0),
        (Float64MultiArray(), "data", 1.0),
        (Float64MultiArray(), "data", [1.0, "2"]),
        (Float64MultiArray(), "data", "12"),
    ],
)
def test_type_errors(obj: Message, field: str, value: object) -> None:
    with pytest.raises(TypeError) as e:
        setattr(obj, field, value)
    text = str(e.value)
    assert f"'{field}" in text and obj._TYPE in text


def test_type_error_messages_read_like_rclpy() -> None:
    with pytest.raises(TypeError, match=r"^The 'x' field of geometry_msgs/msg/Vector3 must be of type 'float'"):
        Vector3().x = "fast"
    with pytest.raises(TypeError, match=r"The 'data\[1\]' field of std_msgs/msg/Float64MultiArray"):
        Float64MultiArray(data=[1.0, "2"])
    with pytest.raises(TypeError, match="geometry_msgs/msg/Vector3"):
        Twist(linear=None)  # type: ignore[arg-type]


def test_integer_ranges() -> None:
    c = Color()
    c.r = 255
    with pytest.raises(ValueError, match=r"unsigned integer in \[0, 255\]"):
        c.r = 256
    with pytest.raises(ValueError):
        c.g = -1
    t = Time()
    t.sec = -(2**31)
    with pytest.raises(ValueError, match=r"integer in \[-2147483648, 2147483647\]"):
        t.sec = 2**31
    with pytest.raises(ValueError):
        t.nanosec = -1
    d = MultiArrayDimension(size=2**32 - 1)
    assert d.size == 2**32 - 1


def test_float32_range() -> None:
    p = Pose(x=1)
    assert p.x == 1.0 and type(p.x) is float
    p.y = math.inf
    p.theta = 3.4e38
    with pytest.raises(ValueError, match="float32"):
        p.theta = 1e39


def test_arrays_fixed_and_unbounded() -> None:
    p = PoseWithCovariance()
    assert p.covariance == [0.0] * 36
    p.covariance = tuple(range(36))
    assert p.covariance == [float(i) for i in range(36)] and isinstance(p.covariance, list)
    assert all(type(v) is float for v in p.covariance)
    with pytest.raises(ValueError, match="exactly 36 elements, not 35"):
        p.covariance = [0.0] * 35
    m = Float64MultiArray(data=[1, 2.5])
    assert m.data == [1.0, 2.5]
    m.layout.dim = [MultiArrayDimension(label="x", size=2, stride=2)]
    with pytest.raises(TypeError, match=r"dim\[0\]"):
        m.layout.dim = [Point()]
    u = UInt8MultiArray(data=b"\x01\xff")
    assert u.data == [1, 255]
    with pytest.raises(ValueError, match=r"data\[0\]"):
        u.data = [256]


def test_arrays_bounded_strings_defaults_and_constants(user_pkg: tuple[ModuleType, ModuleType, Path]) -> None:
    msg, _, _ = user_pkg
    t = msg.Thing()
    # default values written in the .msg
    assert (t.x, t.name, t.arr, t.flags, t.names) == (1.5, "a", [1, 2, 3], [True, False], ["a, b", "c"])
    assert t.arr is not msg.Thing().arr  # a fresh list per instance
    assert t.short == "" and t.few == [] and len(t.pts) == 2 and t.pts[0] is not t.pts[1]
    # constants become class attributes
    assert (msg.Thing.RED, msg.Thing.BIG, msg.Thing.GREETING) == (1, -7, "hi # there")
    # bounds
    t.few = [1, 2]
    with pytest.raises(ValueError, match="at most 2 elements, not 3"):
        t.few = [1, 2, 3]
    t.short = "abcde"
    with pytest.raises(ValueError, match="at most 5 characters"):
        t.short = "abcdef"
    with pytest.raises(ValueError, match="exactly 3"):
        t.arr = [1, 2]
    # references: another package's type, the same package's, and a bare Header
    assert type(t.p) is Point and type(t.q) is msg.Point and type(t.h) is Header
    assert t._FIELDS[-1] == ("pts", "llfsm_test_pkg/msg/Point[2]")


def test_equality_and_repr() -> None:
    assert Twist() == Twist()
    assert Twist(linear=Vector3(x=1.0)) != Twist()
    assert Twist() != Vector3()
    assert repr(Vector3(x=1.0)) == "geometry_msgs.msg.Vector3(x=1.0, y=0.0, z=0.0)"
    assert repr(Spawn.Request(name="t")) == "turtlesim.srv.Spawn_Request(x=0.0, y=0.0, theta=0.0, name='t')"
    with pytest.raises(TypeError):
        hash(Twist())


def test_copy_is_deep() -> None:
    t = Twist(linear=Vector3(x=1.0))
    c = t._copy()
    assert c == t and c is not t and type(c) is Twist
    c.linear.x = 5.0
    assert t.linear.x == 1.0
    m = Float64MultiArray(data=[1.0])
    m.layout.dim = [MultiArrayDimension(label="a")]
    mc = m._copy()
    mc.data.append(2.0)
    mc.layout.dim[0].label = "b"
    assert m.data == [1.0] and m.layout.dim[0].label == "a"
    h = Header(frame_id="map")
    hc = h._copy()
    hc.stamp.sec = 3
    assert h.stamp.sec == 0 and hc.frame_id == "map"
    assert Empty()._copy() == Empty()


def test_services() -> None:
    assert is_service_class(Spawn) and not is_message_class(Spawn)
    assert Spawn._TYPE == "turtlesim/srv/Spawn"
    assert Spawn.Request.__name__ == "Spawn_Request" and Spawn.Response.__name__ == "Spawn_Response"
    assert Spawn.Request._TYPE == "turtlesim/srv/Spawn_Request"
    assert [f for f, _ in Spawn.Request._FIELDS] == ["x", "y", "theta", "name"]
    assert Spawn.Response(name="turtle2").name == "turtle2"
    assert is_message_class(Spawn.Request)


def test_turtle_position_service() -> None:
    assert TurtlePosition._TYPE == "turtle_sensor_interface/srv/TurtlePosition"
    assert TurtlePosition.Request._FIELDS == ()
    assert TurtlePosition.Response._FIELDS == (("x", "float64"), ("y", "float64"), ("theta", "float64"))
    r = TurtlePosition.Response(x=1, y=2)
    assert (r.x, r.y, r.theta) == (1.0, 2.0, 0.0)


SPEC_TYPES = {
    "std_msgs.msg": "Bool Byte ByteMultiArray Char ColorRGBA Empty Float32 Float32MultiArray Float64 "
    "Float64MultiArray Header Int16 Int16MultiArray Int32 Int32MultiArray Int64 Int64MultiArray Int8 "
    "Int8MultiArray MultiArrayDimension MultiArrayLayout String UInt16 UInt16MultiArray UInt32 "
    "UInt32MultiArray UInt64 UInt64MultiArray UInt8 UInt8MultiArray",
    "geometry_msgs.msg": "Accel AccelStamped AccelWithCovariance AccelWithCovarianceStamped Inertia "
    "InertiaStamped Point Point32 PointStamped Polygon PolygonStamped Pose Pose2D PoseArray PoseStamped "
    "PoseWithCovariance PoseWithCovarianceStamped Quaternion QuaternionStamped Transform TransformStamped "
    "Twist TwistStamped TwistWithCovariance TwistWithCovarianceStamped Vector3 Vector3Stamped Wrench "
    "WrenchStamped",
    "builtin_interfaces.msg": "Time Duration",
    "std_srvs.srv": "Empty Trigger SetBool",
    "turtlesim.msg": "Pose Color",
    "turtlesim.srv": "Spawn Kill SetPen TeleportAbsolute TeleportRelative",
    "turtle_sensor_interface.srv": "TurtlePosition",
}


@pytest.mark.parametrize("module", sorted(SPEC_TYPES))
def test_every_spec_type_imports_and_builds(module: str) -> None:
    mod = importlib.import_module(f"llfsm.msgs.{module}")
    pkg, kind = module.split(".")
    for name in SPEC_TYPES[module].split():
        cls = getattr(mod, name)
        assert cls._TYPE.split("/") == [pkg, kind, name]
        for c in (cls.Request, cls.Response) if kind == "srv" else (cls,):
            m = c()
            assert m._copy() == m and isinstance(to_yaml(m), str)


def test_field_types_match_ros() -> None:
    assert dict(Pose._FIELDS)["linear_velocity"] == "float32"
    assert dict(Color._FIELDS) == {"r": "uint8", "g": "uint8", "b": "uint8"}
    assert dict(PoseWithCovariance._FIELDS)["covariance"] == "float64[36]"
    assert PoseWithCovariance.get_fields_and_field_types() == {"pose": "geometry_msgs/Pose", "covariance": "double[36]"}
    from llfsm.msgs.std_srvs.srv import SetBool, Trigger

    assert dict(SetBool.Request._FIELDS) == {"data": "bool"}
    assert dict(Trigger.Response._FIELDS) == {"success": "bool", "message": "string"}


# -- user interfaces through the import hook ------------------------------------------------


def test_user_service_imports_through_the_hook(user_pkg: tuple[ModuleType, ModuleType, Path]) -> None:
    msg, srv, _ = user_pkg
    from llfsm.msgs.llfsm_test_pkg.srv import Do

    assert Do is srv.Do and is_service_class(Do)
    req = Do.Request()
    assert type(req.thing) is msg.Thing and req.thing.x == 1.5
    assert Do.Response().twist == Twist()


def test_search_path_order(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    a, b, c = tmp_path / "a", tmp_path / "b", tmp_path / "c"
    monkeypatch.setenv("LLFSM_INTERFACE_PATH", os.pathsep.join([str(b), ""]))
    monkeypatch.setenv("AMENT_PREFIX_PATH", str(c))
    monkeypatch.setattr(interface_path, "_added", [])
    llfsm.msgs.add_search_path(a)
    llfsm.msgs.add_search_path(a)
    assert llfsm.msgs.search_path() == [a, b, c / "share"]


def test_colcon_installed_interfaces_import(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    write_pkg(tmp_path / "install" / "share", "llfsm_colcon_pkg", {"msg/Reading.msg": "float32 value\n"})
    monkeypatch.setenv("AMENT_PREFIX_PATH", str(tmp_path / "install"))
    try:
        from llfsm.msgs.llfsm_colcon_pkg.msg import Reading

        assert Reading(value=2).value == 2.0
    finally:
        forget("llfsm_colcon_pkg")


def test_second_import_uses_the_cache_without_the_compiler(tmp_path: Path) -> None:
    write_pkg(tmp_path / "ws", "llfsm_cached_pkg", {"srv/Ask.srv": "string q\n---\nint64 a 42\n"})
    env = {**os.environ, "LLFSM_INTERFACE_PATH": str(tmp_path / "ws")}
    probe = textwrap.dedent(
        """
        import sys
        from llfsm.msgs.llfsm_cached_pkg.srv import Ask
        assert Ask.Response().a == 42
        heavy = sorted(m for m in ("rosbags", "jinja2", "yaml", "llfsm.idl.package") if m in sys.modules)
        print(",".join(heavy) or "light")
        """
    )
    first = subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True, text=True, check=True)
    assert "jinja2" in first.stdout and "rosbags" not in first.stdout  # compiled on the first import
    cached = list((Path(env["LLFSM_CACHE_DIR"]) / "interfaces").glob("llfsm_cached_pkg-*/srv/__init__.py"))
    assert len(cached) == 1
    second = subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True, text=True, check=True)
    assert second.stdout.strip() == "light"
    # a changed definition is a new fingerprint, compiled afresh
    (tmp_path / "ws" / "llfsm_cached_pkg" / "srv" / "Ask.srv").write_text("string q\n---\nint64 a 42\nint8 b\n")
    third = subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True, text=True, check=True)
    assert "jinja2" in third.stdout


@pytest.mark.parametrize(
    ("text", "line", "message"),
    [
        ("float64 x\nFloat64 y\n", 2, "unknown message type llfsm_bad_pkg/msg/Float64 (did you mean float64?)"),
        ("geometry_msgs/Pointt p\n", 1, "unknown message type geometry_msgs/msg/Pointt"),
        ("float64\n", 1, "expected 'TYPE NAME'"),
        ("int32 Bad\n", 1, "invalid field name 'Bad'"),
        ("uint8 x 300\n", 1, "out of range for uint8"),
        ("int32[2] a [1, 2, 3]\n", 1, "the default has 3 elements"),
        ("# fine\nfloat64 x\nfloat64 x\n", 3, "x is defined twice"),
        ('string<=3 s "long"\n', 1, "longer than the bound 3"),
        ("float64 from\n", 1, "reserved in Python"),
        ("uint8[] x=1\n", 1, "invalid constant name 'x'"),
    ],
)
def test_broken_definition_is_an_import_error_naming_file_and_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, text: str, line: int, message: str
) -> None:
    path = write_pkg(tmp_path, "llfsm_bad_pkg", {"msg/Bad.msg": text}) / "msg" / "Bad.msg"
    monkeypatch.setenv("LLFSM_INTERFACE_PATH", str(tmp_path))
    try:
        with pytest.raises(ImportError) as e:
            importlib.import_module("llfsm.msgs.llfsm_bad_pkg.msg")
    finally:
        forget("llfsm_bad_pkg")
    assert str(e.value).startswith(f"{path}:{line}: ")
    assert message in str(e.value)
    assert not list((Path(os.environ["LLFSM_CACHE_DIR"]) / "interfaces").glob("llfsm_bad_pkg-*"))


def test_srv_needs_one_separator(tmp_path: Path) -> None:
    with pytest.raises(InterfaceError, match="no '---' line"):
        parser.parse_service("int32 a\n", "p/srv/S", "S.srv")
    with pytest.raises(InterfaceError, match=r"S.srv:3: more than one"):
        parser.parse_service("---\nint32 a\n---\n", "p/srv/S", "S.srv")
    s = parser.parse_service("int32 a # c\n---  # c\n\nint32 b\n", "p/srv/S", "S.srv")
    assert s.response.fields[0].line == 4


def test_unknown_package_is_module_not_found() -> None:
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module("llfsm.msgs.llfsm_no_such_pkg")


# -- the committed modules are what the generator writes ----------------------------------------


def test_committed_modules_match_regeneration() -> None:
    sources = shipped.shipped_sources()
    assert len(sources) >= 13
    stale = [str(p) for p, text in sources.items() if not p.exists() or p.read_text(encoding="utf-8") != text]
    assert not stale, f"run `python -m llfsm.idl` (make msgs): stale {stale}"


def test_regenerating_into_a_folder_gives_the_committed_tree_byte_for_byte(tmp_path: Path) -> None:
    """`python -m llfsm.idl --out DIR` from the shipped definitions alone writes every committed
    module and nothing else: each shipped package comes from its .msg/.srv files (nothing taken
    from rosbags), and no committed module is left that the definitions no longer make."""
    code = subprocess.run(
        [sys.executable, "-m", "llfsm.idl", "--out", str(tmp_path)], capture_output=True, text=True, check=False
    )
    assert code.returncode == 0, code.stderr
    written = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*") if p.is_file())
    committed = sorted(p.relative_to(MSGS_DIR) for p in shipped.generated_files())
    assert written == committed
    assert {p.parts[0] for p in written} == {d.name for d in shipped.SHIPPED_DIR.iterdir() if d.is_dir()}
    differ = [str(p) for p in written if (tmp_path / p).read_bytes() != (MSGS_DIR / p).read_bytes()]
    assert not differ, f"run `python -m llfsm.idl` (make msgs): stale {differ}"


def test_generated_modules_are_marked_generated() -> None:
    """Each committed module says it is generated, and .gitattributes marks it so (a review
    folds it away)."""
    files = shipped.generated_files()
    for path in files:
        assert path.read_text(encoding="utf-8").startswith("# Generated by llfsm from llfsm/msgs/_interfaces/")
    root = MSGS_DIR.parent.parent
    if not (root / ".git").exists():
        pytest.skip("not a git work tree (a copy of the sources)")
    names = "\n".join(p.relative_to(root).as_posix() for p in files)
    got = subprocess.run(
        ["git", "check-attr", "--stdin", "linguist-generated"], cwd=root, input=names, capture_output=True, text=True
    )
    assert got.returncode == 0, got.stderr
    unmarked = [line for line in got.stdout.splitlines() if not line.endswith(": true")]
    assert not unmarked and len(got.stdout.splitlines()) == len(files)


def test_generated_modules_import_nothing_heavy() -> None:
    for path in MSGS_DIR.glob("*/*/__init__.py"):
        imports = [line for line in path.read_text().splitlines() if line.startswith(("import ", "from "))]
        for line in imports:
            assert line.startswith(("from __future__", "import llfsm.msgs.", "from llfsm.msgs import _message")), line


# -- to_yaml: `ros2 topic echo` ----------------------------------------------------------------


def reference_yaml(data: object) -> str:
    """rosidl_runtime_py.message_to_yaml's dump, on plain data in field order."""
    return yaml.dump(data, allow_unicode=True, width=sys.maxsize, default_flow_style=False, sort_keys=False)


def test_to_yaml_twist() -> None:
    t = Twist()
    t.linear.x = 2.0
    t.angular.z = -1.5
    assert to_yaml(t) == "linear:\n  x: 2.0\n  y: 0.0\n  z: 0.0\nangular:\n  x: 0.0\n  y: 0.0\n  z: -1.5\n"


def test_to_yaml_string_quotes_only_when_needed() -> None:
    assert to_yaml(String(data="Hello World: 3")) == "data: 'Hello World: 3'\n"
    assert to_yaml(String(data="hello")) == "data: hello\n"
    assert to_yaml(String()) == "data: ''\n"
    assert to_yaml(String(data="true")) == "data: 'true'\n"
    assert to_yaml(String(data="1.5")) == "data: '1.5'\n"
    assert to_yaml(String(data="tab\there")) == 'data: "tab\\there"\n'
    assert to_yaml(String(data="two\nlines")) == "data: 'two\n\n  lines'\n"


def test_to_yaml_turtlesim_pose() -> None:
    p = Pose(x=5.544445, y=5.544445, theta=0.0)
    assert to_yaml(p) == "x: 5.544445\ny: 5.544445\ntheta: 0.0\nlinear_velocity: 0.0\nangular_velocity: 0.0\n"


def test_to_yaml_arrays_and_empty() -> None:
    m = Float64MultiArray(data=[1.0, 1e-5, 1e16, math.inf])
    m.layout.dim = [MultiArrayDimension(label="x", size=4, stride=4)]
    expected = (
        "layout:\n  dim:\n  - label: x\n    size: 4\n    stride: 4\n  data_offset: 0\n"
        "data:\n- 1.0\n- 1.0e-05\n- 1.0e+16\n- .inf\n"
    )
    assert to_yaml(m) == expected == reference_yaml(m.to_dict())
    assert to_yaml(Float64MultiArray()) == "layout:\n  dim: []\n  data_offset: 0\ndata: []\n"
    assert to_yaml(Empty()) == "{}\n"
    assert to_yaml(Header()) == "stamp:\n  sec: 0\n  nanosec: 0\nframe_id: ''\n"


def test_to_yaml_user_message(user_pkg: tuple[ModuleType, ModuleType, Path]) -> None:
    msg, srv, _ = user_pkg
    for m in (msg.Thing(), srv.Do.Request(), srv.Do.Response(ok=True)):
        assert to_yaml(m) == reference_yaml(m.to_dict())


scalars = st.one_of(
    st.text(max_size=12),
    st.text(alphabet=" \n\t:#-'\"?[]{},&*!|>%@`~=<.0123456789eEtrufalsnoyNYx\x85\u2028\xa0\ufeff😀é", max_size=8),
    st.integers(min_value=-(2**64), max_value=2**64),
    st.floats(allow_nan=False),
    st.booleans(),
)
keys = st.from_regex(r"[a-z][a-z0-9_]{0,6}", fullmatch=True) | st.sampled_from(["on", "yes", "null", "y", "x1"])
documents = st.recursive(
    scalars,
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(keys, inner, max_size=3),
    max_leaves=12,
)


@settings(max_examples=300, deadline=None)
@given(st.dictionaries(keys, documents, max_size=4))
def test_to_yaml_matches_pyyaml(data: dict[str, object]) -> None:
    # lists of lists are not ROS data (a field holds messages or scalars)
    def ros_shaped(v: object) -> bool:
        if isinstance(v, list):
            return all(not isinstance(x, list) and ros_shaped(x) for x in v)
        if isinstance(v, dict):
            return all(ros_shaped(x) for x in v.values())
        return True

    if not ros_shaped(data):
        return
    assert to_yaml(data) == reference_yaml(data)
