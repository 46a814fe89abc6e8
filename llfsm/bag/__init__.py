"""rosbag2 bags: record what a run's bus carries (`--record`), play a bag into a run (`--play`),
and the `llfsm bag` verbs.  A small layer over well-kept libraries: `mcap` writes MCAP,
`rosbags` writes sqlite3 and reads both; llfsm adds the bus tap, rosbag2's metadata layout,
and the behaviour on a full disk.  Optional: `pip install 'llfsm[bag]'`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING

from .errors import BagError

if TYPE_CHECKING:
    from ..ros.bus import Bus
    from .player import Player
    from .recorder import Recorder

__all__ = ["BagError", "RunBags", "need_libraries"]


def need_libraries() -> None:
    """BagError naming what is missing when the bag extra is not installed: said before a run or
    an exploration starts, not when its bag is written."""
    # deferred: optional dependency (the bag extra), checked only by a run that has bags
    try:
        import mcap  # noqa: F401
        import rosbags  # noqa: F401
    except ImportError as e:
        raise BagError(f"bags need the 'bag' extra ({e.name} is missing): pip install 'llfsm[bag]'") from None


class RunBags:
    """The bags of one `llfsm run`: at most one played, at most one recorded."""

    def __init__(
        self,
        record: str | None = None,
        record_topics: Iterable[str] = (),
        storage: str = "mcap",
        play: str | None = None,
        play_topics: Iterable[str] = (),
        play_rate: float = 1.0,
        report: Callable[[str], None] | None = None,
    ) -> None:
        need_libraries()
        self.player: Player | None = None
        self.recorder: Recorder | None = None
        if play is not None and not play_rate > 0:
            raise BagError(f"--play-rate must be greater than 0, not {play_rate:g}")
        if play is not None:  # first: a bad bag to play must not leave a new bag folder behind
            # deferred: start-up (a run that plays no bag never imports the player)
            from .player import Player

            try:
                self.player = Player(play, play_topics, play_rate)
            except BagError as e:
                raise BagError(f"--play {e}") from None
        if record is not None:
            # deferred: start-up (a run that records nothing never imports the recorder)
            from .recorder import Recorder

            try:
                self.recorder = Recorder(record, storage, record_topics, report=report)
            except BagError as e:
                raise BagError(f"--record {record}: {e}") from None

    def attach(self, bus: Bus) -> None:
        if self.recorder is not None:
            self.recorder.attach(bus)
        if self.player is not None:
            self.player.attach(bus)

    def close(self) -> str | None:
        """Close the recording; its error message if it failed.  Another Ctrl-C meanwhile
        waits: a bag cut off while its summary is written would be unreadable."""
        if self.recorder is None:
            return None
        # deferred: start-up (the signal module's enums; only closing a recording needs them)
        import signal
        import threading

        if threading.current_thread() is not threading.main_thread():
            return self.recorder.close()
        old = {s: signal.signal(s, signal.SIG_IGN) for s in (signal.SIGINT, signal.SIGTERM)}
        try:
            return self.recorder.close()
        finally:
            for s, h in old.items():
                signal.signal(s, h)
