"""DDS forms of the message classes (llfsm.msgs._dds): CDR payloads, cyclonedds samples, the
service request header, type hashes.  The comparison with real ROS 2 (rclpy's
serialize_message, the type hashes rosidl writes) is in tests/interop/."""

from __future__ import annotations

import importlib
import random
import struct
from pathlib import Path

import pytest
from samples import CLASSES, sample, shipped_services

from llfsm.idl.package import MSGS_DIR, installed_spec
from llfsm.msgs import _dds
from llfsm.msgs._message import Message, Service


def test_every_shipped_package_has_dds_forms() -> None:
    assert len(CLASSES) > 60
    names = {c._TYPE for c in CLASSES}
    assert {"std_msgs/msg/String", "geometry_msgs/msg/Twist", "turtlesim/msg/Pose", "turtlesim/srv/Spawn_Request",
            "rmw_dds_common/msg/ParticipantEntitiesInfo"} <= names  # fmt: skip


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: c._TYPE)
def test_round_trip_through_cdr_and_samples(cls: type[Message]) -> None:
    rng = random.Random(cls._TYPE)
    for _ in range(3):
        msg = sample(cls, rng)
        data = _dds.cdr(msg)
        assert data[:4] == b"\x00\x01\x00\x00"
        back = _dds.from_cdr(data, cls)
        assert back == msg and type(back) is cls
        assert _dds.from_cdr(data + b"\0\0\0", cls) == msg  # wire padding after the payload is ignored
        assert _dds.from_dds(_dds.to_dds(msg)) == msg
        assert _dds.from_dds(_dds.to_dds(msg), cls) == msg
    default = cls()
    assert _dds.from_cdr(_dds.cdr(default), cls) == default


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: c._TYPE)
def test_idl_type_is_named_as_ros2_names_it(cls: type[Message]) -> None:
    pkg, kind, name = cls._TYPE.split("/")
    t = _dds.dds_type(cls)
    assert t.__idl_typename__ == f"{pkg}::{kind}::dds_::{name}_"


def test_dds_type_names_read_back_to_the_classes() -> None:
    """The one reading of the mangled names (dds_graph), used by the transport, the graph
    verbs, the bag recorder and `llfsm view`: every shipped type's DDS name leads back to it."""
    from llfsm.msgs.std_srvs.srv import Trigger
    from llfsm.ros.transports.dds_graph import message_class, message_type, service_class, service_type

    for cls in CLASSES:
        assert message_class(_dds.dds_type(cls).__idl_typename__) is cls
    for srv in shipped_services():
        for half in (srv.Request, srv.Response):
            name = _dds.dds_type(half).__idl_typename__
            assert service_type(name) == srv._TYPE and service_class(name) is srv
    assert message_type("std_srvs::srv::dds_::Trigger_Request_") == "std_srvs/srv/Trigger_Request"
    assert service_class("std_srvs::srv::dds_::Trigger_Request_") is Trigger
    assert message_type("MyModule::Point") == "MyModule/Point"  # a foreign type, shown as rmw shows it
    for foreign in ("MyModule::Point", "nope_msgs::msg::dds_::Thing_", "std_msgs::msg::dds_::String", "::dds_::_"):
        assert message_class(foreign) is None and service_class(foreign) is None
    assert service_type("std_srvs::srv::dds_::_Request_") is None


def test_cdr_layout_of_well_known_messages() -> None:
    """The CDR rules themselves: strings carry their NUL and a uint32 length, 8-byte values
    align to 8 counted after the encapsulation header, an empty message is one zero byte."""
    from llfsm.msgs.geometry_msgs.msg import Twist
    from llfsm.msgs.std_msgs.msg import Empty, Header, String

    assert _dds.cdr(String(data="hi")) == bytes.fromhex("00010000_03000000_686900".replace("_", ""))
    assert _dds.cdr(Empty()) == bytes.fromhex("0001000000")
    twist = Twist()
    twist.linear.x, twist.angular.z = 2.0, -1.5
    assert _dds.cdr(twist) == b"\x00\x01\x00\x00" + struct.pack("<6d", 2.0, 0, 0, 0, 0, -1.5)
    h = Header(frame_id="map")
    h.stamp.sec, h.stamp.nanosec = 7, 9
    assert _dds.cdr(h) == b"\x00\x01\x00\x00" + struct.pack("<iII", 7, 9, 4) + b"map\0"


def test_bad_payloads_are_value_errors() -> None:
    from llfsm.msgs.geometry_msgs.msg import Twist
    from llfsm.msgs.std_msgs.msg import String

    with pytest.raises(ValueError, match="malformed geometry_msgs/msg/Twist"):
        _dds.from_cdr(b"\x00\x01\x00\x00" + bytes(10), Twist)
    with pytest.raises(ValueError, match="big-endian"):
        _dds.from_cdr(b"\x00\x00\x00\x00" + bytes(48), Twist)
    with pytest.raises(ValueError, match="not a CDR payload"):
        _dds.from_cdr(b"\x00", String)
    with pytest.raises(ValueError, match="malformed std_msgs/msg/String"):
        _dds.from_cdr(b"\x00\x01\x00\x00\x05\x00\x00\x00\xff\xfe\x00\x00\x00", String)
    from llfsm.msgs.rmw_dds_common.msg import ParticipantEntitiesInfo

    # A count of 2**32 - 1 nodes in 8 bytes: refused at once, not looped over.
    bogus = b"\x00\x01\x00\x00" + bytes(16) + b"\xff\xff\xff\xff" + bytes(8)
    with pytest.raises(ValueError, match="elements announced"):
        _dds.from_cdr(bogus, ParticipantEntitiesInfo)
    with pytest.raises(TypeError, match="not a message class"):
        _dds.cdr("text")  # type: ignore[arg-type]


@pytest.mark.parametrize("srv", shipped_services(), ids=lambda c: c._TYPE)
def test_service_payloads_carry_rmw_cyclonedds_request_header(srv: type[Service]) -> None:
    rng = random.Random(srv._TYPE)
    for part, wire_type in ((srv.Request, _dds.request_type(srv)), (srv.Response, _dds.response_type(srv))):
        msg = sample(part, rng)
        guid, seq = 0x0123456789ABCDEF, 42
        data = _dds.wrap(msg, guid, seq)
        assert data[:20] == b"\x00\x01\x00\x00" + struct.pack("<Qq", guid, seq)
        assert data[20:] == _dds.cdr(msg)[4:]
        assert _dds.unwrap(data, part) == (guid, seq, msg)
        assert wire_type.__idl_typename__ == _dds.dds_type(part).__idl_typename__
        wire_sample = _dds.to_wire(msg, guid, seq)
        assert type(wire_sample) is wire_type
        assert wire_sample.serialize(use_version_2=False) == data  # cyclonedds' own XCDR1 agrees
        assert _dds.from_wire(wire_sample, part) == (guid, seq, msg)


def test_cyclonedds_serializer_agrees_with_generated_cdr() -> None:
    """cyclonedds' own XCDR1 serialization of the IdlStruct sample gives the same bytes (so a
    peer reading with cyclonedds' types reads our payloads), for every shipped type without
    wstring (which cyclonedds' Python IDL lacks)."""
    checked = 0
    for cls in CLASSES:
        if any("wstring" in t for _, t in cls._FIELDS):
            continue
        msg = sample(cls, random.Random(cls._TYPE + "xcdr1"))
        idl = _dds.to_dds(msg)
        assert idl.serialize(use_version_2=False) == _dds.cdr(msg), cls._TYPE
        assert _dds.from_dds(type(idl).deserialize(_dds.cdr(msg))) == msg
        checked += 1
    assert checked > 60


def test_type_hashes_are_rihs01() -> None:
    from llfsm.msgs.geometry_msgs.msg import Twist
    from llfsm.msgs.turtlesim.srv import Spawn

    for cls in (Twist, Spawn, Spawn.Request):
        h = _dds.type_hash(cls)
        assert h.startswith("RIHS01_") and len(h) == 7 + 64
    assert len({_dds.type_hash(c) for c in CLASSES}) == len(CLASSES)


def test_user_package_gets_dds_forms(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A user's .msg with arrays (fixed, bounded, unbounded), bounded strings and nested types
    from its own and other packages is compiled with its DDS form."""
    pkg = tmp_path / "llfsm_dds_user_pkg"
    (pkg / "msg").mkdir(parents=True)
    (pkg / "srv").mkdir()
    (pkg / "msg" / "Inner.msg").write_text("int16 a\nstring<=8 name\nfloat64[] values\n")
    (pkg / "msg" / "Outer.msg").write_text(
        "uint8 flag\nInner inner\nInner[2] pair\nInner[<=3] few\nInner[] many\n"
        "geometry_msgs/Point[] points\nstring[<=4] words\nbool[3] bits\nint64[] counts\n"
        "std_msgs/Header header\nchar[4] tag\nbyte[] blob\nwstring wide\nfloat32 last\n"
    )
    (pkg / "srv" / "Ask.srv").write_text("Inner question\n---\nOuter answer\nbool ok\n")
    other = tmp_path / "llfsm_dds_user_pkg2" / "msg"  # a user package using the first one
    other.mkdir(parents=True)
    (other / "Wrapper.msg").write_text("llfsm_dds_user_pkg/Outer[<=2] outers\nllfsm_dds_user_pkg/Inner inner\n")
    monkeypatch.setenv("LLFSM_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv("LLFSM_INTERFACE_PATH", str(tmp_path))
    msg_module = importlib.import_module("llfsm.msgs.llfsm_dds_user_pkg.msg")
    srv_module = importlib.import_module("llfsm.msgs.llfsm_dds_user_pkg.srv")
    wrapper = importlib.import_module("llfsm.msgs.llfsm_dds_user_pkg2.msg").Wrapper
    rng = random.Random(5)
    for cls in (msg_module.Inner, msg_module.Outer, srv_module.Ask.Request, srv_module.Ask.Response, wrapper):
        for _ in range(5):
            msg = sample(cls, rng)
            assert _dds.from_cdr(_dds.cdr(msg), cls) == msg
        assert _dds.dds_type(cls).__idl_typename__.startswith(cls._TYPE.split("/")[0] + "::")
    assert _dds.type_hash(srv_module.Ask).startswith("RIHS01_")
    assert installed_spec("llfsm_dds_user_pkg/msg/Inner").fields[2].type.array == "unbounded"


def test_vendor_of_a_guid_tells_the_service_wire_form() -> None:
    import uuid

    cyclone = uuid.UUID("01103ee2-9a02-e95c-c321-3714000001c1")  # a cyclonedds participant's key
    fast = "010f7f01-3604-56e1-0000-000000001304"  # rmw_fastrtps_cpp's rq/ reader
    assert _dds.vendor_name(cyclone) == "Eclipse Cyclone DDS" and _dds.carries_request_header(cyclone)
    assert _dds.vendor_name(fast) == "eProsima Fast DDS" and not _dds.carries_request_header(fast)
    assert _dds.vendor_name(bytes.fromhex("01aa") + bytes(14)) == "vendor 01.aa"
    with pytest.raises(ValueError):
        _dds.vendor_id(b"")


def test_generated_dds_modules_import_nothing_heavy() -> None:
    """Running pays for no parser or template engine: a `_dds` module imports cyclonedds' IDL
    support, struct, dataclasses and other generated modules only."""
    allowed = (
        "from dataclasses import",
        "from struct import",
        "import cyclonedds.idl.types",
        "from cyclonedds.idl import",
    )
    paths = sorted(MSGS_DIR.glob("*/*/_dds.py"))
    assert len(paths) >= 9
    for path in paths:
        for line in path.read_text().splitlines():
            if line.startswith(("import ", "from ")):
                assert line.startswith(allowed) or line.startswith("import llfsm.msgs."), (path, line)


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: c._TYPE)
def test_damaged_payloads_raise_value_error_only(cls: type[Message]) -> None:
    """What a peer may send: every truncation of a good payload and random byte changes give a
    message or ValueError, never another exception (the transport drops such samples)."""
    rng = random.Random(cls._TYPE + "damage")
    good = _dds.cdr(sample(cls, rng))
    damaged = [good[:n] for n in range(len(good))]
    for _ in range(30):
        data = bytearray(good)
        for _ in range(rng.randint(1, 4)):
            data[rng.randrange(4, len(data))] = rng.randrange(256) if len(data) > 4 else 0
        damaged.append(bytes(data))
    for data in damaged:
        try:
            msg = _dds.from_cdr(data, cls)
        except ValueError:
            continue
        assert type(msg) is cls


def test_messages_of_a_fixed_size_have_a_stamped_record() -> None:
    from llfsm.msgs.geometry_msgs.msg import Twist
    from llfsm.msgs.std_msgs.msg import Header, String
    from llfsm.msgs.turtlesim.msg import Color, Pose

    assert all(_dds.codec(c).stamped is not None for c in (Twist, Pose, Color))
    assert all(_dds.codec(c).stamped is None for c in (String, Header))  # their sizes vary


@pytest.mark.parametrize("cls", [c for c in CLASSES if _dds.codec(c).stamped], ids=lambda c: c._TYPE)
def test_a_stamped_record_is_the_head_then_the_cdr(cls: type[Message]) -> None:
    """What `--record` writes for a message of a fixed size comes from one generated pack (head
    and CDR together): its bytes must be the pipe head, then exactly the message's CDR, at the
    clock's time of the call."""
    records: list[bytes] = []

    class Clock:
        now = 0

    clock = Clock()
    record = _dds.codec(cls).stamped(records.append, 7, clock)
    rng = random.Random(cls._TYPE + "stamped")
    for n in range(5):
        msg = sample(cls, rng)
        clock.now = -(10**18) + n * 123_456_789_012
        record(msg)
        data = _dds.cdr(msg)
        assert records[-1] == struct.pack("<IqI", 7, clock.now, len(data)) + data
