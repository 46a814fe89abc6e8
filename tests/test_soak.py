"""The always-on small version of bench/soak.py: long runs do not grow."""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "bench"))

from soak import soak_messages, soak_ringlets, ten_machines


def test_ringlets_of_ten_machines_do_not_grow_memory(tmp_path: Path) -> None:
    r = soak_ringlets(ten_machines(tmp_path), 200_000)
    assert r["ringlets"] >= 180_000
    assert r["growth"] < 64 * 1024, r


def test_bus_messages_do_not_grow_memory() -> None:
    r = soak_messages(50_000)
    assert r["heard"] > 50_000  # the PUSH subscriber really got them (warm-up included)
    assert r["growth"] < 64 * 1024, r
