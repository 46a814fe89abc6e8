"""The DDS generator: from the same specs as the message classes, the `_dds` module beside each
generated msg/srv/action module (llfsm/msgs/<pkg>/msg/_dds.py, .../srv/_dds.py,
.../action/_dds.py), which llfsm.msgs._dds finds from a class (docs/transports.md, "How it is
built").

Each generated module holds, per message:
- a `cyclonedds.idl.IdlStruct` named as ROS 2 names it on the wire (`pkg::msg::dds_::Name_`,
  `pkg::srv::dds_::Name_Request_`), for creating topics and for code that wants cyclonedds
  samples (`_to_Name`, `_from_Name` convert); for a service's request and response (an
  action's SendGoal and GetResult too), the same with rmw_cyclonedds_cpp's request header
  (`Name_wire_`);
- a CDR encoder and decoder written out field by field (llfsm.idl.cdrgen): `_cdr_Name(msg) ->
  bytes` and `_msg_Name(data) -> (msg, end)`, the elements of arrays of messages inlined;
  `_mk_Name` builds a decoded message (nested ones of other packages too); for a service's
  request and response, `_dec_Name(data, offset)` reads one after rmw_cyclonedds_cpp's header;
- for a message of a fixed size, `_stamped_Name`, its record for a bag recorder, and `_TAP_Name`,
  the same record for the recorder's C tap (llfsm/bag/_tap.c);
- its RIHS01 type hash (llfsm.idl.typehash).

Why hand-written CDR beside the IdlStruct: the IdlStruct route converts a message to a sample
and lets cyclonedds' interpreted serializer walk it, some 40 times slower for a Twist (see
bench/dds_types.py); the IdlStruct is still needed to register the topic's type.

Running never pays for this file: generated modules import only cyclonedds' idl package,
`struct` and the generated message modules.
"""

from __future__ import annotations

import re
import struct
from dataclasses import dataclass
from typing import TYPE_CHECKING

from .cdrgen import Alignment, Lookup, Module, Reader, Writer
from .codeformat import Call, indented, layout, str_literal
from .spec import FieldType, MessageSpec, PackageSpec, ServiceSpec
from .typehash import EMPTY_MEMBER, action_spec, service_specs, type_hash

if TYPE_CHECKING:
    import jinja2

DDS_TEMPLATE = "msgs_dds.py.j2"

# cyclonedds.idl annotations; ROS maps .msg `char` to IDL uint8 and `byte` to octet.
IDL_TYPES = {
    "bool": "bool",
    "byte": "_t.byte",
    "char": "_t.uint8",
    "int8": "_t.int8",
    "uint8": "_t.uint8",
    "int16": "_t.int16",
    "uint16": "_t.uint16",
    "int32": "_t.int32",
    "uint32": "_t.uint32",
    "int64": "_t.int64",
    "uint64": "_t.uint64",
    "float32": "_t.float32",
    "float64": "_t.float64",
}


def dds_name(type_name: str) -> str:
    """The DDS type name rmw gives a ROS type: geometry_msgs/msg/Twist is
    geometry_msgs::msg::dds_::Twist_."""
    pkg, kind, name = type_name.split("/")
    return f"{pkg}::{kind}::dds_::{name}_"


@dataclass
class DdsMessageView:
    name: str
    type_name: str
    idl_fields: list[str]  # `name: annotation` lines of the IdlStruct
    mk: list[str]  # body of _mk_<Name>(a0, a1, ...)
    mk_def: str
    class_line: str  # `class Name_(_IdlStruct, typename=...):`
    wire_line: str  # same for the request/response with rmw_cyclonedds' header
    codec: str  # its entry in CODECS
    cdr: list[str]  # body of _cdr_<Name>(m) -> bytes
    stamped: list[str]  # body of _stamped_<Name>(out, key, clock), [] if the size varies
    tap_layout: str | None  # `_TAP_<Name> = ...`: the same record for the C tap (llfsm/bag/_tap.c)
    msg: list[str]  # body of _msg_<Name>(d) -> (message, end offset)
    dec: list[str] | None  # body of _dec_<Name>(d, o) -> (message, o), for a request or response
    to_dds: list[str]
    from_dds: list[str]
    type_hash: str


def _idl_annotation(t: FieldType, module: Module) -> str:
    if t.is_message:
        element = module.idl_ref(t.base)
    elif t.base in ("string", "wstring"):
        # cyclonedds' Python IDL has no wstring: the sample carries a str either way (the CDR
        # functions write wstring as ROS does; the IdlStruct is for type registration).
        element = f"_t.bounded_str[{t.string_bound}]" if t.string_bound is not None else "str"
    else:
        element = IDL_TYPES[t.base]
    if t.array == "fixed":
        return f"_t.array[{element}, {t.size}]"
    if t.array == "bounded":
        return f"_t.sequence[{element}, {t.size}]"
    if t.array == "unbounded":
        return f"_t.sequence[{element}]"
    return element


def _conversion(t: FieldType, expr: str, module: Module, direction: str) -> str:
    """A field's value converted to (`to`) or from (`from`) its cyclonedds sample form."""
    if t.is_message:
        fn = module.ref(t.base, f"_{direction}")
        return f"[{fn}(e) for e in {expr}]" if t.array else f"{fn}({expr})"
    if t.array:
        return f"list({expr})"
    return expr


def message_view(spec: MessageSpec, module: Module, type_hash_value: str, service_part: bool) -> DdsMessageView:
    """Every generated piece of one message's DDS form, laid out.  `service_part`: a service's
    request or response, which also gets its form after rmw_cyclonedds_cpp's header."""
    name = spec.name
    fields = spec.fields
    idl_fields = [f"{f.name}: {_idl_annotation(f.type, module)}" for f in fields] or [f"{EMPTY_MEMBER}: _t.uint8 = 0"]

    mk_def = layout("def ", Call(f"_mk_{name}", [f"a{i}" for i in range(len(fields))]), ":", 0)
    mk = [f"m = _new(_c_{name})"] + [f"m._{f.name} = a{i}" for i, f in enumerate(fields)] + ["return m"]

    module.n = 0
    top = Writer(module, Alignment(8))
    top.message(spec, "m")
    if not top.lines:  # fixed size: one pack, the encapsulation header included
        packer = module.struct("<4s" + "".join(top.fmt))
        cdr = [layout("return ", Call(f"{packer}.pack", ["_HDR", *top.args]))]
        # the same pack behind a (uint32 key, int64 time, uint32 size) head: 16 bytes, so the
        # CDR's alignment is unchanged; one call per message for a recorder
        size = struct.calcsize("<4s" + "".join(top.fmt))
        stamped_packer = module.record_struct("<IqI4s" + "".join(top.fmt))
        stamped = [
            f"pack = {stamped_packer}.pack",
            "",
            "def record(m):",
            indented(layout("r = ", Call("pack", ["key", "clock.now", str(size), "_HDR", *top.args]), "", 8)),
            "    out(r)",
            "",
            "return record",
        ]
        tap_layout = _tap_layout(name, top.fmt, top.args)
    else:
        top.flush()
        cdr = ["b = bytearray(_HDR)", *top.lines, "return bytes(b)"]
        stamped = []
        tap_layout = None

    module.n = 0
    reader = Reader(module, Alignment(8))
    result = reader.message(spec)
    reader.flush()
    msg = ["o = 4", *reader.lines, layout("m = ", result), "return m, o"]
    dec = None
    if service_part:  # a request or reply, read after rmw_cyclonedds_cpp's header
        module.n = 0
        dec_reader = Reader(module, Alignment(1))
        result = dec_reader.message(spec)
        dec_reader.flush()
        dec = [*dec_reader.lines, layout("m = ", result), "return m, o"]

    to_args = [f"{f.name}={_conversion(f.type, f'm._{f.name}', module, 'to')}" for f in fields]
    to_dds = [layout("return ", Call(f"{name}_", to_args))]
    from_dds = [f"m = _new(_c_{name})"]
    from_dds += [f"m._{f.name} = {_conversion(f.type, f's.{f.name}', module, 'from')}" for f in fields]
    from_dds.append("return m")
    return DdsMessageView(
        name=name,
        type_name=spec.type_name,
        idl_fields=idl_fields,
        mk=mk,
        mk_def=mk_def,
        class_line=_class_line(f"{name}_", spec.type_name),
        wire_line=_class_line(f"{name}_wire_", spec.type_name) if service_part else "",
        codec=_codec_line(name, dec is not None, bool(stamped), tap_layout is not None),
        cdr=cdr,
        stamped=stamped,
        tap_layout=tap_layout,
        msg=msg,
        dec=dec,
        to_dds=to_dds,
        from_dds=from_dds,
        type_hash=type_hash_value,
    )


def _class_line(cls: str, type_name: str) -> str:
    """`class Name_(_IdlStruct, typename="pkg::msg::dds_::Name_"):`, laid out."""
    return layout("class ", Call(cls, ["_IdlStruct", f"typename={str_literal(dds_name(type_name))}"]), ":", 0)


_TAP_ARG = re.compile(r"(\*?)m\.(_\w+(?:\._\w+)*)")


def _tap_layout(name: str, fmt: list[str], args: list[str]) -> str | None:
    """The fixed-size record as (format, path) items for the recorder's C tap: one per item
    of the pack, pads with an empty path, `*` where the value is a list of `count` values
    (`("36d", "*_covariance")`); None if some value is not a plain attribute path (the empty
    message's constant 0)."""
    items: list[str] = []
    values = iter(args)
    for piece in fmt:
        if piece.endswith("x"):
            items.append(f'({str_literal(piece)}, "")')
            continue
        m = _TAP_ARG.fullmatch(next(values))
        if m is None:
            return None
        items.append(f"({str_literal(piece)}, {str_literal(m.group(1) + m.group(2))})")
    if len(items) == 1:
        return f"_TAP_{name} = ({items[0]},)"
    return layout(f"_TAP_{name} = ", Call("", items), "", 0, atom=True)


def _codec_line(name: str, dec: bool, stamped: bool, tap: bool) -> str:
    """Its entry in CODECS, the fields of llfsm.msgs._dds.Codec in order."""
    items = [f"{name}_"] + [f"_{p}_{name}" for p in ("cdr", "msg", "to", "from")]
    items.append(f"_dec_{name}" if dec else "None")
    items.append(f"_stamped_{name}" if stamped else "None")
    items.append(f"_TAP_{name}" if tap else "None")
    return layout(f"{str_literal(name)}: ", Call("", items), ",", atom=True)


def _ordered(messages: list[MessageSpec]) -> list[MessageSpec]:
    """Messages of one module with the ones a field refers to first (IdlStruct annotations
    are evaluated when the class is made)."""
    by_name = {m.type_name: m for m in messages}
    out: list[MessageSpec] = []
    seen: set[str] = set()

    def visit(m: MessageSpec) -> None:
        if m.type_name in seen:
            return
        seen.add(m.type_name)
        for f in m.fields:
            dep = by_name.get(f.type.base)
            if dep is not None:
                visit(dep)
        out.append(m)

    for m in messages:
        visit(m)
    return out


def render_dds_module(
    package: PackageSpec, kind: str, lookup: Lookup, header: list[str], env: jinja2.Environment
) -> str:
    """The source of llfsm.msgs.<pkg>.<kind>._dds."""
    own: dict[str, MessageSpec] = {m.type_name: m for m in package.messages}
    services: list[ServiceSpec] = []
    actions: list[MessageSpec] = []  # the type descriptions of the actions, for their hashes
    if kind == "msg":
        specs = list(package.messages)
    elif kind == "srv":
        specs = [m for s in package.services for m in s.parts]
        services = list(package.services)
    else:
        specs = [m for a in package.actions for m in a.messages]
        services = [s for a in package.actions for s in a.services]
        actions = [action_spec(a) for a in package.actions]
    wholes = []  # the type descriptions of the services, then of the actions: their hashes
    for s in services:
        whole, event = service_specs(s)
        own.update({m.type_name: m for m in (*s.parts, whole, event)})
        wholes.append(whole)
    wholes += actions
    own.update({m.type_name: m for m in specs})

    def find(type_name: str) -> MessageSpec:
        return own[type_name] if type_name in own else lookup(type_name)

    module = Module(package.name, kind, find)
    in_services = {m.type_name for s in services for m in s.parts}
    views = [message_view(m, module, type_hash(m, find), m.type_name in in_services) for m in _ordered(specs)]
    hashes = [(m.name, type_hash(m, find)) for m in wholes]
    source = env.get_template(DDS_TEMPLATE).render(
        header=header,
        package=package.name,
        kind=kind,
        imports=sorted(
            [f"import llfsm.msgs.{pkg}.msg._dds as _{pkg}" for pkg in module.imports]
            + [f"import llfsm.msgs.{package.name}.{kind} as _classes"],
            key=lambda line: line.split()[1],
        ),
        uses=module.uses,
        structs=[
            layout(f"{name} = ", Call("_Struct", [str_literal(fmt)]), indent=0)
            for fmt, name in sorted(module.structs.items(), key=lambda kv: int(kv[1][2:]))
        ]
        + [
            layout(f"{name} = ", Call("_Struct", [str_literal(fmt)]), indent=0)
            for fmt, name in sorted(module.records.items(), key=lambda kv: int(kv[1][2:]))
        ],
        messages=views,
        service_hashes=hashes,
    )
    compile(source, f"<llfsm.msgs.{package.name}.{kind}._dds>", "exec", dont_inherit=True)
    return source
