"""Messages on ROS 2's DDS wire: the runtime API over the generated `_dds` modules.

Every message and service class (shipped or a user's, compiled by the toolchain, llfsm.idl)
has a generated DDS form beside it, `llfsm.msgs.<pkg>.<msg|srv>._dds`.  This module finds it
from the class and offers:

- `cdr(msg) -> bytes`: the serialized payload, encapsulation header (00 01 00 00: plain CDR,
  little endian, XCDR1) included, byte for byte what rclpy's `serialize_message` gives.
  `from_cdr(data, msg_cls)` reads it back.  These are what a transport should put on the wire
  (cyclonedds' raw write/take take bytes): they are several times faster than converting to an
  IdlStruct sample and letting cyclonedds serialize it.
- `dds_type(msg_cls)`: the `cyclonedds.idl.IdlStruct` class named `pkg::msg::dds_::Name_`, to
  create topics with; `to_dds(msg)` and `from_dds(sample, msg_cls=None)` convert samples.
- Services, on rmw_cyclonedds_cpp's wire: `request_type(srv_cls)`, `response_type(srv_cls)` (the
  IdlStruct of the `rq/<name>Request` and `rr/<name>Reply` topics: the request header, then the
  fields), `wrap(msg, guid, seq) -> bytes` and `unwrap(data, msg_cls) -> (guid, seq, msg)`.
  The header (`cdds_request_header_t`) is a uint64 client id (the client's request writer's
  instance handle on rmw_cyclonedds_cpp) and an int64 sequence number, first in the payload of
  requests AND replies; a reply echoes the request's.  Fast DDS (rmw_fastrtps_cpp) sends no
  header (it correlates through RTPS inline QoS instead): `cdr` / `from_cdr` are its payloads;
  `carries_request_header(guid)` tells from a peer's GUID which form it speaks.
- `type_hash(cls) -> str`: the RIHS01 hash ROS 2 (Iron and later) puts in endpoints' USER_DATA
  as `typehash=<hash>;`, for messages and services, computed when the modules were generated.

Nothing here parses a definition or imports the compiler; cyclonedds is imported when the first
`_dds` module is.
"""

from __future__ import annotations

import importlib
from dataclasses import fields as _dataclass_fields
from struct import Struct
from struct import error as StructError
from typing import Any, NamedTuple
from uuid import UUID

from ._message import Action, Message, Service

HEADER = b"\x00\x01\x00\x00"  # encapsulation header: CDR (XCDR1), little endian
_REQUEST_HEADER = Struct("<Qq")  # cdds_request_header_t: client guid, sequence number


class Codec(NamedTuple):
    """The generated functions of one message class."""

    idl: type  # the IdlStruct
    cdr: Any  # (msg) -> bytes
    from_cdr: Any  # (data) -> (msg, end offset)
    to_dds: Any  # (msg) -> sample
    from_dds: Any  # (sample) -> msg
    dec: Any  # (data, offset) -> (msg, offset) for a request or reply after its header; else None
    # (out, key, clock) -> (msg) -> None, appending out(head + CDR) with the head
    # <uint32 key><int64 clock.now><uint32 size>; None where the size varies (or in a module
    # generated before it existed)
    stamped: Any = None
    # the same record as ((format, path), ...) for llfsm.bag._tap.Tap; None where `stamped` is,
    # and for a message without fields (its CDR is a constant byte)
    tap_layout: Any = None


_codecs: dict[type, Codec] = {}
_by_idl: dict[type, type[Message]] = {}


def _module(cls: type) -> Any:
    return importlib.import_module(cls.__module__ + "._dds")


def codec(msg_cls: type[Message]) -> Codec:
    """The generated DDS functions of a message class (cached)."""
    c = _codecs.get(msg_cls)
    if c is None:
        if not (isinstance(msg_cls, type) and issubclass(msg_cls, Message)):
            raise TypeError(f"not a message class: {msg_cls!r}")
        try:
            c = Codec(*_module(msg_cls).CODECS[msg_cls.__name__])
        except (ImportError, KeyError, AttributeError) as e:
            raise TypeError(f"{msg_cls._TYPE or msg_cls!r} has no DDS form ({e})") from None
        _codecs[msg_cls] = c
        _by_idl[c.idl] = msg_cls
    return c


def dds_type(msg_cls: type[Message]) -> type:
    """The cyclonedds IdlStruct class of a message class (`pkg::msg::dds_::Name_`)."""
    return codec(msg_cls).idl


def dds_type_name(cls: type[Message] | type[Service]) -> str:
    """ "geometry_msgs::msg::dds_::Twist_"; for a service class, its Request's type name."""
    if isinstance(cls, type) and issubclass(cls, Service):
        cls = cls.Request
    return dds_type(cls).__idl_typename__  # type: ignore[attr-defined]  # set by cyclonedds


def to_dds(msg: Message) -> Any:
    """The cyclonedds sample of a message."""
    return codec(type(msg)).to_dds(msg)


def from_dds(sample: Any, msg_cls: type[Message] | None = None) -> Message:
    """The message of a cyclonedds sample (of `dds_type(msg_cls)`, which is found from the
    sample when `msg_cls` is not given)."""
    if msg_cls is None:
        msg_cls = _by_idl.get(type(sample))
        if msg_cls is None:
            raise TypeError(f"not a sample of a known message's DDS type: {type(sample).__name__}")
    c = codec(msg_cls)
    if not isinstance(sample, c.idl):  # e.g. cyclonedds' InvalidSample (a dispose, no data)
        raise TypeError(f"not a {dds_type_name(msg_cls)} sample: {type(sample).__name__}")
    return c.from_dds(sample)


def cdr(msg: Message) -> bytes:
    """The serialized payload of `msg`, encapsulation header included (rclpy's
    `serialize_message`)."""
    return codec(type(msg)).cdr(msg)


def _check_header(data: bytes | bytearray | memoryview) -> None:
    if len(data) < 4:
        raise ValueError(f"not a CDR payload: {len(data)} bytes")
    if data[0] != 0 or data[1] != 1:
        kind = "big-endian CDR" if data[0] == 0 and data[1] == 0 else f"encapsulation {bytes(data[:2]).hex()}"
        raise ValueError(f"unsupported payload: {kind} (llfsm reads plain little-endian CDR, 00 01)")


def from_cdr(data: bytes | bytearray | memoryview, msg_cls: type[Message]) -> Message:
    """The message serialized in `data` (a payload with its encapsulation header).  A payload
    that is too short or not plain little-endian CDR raises ValueError."""
    c = codec(msg_cls)
    _check_header(data)
    try:
        msg, end = c.from_cdr(data)
    except (IndexError, UnicodeDecodeError, ValueError, StructError) as e:
        raise ValueError(f"malformed {msg_cls._TYPE} payload ({len(data)} bytes): {e}") from None
    if end > len(data):
        raise ValueError(f"malformed {msg_cls._TYPE} payload: truncated ({len(data)} bytes, {end} needed)")
    return msg


# -- services ----------------------------------------------------------------------------------


def _service(srv_cls: type[Service]) -> type[Service]:
    if not (isinstance(srv_cls, type) and issubclass(srv_cls, Service) and srv_cls is not Service):
        raise TypeError(f"not a service class: {srv_cls!r}")
    return srv_cls


def _wire(msg_cls: type[Message]) -> type:
    codec(msg_cls)
    try:
        return _module(msg_cls).WIRE[msg_cls.__name__]
    except (AttributeError, KeyError):
        raise TypeError(f"{msg_cls._TYPE} is not a service request or response") from None


def request_type(srv_cls: type[Service]) -> type:
    """The IdlStruct of the service's `rq/...Request` topic on rmw_cyclonedds_cpp's wire:
    `client_guid_` (uint64), `sequence_number_` (int64), then the request's fields; named
    `pkg::srv::dds_::Name_Request_`."""
    return _wire(_service(srv_cls).Request)


def response_type(srv_cls: type[Service]) -> type:
    """Same for the `rr/...Reply` topic (`pkg::srv::dds_::Name_Response_`)."""
    return _wire(_service(srv_cls).Response)


def wrap(msg: Message, guid: int, seq: int) -> bytes:
    """The payload of a request or reply on rmw_cyclonedds_cpp's wire: encapsulation header,
    client guid (uint64), sequence number (int64), then the message.  The message's fields
    start at offset 16, a multiple of 8, so their CDR is the same as alone."""
    return HEADER + _REQUEST_HEADER.pack(guid, seq) + codec(type(msg)).cdr(msg)[4:]


def unwrap(data: bytes | bytearray | memoryview, msg_cls: type[Message]) -> tuple[int, int, Message]:
    """(client guid, sequence number, message) of a payload written by `wrap` or by
    rmw_cyclonedds_cpp."""
    c = codec(msg_cls)
    if c.dec is None:
        raise TypeError(f"{msg_cls._TYPE} is not a service request or response")
    _check_header(data)
    try:
        guid, seq = _REQUEST_HEADER.unpack_from(data, 4)
        msg, end = c.dec(data, 20)
    except (IndexError, UnicodeDecodeError, ValueError, StructError) as e:
        raise ValueError(f"malformed {msg_cls._TYPE} request/reply ({len(data)} bytes): {e}") from None
    if end > len(data):
        raise ValueError(f"malformed {msg_cls._TYPE} request/reply: truncated ({len(data)} bytes, {end} needed)")
    return guid, seq, msg


def to_wire(msg: Message, guid: int, seq: int) -> Any:
    """The sample of `request_type`/`response_type` for a request or reply message."""
    wire = _wire(type(msg))
    sample = to_dds(msg)
    return wire(guid, seq, *(getattr(sample, f.name) for f in _dataclass_fields(sample)))


def from_wire(sample: Any, msg_cls: type[Message]) -> tuple[int, int, Message]:
    """(client guid, sequence number, message) of a `request_type`/`response_type` sample."""
    plain = dds_type(msg_cls)
    fields = (getattr(sample, f.name) for f in _dataclass_fields(plain))
    return sample.client_guid_, sample.sequence_number_, from_dds(plain(*fields), msg_cls)


# Vendor ids (the first two bytes of every RTPS GUID prefix: participant keys, endpoint keys).
# Which wire form a service peer speaks follows from it: rmw_cyclonedds_cpp puts the request
# header in the payload; rmw_fastrtps_cpp (and RTI's rmw_connextdds) send the bare message and
# correlate through RTPS inline QoS (PID_RELATED_SAMPLE_IDENTITY), which cyclonedds can neither
# write nor show.  See docs/transports.md, "Services across DDS implementations".
VENDOR_RTI_CONNEXT = 0x0101
VENDOR_FAST_DDS = 0x010F
VENDOR_CYCLONE_DDS = 0x0110
VENDORS = {
    VENDOR_RTI_CONNEXT: "RTI Connext DDS",
    0x0102: "OpenSplice DDS",
    0x0104: "Twin Oaks CoreDX",
    0x010F: "eProsima Fast DDS",
    0x0110: "Eclipse Cyclone DDS",
    0x0112: "RustDDS",
    0x0113: "Zenoh (zenoh-plugin-dds)",
}


def vendor_id(guid: UUID | bytes | str) -> int:
    """The vendor id in a GUID or participant key (a `uuid.UUID` as cyclonedds' builtin topics
    give them, 16 bytes, or their text)."""
    if isinstance(guid, str):
        guid = UUID(guid)
    raw = guid.bytes if isinstance(guid, UUID) else bytes(guid)
    if len(raw) < 2:
        raise ValueError(f"not a GUID: {raw!r}")
    return raw[0] << 8 | raw[1]


def vendor_name(guid: UUID | bytes | str) -> str:
    vid = vendor_id(guid)
    return VENDORS.get(vid, f"vendor {vid >> 8:02x}.{vid & 0xFF:02x}")


def carries_request_header(guid: UUID | bytes | str) -> bool:
    """Whether a service peer (the GUID of its request reader, reply writer or participant)
    expects and sends rmw_cyclonedds_cpp's request header: only Cyclone DDS peers do.  For
    the others, requests and replies are `cdr(msg)` alone."""
    return vendor_id(guid) == VENDOR_CYCLONE_DDS


# -- type hashes -------------------------------------------------------------------------------


def type_hash(cls: type[Message] | type[Service] | type[Action]) -> str:
    """ "RIHS01_<64 hex>": the type hash of a message, service or action class (REP 2011)."""
    if not (isinstance(cls, type) and issubclass(cls, Message | Service | Action)):
        raise TypeError(f"not a message, service or action class: {cls!r}")
    try:
        return _module(cls).TYPE_HASHES[cls.__name__]
    except (ImportError, KeyError, AttributeError):
        raise TypeError(f"{cls._TYPE or cls!r} has no type hash") from None
