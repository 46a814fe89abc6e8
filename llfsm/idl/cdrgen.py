"""CDR encoders and decoders written out field by field: the statements of the `_cdr_`, `_msg_`,
`_enc_`, `_dec_` and `_stamped_` functions of a generated `_dds` module (llfsm.idl.ddsgen).

XCDR1 plain CDR, little endian, byte for byte what rclpy's `serialize_message` gives
(docs/transports.md, "How it is built").  Runs of fixed-size fields whose alignment is known
at generation time become one precompiled `struct.Struct` (a Twist is one `pack` of six
doubles, header included); alignment is worked out at run time only after a string or a
sequence.  Nested messages are inlined, so a PoseStamped is two `unpack` calls.  Two rules
follow Fast CDR (checked against rclpy in tests/interop): an empty sequence of 8-byte values
is its count alone (the elements' alignment comes only with elements), and a wstring is a
count of UTF-16 code units then 4 bytes per unit.
"""

from __future__ import annotations

import struct
from collections.abc import Callable

from .codeformat import Call, indented, layout
from .spec import FieldType, MessageSpec

Lookup = Callable[[str], MessageSpec]

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


class Module:
    """One generated `_dds` module: its struct constants, imports and local names."""

    def __init__(self, package: str, kind: str, lookup: Lookup) -> None:
        self.package, self.kind, self.lookup = package, kind, lookup
        self.structs: dict[str, str] = {}
        self.records: dict[str, str] = {}  # the stamped records' structs, _R<n>
        self.imports: set[str] = set()
        self.uses: set[str] = set()  # module-level helpers the code calls: _pack, _unpack_from, _wstring, _Z
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
        """How this module names the IdlStruct of a message."""
        pkg, kind, name = type_name.split("/")
        if pkg == self.package and kind == self.kind:
            return f"{name}_"
        self.imports.add(pkg)
        return f"_{pkg}.{name}_"


class Alignment:
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

    def __init__(self, module: Module, at: Alignment) -> None:
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


class Writer(_Code):
    """Statements that append a message's CDR to the bytearray `b` (which starts with the
    4-byte encapsulation header: CDR offsets are len(b) - 4)."""

    position = "len(b)"

    def __init__(self, module: Module, at: Alignment) -> None:
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
            self.module.uses.add("_Z")
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
                self.module.uses.add("_Z")
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
        inner = Writer(self.module, Alignment(1))  # each element starts where the last ended
        inner.field(element, e)
        inner.flush()
        self.lines.append(f"for {e} in {v}:")
        self.lines += [indented(line) for line in inner.lines]
        self.at.unknown()


class Reader(_Code):
    """Statements that read a message's CDR from `d` at offset `o` (o counts the 4-byte
    header); each value read is an expression, a message a call of its `_mk_` function."""

    position = "o"

    def __init__(self, module: Module, at: Alignment) -> None:
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
        inner = Reader(self.module, Alignment(1))
        e = self.var("e")
        item = inner.field(element)  # each element starts where the last ended
        inner.flush()
        inner.lines.append(layout(f"{e} = ", item))
        if t.array != "fixed":  # every element takes a byte at least: a bogus count fails now
            self.lines.append(f"if {n} > len(d) - o:")
            self.lines.append(f'    raise ValueError(f"{{{n}}} elements announced, {{len(d) - o}} bytes left")')
        self.lines.append(f"{v} = []")
        self.lines.append(f"for _ in range({n}):")
        self.lines += [indented(line) for line in inner.lines]
        self.lines.append(f"    {v}.append({e})")
        self.at.unknown()
        return v
