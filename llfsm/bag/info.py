"""`llfsm bag info DIR`: what `ros2 bag info` prints, from the bag's metadata.yaml; and the one
reader of metadata.yaml, which every verb that opens a bag folder goes through.

Layout as rosbag2_py's format_bag_metadata.cpp: labels padded to 19 columns, times in local
time (`%b %e %Y %H:%M:%S.nnnnnnnnn (seconds.nanoseconds)`), sizes in KiB/MiB with one decimal,
topics sorted by name, service event topics counted apart.

A bag is a file from anywhere, so its metadata.yaml is read as untrusted: bounded in size, a
regular file (not a FIFO or a device), YAML without aliases and nested no deeper than rosbag2
ever writes (an alias bomb or a deep nesting costs nothing), then checked against a model of
what rosbag2 writes (`BagMetadata`: integers in the ranges rosbag2's C++ types hold, strings
that print on one line), and its storage files must be inside the bag folder.  Anything else is
a `MetadataError` naming metadata.yaml, the line and the field.
"""

from __future__ import annotations

import math
import stat
import time
from pathlib import Path, PurePath
from typing import Annotated, Any

import yaml
from pydantic import (
    AfterValidator,
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    StrictInt,
    StrictStr,
    ValidationError,
)
from pydantic_core import PydanticCustomError

from .. import yamlfile
from .errors import BagError

INDENT = 19  # the longest label ("Topics with Type:") and a space, as rosbag2 has it

# -- reading metadata.yaml -----------------------------------------------------------------------

#: rosbag2's metadata.yaml holds a few lines per topic: 16 MiB is tens of thousands of topics
MAX_METADATA_BYTES = 16 * 1024 * 1024
#: rosbag2 nests five deep (topics_with_message_count, a topic, its QoS profiles, a profile, a
#: duration); anything much deeper is not a bag's, and must not reach a recursive parser
#: (rosbags reads metadata.yaml again with ruamel.yaml, which recurses)
MAX_DEPTH = 16
INT64 = (-(2**63), 2**63 - 1)
UINT64_MAX = 2**64 - 1


class MetadataError(BagError):
    """A metadata.yaml that is not rosbag2's.  `detail` says where and why ("metadata.yaml:
    line 12: message_count: ..."), for a caller that names the bag itself."""

    def __init__(self, meta_path: Path, line: int | None, what: str) -> None:
        where = f": line {line}" if line is not None else ""
        super().__init__(f"{meta_path}{where}: {what}")
        self.detail = f"{meta_path.name}{where}: {what}"


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def _printable(text: str) -> str:
    return text if text.isprintable() else ascii(text)[1:-1]


def _check_text(value: str) -> str:
    if not value.isprintable():
        raise PydanticCustomError("not_printable", "control characters are not allowed here")
    return value


def _scalar_text(value: Any) -> Any:
    """custom_data is rosbag2's map<string, string>; yaml-cpp writes `3` or `true` unquoted,
    so a number or a bool there is the text it was written from."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return str(value)
    return value


def _check_qos(value: Any) -> Any:
    """offered_qos_profiles: a YAML text (rosbag2 up to version 8) or a list of profiles (9)."""
    if isinstance(value, str) or (isinstance(value, list) and all(isinstance(p, dict) for p in value)):
        return value
    raise PydanticCustomError("qos", "expected a list of QoS profiles or their YAML text")


# A string that prints on one line: what `bag info` shows, and what names a topic or a type.
Text = Annotated[StrictStr, Field(max_length=4096), AfterValidator(_check_text)]
Int64 = Annotated[StrictInt, Field(ge=INT64[0], le=INT64[1])]
NonNegativeInt64 = Annotated[StrictInt, Field(ge=0, le=INT64[1])]
Count = Annotated[StrictInt, Field(ge=0, le=UINT64_MAX)]


class _Model(BaseModel):
    # fields rosbag2 may add in later versions are kept, not refused (they are never read)
    model_config = ConfigDict(extra="allow", frozen=True)


class Duration(_Model):
    nanoseconds: NonNegativeInt64


class StartingTime(_Model):
    nanoseconds_since_epoch: Int64


class TopicMetadata(_Model):
    name: Text
    type: Text
    serialization_format: Text = ""
    offered_qos_profiles: Annotated[Any, AfterValidator(_check_qos)] = ""
    type_description_hash: Text = ""


class TopicWithMessageCount(_Model):
    topic_metadata: TopicMetadata
    message_count: Count


class FileInformation(_Model):
    path: Text
    starting_time: StartingTime | None = None
    duration: Duration | None = None
    message_count: Count | None = None


class BagMetadata(_Model):
    """rosbag2_bagfile_information, as rosbag2 (versions 1 to 9) and rosbags write it."""

    version: Annotated[StrictInt, Field(ge=1, le=1000)]
    storage_identifier: Text
    relative_file_paths: list[Text]
    duration: Duration
    starting_time: StartingTime
    message_count: Count
    topics_with_message_count: list[TopicWithMessageCount]
    compression_format: Text | None = ""
    compression_mode: Text | None = ""
    files: list[FileInformation] | None = None
    custom_data: dict[StrictStr, Annotated[StrictStr, BeforeValidator(_scalar_text)]] | None = None
    ros_distro: Text | None = None


class MetadataFile(_Model):
    rosbag2_bagfile_information: BagMetadata


#: metadata.yaml's words for what llfsm.yamlfile refuses; those with a line say it.
_WORDS = {
    "unreadable": "cannot read it: {detail}",
    "folder": "not a regular file",
    "not_file": "not a regular file",
    "large": "larger than {mib} MiB: not rosbag2 metadata",
    "encoding": "not rosbag2 metadata (not UTF-8 text)",
    "alias": "not rosbag2 metadata (a YAML anchor or alias; rosbag2 writes none)",
    "depth": "not rosbag2 metadata (nested deeper than {limit})",
    "syntax": "not rosbag2 metadata (YAML: {detail})",
}
_AT_A_LINE = frozenset({"encoding", "alias", "depth", "syntax"})


def _load(meta_path: Path) -> tuple[Any, yaml.Node]:
    """The document and its YAML node tree (which knows the line of each value), read as
    untrusted (llfsm.yamlfile): a regular file (a FIFO does not hang the reader) of at most
    MAX_METADATA_BYTES, UTF-8, no YAML anchor or alias (rosbag2 writes none, and an alias bomb
    or a self-reference is made of them), no nesting deeper than MAX_DEPTH; any YAML error is
    one line here."""
    try:
        node = yamlfile.load(meta_path, MAX_METADATA_BYTES, MAX_DEPTH)
    except yamlfile.Refused as e:
        line = e.line if e.kind in _AT_A_LINE else None
        raise MetadataError(meta_path, line, _one_line(e.say("", words=_WORDS))) from None
    if node is None:
        raise MetadataError(meta_path, None, "not rosbag2 metadata (the file is empty)")
    try:
        return yamlfile.LOADER("").construct_document(node), node
    except yaml.MarkedYAMLError as e:  # an unknown tag, an unhashable key
        mark = e.problem_mark or e.context_mark
        what = _one_line(e.problem or e.context or type(e).__name__)
        raise MetadataError(
            meta_path, mark.line + 1 if mark else None, f"not rosbag2 metadata (YAML: {what})"
        ) from None
    except (yaml.YAMLError, RecursionError, ValueError, TypeError, OverflowError) as e:
        # a timestamp out of range
        what = _one_line(str(e)) or type(e).__name__
        raise MetadataError(meta_path, None, f"not rosbag2 metadata (YAML: {what})") from None


def _node_at(node: yaml.Node, loc: tuple[Any, ...]) -> yaml.Node:
    """The deepest node along a pydantic error location (the field's node, or the mapping a
    missing field should be in)."""
    for key in loc:
        if isinstance(node, yaml.MappingNode):
            found = next((v for k, v in node.value if isinstance(k, yaml.ScalarNode) and k.value == str(key)), None)
        elif isinstance(node, yaml.SequenceNode) and isinstance(key, int) and 0 <= key < len(node.value):
            found = node.value[key]
        else:
            found = None
        if found is None:
            break
        node = found
    return node


def _field(loc: tuple[Any, ...]) -> str:
    out = ""
    for key in loc:
        out += f"[{key}]" if isinstance(key, int) else f"{'.' if out else ''}{_printable(str(key))}"
    return out or "rosbag2_bagfile_information"


def _kind(value: Any) -> str:
    """What a YAML value is, in words (never the value itself: it may be huge or hostile)."""
    if isinstance(value, float):
        return "a number with a fraction" if math.isfinite(value) else "infinity or NaN"
    names = {type(None): "null", bool: "true/false", int: "an integer", str: "text", list: "a list", dict: "a mapping"}
    return names.get(type(value), type(value).__name__)


def _storage_file(folder: Path, name: str) -> tuple[Path | None, str]:
    """Where a storage file named in metadata.yaml is: the bag folder and the file's name, as
    rosbags opens it (rosbag2 before version 4 wrote the bag's own folder in front).  (None,
    why) for a path with `..`, an absolute one, a link that leads out of the folder, or
    something that is not a regular file (a FIFO would hang the reader)."""
    pure = PurePath(name)
    if pure.is_absolute() or ".." in pure.parts or pure.name in ("", "."):
        return None, "is outside the bag; it is not read"
    path = folder / pure.name
    if path.is_symlink() or path.exists():
        try:
            target = path.resolve(strict=True)
            inside = target.is_relative_to(folder.resolve(strict=True))
        except (OSError, RuntimeError):  # a dangling link, a loop
            return None, "is a broken link"
        if not inside:
            return None, "is outside the bag; it is not read"
        if not target.is_file():
            return None, "is not a regular file"
    return path, ""


def read_metadata(path: str | Path) -> BagMetadata:
    """The rosbag2_bagfile_information of a bag folder, checked (see the module's docstring);
    a MetadataError (a BagError) names metadata.yaml, the line and the field otherwise."""
    folder = Path(path)
    if not folder.exists():
        raise BagError(f"{path}: no such bag")
    meta_path = folder / "metadata.yaml"
    if not meta_path.exists():
        raise BagError(f"{path}: not a bag (no metadata.yaml in it)")
    doc, node = _load(meta_path)
    if not isinstance(doc, dict) or not isinstance(doc.get("rosbag2_bagfile_information"), dict):
        raise MetadataError(
            meta_path, node.start_mark.line + 1, "not rosbag2 metadata (no rosbag2_bagfile_information mapping)"
        )
    try:
        meta = MetadataFile.model_validate(doc).rosbag2_bagfile_information
    except ValidationError as e:
        first = e.errors(include_url=False)[0]
        loc = tuple(first["loc"])
        line = _node_at(node, loc).start_mark.line + 1
        got = f" (got {_kind(first['input'])})" if first["type"].endswith("_type") else ""
        more = e.error_count() - 1
        tail = f" (and {more} more problem{'s' if more > 1 else ''})" if more else ""
        what = f"{_field(loc[1:])}: {_one_line(first['msg'])}{got}{tail}"
        raise MetadataError(meta_path, line, what) from None
    info = _node_at(node, ("rosbag2_bagfile_information",))
    named = [("relative_file_paths", i, p) for i, p in enumerate(meta.relative_file_paths)]
    named += [("files", i, f.path) for i, f in enumerate(meta.files or [])]
    for key, i, name in named:
        where, why = _storage_file(folder, name)
        if where is None:
            loc = (key, i) if key == "relative_file_paths" else (key, i, "path")
            line = _node_at(info, loc).start_mark.line + 1
            raise MetadataError(meta_path, line, f"{_field(loc)}: {name!r} {why}")
    return meta


def storage_files(folder: Path, meta: BagMetadata) -> list[Path]:
    """The storage files of a checked bag, inside its folder (see `_storage_file`)."""
    return [p for p in (_storage_file(folder, name)[0] for name in meta.relative_file_paths) if p is not None]


# -- ros2 bag info -----------------------------------------------------------------------------------


def _seconds(ns: int) -> str:
    s, frac = divmod(ns, 1_000_000_000)
    return f"{s}.{frac:09d}"


def _time_point(ns: int) -> str:
    s, frac = divmod(ns, 1_000_000_000)
    try:
        t = time.localtime(s)
        date = f"{time.strftime('%b %e %Y', t)} {time.strftime('%H:%M:%S', t)}.{frac:09d} "
    except (OverflowError, OSError, ValueError):  # beyond this platform's calendar: the seconds
        date = ""
    return f"{date}({_seconds(ns)})"


def _size(n: int) -> str:
    units = ("B", "KiB", "MiB", "GiB", "TiB")
    size, i = float(n), 0
    while size >= 1024 and i < 4:
        size /= 1024
        i += 1
    return f"{size:.0f} {units[i]}" if i == 0 else f"{size:.1f} {units[i]}"


def _is_service_event(name: str, type_name: str) -> bool:
    return name.endswith("/_service_event") and type_name.endswith("_Event")


def _file_size(path: Path) -> int:
    try:
        st = path.stat()
    except OSError:
        return 0
    return st.st_size if stat.S_ISREG(st.st_mode) else 0


def format_info(path: str | Path) -> str:
    """`ros2 bag info` for the bag at path (its output, trailing newline included)."""
    meta = read_metadata(path)
    folder = Path(path)
    files = list(meta.relative_file_paths)
    size = sum(_file_size(p) for p in storage_files(folder, meta))
    start = meta.starting_time.nanoseconds_since_epoch
    duration = meta.duration.nanoseconds
    topics: list[tuple[str, str, int, str]] = []
    services: list[tuple[str, str, int, str]] = []
    for entry in meta.topics_with_message_count:
        tm = entry.topic_metadata
        item = (tm.name, tm.type, entry.message_count, tm.serialization_format)
        (services if _is_service_event(item[0], item[1]) else topics).append(item)
    pad = " " * INDENT
    out = ["", "Files:             " + (f"\n{pad}".join(files))]
    out.append(f"Bag size:          {_size(size)}")
    out.append(f"Storage id:        {meta.storage_identifier}")
    out.append(f"ROS Distro:        {meta.ros_distro or 'unknown'}")
    out.append(f"Duration:          {_seconds(duration)}s")
    out.append(f"Start:             {_time_point(start)}")
    out.append(f"End:               {_time_point(start + duration)}")
    out.append(f"Messages:          {meta.message_count - sum(s[2] for s in services)}")
    lines = [f"Topic: {n} | Type: {t} | Count: {c} | Serialization Format: {f}" for n, t, c, f in sorted(topics)]
    out.append("Topic information: " + f"\n{pad}".join(lines))
    out.append(f"Service:           {len(services)}")
    svc = [
        f"Service: {n[: -len('/_service_event')]} | Type: {t[: -len('_Event')]} | Event Count: {c} | "
        f"Serialization Format: {f}"
        for n, t, c, f in sorted(services)
    ]
    out.append("Service information: " + f"\n{pad}  ".join(svc))
    return "\n".join(out) + "\n"
