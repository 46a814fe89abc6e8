"""Writing rosbag2 bags: `DIR/metadata.yaml` plus one storage file, MCAP (default) or sqlite3.

What is on disk is what rosbag2 (Jazzy, metadata version 9) writes, so `ros2 bag info/play`,
Foxglove, PlotJuggler, rosbags and the mcap tools read it:
- MCAP, written with the `mcap` library as rosbag2_storage_mcap does: profile `ros2`, one schema
  per type (`ros2msg`, the concatenated definitions), one channel per topic (`cdr`, with
  `offered_qos_profiles` and `topic_type_hash` metadata), uncompressed chunks, a summary, and
  a `rosbag2` metadata record holding the bag's metadata.
- sqlite3, written with rosbags' storage writer (rosbag2's schema version 4); one transaction
  per batch, so that what was committed survives whatever comes later.
- `metadata.yaml` in yaml-cpp's layout, field for field as rosbag2's `yaml.hpp` encodes it.

Durability.  The MCAP library writes into memory; each batch is then appended to the file in
one go, so the file always ends on a whole record.  A placeholder `metadata.yaml` is written
when the bag opens and keeps some disk space in reserve.  If the disk fills up (or the file
cannot be written any more) the file is cut back to its last whole record, the reserve is
given back, and the bag is closed with what made it to disk: a data-end record and a footer
without a summary (readers then scan the file, as the MCAP specification allows) and a final
`metadata.yaml` counting what the file holds.  Nothing already written is lost.
"""

from __future__ import annotations

import errno
import json
import os
import sqlite3
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

from .. import __version__
from .errors import BagError

VERSION = 9  # rosbag2's metadata version since Jazzy
ROS_DISTRO = "jazzy"  # the rosbag2 whose files these are (ROS_DISTRO overrides, as rosbag2 reads it)
CHUNK_SIZE = 64 * 1024  # rosbag2: 768 KiB; smaller chunks reach the disk sooner (less lost to a kill or a full disk)
COMMIT_EVERY = 1000  # sqlite3: messages per transaction at most (a transaction is kept or lost whole)
RESERVE = 32 * 1024  # bytes the placeholder metadata.yaml keeps free for closing a full disk's bag
INFINITE = {"sec": 9223372036, "nsec": 854775807}  # RMW_DURATION_INFINITE, as rosbag2 writes it


def qos_profile(depth: int = 0, durability: str = "volatile", reliability: str = "reliable") -> dict[str, Any]:
    """A QoS profile as rosbag2 version 9 writes it (offered QoS as DDS discovery reports it:
    history unknown, depth 0)."""
    return {
        "history": "unknown",
        "depth": depth,
        "reliability": reliability,
        "durability": durability,
        "deadline": dict(INFINITE),
        "lifespan": dict(INFINITE),
        "liveliness": "automatic",
        "liveliness_lease_duration": dict(INFINITE),
        "avoid_ros_namespace_conventions": False,
    }


# -- yaml-cpp's layout ---------------------------------------------------------------------------

_PLAIN_OK = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_/.-+=()")
_SPECIAL = {"", "~", "null", "Null", "NULL", "true", "True", "TRUE", "false", "False", "FALSE", "y", "n", "yes", "no"}


def _scalar(value: Any) -> str:
    if value is None:
        return "~"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    text = str(value)
    if text in _SPECIAL or not set(text) <= _PLAIN_OK or text[0] in "-+.=" or _numeric(text):
        return json.dumps(text)
    return text


def _numeric(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _empty(value: Any) -> bool:
    return isinstance(value, dict | list) and not value


def dump_yaml(value: Any, indent: int = 0) -> str:
    """Block YAML as yaml-cpp's emitter writes it: two-space indents, sequences indented under
    their key, `~` for an empty map, `[]` for an empty sequence, `""` for an empty string."""
    return "".join(_emit(value, indent))


def _emit(value: Any, indent: int) -> list[str]:
    pad = " " * indent
    out: list[str] = []
    if isinstance(value, dict):
        for key, v in value.items():
            if isinstance(v, dict | list) and v:
                out.append(f"{pad}{key}:\n")
                out += _emit(v, indent + 2)
            else:
                out.append(f"{pad}{key}: {'~' if isinstance(v, dict) else '[]' if _empty(v) else _scalar(v)}\n")
    elif isinstance(value, list):
        for item in value:
            lines = _emit(item, indent + 2) if isinstance(item, dict | list) and item else [f"{pad}  {_scalar(item)}\n"]
            first = lines[0]
            out.append(f"{pad}- {first[indent + 2 :]}")
            out += lines[1:]
    else:
        out.append(f"{pad}{_scalar(value)}\n")
    return out


# -- the bag's metadata ----------------------------------------------------------------------------


@dataclass
class Connection:
    """A topic in the bag."""

    id: int
    topic: str
    type: str
    definition: str
    type_hash: str
    qos: list[dict[str, Any]]
    count: int = 0
    storage_id: Any = None  # the storage's own handle (MCAP channel id, rosbags Connection)


@dataclass
class Stats:
    count: int = 0
    start: int | None = None
    end: int = 0
    connections: list[Connection] = field(default_factory=list)

    def add(self, t: int) -> None:
        self.count += 1
        self.start = t if self.start is None or t < self.start else self.start
        self.end = max(self.end, t)


def metadata(storage_id: str, file_name: str, stats: Stats, custom: dict[str, str] | None = None) -> dict[str, Any]:
    """rosbag2's BagMetadata, in its field order (rosbag2_storage/yaml.hpp)."""
    start = stats.start or 0
    duration = stats.end - start if stats.count else 0
    return {
        "version": VERSION,
        "storage_identifier": storage_id,
        "duration": {"nanoseconds": duration},
        "starting_time": {"nanoseconds_since_epoch": start},
        "message_count": stats.count,
        "topics_with_message_count": [
            {
                "topic_metadata": {
                    "name": c.topic,
                    "type": c.type,
                    "serialization_format": "cdr",
                    "offered_qos_profiles": c.qos,
                    "type_description_hash": c.type_hash,
                },
                "message_count": c.count,
            }
            for c in stats.connections
        ],
        "compression_format": "",
        "compression_mode": "",
        "relative_file_paths": [file_name],
        "files": [
            {
                "path": file_name,
                "starting_time": {"nanoseconds_since_epoch": start},
                "duration": {"nanoseconds": duration},
                "message_count": stats.count,
            }
        ],
        "custom_data": dict(custom or {}),
        "ros_distro": os.environ.get("ROS_DISTRO") or ROS_DISTRO,
    }


def metadata_yaml(meta: dict[str, Any]) -> str:
    return dump_yaml({"rosbag2_bagfile_information": meta})


# -- storages ----------------------------------------------------------------------------------------


class _Storage(Protocol):
    """A bag's storage file as BagWriter drives it, so that MCAP and sqlite3 are interchangeable."""

    identifier: str
    suffix: str

    def __init__(self, path: Path) -> None: ...
    def add(self, c: Connection) -> None: ...
    def write(self, c: Connection, t: int, data: bytes) -> None: ...
    def chunk(self) -> None: ...
    def sync(self) -> None: ...
    def close(self, meta: dict[str, Any]) -> None: ...
    def salvage(self) -> None: ...
    def abandon(self) -> None: ...


class _Spool:
    """The MCAP library's output stream: bytes wait here until the batch is appended to the file."""

    def __init__(self) -> None:
        self.parts: list[bytes] = []
        self.pos = 0

    def write(self, data: bytes | bytearray | memoryview) -> int:
        self.parts.append(bytes(data))
        self.pos += len(data)
        return len(data)

    def tell(self) -> int:
        return self.pos

    def flush(self) -> None:
        pass

    def take(self) -> bytes:
        data = b"".join(self.parts)
        self.parts = []
        return data


class _McapStorage:
    identifier = "mcap"
    suffix = ".mcap"

    def __init__(self, path: Path) -> None:
        # deferred: optional dependency (mcap, the bag extra) and start-up (only the writer process writes)
        from mcap.writer import CompressionType, Writer

        self.path = path
        self.fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        self.good = 0  # the file ends on a whole record here
        self.spool = _Spool()
        self.writer = Writer(
            self.spool,  # type: ignore[arg-type]  # mcap calls write, tell and flush only; its hint asks for IO
            chunk_size=CHUNK_SIZE,
            compression=CompressionType.NONE,
            enable_crcs=False,
        )
        self.writer.start(profile="ros2", library=f"llfsm-{__version__}")
        self.schemas: dict[str, int] = {}
        self.sync()

    def add(self, c: Connection) -> None:
        schema = self.schemas.get(c.type)
        if schema is None:
            schema = self.schemas[c.type] = self.writer.register_schema(c.type, "ros2msg", c.definition.encode())
        c.storage_id = self.writer.register_channel(
            c.topic,
            "cdr",
            schema,
            {"offered_qos_profiles": dump_yaml(c.qos).rstrip("\n"), "topic_type_hash": c.type_hash},
        )

    def write(self, c: Connection, t: int, data: bytes) -> None:
        self.writer.add_message(c.storage_id, log_time=t, data=data, publish_time=t)
        if self.spool.parts:  # a chunk is complete: to the disk with it, so the file ends on it
            self.sync()

    def chunk(self) -> None:
        """End the chunk in progress (wall-clock recordings reach the disk every second or so)."""
        self.writer.flush()

    def sync(self) -> None:
        """Append what the library wrote since the last call; the file then ends on a record."""
        data = self.spool.take()
        view = memoryview(data)
        while view:
            n = os.write(self.fd, view)
            view = view[n:]
        self.good = self.spool.pos

    def close(self, meta: dict[str, Any]) -> None:
        self.writer.add_metadata("rosbag2", {"serialized_metadata": dump_yaml(meta)})
        self.writer.finish()
        self.sync()
        os.close(self.fd)

    def salvage(self) -> None:
        """After a failed write: cut the file back to its last whole record and end it there
        (data end and footer, no summary)."""
        # deferred: optional dependency and start-up, as in __init__ (salvaging only)
        from mcap.data_stream import RecordBuilder
        from mcap.records import DataEnd, Footer

        os.ftruncate(self.fd, self.good)
        os.lseek(self.fd, self.good, os.SEEK_SET)
        b = RecordBuilder()
        DataEnd(data_section_crc=0).write(b)
        Footer(summary_start=0, summary_offset_start=0, summary_crc=0).write(b)
        tail = b.end() + b"\x89MCAP0\r\n"
        os.write(self.fd, tail)
        os.close(self.fd)

    def abandon(self) -> None:
        try:
            os.close(self.fd)
        except OSError:
            pass


class _Sqlite3Storage:
    identifier = "sqlite3"
    suffix = ".db3"

    def __init__(self, path: Path) -> None:
        # deferred: optional dependency (rosbags, the bag extra) and start-up (sqlite3 bags only)
        from rosbags.rosbag2.storage_sqlite3 import Sqlite3Writer

        class Writer(Sqlite3Writer):
            """rosbags' writer with rosbag2's file name (NAME_0.db3) and distro."""

            def __init__(self, file: Path) -> None:
                self.path = file
                self.conn = sqlite3.connect(f"file:{file}", uri=True, check_same_thread=False)  # the writer thread
                self.conn.executescript(self.SQLITE_SCHEMA.replace("'rosbags'", repr(_distro())))
                self.cursor = self.conn.cursor()

        self.path = path
        self.writer = Writer(path)
        self.types: set[str] = set()
        self.uncommitted = 0

    def add(self, c: Connection) -> None:
        # deferred: optional dependency and start-up, as in __init__
        from rosbags.interfaces import (
            Connection as RConnection,
        )
        from rosbags.interfaces import (
            ConnectionExtRosbag2,
            MessageDefinition,
            MessageDefinitionFormat,
        )

        rc = RConnection(
            id=c.id,
            topic=c.topic,
            msgtype=c.type,
            msgdef=MessageDefinition(MessageDefinitionFormat.MSG, c.definition),
            digest=c.type_hash,
            msgcount=0,
            ext=ConnectionExtRosbag2(serialization_format="cdr", offered_qos_profiles=[]),
            owner=None,
        )
        if c.type not in self.types:
            self.types.add(c.type)
            self.writer.add_msgtype(rc)
        self.writer.add_connection(rc, dump_yaml(c.qos).rstrip("\n"))
        c.storage_id = rc

    def write(self, c: Connection, t: int, data: bytes) -> None:
        self.writer.write(c.storage_id, t, data)
        self.uncommitted += 1
        if self.uncommitted >= COMMIT_EVERY:
            self.sync()

    def chunk(self) -> None:
        pass

    def sync(self) -> None:
        self.writer.conn.commit()
        self.uncommitted = 0

    def close(self, meta: dict[str, Any]) -> None:
        self.writer.close(VERSION, dump_yaml(meta).rstrip("\n"))

    def salvage(self) -> None:
        try:
            self.writer.conn.rollback()
        finally:
            self.writer.conn.close()

    def abandon(self) -> None:
        try:
            self.writer.conn.close()
        except sqlite3.Error:
            pass


def _distro() -> str:
    return os.environ.get("ROS_DISTRO") or ROS_DISTRO


STORAGES: dict[str, type[_Storage]] = {"mcap": _McapStorage, "sqlite3": _Sqlite3Storage}


def _reason(e: BaseException) -> str:
    if (isinstance(e, OSError) and e.errno == errno.ENOSPC) or "full" in str(e):
        return "the disk is full"
    if isinstance(e, OSError):
        return e.strerror or str(e)
    return str(e)


class BagWriter:
    """One bag being written: open, add topics, write (timestamp, topic, bytes), close.

    Not thread-safe: one thread uses it (in the writer process, `_writer_process`).
    """

    def __init__(self, path: str | os.PathLike[str], storage: str = "mcap") -> None:
        if storage not in STORAGES:
            raise BagError(f"unknown storage {storage!r} (mcap or sqlite3)")
        self.dir = Path(path)
        self.storage_id = storage
        if self.dir.exists():
            raise BagError(f"output folder '{self.dir}' already exists")
        self.file_name = f"{self.dir.name}_0{STORAGES[storage].suffix}"
        self.stats = Stats()
        #: rosbag2's custom_data: llfsm notes `llfsm.clock: sim` when times are run times
        self.custom: dict[str, str] = {}
        self.by_topic: dict[str, Connection] = {}
        self.failed: str | None = None
        try:
            self.dir.mkdir(parents=True)
        except OSError as e:
            raise BagError(f"cannot create the bag folder '{self.dir}': {e.strerror}") from None
        self.meta_path = self.dir / "metadata.yaml"
        try:
            # a valid placeholder (no messages yet), padded: the padding is the disk reserve
            text = metadata_yaml(metadata(storage, self.file_name, self.stats))
            self.meta_path.write_text(text + " " * max(0, RESERVE - len(text)) + "\n", encoding="utf-8")
            self.storage = STORAGES[storage](self.dir / self.file_name)
        except (OSError, sqlite3.Error) as e:
            raise BagError(f"cannot write the bag '{self.dir}': {_reason(e)}") from None

    # -- writing ---------------------------------------------------------------------------------
    def connection(
        self, topic: str, type_name: str, definition: str, type_hash: str, qos: list[dict[str, Any]]
    ) -> Connection:
        c = self.by_topic.get(topic)
        if c is None:
            c = Connection(len(self.stats.connections) + 1, topic, type_name, definition, type_hash, qos)
            self.storage.add(c)
            self.by_topic[topic] = c
            self.stats.connections.append(c)
        return c

    def write(self, c: Connection, t: int, data: bytes) -> None:
        self.storage.write(c, t, data)
        c.count += 1
        self.stats.add(t)

    def sync(self, end_chunk: bool = False) -> None:
        """End of a batch: everything written so far goes to the disk."""
        if end_chunk:
            self.storage.chunk()
        self.storage.sync()

    # -- closing ---------------------------------------------------------------------------------
    def close(self) -> None:
        """Close the bag properly; on a write error, salvage what is on disk (then BagError)."""
        meta = metadata(self.storage_id, self.file_name, self.stats, self.custom)
        try:
            self.storage.close(meta)
            self._write_metadata(meta)
        except (OSError, sqlite3.Error) as e:
            self.fail(e)

    def fail(self, e: BaseException) -> None:
        """A write failed: keep what is on disk, close the bag around it, raise BagError."""
        reason = _reason(e)
        try:
            self.meta_path.write_text("", encoding="utf-8")  # give the reserve back
        except OSError:
            pass
        try:
            self.storage.salvage()
        except (OSError, sqlite3.Error):
            self.storage.abandon()
        kept = self._rescan()
        raise BagError(
            f"cannot write the bag '{self.dir}': {reason}; it was closed with the {kept} "
            f"message{'s' if kept != 1 else ''} already written"
        )

    def _rescan(self) -> int:
        """Count what the salvaged file holds, and write metadata.yaml to match."""
        # deferred: start-up (only a salvaged bag is read back)
        from .reader import BagReader

        stats = Stats()
        try:
            with BagReader(self.dir, storage=self.storage_id, file_name=self.file_name) as r:
                conns = {}
                for rc in r.connections:
                    c = self.by_topic.get(rc.topic)
                    if c is None:
                        continue
                    conns[rc.id] = Connection(c.id, c.topic, c.type, c.definition, c.type_hash, c.qos)
                for cid, t in r.timestamps():
                    conns[cid].count += 1
                    stats.add(t)
                stats.connections = sorted((c for c in conns.values() if c.count), key=lambda c: c.id)
        except BagError:
            pass
        try:
            self._write_metadata(metadata(self.storage_id, self.file_name, stats, self.custom))
        except OSError:
            pass
        return stats.count

    def _write_metadata(self, meta: dict[str, Any]) -> None:
        with open(self.meta_path, "r+", encoding="utf-8") as f:  # in place: the reserve is ours
            f.write(metadata_yaml(meta))
            f.truncate()
