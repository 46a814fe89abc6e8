"""The DDS side of the interface compiler: from the same parsed definitions as the message
classes, the `_dds` module of each package and kind (llfsm/msgs/<pkg>/msg/_dds.py, .../srv/_dds.py).

Each generated module holds, per message:
- a `cyclonedds.idl.IdlStruct` named as ROS 2 names it on the wire (`pkg::msg::dds_::Name_`,
  `pkg::srv::dds_::Name_Request_`), for creating topics and for code that wants cyclonedds
  samples (`_to_Name`, `_from_Name` convert);
- a CDR encoder and decoder written out field by field (`_cdr_Name(msg) -> bytes`,
  `_msg_Name(data) -> (msg, end)`, and `_enc_Name`/`_dec_Name` for a message at any offset):
  XCDR1 plain CDR, little endian, with the encapsulation header 00 01 00 00, byte for byte what
  rclpy's `serialize_message` gives.  Runs of fixed-size fields whose alignment is known at
  generation time become one precompiled `struct.Struct` (a Twist is one `pack` of six doubles,
  header included); alignment is worked out at run time only after a string or a sequence.
  Nested messages are inlined, so a PoseStamped is two `unpack` calls.  Two rules follow Fast
  CDR (checked against rclpy in tests/interop): an empty sequence of 8-byte values is its count
  alone (the elements' alignment comes only with elements), and a wstring is a count of UTF-16
  code units then 4 bytes per unit;
- its RIHS01 type hash (REP 2011), computed here from the type description, as rosidl does.

Why hand-written CDR beside the IdlStruct: the IdlStruct route converts a message to a sample
and lets cyclonedds' interpreted serializer walk it, some 40 times slower for a Twist (see
bench/dds_types.py); the IdlStruct is still needed to register the topic's type.

Long statements are laid out as ruff format lays them out (`layout`), so the committed modules
pass the project's lint like hand-written code.

Running never pays for this file: generated modules import only cyclonedds' idl package,
`struct` and the generated message modules.
"""

from __future__ import annotations

import hashlib
import json
import re
import struct
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from .package import (
    LINE_LIMIT,
    FieldSpec,
    FieldType,
    MessageSpec,
    PackageSpec,
    ServiceSpec,
    _str_literal,
)

DDS_TEMPLATE = "msgs_dds.py.j2"

# The stand-in member rosidl gives an empty message (IDL structs need one): a uint8 0 on the wire.
EMPTY_MEMBER = "structure_needs_at_least_one_member"

SIZES = {
    "bool": 1,
    "byte": 1,
    "char": 1,
    "int8": 1,
    "uint8": 1,
    "int16": 2,
    "uint16": 2,
    "int32": 4,
    "uint32": 4,
    "float32": 4,
    "int64": 8,
    "uint64": 8,
    "float64": 8,
}
FORMATS = {
    "bool": "?",
    "byte": "B",
    "char": "B",
    "int8": "b",
    "uint8": "B",
    "int16": "h",
    "uint16": "H",
    "int32": "i",
    "uint32": "I",
    "float32": "f",
    "int64": "q",
    "uint64": "Q",
    "float64": "d",
}
_BYTES = ("byte", "char", "uint8")  # sequences of these are copied as bytes

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

# type_description_interfaces/msg/FieldType ids (rosidl_generator_type_description).
_TYPE_IDS = {
    "int8": 2,
    "uint8": 3,
    "char": 3,  # .msg char is IDL uint8
    "int16": 4,
    "uint16": 5,
    "int32": 6,
    "uint32": 7,
    "int64": 8,
    "uint64": 9,
    "float32": 10,
    "float64": 11,
    "bool": 15,
    "byte": 16,
    "string": 17,
    "wstring": 18,
}
_ARRAY_OFFSET = {None: 0, "fixed": 48, "bounded": 96, "unbounded": 144}

Lookup = Callable[[str], MessageSpec]


def dds_name(type_name: str) -> str:
    """The DDS type name rmw gives a ROS type: geometry_msgs/msg/Twist is
    geometry_msgs::msg::dds_::Twist_."""
    pkg, kind, name = type_name.split("/")
    return f"{pkg}::{kind}::dds_::{name}_"


def _fields(spec: MessageSpec) -> list[FieldSpec]:
    """The members on the wire: an empty message has rosidl's stand-in uint8."""
    return spec.fields or [FieldSpec(EMPTY_MEMBER, FieldType("uint8"))]


# -- type hashes (RIHS01) ----------------------------------------------------------------------


def _field_description(f: FieldSpec) -> dict[str, Any]:
    t = f.type
    base = 1 if t.is_message else _TYPE_IDS[t.base]
    if t.string_bound is not None:
        base = 21 if t.base == "string" else 22
    return {
        "name": f.name,
        "type": {
            "type_id": base + _ARRAY_OFFSET[t.array],
            "capacity": t.size or 0,
            "string_capacity": t.string_bound or 0,
            "nested_type_name": t.base if t.is_message else "",
        },
    }


def _individual(spec: MessageSpec) -> dict[str, Any]:
    return {"type_name": spec.type_name, "fields": [_field_description(f) for f in _fields(spec)]}


def _nested(f: FieldSpec) -> str | None:
    return f.type.base if f.type.is_message else None


def type_hash(top: MessageSpec, lookup: Lookup) -> str:
    """RIHS01_<sha256> of the type description of `top` and every type it references, as
    rosidl_generator_type_description computes it: compact JSON with ", " and ": " separators,
    referenced types sorted by name, default values left out."""
    seen: dict[str, MessageSpec] = {}
    queue = [n for f in _fields(top) if (n := _nested(f))]
    while queue:
        name = queue.pop()
        if name in seen:
            continue
        spec = lookup(name)
        seen[name] = spec
        queue += [n for f in _fields(spec) if (n := _nested(f))]
    description = {
        "type_description": _individual(top),
        "referenced_type_descriptions": [_individual(seen[n]) for n in sorted(seen)],
    }
    text = json.dumps(description, ensure_ascii=True, allow_nan=False, separators=(", ", ": "))
    return "RIHS01_" + hashlib.sha256(text.encode("utf-8")).hexdigest()


def service_specs(service: ServiceSpec) -> tuple[MessageSpec, MessageSpec]:
    """The two messages a service's type description adds beside Request and Response (ROS 2
    Iron and later): the service itself (request_message, response_message, event_message) and
    its Event (info, request[<=1], response[<=1])."""
    name = service.type_name
    event = MessageSpec(
        f"{name}_Event",
        [
            FieldSpec("info", FieldType("service_msgs/msg/ServiceEventInfo")),
            FieldSpec("request", FieldType(f"{name}_Request", array="bounded", size=1)),
            FieldSpec("response", FieldType(f"{name}_Response", array="bounded", size=1)),
        ],
    )
    whole = MessageSpec(
        name,
        [
            FieldSpec("request_message", FieldType(f"{name}_Request")),
            FieldSpec("response_message", FieldType(f"{name}_Response")),
            FieldSpec("event_message", FieldType(f"{name}_Event")),
        ],
    )
    return whole, event


# -- CDR code ----------------------------------------------------------------------------------


class _Alignment:
    """What is known at generation time of the write (or read) position: offset % mod == rem,
    the offset counted from the end of the encapsulation header, as CDR aligns."""

    def __init__(self, mod: int, rem: int = 0) -> None:
        self.mod, self.rem = mod, rem

    def static_pad(self, a: int) -> int | None:
        """The padding before a value aligned to `a`, if known now."""
        return (-self.rem) % a if a <= self.mod else None

    def advance(self, n: int) -> None:
        self.rem = (self.rem + n) % self.mod

    def aligned(self, a: int) -> None:
        self.mod, self.rem = a, 0

    def unknown(self) -> None:
        self.mod, self.rem = 1, 0


class _Code:
    """Statements being generated, with the run of fixed-size values not yet flushed into one
    struct call, and what is known of the alignment."""

    def __init__(self, module: _Module, at: _Alignment) -> None:
        self.module = module
        self.at = at
        self.lines: list[str] = []
        self.fmt: list[str] = []

    def var(self, stem: str) -> str:
        return self.module.var(stem)

    def pad(self, a: int) -> str | None:
        """Align to `a`: a pad folded into the pending run, or (returned) the runtime
        expression of the pad length when the position is not known."""
        if a == 1:
            return None
        pad = self.at.static_pad(a)
        if pad is None:
            self.flush()
            self.at.aligned(a)
            return f"(4 - {self.position}) & {a - 1}"
        if pad:
            self.fmt.append(f"{pad}x")
            self.at.advance(pad)
        return None

    position = ""

    def flush(self) -> None:
        raise NotImplementedError


class _Writer(_Code):
    """Statements that append a message's CDR to the bytearray `b` (which starts with the
    4-byte encapsulation header: CDR offsets are len(b) - 4)."""

    position = "len(b)"

    def __init__(self, module: _Module, at: _Alignment) -> None:
        super().__init__(module, at)
        self.args: list[str] = []

    def flush(self) -> None:
        if self.fmt:
            name = self.module.struct("<" + "".join(self.fmt))
            self.lines.append(layout("b += ", Call(f"{name}.pack", self.args)))
            self.fmt, self.args = [], []

    def align(self, a: int) -> None:
        runtime = self.pad(a)
        if runtime is not None:
            self.lines.append(f"b += _Z[{runtime}]")

    def primitive(self, base: str, expr: str, count: int = 1) -> None:
        size = SIZES[base]
        self.align(size)
        self.fmt.append(FORMATS[base] if count == 1 else f"{count}{FORMATS[base]}")
        self.args.append(expr if count == 1 else f"*{expr}")
        self.at.advance(size * count)

    def message(self, spec: MessageSpec, expr: str) -> None:
        if not spec.fields:
            self.primitive("uint8", "0")
        for f in spec.fields:
            self.field(f.type, f"{expr}._{f.name}")

    def string(self, base: str, expr: str) -> None:
        """string: uint32 length counting the NUL, the UTF-8 bytes, the NUL.  wstring: uint32
        count of UTF-16 code units, then each unit as 4 bytes (a wchar_t), no NUL: what both
        Fast CDR and rmw_cyclonedds_cpp write for XCDR1."""
        s = self.var("s")
        if base == "string":
            self.lines.append(f"{s} = {expr}.encode()")
            self.primitive("uint32", f"len({s}) + 1")
            self.flush()
            self.lines += [f"b += {s}", "b.append(0)"]
            self.at.unknown()
        else:
            n = self.var("n")
            self.module.uses.update(("_pack", "_unpack_from", "_wstring"))
            self.lines.append(f"{n}, {s} = _wstring_units({expr})")
            self.primitive("uint32", n)
            self.flush()
            self.lines.append(f"b += {s}")
            self.at.aligned(4)

    def field(self, t: FieldType, expr: str) -> None:
        if t.array is None:
            if t.is_message:
                self.message(self.module.lookup(t.base), expr)
            elif t.base in ("string", "wstring"):
                self.string(t.base, expr)
            else:
                self.primitive(t.base, expr)
            return
        element = FieldType(t.base, t.string_bound)
        if t.array == "fixed" and t.base in SIZES:
            self.primitive(t.base, expr, t.size or 0)
            return
        v = self.var("v")
        self.lines.append(f"{v} = {expr}")
        if t.array != "fixed":
            self.primitive("uint32", f"len({v})")
        if t.base in SIZES:  # a sequence of primitives: one pack, after the element's alignment
            size = SIZES[t.base]
            if size == 8 and t.array != "fixed" and self.at.static_pad(8) != 0:
                # Fast CDR aligns the elements only when there are some: an empty sequence of
                # 8-byte values is its count alone.
                self.flush()
                self.lines.append(f"if {v}:")
                self.lines.append("    b += _Z[(4 - len(b)) & 7]")
                self.at.aligned(4)
            else:
                self.align(size)
            self.flush()
            if t.base in _BYTES:
                self.lines.append(f"b += bytes({v})")
            else:
                self.module.uses.add("_pack")
                self.lines.append(f'b += _pack(f"<{{len({v})}}{FORMATS[t.base]}", *{v})')
            self.at.aligned(min(size, 4))  # an empty sequence of 8-byte values leaves 4
            return
        self.flush()
        e = self.var("e")
        inner = _Writer(self.module, _Alignment(1))
        if element.is_message:
            inner.lines.append(f"{self.module.ref(element.base, '_enc')}({e}, b)")
        else:
            inner.field(element, e)
            inner.flush()
        self.lines.append(f"for {e} in {v}:")
        self.lines += [_indented(line) for line in inner.lines]
        self.at.unknown()


class _Reader(_Code):
    """Statements that read a message's CDR from `d` at offset `o` (o counts the 4-byte
    header); each value read is an expression, a message a call of its `_mk_` function."""

    position = "o"

    def __init__(self, module: _Module, at: _Alignment) -> None:
        super().__init__(module, at)
        self.tuple = ""
        self.count = 0  # values in the pending run

    def flush(self) -> None:
        if not self.fmt:
            return
        fmt = "<" + "".join(self.fmt)
        if self.count:
            self.lines.append(f"{self.tuple} = {self.module.struct(fmt)}.unpack_from(d, o)")
        self.lines.append(f"o += {struct.calcsize(fmt)}")
        self.fmt, self.tuple, self.count = [], "", 0

    def align(self, a: int) -> None:
        runtime = self.pad(a)
        if runtime is not None:
            self.lines.append(f"o += {runtime}")

    def primitive(self, base: str, count: int = 1) -> str:
        size = SIZES[base]
        self.align(size)
        if not self.tuple:
            self.tuple = self.var("t")
        i = self.count
        self.fmt.append(FORMATS[base] if count == 1 else f"{count}{FORMATS[base]}")
        self.count += count
        self.at.advance(size * count)
        return f"{self.tuple}[{i}]" if count == 1 else f"list({self.tuple}[{i}:{i + count}])"

    def value(self, stem: str, expr: str) -> str:
        """`expr` kept in a local now (it refers to a run that the next flush replaces)."""
        v = self.var(stem)
        self.lines.append(f"{v} = {expr}")
        return v

    def message(self, spec: MessageSpec) -> Call:
        if not spec.fields:  # the stand-in uint8, skipped
            self.fmt.append("x")
            self.at.advance(1)
            return Call(self.module.ref(spec.type_name, "_mk"), [])
        args = [self.field(f.type) for f in spec.fields]
        return Call(self.module.ref(spec.type_name, "_mk"), args)

    def string(self, base: str) -> str:
        n = self.primitive("uint32")
        self.flush()
        n = self.value("n", n) if not n.isidentifier() else n
        s = self.var("s")
        if base == "string":
            self.lines.append(f'{s} = str(d[o : o + {n} - 1], "utf-8") if {n} else ""')
            self.lines.append(f"o += {n}")
            self.at.unknown()
        else:
            self.module.uses.update(("_pack", "_unpack_from", "_wstring"))
            self.lines.append(f"{s} = _wstring_text(d, o, {n})")
            self.lines.append(f"o += 4 * {n}")
            self.at.aligned(4)
        return s

    def field(self, t: FieldType) -> str | Call:
        if t.array is None:
            if t.is_message:
                return self.message(self.module.lookup(t.base))
            if t.base in ("string", "wstring"):
                return self.string(t.base)
            value = self.primitive(t.base)
            return value
        element = FieldType(t.base, t.string_bound)
        if t.array == "fixed" and t.base in SIZES:
            return self.primitive(t.base, t.size or 0)
        if t.array == "fixed":
            self.flush()
            n = str(t.size)
        else:
            n = self.primitive("uint32")
            self.flush()
            n = self.value("n", n)
        v = self.var("v")
        if t.base in SIZES:
            size = SIZES[t.base]
            if size == 8 and t.array != "fixed" and self.at.static_pad(8) != 0:
                self.flush()  # elements aligned only if there are some, as Fast CDR does
                self.lines.append(f"if {n}:")
                self.lines.append("    o += (4 - o) & 7")
                self.at.aligned(4)
            else:
                self.align(size)
            self.flush()
            if t.base in _BYTES:
                self.lines.append(f"{v} = list(d[o : o + {n}])")
                self.lines.append(f"o += {n}")
            else:
                self.module.uses.add("_unpack_from")
                self.lines.append(f'{v} = list(_unpack_from(f"<{{{n}}}{FORMATS[t.base]}", d, o))')
                self.lines.append(f"o += {n} * {size}")
            self.at.aligned(min(size, 4))  # an empty sequence of 8-byte values leaves 4
            return v
        inner = _Reader(self.module, _Alignment(1))
        e = self.var("e")
        if element.is_message:
            inner.lines.append(f"{e}, o = {self.module.ref(element.base, '_dec')}(d, o)")
        else:
            inner.lines.append(layout(f"{e} = ", inner.field(element)))
        if t.array != "fixed":  # every element takes a byte at least: a bogus count fails now
            self.lines.append(f"if {n} > len(d) - o:")
            self.lines.append(f'    raise ValueError(f"{{{n}}} elements announced, {{len(d) - o}} bytes left")')
        self.lines.append(f"{v} = []")
        self.lines.append(f"for _ in range({n}):")
        self.lines += [_indented(line) for line in inner.lines]
        self.lines.append(f"    {v}.append({e})")
        self.at.unknown()
        return v


@dataclass
class Call:
    """A call expression kept as a tree, so that a long one is laid out as ruff lays it out."""

    fn: str
    args: list[Any]  # str | Call

    def __str__(self) -> str:
        return f"{self.fn}({', '.join(map(str, self.args))})"


def layout(prefix: str, expr: Any, suffix: str = "", indent: int = 4, *, atom: bool = False) -> str:
    """`prefix + expr + suffix` as a statement at `indent`, split as ruff format splits it: on
    one line if it fits; else the arguments on one line of their own if they fit (calls only:
    a bracketed collection, `atom`, is always exploded); else one argument a line, each laid
    out likewise, with a trailing comma."""
    one = f"{prefix}{expr}{suffix}"
    if indent + len(one) <= LINE_LIMIT or not isinstance(expr, Call) or not expr.args:
        return one
    body = ", ".join(map(str, expr.args))
    if not atom and indent + 4 + len(body) <= LINE_LIMIT:
        return f"{prefix}{expr.fn}(\n    {body}\n){suffix}"
    items = [layout("", a, ",", indent + 4) for a in expr.args]
    return f"{prefix}{expr.fn}(\n" + "".join(_indented(i) + "\n" for i in items) + f"){suffix}"


def _indented(text: str, by: str = "    ") -> str:
    return "\n".join(by + line for line in text.split("\n"))


class _Module:
    """One generated `_dds` module: its struct constants, imports and local names."""

    def __init__(self, package: str, kind: str, lookup: Lookup) -> None:
        self.package, self.kind, self.lookup = package, kind, lookup
        self.structs: dict[str, str] = {}
        self.records: dict[str, str] = {}  # the stamped records' structs, _R<n>
        self.imports: set[str] = set()
        self.uses: set[str] = set()  # helpers of the struct module the code calls
        self.n = 0

    def var(self, stem: str) -> str:
        self.n += 1
        return f"{stem}{self.n}"

    def struct(self, fmt: str) -> str:
        if fmt not in self.structs:
            self.structs[fmt] = f"_S{len(self.structs)}"
        return self.structs[fmt]

    def record_struct(self, fmt: str) -> str:
        if fmt not in self.records:
            self.records[fmt] = f"_R{len(self.records)}"
        return self.records[fmt]

    def ref(self, type_name: str, prefix: str) -> str:
        """How this module names `<prefix>_<Name>` of a message: local, or through the `_dds`
        module of another package."""
        pkg, kind, name = type_name.split("/")
        if pkg == self.package and kind == self.kind:
            return f"{prefix}_{name}"
        self.imports.add(pkg)
        return f"_{pkg}.{prefix}_{name}"

    def idl_ref(self, type_name: str) -> str:
        pkg, kind, name = type_name.split("/")
        if pkg == self.package and kind == self.kind:
            return f"{name}_"
        self.imports.add(pkg)
        return f"_{pkg}.{name}_"


@dataclass
class DdsMessageView:
    name: str
    type_name: str
    typename: str  # the DDS type name
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
    enc: list[str]  # body of _enc_<Name>(m, b)
    dec: list[str]  # body of _dec_<Name>(d, o) -> (message, o)
    to_dds: list[str]
    from_dds: list[str]
    type_hash: str


def _idl_annotation(t: FieldType, module: _Module) -> str:
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


def _conversion(t: FieldType, expr: str, module: _Module, direction: str) -> str:
    """A field's value converted to (`to`) or from (`from`) its cyclonedds sample form."""
    if t.is_message:
        fn = module.ref(t.base, f"_{direction}")
        return f"[{fn}(e) for e in {expr}]" if t.array else f"{fn}({expr})"
    if t.array:
        return f"list({expr})"
    return expr


def message_view(spec: MessageSpec, module: _Module, type_hash_value: str) -> DdsMessageView:
    name = spec.name
    fields = spec.fields
    idl_fields = [f"{f.name}: {_idl_annotation(f.type, module)}" for f in fields] or [f"{EMPTY_MEMBER}: _t.uint8 = 0"]

    mk_def = layout("def ", Call(f"_mk_{name}", [f"a{i}" for i in range(len(fields))]), ":", 0)
    mk = [f"m = _new(_c_{name})"] + [f"m._{f.name} = a{i}" for i, f in enumerate(fields)] + ["return m"]

    module.n = 0
    top = _Writer(module, _Alignment(8))
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
            _indented(layout("r = ", Call("pack", ["key", "clock.now", str(size), "_HDR", *top.args]), "", 8)),
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
    anywhere = _Writer(module, _Alignment(1))
    anywhere.message(spec, "m")
    anywhere.flush()

    module.n = 0
    reader = _Reader(module, _Alignment(8))
    result = reader.message(spec)
    reader.flush()
    msg = ["o = 4", *reader.lines, layout("m = ", result), "return m, o"]
    module.n = 0
    dec_reader = _Reader(module, _Alignment(1))
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
        typename=dds_name(spec.type_name),
        idl_fields=idl_fields,
        mk=mk,
        mk_def=mk_def,
        class_line=_class_line(f"{name}_", spec.type_name),
        wire_line=_class_line(f"{name}_wire_", spec.type_name),
        codec=_codec_line(name, bool(stamped), tap_layout is not None),
        cdr=cdr,
        stamped=stamped,
        tap_layout=tap_layout,
        msg=msg,
        enc=anywhere.lines or ["pass"],
        dec=dec,
        to_dds=to_dds,
        from_dds=from_dds,
        type_hash=type_hash_value,
    )


def _class_line(cls: str, type_name: str) -> str:
    return layout("class ", Call(cls, ["_IdlStruct", f"typename={_str_literal(dds_name(type_name))}"]), ":", 0)


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
            items.append(f'({_str_literal(piece)}, "")')
            continue
        m = _TAP_ARG.fullmatch(next(values))
        if m is None:
            return None
        items.append(f"({_str_literal(piece)}, {_str_literal(m.group(1) + m.group(2))})")
    if len(items) == 1:
        return f"_TAP_{name} = ({items[0]},)"
    return layout(f"_TAP_{name} = ", Call("", items), "", 0, atom=True)


def _codec_line(name: str, stamped: bool, tap: bool) -> str:
    items = [f"{name}_"] + [f"_{p}_{name}" for p in ("cdr", "msg", "to", "from", "enc", "dec")]
    items.append(f"_stamped_{name}" if stamped else "None")
    items.append(f"_TAP_{name}" if tap else "None")
    return layout(f"{_str_literal(name)}: ", Call("", items), ",", atom=True)


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


def render_dds_module(package: PackageSpec, kind: str, lookup: Lookup, header: list[str], env: Any) -> str:
    """The source of llfsm.msgs.<pkg>.<kind>._dds."""
    own: dict[str, MessageSpec] = {m.type_name: m for m in package.messages}
    hashes: list[tuple[str, str]] = []
    if kind == "msg":
        specs = list(package.messages)
    else:
        specs = [m for s in package.services for m in (s.request, s.response)]
        for s in package.services:
            whole, event = service_specs(s)
            own.update({m.type_name: m for m in (s.request, s.response, whole, event)})
    own.update({m.type_name: m for m in specs})

    def find(type_name: str) -> MessageSpec:
        return own[type_name] if type_name in own else lookup(type_name)

    module = _Module(package.name, kind, find)
    views = [message_view(m, module, type_hash(m, find)) for m in _ordered(specs)]
    if kind == "srv":
        hashes = [(s.name, type_hash(service_specs(s)[0], find)) for s in package.services]
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
            layout(f"{name} = ", Call("_Struct", [_str_literal(fmt)]), indent=0)
            for fmt, name in sorted(module.structs.items(), key=lambda kv: int(kv[1][2:]))
        ]
        + [
            layout(f"{name} = ", Call("_Struct", [_str_literal(fmt)]), indent=0)
            for fmt, name in sorted(module.records.items(), key=lambda kv: int(kv[1][2:]))
        ],
        messages=views,
        services=[(s.name, s.request.name, s.response.name) for s in package.services] if kind == "srv" else [],
        service_hashes=hashes,
    )
    compile(source, f"<llfsm.msgs.{package.name}.{kind}._dds>", "exec", dont_inherit=True)
    return source
