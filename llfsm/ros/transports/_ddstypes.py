"""DDS forms of llfsm's message classes: the one place the DDS transport gets its types from.

PROVISIONAL: built at run time from each class's `_FIELDS` with cyclonedds' IdlStruct, until
the generated types of `llfsm.msgs._dds` (branch ddstypes) replace this module's insides.  The
API is the one the transport needs and stays: `topic_type`, `to_sample`, `from_sample`,
`request_type`, `reply_type`, `wrap`, `unwrap`, `discovery_info_type`.
"""

import dataclasses
from functools import cache
from typing import Any

from cyclonedds.idl import IdlStruct, make_idl_struct
from cyclonedds.idl import types as t
from cyclonedds.idl.annotations import final

from ...msgs._message import Message, Service

_PRIM: dict[str, Any] = {
    "bool": bool,
    "byte": t.uint8,
    "char": t.uint8,
    "int8": t.int8,
    "uint8": t.uint8,
    "int16": t.int16,
    "uint16": t.uint16,
    "int32": t.int32,
    "uint32": t.uint32,
    "int64": t.int64,
    "uint64": t.uint64,
    "float32": t.float32,
    "float64": t.float64,
    "string": str,
    "wstring": str,
}


def dds_name(ros_type: str, suffix: str = "") -> str:
    """`geometry_msgs/msg/Twist` -> `geometry_msgs::msg::dds_::Twist_` (rosidl's DDS IDL names)."""
    pkg, kind, name = ros_type.split("/")
    return f"{pkg}::{kind}::dds_::{name}{suffix}_"


def _msg_class(ros_type: str) -> type[Message]:
    import importlib

    pkg, kind, name = ros_type.split("/")
    return getattr(importlib.import_module(f"llfsm.msgs.{pkg}.{kind}"), name)


def _field_type(ros: str) -> Any:
    base, bracket, rest = ros.partition("[")
    if "<=" in base:
        base = base.split("<=")[0]
    elem = _PRIM.get(base)
    if elem is None:
        elem = topic_type(_msg_class(base))
    if not bracket:
        return elem
    size = rest.rstrip("]")
    if size and not size.startswith("<="):
        return t.array[elem, int(size)]
    return t.sequence[elem]


@cache
def topic_type(cls: type[Message]) -> type[IdlStruct]:
    return _plain_struct(dds_name(cls._TYPE), cls)


def _plain_struct(typename: str, cls: type[Message], header: bool = False) -> type[IdlStruct]:
    fields = [(n, _field_type(ros)) for n, ros in cls._FIELDS]
    if header:
        fields = [("_guid", t.uint64), ("_seq", t.int64)] + (
            fields or [("structure_needs_at_least_one_member", t.uint8)]
        )
    kls = make_idl_struct(typename.replace("::", "_"), typename, dict(fields), dataclassify=False)
    return dataclasses.dataclass(final(kls))


def to_sample(msg: Message) -> Any:
    return _to(msg, topic_type(type(msg)))


def _to(msg: Message, kls: Any) -> Any:
    return kls(**{n: _value(getattr(msg, n), ros) for n, ros in msg._FIELDS} | _pad(msg, kls))


def _pad(msg: Message, kls: Any) -> dict[str, Any]:
    return {"structure_needs_at_least_one_member": 0} if not msg._FIELDS else {}


def _value(v: Any, ros: str) -> Any:
    if isinstance(v, Message):
        return _to(v, topic_type(type(v)))
    if isinstance(v, list | tuple) and v and isinstance(v[0], Message):
        return [_to(x, topic_type(type(x))) for x in v]
    if isinstance(v, bytes | bytearray):
        return list(v)
    return v


def from_sample(sample: Any, cls: type[Message]) -> Message:
    kwargs = {}
    for n, ros in cls._FIELDS:
        v = getattr(sample, n)
        kwargs[n] = _back(v, ros)
    return cls(**kwargs)


def _back(v: Any, ros: str) -> Any:
    base = ros.partition("[")[0].split("<=")[0]
    if base in _PRIM:
        if isinstance(v, list) and base in ("byte", "char", "uint8"):
            return bytes(v) if base != "uint8" else list(v)
        return v
    cls = _msg_class(base)
    if isinstance(v, list):
        return [from_sample(x, cls) for x in v]
    return from_sample(v, cls)


@cache
def request_type(srv: type[Service]) -> type[IdlStruct]:
    return _plain_struct(dds_name(srv._TYPE, "_Request"), srv.Request, header=True)


@cache
def reply_type(srv: type[Service]) -> type[IdlStruct]:
    return _plain_struct(dds_name(srv._TYPE, "_Response"), srv.Response, header=True)


def wrap(kls: Any, guid: int, seq: int, msg: Message) -> Any:
    return kls(_guid=guid, _seq=seq, **{n: _value(getattr(msg, n), r) for n, r in msg._FIELDS} | _pad(msg, kls))


def unwrap(sample: Any, cls: type[Message]) -> tuple[int, int, Message]:
    return sample._guid, sample._seq, from_sample(sample, cls)


# -- rmw_dds_common: ros_discovery_info (Gid of current ROS 2: 16 bytes; Humble used 24) --------


@dataclasses.dataclass
class Gid(IdlStruct, typename="rmw_dds_common::msg::dds_::Gid_"):
    data: t.array[t.uint8, 16]


@dataclasses.dataclass
class NodeEntitiesInfo(IdlStruct, typename="rmw_dds_common::msg::dds_::NodeEntitiesInfo_"):
    node_namespace: t.bounded_str[256]
    node_name: t.bounded_str[256]
    reader_gid_seq: t.sequence[Gid]
    writer_gid_seq: t.sequence[Gid]


@dataclasses.dataclass
class ParticipantEntitiesInfo(IdlStruct, typename="rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_"):
    gid: Gid
    node_entities_info_seq: t.sequence[NodeEntitiesInfo]


def gid(guid_bytes: bytes) -> Gid:
    return Gid(data=list(guid_bytes[:16].ljust(16, b"\0")))
