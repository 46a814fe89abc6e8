"""The recorder's C tap (llfsm/bag/_tap.c) against the generated Python one it stands in for:
the same bytes for every message of a fixed size, the same error (and nothing appended) for a
value the Python one refuses, and the same bag from a whole recorded run."""

from __future__ import annotations

import importlib.util
import math
import os
import random
import struct
import subprocess
import sys
import textwrap
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import hypothesis
import pytest
from helpers import driver, run_sim, skip_unless_built
from hypothesis import strategies as st
from samples import CLASSES, sample

import llfsm
from llfsm.bag import recorder, typesupport
from llfsm.msgs import _dds
from llfsm.msgs._message import Message

FIXED = [c for c in CLASSES if _dds.codec(c).stamped]
TAPPED = [c for c in FIXED if _dds.codec(c).tap_layout]
ROOT = Path(llfsm.__file__).resolve().parents[1]  # the tree under test (make asan's copy, too)

# Skipped, saying why, where the C tap is off on purpose or was not built (helpers.skip_unless_built);
# under LLFSM_REQUIRE_C=1, as `make test` runs, an unbuilt tap fails instead.
needs_c = skip_unless_built(typesupport._Tap is not None, "the C tap (llfsm/bag/_tap.c)")


class Clock:
    now = 0


@needs_c
def test_the_c_tap_is_built() -> None:
    """setup.py builds it wherever a C compiler and the Python headers are (every machine this
    project runs on): without it `--record` still works but costs a busy run more (the
    benchmark's numbers assume it)."""
    assert typesupport._Tap is not None, "llfsm/bag/_tap.c was not built: is gcc there? (pip install -e . says why)"


def test_llfsm_no_c_runs_the_python_code_instead() -> None:
    """LLFSM_NO_C=1 makes both extensions refuse to import, so that the Python code they stand
    in for runs (the recorder's ByteSpool and generated taps, the Python stroke painter)."""
    code = (
        "from llfsm.bag import typesupport; from llfsm.sim import world; "
        "print(typesupport._Tap is None, typesupport.Spool is typesupport.ByteSpool, world._c_fill_stroke is None)"
    )
    built = importlib.util.find_spec("llfsm.bag._tap") is not None  # (finds it without importing it)
    for value, off in (("1", True), ("0", not built)):
        r = subprocess.run(
            [sys.executable, "-c", code], env=dict(os.environ, LLFSM_NO_C=value), capture_output=True, text=True
        )
        assert r.returncode == 0, r.stderr
        assert r.stdout.split() == [str(off)] * 3, (value, r.stdout)


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


@needs_c
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


@needs_c
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


@needs_c
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


@needs_c
def test_a_bad_layout_is_refused_when_the_tap_is_made() -> None:
    tap = typesupport._Tap
    for layout in ((("z", "_x"),), (("d", ""),), (("2d", "_x"),), (("3x", "_x"),), (("d", "_a.._b"),), (("d",),)):
        with pytest.raises((ValueError, TypeError)):
            tap(typesupport.Spool(), 1, Clock(), layout, print)
    with pytest.raises(TypeError):
        tap(bytearray(), 1, Clock(), (("d", "_x"),), print)  # not a Spool
    for key in (2**32, 2**64, -1):  # (2**64 once wrapped round to key 0)
        with pytest.raises(ValueError):
            tap(typesupport.Spool(), key, Clock(), (("d", "_x"),), print)


@pytest.mark.parametrize("spool", [pytest.param("c", marks=needs_c), "python"])
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


@needs_c
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


@needs_c
def test_the_record_head_is_little_endian() -> None:
    from llfsm.msgs.std_msgs.msg import UInt8

    tap, _, c_out, _, clock = both(UInt8, key=0x01020304)
    clock.now = 0x0102030405060708
    msg = UInt8()
    msg.data = 9
    tap(msg)
    assert c_out() == struct.pack("<IqI", 0x01020304, clock.now, 5) + b"\x00\x01\x00\x00\x09"


# -- what is not exactly a generated message class (issue 18, item 8) ------------------------------


def _compare(cls: type[Message], *messages: Any, clock: Any = None) -> tuple[Any, list[Any]]:
    """Hand each message to a C tap and to the Python tap for `cls`: the same bytes appended, or
    the same error (type and text) with nothing appended.  Returns the C tap and, for each
    message, its error (type, text) or None."""
    tap, python, c_out, python_out, own_clock = both(cls)
    if clock is not None:
        own_clock.now = clock
    errors = []
    for msg in messages:
        got = []
        for fn in (tap, python):
            try:
                fn(msg)
                got.append(None)
            except Exception as e:  # any error, compared as it is
                got.append((type(e), str(e)))
        assert got[0] == got[1], msg
        assert c_out() == python_out(), msg
        errors.append(got[0])
    return tap, errors


@needs_c
def test_a_subclass_with_another_class_slot_descriptor_reads_no_slot_of_it() -> None:
    """A subclass of Twist whose `_linear` is another class's slot descriptor: Python refuses
    to read it (TypeError: the descriptor does not apply); the C tap read Twist's `_angular`
    through it, at the other class's offset."""
    from llfsm.msgs.geometry_msgs.msg import Twist, Vector3

    class Foreign:
        __slots__ = ("a", "b")

    class Sub(Twist):
        __slots__ = ()
        _linear = Foreign.a  # type: ignore[assignment]

    msg = Twist(linear=Vector3(x=1.0), angular=Vector3(x=2.0))
    msg.__class__ = Sub
    refused = (TypeError, "descriptor 'a' for 'Foreign' objects doesn't apply to a 'Sub' object")
    assert _compare(Twist, msg, msg)[1] == [refused, refused]
    tap, errors = _compare(Twist, Twist(), msg, Twist())  # learnt on a Twist, then a Sub
    assert errors == [None, refused, None] and tap.fallbacks == 1


def _run_apart(code: str, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    """Python code in a process of its own, against this tree (its C parts as built, under make
    asan's sanitizers too): a crash is this test's failure, not pytest's end."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, (str(ROOT), os.environ.get("PYTHONPATH")))))
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        env=env,
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


@needs_c
def test_a_foreign_slot_descriptor_far_outside_the_message_does_not_crash() -> None:
    """The same with descriptors of a class of 2,000 slots: their offsets are far past the end of
    a Twist, and the C tap followed whatever pointer it found there (rc 139)."""
    r = _run_apart(
        """
        from llfsm.bag import typesupport
        from llfsm.msgs import _dds
        from llfsm.msgs.geometry_msgs.msg import Twist

        class Clock:
            now = 5

        Foreign = type("Foreign", (), {"__slots__": tuple(f"s{i}" for i in range(2000))})

        c = _dds.codec(Twist)
        out = typesupport.Spool()
        refused = set()
        for k in range(2, 2000, 3):  # whatever lies there, one of them is not an object
            Sub = type("Sub", (Twist,), {"__slots__": (), "_linear": getattr(Foreign, f"s{k}")})
            msg = Twist()
            msg.__class__ = Sub
            tap = typesupport._Tap(out, 1, Clock(), c.tap_layout, c.stamped(out.extend, 1, Clock()))
            for _ in range(2):
                try:
                    tap(msg)
                except TypeError as e:
                    refused.add(str(e).replace(str(k), "N"))
        print(refused, len(out), tap.fallbacks)
        """
    )
    assert r.returncode == 0, (r.returncode, r.stderr[-3000:])
    assert r.stdout.strip() == "{\"descriptor 'sN' for 'Foreign' objects doesn't apply to a 'Sub' object\"} 0 2"


@needs_c
def test_what_python_reads_some_other_way_goes_to_python() -> None:
    """Classes whose attribute `_x` is not simply their own slot, each read by Python its own way:
    the C tap leaves every one to the Python tap, even after learning the plain class."""
    from llfsm.msgs.geometry_msgs.msg import Vector3

    class Overridden(Vector3):
        __slots__ = ("_x", "_y", "_z")  # its own slots, but read through __getattribute__

        def __getattribute__(self, name: str) -> Any:
            return 7.0 if name == "_x" else object.__getattribute__(self, name)

    class Property(Vector3):
        __slots__ = ()
        _x = property(lambda self: 8.0)  # type: ignore[assignment]

    class Plain(Vector3):
        __slots__ = ()
        _x = 9.0  # type: ignore[assignment]

    class Inherited(Vector3):  # Vector3's own slots: read the same, but not the generated class
        __slots__ = ()

    class Fallback(Vector3):
        __slots__ = ("_x", "_y", "_z")

        def __getattr__(self, name: str) -> Any:  # only for an unset slot
            return 6.0

    messages = []
    for cls in (Overridden, Property, Plain, Inherited, Fallback):
        m = cls.__new__(cls)
        for name in ("_x", "_y", "_z"):
            try:
                object.__setattr__(m, name, 1.0)
            except AttributeError:  # a property or a class attribute: Vector3's slot under it
                Vector3.__dict__[name].__set__(m, 1.0)
        messages.append(m)
    del messages[-1]._x  # type: ignore[attr-defined]
    tap, errors = _compare(Vector3, Vector3(x=1.0), *messages)
    assert errors == [None] * 6 and tap.fallbacks == 5
    for m in messages:  # and learnt on one of them first
        assert _compare(Vector3, m, Vector3())[0].fallbacks >= 1


@needs_c
def test_a_class_changed_after_the_tap_learnt_it_is_read_as_python_reads_it() -> None:
    from llfsm.msgs.geometry_msgs.msg import Vector3

    class Own(Vector3):  # declares its slots again: read in C, as Python reads the same slots
        __slots__ = ("_x", "_y", "_z")

    m = Own.__new__(Own)
    for name in ("_x", "_y", "_z"):
        object.__setattr__(m, name, 1.0)
    tap, python, c_out, python_out, _ = both(Vector3)
    tap(m)
    python(m)
    assert tap.fallbacks == 0 and c_out() == python_out()
    Own._x = property(lambda self: 5.0)  # type: ignore[assignment]
    tap(m)
    python(m)
    assert tap.fallbacks == 1 and c_out() == python_out()
    Own._x = Own._y  # type: ignore[assignment]  # another slot of its own: C again, the new offset
    tap(m)
    python(m)
    assert c_out() == python_out()


# -- state kept across Python code (issue 18, item 9) ----------------------------------------------


@needs_c
def test_a_tap_re_initialised_by_its_clock_mid_call_records_whole() -> None:
    """clock.now runs Python code in the middle of the C tap's call.  Here it re-initialises the
    tap: with a layout that fails (15 MiB of items, then a bad one), which left a layout of
    15 MiB with the size of the old one and the tap wrote it into a 68-byte record; with a good
    one, another spool and another clock.  The call in progress finishes with what it began
    with, a failed __init__ leaves the tap as it was, and the next call uses a good new one."""
    r = _run_apart(
        """
        from llfsm.bag import typesupport
        from llfsm.msgs import _dds
        from llfsm.msgs.geometry_msgs.msg import Twist, Vector3
        from llfsm.msgs.std_msgs.msg import UInt8

        c = _dds.codec(Twist)
        out, other = typesupport.Spool(), typesupport.Spool()
        expected = bytearray()
        python = c.stamped(expected.extend, 1, type("C", (), {"now": 5})())

        class Clock:
            def __init__(self, action):
                self.action = action

            @property
            def now(self):
                action, self.action = self.action, None
                if action == "bad":
                    try:
                        tap.__init__(out, 1, self, (("1048576x", ""),) * 15 + (("z", ""),), print)
                    except ValueError as e:
                        print("refused:", e)
                elif action == "good":
                    u = _dds.codec(UInt8)
                    tap.__init__(other, 2, type("C", (), {"now": 6})(), u.tap_layout, u.stamped(other.extend, 2, self))
                return 5

        msg = Twist(linear=Vector3(x=1.5))
        tap = typesupport._Tap(out, 1, Clock("bad"), c.tap_layout, c.stamped(out.extend, 1, Clock(None)))
        tap(msg)
        python(msg)
        tap(msg)  # the tap as it was
        python(msg)
        print(out.take() == bytes(expected), len(expected))
        tap.__init__(out, 1, Clock("good"), c.tap_layout, c.stamped(out.extend, 1, Clock(None)))
        tap(msg)  # finishes as a Twist tap, into `out`
        print(out.take() == bytes(expected[:68]))
        u8 = UInt8(data=9)
        tap(u8)
        print(other.take().hex(), len(out), tap.fallbacks)
        """
    )
    assert r.returncode == 0, (r.returncode, r.stderr[-3000:])
    assert r.stdout.splitlines() == [
        "refused: a tap item's format must be [count]code: z",
        "True 136",
        "True",
        (struct.pack("<IqI", 2, 6, 5) + b"\x00\x01\x00\x00\x09").hex() + " 0 0",
    ]


@needs_c
def test_an_uninitialised_tap_refuses_to_be_called() -> None:
    tap = typesupport._Tap.__new__(typesupport._Tap)
    with pytest.raises(TypeError):
        tap(object())


# -- fuzzing: generated subclasses and values against the Python tap --------------------------------

_FOREIGN: dict[int, type] = {}


def _foreign(n: int) -> type:
    """A class of n slots, whose descriptors a message subclass borrows."""
    if n not in _FOREIGN:
        _FOREIGN[n] = type(f"Foreign{n}", (), {"__slots__": tuple(f"s{i}" for i in range(n))})
    return _FOREIGN[n]


class _Int(int):
    pass


class _Float(float):
    pass


_ODD_SCALARS = st.one_of(
    st.integers(min_value=-(2**65), max_value=2**65),
    st.sampled_from([0, 1, -1, 127, 128, 255, 256, -129, 2**31, 2**32, -(2**31) - 1, 2**63, 2**64 - 1, 2**64]),
    st.booleans(),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([-0.0, 1e-45, 3.4028235e38, 3.4028236e38, 1e300, 2.5e-39, math.nan]),
    st.builds(_Int, st.integers(min_value=-300, max_value=300)),
    st.builds(_Float, st.floats(allow_nan=False, width=32)),
    st.sampled_from(["1.0", "x", None, b"\x01", (), SimpleNamespace()]),
)


def _odd_value(data: st.DataObject, current: Any) -> Any:
    """Something to put in a slot in place of `current`: a scalar, or a sequence like (or not
    like) the array there."""
    if isinstance(current, list | tuple | bytes):
        n = len(current)
        length = data.draw(st.sampled_from([n, n, n - 1, n + 1, 0]).filter(lambda k: k >= 0))
        items = data.draw(st.lists(st.one_of(_ODD_SCALARS, st.sampled_from(list(current) or [0])), min_size=length,
                                   max_size=length))  # fmt: skip
        kind = data.draw(st.sampled_from([list, tuple, bytes, bytearray]))
        if kind in (bytes, bytearray):
            return kind(data.draw(st.binary(min_size=length, max_size=length)))
        return kind(items)
    return data.draw(_ODD_SCALARS)


def _messages_in(msg: Message) -> list[tuple[Message, Message | None, str | None]]:
    """Each message object of the tree, children before parents: (object, parent, slot)."""
    out: list[tuple[Message, Message | None, str | None]] = []

    def visit(m: Message, parent: Message | None, slot: str | None) -> None:
        for name, _ in type(m)._FIELDS:
            v = getattr(m, "_" + name)
            if isinstance(v, Message):
                visit(v, m, "_" + name)
        out.append((m, parent, slot))

    visit(msg, None, None)
    return out


# what may happen to each message object of a tree: nothing, an odd value or none in one of its
# slots, or another class (see _mutate)
_MUTATIONS = (
    "none",
    "value",
    "unset",
    "subclass",
    "foreign",
    "property",
    "getattribute",
    "getattr",
    "plain",
    "redeclare",
)


def _mutate(data: st.DataObject, msg: Message) -> Message:
    """The message with some of its objects given odd classes or odd values (drawn); returns the
    top object, which may be a new one."""
    top = msg
    replaced: dict[int, Message] = {}
    for obj, parent, _slot in _messages_in(msg):
        cls = type(obj)  # the generated class
        slots = list(cls.__slots__)
        for name in slots:  # children first: a child replaced goes in here, by cls's own slot
            child = object.__getattribute__(obj, name) if name in _set_slots(obj) else None
            if child is not None and id(child) in replaced:
                cls.__dict__[name].__set__(obj, replaced[id(child)])
        # half the objects as they were: the C tap then packs the rest of the tree itself
        kind = data.draw(st.sampled_from(_MUTATIONS)) if data.draw(st.booleans()) else "none"
        name = data.draw(st.sampled_from(slots)) if slots else None
        new: Message = obj
        if kind == "value" and name:
            current = object.__getattribute__(obj, name)
            cls.__dict__[name].__set__(obj, _odd_value(data, current))
        elif kind == "unset" and name:
            cls.__dict__[name].__delete__(obj)
        elif kind in ("subclass", "foreign", "property", "getattribute", "getattr", "plain") and name:
            body: dict[str, Any] = {"__slots__": ()}
            value = data.draw(_ODD_SCALARS)
            if kind == "foreign":
                n = data.draw(st.sampled_from([1, 2, 3, 8, 100, 3000]))
                body[name] = _foreign(n).__dict__[f"s{data.draw(st.integers(0, n - 1))}"]
            elif kind == "property":
                body[name] = property(lambda self, v=value: v)
            elif kind == "plain":
                body[name] = value
            elif kind == "getattribute":
                raises = data.draw(st.booleans())

                def getattribute(self: Any, attr: str, name: str = name, v: Any = value, raises: bool = raises) -> Any:
                    if attr == name:
                        if raises:
                            raise ValueError(f"no {attr}")
                        return v
                    return object.__getattribute__(self, attr)

                body["__getattribute__"] = getattribute
            elif kind == "getattr":
                body["__getattr__"] = lambda self, attr, v=value: v
                if data.draw(st.booleans()):
                    cls.__dict__[name].__delete__(obj)
            obj.__class__ = type(f"{kind}{cls.__name__}", (cls,), body)
        elif kind == "redeclare" and slots:
            own = data.draw(st.lists(st.sampled_from(slots), min_size=1, unique=True))
            sub = type(f"Own{cls.__name__}", (cls,), {"__slots__": tuple(own)})
            new = sub.__new__(sub)
            for s in _set_slots(obj):
                object.__setattr__(new, s, object.__getattribute__(obj, s))
            replaced[id(obj)] = new
        if parent is None:
            top = new
    return top


def _set_slots(obj: Message) -> list[str]:
    """The generated class's slots of obj that hold something."""
    cls = next(c for c in type(obj).__mro__ if c.__dict__.get("_TYPE"))
    return [s for s in cls.__slots__ if _slot_is_set(cls, s, obj)]


def _slot_is_set(cls: type, name: str, obj: Any) -> bool:
    try:
        cls.__dict__[name].__get__(obj)
    except AttributeError:
        return False
    return True


_CLOCKS = st.one_of(  # mostly a time the C tap takes itself
    st.integers(min_value=-(2**63), max_value=2**63 - 1),
    st.integers(min_value=0, max_value=2**62),
    st.integers(min_value=-(2**63), max_value=2**63 - 1),
    st.sampled_from([2**63, -(2**63) - 1, True, 1.5, None, _Int(3)]),
)


def _fuzz_once(data: st.DataObject) -> None:
    cls = data.draw(st.sampled_from(TAPPED), label="class")
    seed = data.draw(st.integers(0, 2**32), label="seed")
    plain = sample(cls, random.Random(seed))
    odd = _mutate(data, sample(cls, random.Random(seed)))
    first = data.draw(st.booleans(), label="a plain message first")
    _compare(cls, *((plain, odd) if first else (odd, plain)), odd, clock=data.draw(_CLOCKS, label="clock.now"))


def fuzz(examples: int) -> None:
    """Hypothesis's search, `examples` messages long (run in a process of its own by the tests
    below: a crash of the C tap is then their failure, with the falsifying example)."""

    @hypothesis.settings(
        max_examples=examples, deadline=None, database=None, suppress_health_check=list(hypothesis.HealthCheck)
    )
    @hypothesis.given(data=st.data())
    def check(data: st.DataObject) -> None:
        _fuzz_once(data)

    check()


def _fuzz_apart(examples: int, timeout: float) -> None:
    r = _run_apart(
        f"import sys; sys.path.insert(0, 'tests'); import test_bag_tap; test_bag_tap.fuzz({examples})", timeout
    )
    assert r.returncode == 0, (r.returncode, r.stdout[-6000:] + r.stderr[-6000:])


@needs_c
def test_the_c_tap_does_what_the_python_tap_does_with_odd_classes_and_values() -> None:
    """Generated subclasses of message classes at any level (borrowing other classes' slot
    descriptors, properties, __getattribute__ and __getattr__, plain class attributes, slots
    declared again), odd values in the slots (out of range, of other types, sequences of
    other lengths) and odd clocks: the same bytes, or the same error, as the Python tap."""
    _fuzz_apart(300, timeout=300)  # about 2 s (5 s under make asan)


@pytest.mark.slow
@needs_c
def test_the_c_tap_does_what_the_python_tap_does_at_volume() -> None:
    _fuzz_apart(100_000, timeout=3600)  # about 4 minutes
