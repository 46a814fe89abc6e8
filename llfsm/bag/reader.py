"""Reading rosbag2 bags (ours and ROS 2's, MCAP or sqlite3) with rosbags' reader."""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from pathlib import Path
from types import TracebackType
from typing import Any

from .errors import BagError


def _reader_errors() -> tuple[type[BaseException], ...]:
    # deferred: optional dependency (the bag extra; reading a bag checks for it below)
    from rosbags.rosbag2 import ReaderError

    return (ReaderError, OSError, KeyError, ValueError, IndexError, EOFError, TypeError)


def _one_line(e: BaseException) -> str:
    return " ".join(str(e).split())


def _checked_custom_data(folder: Path, path: str | Path) -> dict[str, str]:
    """Check a bag folder's metadata.yaml (llfsm.bag.info's model: fields, ranges, files inside
    the folder) before rosbags reads it; its custom_data."""
    # deferred: start-up (pydantic and PyYAML, only where a folder's metadata.yaml is read)
    from .info import MetadataError, read_metadata

    try:
        meta = read_metadata(folder)
    except MetadataError as e:
        raise BagError(f"{path}: cannot read the bag: {e.detail}") from None
    return dict(meta.custom_data or {})


class BagReader:
    """A bag folder (with its metadata.yaml) or one storage file (`x.mcap`, `x.db3`)."""

    def __init__(self, path: str | Path, storage: str | None = None, file_name: str | None = None) -> None:
        self.path = Path(path)
        if file_name is not None:  # a bag being salvaged: its metadata.yaml is not written yet
            self.path = self.path / file_name
        if not self.path.exists():
            raise BagError(f"{path}: no such bag")
        self._custom: dict[str, str] = {}
        if self.path.is_dir():
            self._custom = _checked_custom_data(self.path, path)
        # deferred: optional dependency (the bag extra)
        try:
            from rosbags.highlevel import AnyReader  # noqa: F401  (rosbags is installed)
            from rosbags.rosbag2 import Reader
        except ImportError:  # pragma: no cover - the bag extra is missing
            raise BagError("reading bags needs rosbags: pip install 'llfsm[bag]'") from None
        try:
            self._reader = Reader(self.path)
            self._reader.open()
        except _reader_errors() as e:
            raise BagError(f"{path}: cannot read the bag: {_one_line(e)}") from None
        except (AttributeError, ArithmeticError, RecursionError, LookupError) as e:
            # rosbags parses metadata.yaml again (checked above) and the storage files: what it
            # raises on a file made to break it is the file's fault, never a traceback
            raise BagError(f"{path}: cannot read the bag: {type(e).__name__}: {_one_line(e)}") from None

    def __enter__(self) -> BagReader:
        return self

    def __exit__(self, t: type[BaseException] | None, e: BaseException | None, tb: TracebackType | None) -> None:
        self.close()

    def close(self) -> None:
        try:
            self._reader.close()
        except Exception:
            pass

    @property
    def connections(self) -> list[Any]:
        return list(self._reader.connections)

    @property
    def start_time(self) -> int:
        return self._reader.start_time

    @property
    def custom_data(self) -> dict[str, str]:
        """The bag's custom_data (metadata.yaml), {} for a lone storage file."""
        return dict(self._custom)

    @property
    def message_count(self) -> int:
        return self._reader.message_count

    def messages(self, connections: Iterable[Any] | None = None) -> Iterator[tuple[Any, int, bytes]]:
        """(connection, timestamp ns, CDR bytes) in time order; a damaged file is a BagError."""
        try:
            conns = None if connections is None else list(connections)
            for conn, t, data in self._reader.messages(connections=conns or ()):
                yield conn, t, bytes(data)
        except BagError:
            raise
        except _reader_errors() as e:
            raise BagError(f"{self.path}: the bag is damaged: {_one_line(e)}") from None

    def timestamps(self) -> Iterator[tuple[int, int]]:
        for conn, t, _data in self.messages():
            yield conn.id, t
