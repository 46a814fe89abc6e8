"""Types in bags: the message definitions and type hashes a bag embeds, CDR bytes, and classes
for the types a bag brings that llfsm has no class for.

Definitions follow rosbag2 (rosbag2_cpp's LocalMessageDefinitionSource): the type's own `.msg`
text, then each dependency once, depth first in name order, after a line of 80 `=` and
`MSG: pkg/Name`.  That is the `ros2msg` schema Foxglove and `ros2 bag play` read.  The text of
a type is its `.msg` file, as rosbag2 reads it from `share/`: the shipped definitions that
llfsm's own classes are generated from (llfsm/msgs/_interfaces/), or a user package's (a type a
bag brought is written as one); a type with no file at all is rebuilt from rosbags' type store
(fields and constants, without comments).  Type hashes are RIHS01 as rosidl computes them, by rosbags.

An action's topics carry types its `.action` file defines (`pkg/action/Name_Feedback`, the
feedback topic's `pkg/action/Name_FeedbackMessage`): their text is the file's section, or for
the derived messages their fields as rosidl derives them (docs/actions.md), and their hashes
are llfsm's own (the rosidl ones, computed when the classes were generated).  They are recorded
and played with llfsm's classes; a bag's action type that llfsm has no class for is refused,
not compiled from the bag.

Bytes are XCDR1 (plain CDR, little endian) as rclpy's `serialize_message` gives them, from
llfsm's own DDS type support (`llfsm.msgs._dds`); a class without a DDS form (none should be
left) goes through rosbags' serializer instead.

Everything here is loaded only by a run that records or plays a bag, never by a plain run.
"""

from __future__ import annotations

import importlib
import os
import re
import stat
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..msgs import Message, is_message_class, search_path
from .errors import BagError

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable

    from rosbags.typesys.store import Typestore

    from . import _tap


class ByteSpool(bytearray):
    """The recorder's buffer where the C one (llfsm.bag._tap.Spool) is not built: a bytearray
    that gives away what it holds, as the C one does."""

    def take(self) -> bytes:
        batch = bytes(self)  # one C call: atomic under the GIL, as the deletion is
        del self[: len(batch)]  # not more: the run's thread may have appended in between
        return batch


# The recorder's tap and buffer in C (setup.py builds them where a C compiler is; optional).
Spool: type[ByteSpool] | type[_tap.Spool]
_Tap: type[_tap.Tap] | None
try:
    from ._tap import Spool
    from ._tap import Tap as _Tap
except ImportError:  # pragma: no cover - installs without a compiler
    Spool, _Tap = ByteSpool, None

DELIMITER = "=" * 80 + "\n"
_MSG_FIELD_TYPE = re.compile(r"(?:^|\n)\s*([a-zA-Z0-9_/]+)(?:\[[^\]]*\])?\s+")
_PRIMITIVES = frozenset(
    (
        "bool",
        "byte",
        "char",
        "float32",
        "float64",
        "int8",
        "uint8",
        "int16",
        "uint16",
        "int32",
        "uint32",
        "int64",
        "uint64",
        "string",
        "wstring",
    )
)
_BUILTIN_DIR = Path(__file__).resolve().parent.parent / "msgs" / "_interfaces"


# rosidl's rules for names (as llfsm.idl.spec.PACKAGE_NAME and TYPE_NAME: the bag, beside the
# interface toolchain, does not import it).  A name a bag brings becomes a folder, a file and a
# module path: `..`, `/x`, `os.path` must never pass.
_PACKAGE_NAME = re.compile(r"(?!.*__)(?!.*_\Z)[a-z][a-z0-9_]*\Z")
_TYPE_NAME = re.compile(r"[A-Z][A-Za-z0-9]*\Z")


def _split(type_name: str) -> tuple[str, str]:
    """`pkg/msg/Name` or `pkg/Name` -> (pkg, Name), both checked against ROS's rules, so that
    either can be joined to a path or a module name: every name read from a bag passes here
    before it is used."""
    parts = type_name.split("/")
    if len(parts) == 3 and parts[1] == "msg":
        parts = [parts[0], parts[2]]
    if len(parts) == 2 and _PACKAGE_NAME.match(parts[0]) and _TYPE_NAME.match(parts[1]):
        return parts[0], parts[1]
    raise BagError(
        f"not a valid message type name: {_printable(type_name)} (pkg/msg/Name: the package in "
        "lower_snake_case, the name in CamelCase)"
    )


#: The messages an action's topics and services carry, by the suffix of their names, and the
#: text of the derived ones (`{a}`: the action's own type name).
_ACTION_SECTIONS = ("Goal", "Result", "Feedback")
_ACTION_DERIVED = {
    "FeedbackMessage": "unique_identifier_msgs/UUID goal_id\n{a}_Feedback feedback\n",
    "SendGoal_Request": "unique_identifier_msgs/UUID goal_id\n{a}_Goal goal\n",
    "SendGoal_Response": "bool accepted\nbuiltin_interfaces/Time stamp\n",
    "GetResult_Request": "unique_identifier_msgs/UUID goal_id\n",
    "GetResult_Response": "int8 status\n{a}_Result result\n",
}
_ACTION_PART = re.compile(r"([A-Z][A-Za-z0-9]*)_(Goal|Result|Feedback|FeedbackMessage|SendGoal_Request|"
                          r"SendGoal_Response|GetResult_Request|GetResult_Response)\Z")  # fmt: skip


def _action_part(type_name: str) -> tuple[str, str, str] | None:
    """(pkg, action, part) of `pkg/action/<Action>_<Part>`, both names checked; None for a name
    of any other form."""
    parts = type_name.split("/")
    if len(parts) != 3 or parts[1] != "action" or not _PACKAGE_NAME.match(parts[0]):
        return None
    m = _ACTION_PART.match(parts[2])
    return None if m is None else (parts[0], m[1], m[2])


def _action_text(type_name: str) -> str:
    """The text of an action's message: its section of the .action file (shipped, or in the
    interface search path), or the fields rosidl derives."""
    found = _action_part(type_name)
    assert found is not None
    pkg, action, part = found
    if part in _ACTION_DERIVED:
        return _ACTION_DERIVED[part].format(a=f"{pkg}/action/{action}")
    for root in [_BUILTIN_DIR, *search_path()]:
        path = root / pkg / "action" / f"{action}.action"
        if path.is_file():
            text = path.read_text(encoding="utf-8")
            break
    else:
        raise BagError(f"{type_name}: no action definition found for this type")
    sections: list[list[str]] = [[]]
    for line in text.splitlines(keepends=True):
        if line.split("#", 1)[0].strip() == "---":
            sections.append([])
        else:
            sections[-1].append(line)
    if len(sections) != len(_ACTION_SECTIONS):
        raise BagError(f"{path}: not an action definition (goal, result and feedback between two '---' lines)")
    return "".join(sections[_ACTION_SECTIONS.index(part)])


def _printable(text: str) -> str:
    """A name from a file, quoted, with anything that is not printable escaped: it is shown on
    one line of a terminal."""
    return ascii(text) if not text.isprintable() else repr(text)


class TypeSupport:
    """Definitions, hashes and (de)serialisers, one store per bag written or read."""

    def __init__(self) -> None:
        self._store: Typestore | None = None
        self._texts: dict[str, str] = {}  # pkg/msg/Name -> own .msg text
        self._full: dict[str, tuple[str, str]] = {}  # pkg/msg/Name -> (definition, RIHS01 hash)
        self._ser: dict[type, Callable[[Any], bytes]] = {}

    # -- the type store (rosbags) -------------------------------------------------------------
    @property
    def store(self) -> Typestore:
        if self._store is None:
            self._store = _base_store()
        return self._store

    def _register(self, type_name: str, seen: set[str] | None = None) -> None:
        """Make sure the store knows type_name and what it uses (from .msg texts where needed)."""
        seen = set() if seen is None else seen
        if type_name in seen:
            return
        seen.add(type_name)
        text = self.own_text(type_name)
        for dep in self._dependencies(text, type_name):
            self._register(dep, seen)
        if type_name not in self.store.fielddefs:
            # deferred: optional dependency (the bag extra) and start-up (rosbags' type store is slow to load)
            from rosbags.typesys import get_types_from_msg

            self.store.register(get_types_from_msg(text, type_name))

    # -- definitions ------------------------------------------------------------------------
    def own_text(self, type_name: str) -> str:
        """The type's own .msg text (without its dependencies)."""
        if _action_part(type_name) is not None:
            text = self._texts.get(type_name)
            if text is None:
                text = self._texts[type_name] = _action_text(type_name)
            return text
        pkg, name = _split(type_name)
        full_name = f"{pkg}/msg/{name}"
        text = self._texts.get(full_name)
        if text is not None:
            return text
        for root in [_BUILTIN_DIR, *search_path()]:
            path = root / pkg / "msg" / f"{name}.msg"
            if path.is_file():
                text = path.read_text(encoding="utf-8")
                break
        else:
            if full_name not in self.store.fielddefs:
                raise BagError(f"{full_name}: no message definition found for this type")
            generated, _ = self.store.generate_msgdef(full_name, ros_version=2)
            text = generated.split("\n" + DELIMITER, 1)[0]
            text = text if text.endswith("\n") else text + "\n"
        self._texts[full_name] = text
        return text

    @staticmethod
    def _dependencies(text: str, type_name: str) -> list[str]:
        """Message types a .msg text uses, sorted: rosbag2's own regular expression and order."""
        action = _action_part(type_name)
        pkg = action[0] if action is not None else _split(type_name)[0]
        deps = set()
        for m in _MSG_FIELD_TYPE.finditer(text):
            t = m.group(1)
            if t not in _PRIMITIVES:
                deps.add(t if "/" in t else f"{pkg}/{t}")
        return sorted(deps)

    def definition(self, type_name: str) -> tuple[str, str]:
        """(concatenated ros2msg definition, RIHS01 type hash) of a message type."""
        got = self._full.get(type_name)
        if got is not None:
            return got
        seen: set[str] = set()

        def append(t: str) -> str:
            out = self.own_text(t)
            for dep in self._dependencies(out, t):
                if dep not in seen:
                    seen.add(dep)
                    if _action_part(dep) is not None:
                        out += "\n" + DELIMITER + f"MSG: {dep}\n" + append(dep)
                        continue
                    pkg, name = _split(dep)
                    out += "\n" + DELIMITER + f"MSG: {dep}\n" + append(f"{pkg}/msg/{name}")
            return out

        text = append(type_name)
        if _action_part(type_name) is not None:  # llfsm's class has rosidl's hash; rosbags' store need not know it
            # deferred: start-up, as in _codec (the DDS forms, only for the classes a bag holds)
            from ..msgs._dds import type_hash

            got = self._full[type_name] = (text, type_hash(class_for(type_name)))
            return got
        self._register(type_name)
        got = self._full[type_name] = (text, self.store.hash_rihs01(type_name))
        return got

    # -- bytes --------------------------------------------------------------------------------
    def serializer(self, cls: type[Message]) -> Callable[[Any], bytes]:
        fn = self._ser.get(cls)
        if fn is None:
            fn = self._ser[cls] = _native_serializer(cls) or self._rosbags_serializer(cls)
        return fn

    @staticmethod
    def stamped(cls: type[Message]) -> Callable[[Any, int, Any], Callable[[Any], None]] | None:
        """What makes a recorder's tap for a fixed-size message, `(spool, key, clock) -> tap`:
        the C tap (llfsm.bag._tap) where it is built, else the generated
        `_stamped_<Name>(out, key, clock)` (one pack of the record head and the CDR together).
        Both append the same bytes; the C tap hands anything unusual to the Python one.  None
        for a message whose size varies, or a class without llfsm's DDS form."""
        c = _codec(cls)
        if c is None or c.stamped is None:
            return None
        python, layout = c.stamped, c.tap_layout
        if _Tap is None or layout is None:
            return lambda records, key, clock: python(records.extend, key, clock)
        tap = _Tap

        def make(records: Any, key: int, clock: Any) -> Callable[[Any], None]:
            return tap(records, key, clock, layout, python(records.extend, key, clock))

        return make

    def _rosbags_serializer(self, cls: type[Message]) -> Callable[[Any], bytes]:
        self._register(cls._TYPE)
        store, type_name = self.store, cls._TYPE

        def serialize(msg: Any) -> bytes:
            return bytes(store.serialize_cdr(_to_rosbags(msg, store), type_name))

        return serialize

    def deserializer(self, cls: type[Message]) -> Callable[[bytes], Any]:
        native = _native_deserializer(cls)
        if native is not None:
            return native
        self._register(cls._TYPE)
        store, type_name = self.store, cls._TYPE

        def deserialize(data: bytes) -> Any:
            return _from_rosbags(store.deserialize_cdr(data, type_name), cls)

        return deserialize


_BASE_STORE: Typestore | None = None


def _base_store() -> Typestore:
    """rosbags' store of the ROS 2 Humble types (the definitions of llfsm's standard packages are
    Humble's too), with the types of other .msg files added as they are needed: one per process
    (loading it takes a few tenths of a second)."""
    global _BASE_STORE
    if _BASE_STORE is None:
        # deferred: optional dependency and start-up, as in _register
        from rosbags.typesys import Stores, get_typestore

        _BASE_STORE = get_typestore(Stores.ROS2_HUMBLE)
    return _BASE_STORE


def _codec(cls: type[Message]) -> Any:
    """The generated DDS functions of the class (llfsm.msgs._dds.Codec), or None if it has none."""
    try:
        # deferred: start-up (the DDS forms of the messages, only for the classes a bag holds)
        from ..msgs._dds import codec
    except ImportError:  # pragma: no cover - the DDS type support is part of llfsm
        return None
    try:
        return codec(cls)
    except TypeError:
        return None


def _native_serializer(cls: type[Message]) -> Callable[[Any], bytes] | None:
    """llfsm's own XCDR1 encoder of the class (llfsm.msgs._dds), if it has one: the class's
    generated function itself (what `_dds.cdr` calls after looking the class up), since a
    recorder calls it once per message and knows the class already."""
    c = _codec(cls)
    return c.cdr if c is not None else None


def loaded_message_classes() -> list[type[Message]]:
    """Every message class imported so far (the machines of a run import theirs when they load)."""
    found: list[type[Message]] = []
    todo = list(Message.__subclasses__())
    while todo:
        cls = todo.pop()
        found.append(cls)
        todo += cls.__subclasses__()
    return found


def preload_native(classes: Iterable[type[Message]]) -> None:
    """Import the generated DDS forms of these message classes now.  The first import pulls in
    cyclonedds and builds its types (a quarter of a second): a recorder does it before the
    first round for every class loaded so far, not when a machine makes its publisher mid-run."""
    for cls in classes:
        if getattr(cls, "_TYPE", None):
            _native_serializer(cls)


def _native_deserializer(cls: type[Message]) -> Callable[[bytes], Any] | None:
    if _codec(cls) is None:
        return None
    # deferred: start-up, as in _codec
    from ..msgs._dds import from_cdr

    return lambda data: from_cdr(data, cls)


_NUMPY_TYPES = {
    "bool": "bool",
    "byte": "uint8",
    "char": "uint8",
    "int8": "int8",
    "uint8": "uint8",
    "int16": "int16",
    "uint16": "uint16",
    "int32": "int32",
    "uint32": "uint32",
    "int64": "int64",
    "uint64": "uint64",
    "float32": "float32",
    "float64": "float64",
}


def _to_rosbags(msg: Message, store: Typestore) -> Any:
    cls = store.types[msg._TYPE]
    kwargs = {}
    for field, ftype in msg._FIELDS:
        value = getattr(msg, field)
        if isinstance(value, Message):
            value = _to_rosbags(value, store)
        elif isinstance(value, list):
            element = ftype.partition("[")[0]
            if element in _NUMPY_TYPES:
                # deferred: optional dependency (numpy comes with rosbags, for its arrays only)
                import numpy

                value = numpy.array(value, dtype=_NUMPY_TYPES[element])
            elif value and isinstance(value[0], Message):
                value = [_to_rosbags(v, store) for v in value]
        kwargs[field] = value
    if not msg._FIELDS:
        fields = cls.__dataclass_fields__  # type: ignore[attr-defined]  # a dataclass: rosbags' MsgType does not say
        if "structure_needs_at_least_one_member" in fields:
            kwargs["structure_needs_at_least_one_member"] = 0
    return cls(**kwargs)


def _from_rosbags(obj: Any, cls: type[Message]) -> Message:
    kwargs = {}
    for field, ftype in cls._FIELDS:
        value = getattr(obj, field)
        element = ftype.partition("[")[0].partition("<=")[0]
        if "/" in element:
            sub = class_for(element)
            value = [_from_rosbags(v, sub) for v in value] if ftype.endswith("]") else _from_rosbags(value, sub)
        elif hasattr(value, "tolist"):
            value = value.tolist()
        kwargs[field] = value
    return cls(**kwargs)


# -- classes -----------------------------------------------------------------------------------


def class_for(type_name: str) -> type[Message]:
    """llfsm's class of a message type; raises BagError naming the type if there is none."""
    action = _action_part(type_name)
    if action is not None:  # a message of an action's (its feedback topic's)
        try:
            module = importlib.import_module(f"llfsm.msgs.{action[0]}.action")
        except ImportError as e:
            raise BagError(f"{type_name}: llfsm has no class for this type ({e})") from None
        cls = getattr(module, type_name.rsplit("/", 1)[1], None)
        if not is_message_class(cls):
            raise BagError(f"{type_name}: llfsm has no class for this type")
        return cls
    pkg, name = _split(type_name)
    try:
        module = importlib.import_module(f"llfsm.msgs.{pkg}.msg")
    except ImportError as e:
        raise BagError(f"{pkg}/msg/{name}: llfsm has no class for this type ({e})") from None
    cls = getattr(module, name, None)
    if not is_message_class(cls):
        raise BagError(f"{pkg}/msg/{name}: llfsm has no class for this type")
    return cls


def class_from_definition(type_name: str, encoding: str, definition: str, folder: Path) -> type[Message]:
    """The class of a type a bag brings: llfsm's own if it has one, else compiled from the
    definition the bag embeds, through the interface import hook (the compiler's one door):
    the definition is split into PKG/msg/Name.msg files under `folder`, which joins the
    interface search path.  Every name (the type's, and each `MSG: pkg/Name` in the text) is
    checked before it is used, and nothing is written outside `folder`."""
    if _action_part(type_name) is not None:  # llfsm's class, or a clear no: not compiled from the bag
        try:
            return class_for(type_name)
        except BagError as e:
            raise BagError(f"{e}; an action's types are not compiled from a bag: add its .action file") from None
    _split(type_name)  # a bad name is refused as such, before any lookup or message names it
    try:
        return class_for(type_name)
    except BagError:
        if not definition.strip():
            raise BagError(
                f"{type_name}: llfsm has no class for this type and the bag holds no definition of it"
            ) from None
        if encoding != "ros2msg":
            raise BagError(
                f"{type_name}: llfsm has no class for this type and cannot read its {encoding or 'unknown'} definition"
            ) from None
    # deferred: start-up (only a type llfsm has no class for is compiled from the bag)
    from ..msgs import add_search_path

    root_pkg, root_name = _split(type_name)
    sections = [(root_pkg, root_name, definition.split("\n" + DELIMITER)[0])]
    for part in definition.split(DELIMITER)[1:]:
        header, _, body = part.partition("\n")
        if header.startswith("MSG: "):
            body = body.rsplit("\n\n", 1)[0] + "\n" if body.endswith("\n\n") else body
            sections.append((*_split(header[5:].strip()), body))
    # every name is checked (above) before the first file is written
    for pkg, name, text in sections:
        _write_definition(folder, pkg, name, text)
    add_search_path(folder)
    importlib.invalidate_caches()
    try:
        return class_for(type_name)
    except BagError as e:
        raise BagError(f"{e}; the definition in the bag did not compile") from None
    except Exception as e:  # the interface compiler's own error names the file and line
        raise BagError(f"{type_name}: the definition in the bag does not compile: {e}") from None


def _write_definition(folder: Path, pkg: str, name: str, text: str) -> None:
    """Write `folder/pkg/msg/Name.msg`, where pkg and Name are checked names, without following
    a link: the folders are made here or must be real folders, the file is created new
    (O_EXCL | O_NOFOLLOW).  A file already written for the same type is kept, as the first of
    two definitions of one type in a bag wins."""
    d = folder
    for part in (pkg, "msg"):
        d = d / part
        try:
            os.mkdir(d, 0o700)
        except FileExistsError:
            if not stat.S_ISDIR(os.lstat(d).st_mode):  # a link, or a file, where a folder goes
                raise BagError(f"{d}: not a folder of llfsm's; the definitions of the bag are not written") from None
        except OSError as e:
            raise BagError(f"{d}: cannot write the definitions of the bag: {e.strerror}") from None
    target = d / f"{name}.msg"
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | os.O_CLOEXEC
    try:
        fd = os.open(target, flags, 0o600)
    except FileExistsError:
        if stat.S_ISREG(os.lstat(target).st_mode):
            return
        raise BagError(f"{target}: not a file of llfsm's; the definitions of the bag are not written") from None
    except OSError as e:
        raise BagError(f"{target}: cannot write the definitions of the bag: {e.strerror}") from None
    with os.fdopen(fd, "w", encoding="utf-8") as f:
        f.write(text)


def scratch_folder() -> Path:
    """A folder for definitions taken from bags, removed when the process ends."""
    # deferred: start-up (only a bag's own definitions need a scratch folder)
    import atexit
    import shutil

    folder = Path(tempfile.mkdtemp(prefix=f"llfsm-bag-types-{os.getpid()}-"))
    atexit.register(shutil.rmtree, folder, True)
    return folder
