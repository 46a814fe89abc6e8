"""`topic hz`: the publishing rate of topics each second, as `ros2 topic hz` prints it (for
several topics, its table).

Only messages that decode are counted, as ros2 counts what it can read; the reader is
best effort and volatile, as ros2's.
"""

from __future__ import annotations

import math
import sys
import time
from typing import Any, TextIO

from .. import NOT_FOUND, TIMEOUT, CliError
from ..arguments import full_name
from ..discovery import open_graph, wait_for_topic_types, where
from ..endpoints import Waiter, samples, topic_reader
from ..lookup import use_working_directory
from . import class_of_topic


class RateMeter:
    """ros2 topic hz's statistics over the gaps between the last `window` messages."""

    def __init__(self, window: int = 10000) -> None:
        self.window = window
        self.last_ns: int | None = None
        self.gaps: list[int] = []
        self._printed_at: int | None = None

    def tick(self, now_ns: int) -> None:
        if self.last_ns is not None and now_ns >= self.last_ns:
            self.gaps.append(now_ns - self.last_ns)
            if len(self.gaps) > self.window:
                del self.gaps[0]
        self.last_ns = now_ns

    def stats(self) -> tuple[float, float, float, float, int] | None:
        """(rate in Hz, min, max and standard deviation of the gaps in s, window), or None when
        there is nothing new since the last call."""
        if not self.gaps or self.last_ns == self._printed_at:
            return None
        self._printed_at = self.last_ns
        n = len(self.gaps)
        mean = sum(self.gaps) / n
        rate = 1e9 / mean if mean > 0 else 0.0
        std = math.sqrt(sum((g - mean) ** 2 for g in self.gaps) / n)
        return rate, min(self.gaps) * 1e-9, max(self.gaps) * 1e-9, std * 1e-9, n

    def report(self) -> str | None:
        """The text ros2 prints each second for one topic, or None with nothing new to say."""
        s = self.stats()
        if s is None:
            return None
        rate, lo, hi, std, n = s
        return f"average rate: {rate:.3f}\n\tmin: {lo:.3f}s max: {hi:.3f}s std dev: {std:.5f}s window: {n}\n"


def rate_table(meters: dict[str, RateMeter]) -> str | None:
    """What ros2 topic hz prints each second for several topics: a table, one row per topic
    with something new, or None."""
    header = ["topic", "rate", "min_delta", "max_delta", "std_dev", "window"]
    rows = []
    for topic, meter in meters.items():
        s = meter.stats()
        if s is not None:
            rate, lo, hi, std, n = s
            rows.append([topic, f"{rate:.3f}", f"{lo:.3f}", f"{hi:.3f}", f"{std:.5f}", str(n)])
    if not rows:
        return None
    widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(header)]
    head = "   ".join(h.center(w) for h, w in zip(header, widths, strict=True))
    line = "=" * (sum(widths) + 3 * (len(header) - 1))
    body = "\n".join("   ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)) for r in rows)
    return f"{head}\n{line}\n{body}\n\n"


def hz(
    topics: str | list[str],
    *,
    window: int = 10000,
    duration: float | None = None,
    timeout: float = TIMEOUT,
    out: TextIO | None = None,
) -> None:
    """`ros2 topic hz`: the publishing rate every second (a table for several topics), until
    interrupted or `duration` ends."""
    out = out or sys.stdout
    names = list(dict.fromkeys(full_name(t) for t in ([topics] if isinstance(topics, str) else topics)))
    use_working_directory()
    graph = open_graph()
    try:
        started = time.monotonic()
        readers: dict[str, Any] = {}
        taken: dict[str, Any] = {}
        for name in names:
            left = max(0.0, timeout - (time.monotonic() - started))
            cls = class_of_topic(name, wait_for_topic_types(graph, name, left))
            reader = topic_reader(graph, name, cls, reliable=False, transient_local=False)
            readers[name] = reader
            taken[name] = samples(reader, name, cls)
            if len(names) > 1:
                out.write(f"Subscribed to [{name}]\n")
        waiter = Waiter(graph, *readers.values())
        meters = {name: RateMeter(window) for name in names}
        next_print = time.monotonic() + 1.0
        end = started + duration if duration else math.inf
        while True:
            now = time.monotonic()
            if now >= end:
                return
            if now - started >= timeout:
                for name, reader in readers.items():
                    if meters[name].last_ns is None and not reader.get_subscription_matched_status().current_count:
                        raise CliError(f"no publisher of '{name}' matched within {timeout:g} s ({where()})", NOT_FOUND)
            if waiter.wait(min(next_print, end) - now):
                for name, topic_samples in taken.items():
                    for _msg, _info in topic_samples.take():  # decoded: what ros2 could not read is not counted
                        meters[name].tick(time.monotonic_ns())
            if time.monotonic() >= next_print:
                text = meters[names[0]].report() if len(names) == 1 else rate_table(meters)
                if text:
                    out.write(text)
                    out.flush()
                next_print += 1.0
    finally:
        graph.close()
