"""The bag writer process (`python -m llfsm.bag._writer_process DIR STORAGE`).

A recording run hands its serialized messages to this process through a pipe, so that the
MCAP/sqlite3 libraries, which are pure Python and cost far more per message than the bus
does, run on another core instead of taking the run's interpreter from its rounds.  It also
makes the bag outlive its run: if the run dies (even `kill -9`), the pipe closes and the bag
is closed properly with everything sent so far.

Protocol, on standard input, frames of one kind byte and a 4-byte little-endian length:
- `T` a topic (JSON: id, topic, type, definition, hash, qos; or id, topic, type, error if it
  cannot be recorded), sent before any message of it,
- `M` messages: records of <uint32 topic id><int64 time ns><uint32 size><CDR bytes>, one
  stream cut into frames anywhere (a record may begin in one `M` frame and end in the next:
  the run sends what it has in pieces of a size, never looking for where records end); a
  topic's connection is made when its first message comes (so connections follow first
  messages),
- `S` a batch ends (one byte: 1 = also end the MCAP chunk in progress),
- `X` the bag's custom_data (JSON),
- `C` close.  End of input without `C` closes the bag as well.
Replies on standard output, one JSON line each: `{"ok": true}` once the bag is created (or
`{"error": ...}`), `{"error": ...}` as soon as writing fails (the bag is then closed around
what is on disk), `{"warning": ...}` when the first message of a topic that cannot be
recorded comes, `{"ok": true, "count": N}` when the bag is closed.
Signals: Ctrl-C and SIGTERM are ignored here; the run asks for the close.  The process runs
at a lower priority (nice 10) than the run: with a core to spare it changes nothing, without
one the rounds go first and the records wait in the pipe and the run's buffer.
"""

from __future__ import annotations

import json
import os
import signal
import struct
import sys
from typing import IO, Any

FRAME = struct.Struct("<cI")
RECORD = struct.Struct("<IqI")
NICE = 10  # the writer's scheduling priority below the run's


def _reply(out: IO[bytes], **fields: Any) -> None:
    try:
        out.write(json.dumps(fields).encode() + b"\n")
        out.flush()
    except OSError:  # the run is gone (killed): the bag is closed all the same, nobody to tell
        pass


def _read(inp: IO[bytes], n: int) -> bytes | None:
    data = inp.read(n)
    if data is None or len(data) < n:
        return None
    return data


def _connection(writer: Any, t: dict[str, Any], out: IO[bytes]) -> Any:
    """The connection of a topic at its first message (None, said, if it cannot be recorded)."""
    if "error" in t:
        _reply(out, warning=t["error"])
        return None
    return writer.connection(t["topic"], t["type"], t["definition"], t["hash"], t["qos"])


def serve(path: str, storage: str, inp: IO[bytes], out: IO[bytes]) -> int:
    # deferred: start-up (the recorder imports this module for FRAME and RECORD; only the writer
    # process loads the writer and its storage libraries)
    from .errors import BagError
    from .writer import BagWriter

    try:
        writer = BagWriter(path, storage)
    except BagError as e:
        _reply(out, error=str(e))
        return 1
    _reply(out, ok=True)
    topics: dict[int, dict[str, Any]] = {}
    conns: dict[int, Any] = {}  # a topic's connection, or None if it cannot be recorded
    failed = False
    unpack = RECORD.unpack_from
    size = RECORD.size
    rest = b""  # the start of a record whose end is in the next `M` frame
    while True:
        head = _read(inp, FRAME.size)
        if head is None:
            break  # the run is gone: close what we have
        kind, length = FRAME.unpack(head)
        payload = _read(inp, length) if length else b""
        if payload is None:
            break
        if failed:
            if kind == b"C":
                break
            continue
        try:
            if kind == b"T":
                t = json.loads(payload)
                topics[t["id"]] = t
            elif kind == b"M":
                if rest:
                    payload = rest + payload
                view = memoryview(payload)
                pos, end = 0, len(payload)
                while pos + size <= end:
                    cid, stamp, n = unpack(view, pos)
                    if pos + size + n > end:
                        break
                    pos += size
                    try:
                        c = conns[cid]
                    except KeyError:
                        c = conns[cid] = _connection(writer, topics[cid], out)
                    if c is not None:
                        writer.write(c, stamp, bytes(view[pos : pos + n]))
                    pos += n
                rest = bytes(view[pos:])
            elif kind == b"S":
                writer.sync(end_chunk=payload == b"\x01")
            elif kind == b"X":
                writer.custom.update(json.loads(payload))
            elif kind == b"C":
                break
        except Exception as e:  # a full disk above all: the bag is closed around what is on disk
            failed = True
            try:
                writer.fail(e)
            except BagError as err:
                _reply(out, error=str(err))
    if failed:
        return 1
    try:
        writer.close()
    except BagError as e:
        _reply(out, error=str(e))
        return 1
    _reply(out, ok=True, count=writer.stats.count)
    return 0


def main() -> int:
    for s in (signal.SIGINT, signal.SIGTERM):
        signal.signal(s, signal.SIG_IGN)
    try:  # the run first: on a machine with no core to spare, the bag waits (in the pipe)
        os.nice(NICE)
    except OSError:
        pass
    path, storage = sys.argv[1], sys.argv[2]
    return serve(path, storage, sys.stdin.buffer, sys.stdout.buffer)


if __name__ == "__main__":
    sys.exit(main())
