"""The recorder's C tap (llfsm/bag/_tap.c) against the generated Python one it stands in for:
the same bytes for every message of a fixed size, the same error (and nothing appended) for a
value the Python one refuses, and the same bag from a whole recorded run."""

from __future__ import annotations

import math
import random
import struct
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest
from conftest import run_sim
from test_bag import driver
from test_dds_types import CLASSES, sample

from llfsm.bag import recorder, typesupport
from llfsm.msgs import _dds
from llfsm.msgs._message import Message

FIXED = [c for c in CLASSES if _dds.codec(c).stamped]


class Clock:
    now = 0


def test_the_c_tap_is_built() -> None:
    """setup.py builds it wherever a C compiler and the Python headers are (every machine this
    project runs on): without it `--record` still works but costs a busy run more (the
    benchmark's numbers assume it)."""
    assert typesupport._Tap is not None, "llfsm/bag/_tap.c was not built: is gcc there? (pip install -e . says why)"


class Out:
    """What a tap appended: the C tap's Spool, or the Python tap's bytearray."""

    def __init__(self, spool: Any) -> None:
        self.spool, self.got = spool, bytearray()

    def __call__(self) -> bytes:
        """Everything appended so far."""
        if isinstance(self.spool, bytearray):
            self.got += self.spool
            self.spool.clear()
        else:
            self.got += self.spool.take()
        return bytes(self.got)


def both(cls: type[Message], key: int = 7) -> tuple[Any, Any, Out, Out, Clock]:
    """A C tap on a Spool and a Python tap on a bytearray, for `cls`, sharing one clock."""
    c = _dds.codec(cls)
    clock = Clock()
    python_out, c_out = bytearray(), typesupport.Spool()
    python = c.stamped(python_out.extend, key, clock)
    tap = typesupport._Tap(c_out, key, clock, c.tap_layout, c.stamped(c_out.extend, key, clock))
    return tap, python, Out(c_out), Out(python_out), clock


def test_every_fixed_size_message_has_a_layout_for_the_c_tap() -> None:
    missing = [c._TYPE for c in FIXED if _dds.codec(c).tap_layout is None]
    empty = [c._TYPE for c in FIXED if not c._FIELDS]  # their CDR is a constant byte
    assert missing == empty
    assert "std_msgs/msg/Empty" in empty


@pytest.mark.parametrize("cls", [c for c in FIXED if _dds.codec(c).tap_layout], ids=lambda c: c._TYPE)
def test_the_c_tap_appends_what_the_python_tap_appends(cls: type[Message]) -> None:
    tap, python, c_out, python_out, clock = both(cls)
    rng = random.Random(cls._TYPE + "tap")
    for n in range(40):
        msg = sample(cls, rng)
        if n % 3 == 0:
            _odd_floats(msg, rng)
        clock.now = rng.choice([0, -(2**63), 2**63 - 1, n * 987_654_321])
        tap(msg)
        python(msg)
        assert c_out() == python_out()
    assert tap.fallbacks == 0
    assert len(c_out()) == 40 * (16 + len(_dds.cdr(sample(cls, rng))))


def _odd_floats(msg: Message, rng: random.Random) -> None:
    """Floats that round when packed as float32, signed zeros, infinities and NaN, set in the
    slots directly (whatever a field's setter would say about them)."""
    for name, ros_type in type(msg)._FIELDS:
        value = getattr(msg, name)
        if isinstance(value, Message):
            _odd_floats(value, rng)
        elif ros_type in ("float32", "float64"):
            odd = [0.1, -0.0, math.inf, -math.inf, math.nan, 1e-45, 3.4028235e38, 2.5e-39]
            object.__setattr__(msg, "_" + name, rng.choice(odd))


def test_a_value_struct_refuses_raises_the_same_error_and_appends_nothing() -> None:
    from llfsm.msgs.geometry_msgs.msg import TwistWithCovariance
    from llfsm.msgs.std_msgs.msg import Int64, UInt8, UInt64
    from llfsm.msgs.turtlesim.msg import Pose

    cases: list[tuple[type[Message], str, object]] = [
        (UInt8, "_data", 256),
        (UInt8, "_data", -1),
        (UInt8, "_data", "7"),
        (Int64, "_data", 2**63),
        (UInt64, "_data", -1),
        (UInt64, "_data", 2**64),
        (Pose, "_x", 1e300),  # too large for a float32
        (Pose, "_x", "1.0"),
        (TwistWithCovariance, "_covariance", [0.0] * 35),
        (TwistWithCovariance, "_covariance", None),
    ]
    for cls, slot, value in cases:
        tap, python, c_out, python_out, _ = both(cls)
        msg = cls()
        object.__setattr__(msg, slot, value)
        with pytest.raises(Exception) as python_error:
            python(msg)
        with pytest.raises(type(python_error.value)) as c_error:
            tap(msg)
        assert str(c_error.value) == str(python_error.value), (cls, value)
        assert c_out() == python_out() == b"", (cls, value)
        assert tap.fallbacks == 1


def test_values_the_python_tap_converts_go_through_it() -> None:
    """An int in a float64 field, a bool subclass's cousin, a look-alike nested object, a tuple
    for an array, bytes for uint8[16]: packed as before (by the C tap, or by the Python tap it
    hands them to)."""
    from llfsm.msgs.geometry_msgs.msg import Twist, TwistWithCovariance
    from llfsm.msgs.rmw_dds_common.msg import Gid
    from llfsm.msgs.std_msgs.msg import Bool, Float64, UInt64

    class Floaty:
        def __float__(self) -> float:
            return 2.5

    odd: list[tuple[type[Message], str, object]] = [
        (Float64, "_data", 3),
        (Float64, "_data", 2**80),
        (Float64, "_data", Floaty()),
        (Bool, "_data", 1),
        (UInt64, "_data", 2**64 - 1),
        (Twist, "_linear", SimpleNamespace(_x=1.0, _y=2.0, _z=3.0)),
        (TwistWithCovariance, "_covariance", tuple(float(i) for i in range(36))),
        (Gid, "_data", bytes(range(16))),
    ]
    for cls, slot, value in odd:
        tap, python, c_out, python_out, _ = both(cls)
        msg = cls()
        object.__setattr__(msg, slot, value)
        tap(msg)
        python(msg)
        assert c_out() == python_out(), (cls, value)
    ordinary = Twist()
    tap, python, c_out, python_out, _ = both(Twist)
    tap(ordinary)
    object.__setattr__(ordinary, "_linear", SimpleNamespace(_x=1.0, _y=2.0, _z=3.0))
    tap(ordinary)  # another class than the one it learnt: handed over
    python(Twist())
    python(ordinary)
    assert c_out() == python_out()
    assert tap.fallbacks == 1


def test_a_bad_layout_is_refused_when_the_tap_is_made() -> None:
    tap = typesupport._Tap
    for layout in ((("z", "_x"),), (("d", ""),), (("2d", "_x"),), (("3x", "_x"),), (("d", "_a.._b"),), (("d",),)):
        with pytest.raises((ValueError, TypeError)):
            tap(typesupport.Spool(), 1, Clock(), layout, print)
    with pytest.raises(TypeError):
        tap(bytearray(), 1, Clock(), (("d", "_x"),), print)  # not a Spool
    with pytest.raises(ValueError):
        tap(typesupport.Spool(), 2**32, Clock(), (("d", "_x"),), print)


@pytest.mark.parametrize("spool", ["c", "python"])
def test_a_spool_gives_what_was_appended_in_order_once(spool: str) -> None:
    s = typesupport.Spool() if spool == "c" else typesupport.ByteSpool()
    assert len(s) == 0 and s.take() == b""
    chunks = [bytes([i % 256]) * (i * 37 % 5000) for i in range(300)]
    got = b""
    for i, chunk in enumerate(chunks):
        s.extend(chunk)
        s.extend(memoryview(chunk))
        if i % 7 == 0:
            assert len(s) > 0 or not chunk
            got += s.take()
            assert len(s) == 0
    got += s.take()
    assert got == b"".join(c + c for c in chunks)
    s.extend(b"x" * (20 << 20))  # a burst past its usual size, then small batches again
    assert s.take() == b"x" * (20 << 20)
    s.extend(b"abc")
    assert s.take() == b"abc"
    with pytest.raises(TypeError):
        s.extend("text")


def test_a_recorded_run_gives_the_same_bag_with_either_tap(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    m = driver(tmp_path)
    bags = []
    for run, tap, spool in (("c", typesupport._Tap, typesupport.Spool), ("python", None, typesupport.ByteSpool)):
        monkeypatch.setattr(typesupport, "_Tap", tap)
        monkeypatch.setattr(recorder, "Spool", spool)
        (tmp_path / run).mkdir()
        bag = tmp_path / run / "same"
        r = run_sim(m, "--node", "turtlesim", "--duration", "2s", "--record", bag)
        assert r.status == 0, r.stderr
        bags.append(bag)
    for name in sorted(p.name for p in bags[0].iterdir()):
        assert (bags[0] / name).read_bytes() == (bags[1] / name).read_bytes(), name


def test_the_record_head_is_little_endian() -> None:
    from llfsm.msgs.std_msgs.msg import UInt8

    tap, _, c_out, _, clock = both(UInt8, key=0x01020304)
    clock.now = 0x0102030405060708
    msg = UInt8()
    msg.data = 9
    tap(msg)
    assert c_out() == struct.pack("<IqI", 0x01020304, clock.now, 5) + b"\x00\x01\x00\x00\x09"
