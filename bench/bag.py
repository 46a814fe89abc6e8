"""Bags: what recording costs a run, and how fast each library writes MCAP.

    python bench/bag.py            both tables
    python bench/bag.py --quick    smaller sizes (a smoke run)

1. Round rate of a run recording every topic beside the same run not recording, with the bus
   busy, under the sim clock (rounds back to back, never sleeping: the hardest case for a
   writer that must share the interpreter).  A third run has a do-nothing subscriber on every
   topic instead of the recorder: any recorder makes turtlesim sense colours (it does only while
   the colour sensor has a subscriber), so "ratio to subscribed" is what the recorder costs
   beside the cheapest ordinary subscriber (which the bus hands a copy of each message; the
   recorder's taps take the message itself, so the ratio may pass 1 where messages are many).
   Runs alternate; a ratio is the median of the ratios of each interleaved pair.  Beside the
   wall-clock ratio, the same in CPU time of the run's process (its threads, not the writer
   process): the cost to the run itself, which a busy neighbour on a shared machine moves
   less.  The time the writer needs after the last round to empty its queue and close the
   bag is shown apart.  Goal: ratio >= 0.8.
2. Messages written per second to an MCAP bag, the same Twist payload (CDR bytes, made once)
   written by rosbags' writer, by the mcap library's writer, and by llfsm's BagWriter (the
   mcap writer behind llfsm's spool, with its rosbag2 metadata), interleaved, medians.

Every number is printed, never asserted.
"""

from __future__ import annotations

import argparse
import os
import platform
import shutil
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from run import Table, render  # noqa: E402  (one table renderer for every benchmark)

PUBLISHER = """\
states:
  - name: INITIAL
    transitions: [SEND]
  - name: SEND
    transitions: [SEND]
"""


def write_publisher(root: Path, name: str, every: int = 1) -> Path:
    """A machine that publishes a Twist on its own topic every `every` ringlets."""
    d = root / f"{name}.machine"
    d.mkdir(parents=True, exist_ok=True)
    (d / "machine.yaml").write_text(PUBLISHER)
    (d / "Includes.py").write_text("from llfsm import ros\nfrom llfsm.msgs.geometry_msgs.msg import Twist\n")
    (d / "Variables.py").write_text("node: ros.Node\npub: ros.Publisher\nmsg: Twist\nn: int = 0\n")
    (d / "State_INITIAL_OnEntry.py").write_text(
        f"ros.init()\nnode = ros.Node('{name}')\npub = node.create_publisher(Twist, '/{name}/cmd_vel', 10)\n"
        "msg = Twist()\n"
    )
    (d / "State_INITIAL_Transition_0.expr").write_text("True\n")
    (d / "State_SEND_Transition_0.expr").write_text("False\n")
    (d / "State_SEND_Internal.py").write_text(
        f"n += 1\nif n % {every} == 0:\n    msg.linear.x = float(n)\n    pub.publish(msg)\n"
    )
    return d


class NullReader:
    """A reader that drops what it gets: the run with it does what the run does for any
    subscriber (turtlesim senses colours only while /turtleN/color_sensor has one)."""

    def _deliver(self, msg: object) -> None:
        pass


class Run(NamedTuple):
    """One sim-clock run of the machines beside turtlesim."""

    rate: float  # rounds per wall second
    cpu_rate: float  # rounds per CPU second of the run's process (all its threads)
    closing: float  # seconds to close the bag after the last round
    recorded: int  # messages in the bag
    rounds: int


def one_run(classes: list[type], seconds: float, record: Path | None, subscribed: bool = False) -> Run:
    from llfsm.bag import RunBags
    from llfsm.nodes import NodeOptions, start
    from llfsm.ros import bus_of
    from llfsm.runtime import Arrangement, RunContext, SimClock
    from llfsm.runtime.context import activate

    ctx = RunContext(SimClock())
    prev = activate(ctx)
    try:
        bus = bus_of(ctx)
        bus.log_stream = open(os.devnull, "w")  # noqa: SIM115
        bus.initialised = True
        start("turtlesim", ctx, NodeOptions())
    finally:
        activate(prev)
    bags = RunBags(record=str(record)) if record is not None else None
    if subscribed:
        bus.add_tap(lambda topic: topic.readers.append(NullReader()))  # type: ignore[arg-type]
    if bags is not None:
        bags.attach(bus)
    arr = Arrangement(classes, context=ctx)
    c0 = time.process_time()
    t0 = time.perf_counter()
    result = arr.run(round(seconds * 1e9))
    t1 = time.perf_counter()
    c1 = time.process_time()
    recorded = 0
    if bags is not None:
        assert bags.close() is None
        recorded = (bags.recorder.count or 0) if bags.recorder else 0
    t2 = time.perf_counter()
    return Run(result.rounds / (t1 - t0), result.rounds / (c1 - c0), t2 - t1, recorded, result.rounds)


REPO = HERE.parent
WORKLOADS = (  # (label, machines: a list of paths, or (count, publish every N ringlets))
    (
        "the follower demo: ros2_blind_turtle_bot, turtle_follower, turtlesim (two turtles)",
        [REPO / "machines" / "ros2_blind_turtle_bot.machine", REPO / "machines" / "turtle_follower.machine"],
    ),
    ("10 machines publishing a Twist at 100 Hz of run time each, turtlesim", (10, 10)),
    ("3 machines publishing a Twist in every ringlet (1 kHz each), turtlesim: the worst case", (3, 1)),
)


def section_recording(tmp: Path, quick: bool) -> Table:
    from llfsm.targets import load

    # Long enough that a run takes half a second or more of wall time: shorter runs measure the
    # start of a run (imports, the first batches) more than its rounds.
    seconds = 60.0 if quick else 300.0
    repeats = 3 if quick else 7
    rows = []
    for label, machines in WORKLOADS:
        if isinstance(machines, tuple):
            count, every = machines
            paths = [write_publisher(tmp, f"pub{every}_{i}", every) for i in range(count)]
        else:
            paths = machines
        classes = [load(str(p)) for p in paths]
        plain: list[Run] = []
        sub: list[Run] = []
        rec: list[Run] = []
        for i in range(repeats):  # interleaved: plain, subscribed, recording, plain, ...
            plain.append(one_run(classes, seconds, None))
            sub.append(one_run(classes, seconds, None, subscribed=True))
            bag = tmp / f"bag{i}"
            rec.append(one_run(classes, seconds, bag))
            shutil.rmtree(bag)

        def ratio(a: list[Run], b: list[Run], cpu: bool = False) -> str:
            """The median of the ratios of each interleaved pair: a slow spell of the machine
            slows both runs of a pair more often than runs far apart."""
            if cpu:
                return f"{statistics.median(y.cpu_rate / x.cpu_rate for x, y in zip(a, b, strict=True)):.2f}"
            return f"{statistics.median(y.rate / x.rate for x, y in zip(a, b, strict=True)):.2f}"

        last = rec[-1]
        rows.append(
            [
                label,
                f"{last.recorded / (last.rounds / 1000):,.0f}",
                f"{statistics.median(r.rate for r in plain):,.0f}",
                f"{statistics.median(r.rate for r in sub):,.0f}",
                f"{statistics.median(r.rate for r in rec):,.0f}",
                f"**{ratio(plain, rec)}**",
                ratio(plain, rec, cpu=True),
                f"**{ratio(sub, rec)}**",
                f"{statistics.median(r.closing for r in rec):.2f} s",
            ]
        )
    return (
        f"Round rate with --record beside without (sim clock, {seconds:g} s of run time per run; "
        f"medians of {repeats} interleaved runs of each; goal: ratio >= 0.8)",
        [
            "bus",
            "messages per s of run time",
            "rounds/s: plain",
            "subscribed, not recording",
            "recording",
            "ratio to plain",
            "same, in CPU time of the run",
            "ratio to subscribed",
            "closing after the run",
        ],
        rows,
    )


def section_writers(tmp: Path, quick: bool) -> Table:
    from mcap.writer import CompressionType
    from mcap.writer import Writer as McapWriter
    from rosbags.rosbag2 import StoragePlugin
    from rosbags.rosbag2 import Writer as RosbagsWriter

    from llfsm.bag.typesupport import TypeSupport
    from llfsm.bag.writer import BagWriter, qos_profile
    from llfsm.msgs.geometry_msgs.msg import Twist

    n = 50_000 if quick else 200_000
    msg = Twist()
    msg.linear.x = 1.5
    ts = TypeSupport()
    data = ts.serializer(Twist)(msg)
    definition, type_hash = ts.definition("geometry_msgs/msg/Twist")
    counter = iter(range(10**9))

    def rosbags(plugin: StoragePlugin) -> float:
        w = RosbagsWriter(tmp / f"r{next(counter)}", version=9, storage_plugin=plugin)
        w.open()
        c = w.add_connection("/cmd_vel", "geometry_msgs/msg/Twist", msgdef=definition, rihs01=type_hash)
        t = time.perf_counter()
        for i in range(n):
            w.write(c, i, data)
        w.close()
        return n / (time.perf_counter() - t)

    def mcap_library() -> float:
        path = tmp / f"m{next(counter)}.mcap"
        with open(path, "wb") as f:
            w = McapWriter(f, chunk_size=64 * 1024, compression=CompressionType.NONE, enable_crcs=False)
            w.start(profile="ros2", library="bench")
            s = w.register_schema("geometry_msgs/msg/Twist", "ros2msg", definition.encode())
            c = w.register_channel("/cmd_vel", "cdr", s, {"topic_type_hash": type_hash})
            t = time.perf_counter()
            for i in range(n):
                w.add_message(c, log_time=i, data=data, publish_time=i)
            w.finish()
        return n / (time.perf_counter() - t)

    def llfsm_writer() -> float:
        w = BagWriter(tmp / f"l{next(counter)}")
        c = w.connection("/cmd_vel", "geometry_msgs/msg/Twist", definition, type_hash, [qos_profile()])
        t = time.perf_counter()
        for i in range(n):
            w.write(c, i, data)
        w.sync()
        w.close()
        return n / (time.perf_counter() - t)

    writers: list[tuple[str, Callable[[], float]]] = [
        ("rosbags Writer, MCAP", lambda: rosbags(StoragePlugin.MCAP)),
        ("mcap Writer (uncompressed 64 KiB chunks, no CRCs)", mcap_library),
        ("llfsm BagWriter (mcap Writer + spool + rosbag2 metadata)", llfsm_writer),
        ("rosbags Writer, sqlite3 (for comparison)", lambda: rosbags(StoragePlugin.SQLITE3)),
    ]
    results: dict[str, list[float]] = {name: [] for name, _ in writers}
    for _ in range(3 if quick else 5):  # interleaved rounds of all writers
        for name, fn in writers:
            results[name].append(fn())
    base = statistics.median(results[writers[0][0]])
    rows = []
    for name, _ in writers:
        m = statistics.median(results[name])
        rows.append([name, f"{m:,.0f}", f"{m / base:.2f}"])
    return (
        f"MCAP writing, messages per second ({n:,} Twists of {len(data)} bytes; medians)",
        ["writer", "messages/s", "vs rosbags"],
        rows,
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="smaller sizes, for a smoke run")
    args = ap.parse_args()
    os.environ.setdefault("LLFSM_CACHE_DIR", tempfile.mkdtemp(prefix="llfsm-bench-cache-"))
    stamp = time.strftime("%Y-%m-%d")
    from llfsm.bag import typesupport
    from llfsm.sim import world

    built = {"the recorder's tap": typesupport._Tap is not None, "the stroke painter": world._c_fill_stroke is not None}
    parts = ", ".join(f"{name} {'in C' if c else 'in Python (the C part is not built)'}" for name, c in built.items())
    print(f"llfsm bag benchmarks: Python {platform.python_version()}, {os.cpu_count()} CPUs, {stamp}; {parts}\n")
    with tempfile.TemporaryDirectory(prefix="llfsm-bench-bag-") as tmp:
        for section in (section_recording, section_writers):
            folder = Path(tmp) / section.__name__
            folder.mkdir()
            print(render([section(folder, args.quick)]), flush=True)


if __name__ == "__main__":
    main()
