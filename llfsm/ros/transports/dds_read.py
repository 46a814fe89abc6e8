"""Reading what other processes wrote: the one path by which every DDS reader of llfsm turns
samples into messages (the run's subscriptions, service servers and clients, `topic echo`,
`topic hz`, the graph's `ros_discovery_info`, `bag record`).

A DDS domain is shared: any process on it can publish anything under a ROS type name.  Cyclone
checks a sample's CDR structure against the type before it hands it over (a sequence longer
than its sample, a misaligned field: dropped in C), but not what Python's decoding adds: a
string that is not UTF-8, a payload in an encapsulation llfsm does not read.  So every reader
takes serialized samples (no cyclonedds IdlStruct deserialization, which would raise out of
`take`) and decodes them here, where a sample that cannot be decoded is dropped and said once
per topic and peer, never per sample: a peer that sends a thousand bad samples a second must
neither flood the terminal nor grow a set of warnings without bound.

What a reader keeps is bounded whatever peers do: Cyclone's history (keep last N) bounds the
samples waiting, one `take` returns at most `TAKE_BATCH`, and the peers a reader remembers
having warned about are at most `MAX_WARNED_PEERS` (then one line says the rest are dropped
without a word).
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import Any, Generic, TypeVar
from uuid import UUID

from cyclonedds._clayer import ddspy_take
from cyclonedds.core import InstanceState, SampleState, ViewState

T = TypeVar("T")

ANY = SampleState.Any | ViewState.Any | InstanceState.Any
#: Samples one take returns at most: a reader flooded by a peer still hands control back.
TAKE_BATCH = 256
#: Peers a reader warns about, one line each; further peers sending undecodable samples on the
#: same topic are dropped silently (a peer can make endpoints and participants by the thousand).
MAX_WARNED_PEERS = 32
#: Writer handles whose participant a reader remembers (a lookup per new writer otherwise).
PEER_CACHE = 1024


def take_raw(reader: Any, n: int = TAKE_BATCH) -> list[tuple[bytes, Any]]:
    """Serialized samples with valid data (encapsulation header included) and their sample
    infos, at most `n`; disposals and unregistrations (no data) are left out."""
    ret = ddspy_take(reader._ref, ANY, n)
    if isinstance(ret, int):  # a negative return code: nothing taken
        return []
    return [(data, info) for data, info in ret if info.valid_data]


def stderr_warning(text: str) -> None:
    """A warning of a command-line verb, in the form of the run's log lines (rclpy's `[WARN]`),
    on stderr: the verb's own output (stdout) stays what `ros2` prints."""
    now = time.time_ns()
    try:
        sys.stderr.write(f"[WARN] [{now // 1_000_000_000}.{now % 1_000_000_000:09d}] [llfsm.dds]: {text}\n")
        sys.stderr.flush()
    except (OSError, ValueError):  # stderr closed: the warning is not worth stopping for
        pass


class Samples(Generic[T]):
    """The decoded samples of one DDS reader.  `decode(payload)` makes a value of a payload or
    raises ValueError (llfsm.msgs._dds.from_cdr and unwrap do); a sample it refuses is dropped,
    and `say` is told once per peer (the writer's participant) with what was wrong."""

    def __init__(
        self,
        reader: Any,
        decode: Callable[[bytes], T],
        topic: str,
        what: str,
        say: Callable[[str], None] = stderr_warning,
        kind: str = "sample",
    ) -> None:
        self.reader, self.decode, self.topic, self.what, self.say = reader, decode, topic, what, say
        self.kind = kind  # "sample", "request", "reply": the warnings' word for one
        self.dropped = 0
        self._warned: set[str] = set()
        self._muted = False
        self._peers: dict[int, str] = {}

    def take(self, n: int = TAKE_BATCH) -> list[tuple[T, Any]]:
        """What arrived, decoded, with each sample's info; at most `n` samples are taken."""
        out = []
        decode = self.decode
        for data, info in take_raw(self.reader, n):
            try:
                value = decode(data)
            except ValueError as e:
                self.drop(info, e)
                continue
            out.append((value, info))
        return out

    def drop(self, info: Any, error: Exception) -> None:
        """Count a sample that could not be decoded; say so if its peer was not named yet."""
        self.dropped += 1
        if self._muted:
            return
        peer = self._peer(getattr(info, "publication_handle", 0))
        if peer in self._warned:
            return
        if len(self._warned) >= MAX_WARNED_PEERS:
            self._muted = True
            self.say(
                f"{self.topic}: more than {MAX_WARNED_PEERS} peers send {self.kind}s that are not {self.what}; "
                "theirs are dropped without further warnings"
            )
            return
        self._warned.add(peer)
        self.say(
            f"{self.topic}: dropped a {self.kind} that is not {self.what} (from {peer}): {error}; "
            "further ones from this peer are dropped without a warning"
        )

    def _peer(self, handle: int) -> str:
        """The participant that owns a writer (its GUID, as `ros2` tools show peers), or the
        writer's handle when Cyclone no longer knows it."""
        peer = self._peers.get(handle)
        if peer is None:
            try:
                ep = self.reader.get_matched_publication_data(handle)
                key = getattr(ep, "participant_key", None)
            except Exception:  # the writer is gone already; cyclonedds raises DDSException
                key = None
            peer = f"participant {key}" if isinstance(key, UUID) else f"writer {handle:#x}"
            if len(self._peers) >= PEER_CACHE:
                self._peers.clear()
            self._peers[handle] = peer
        return peer
