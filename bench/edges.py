"""What issue 22's rough edges cost where they touch a hot path.

    .venv/bin/python bench/edges.py [--quick]

Prints three tables, each a ratio of two contestants timed in the same process, interleaved
(A, B, A, B...), the median over the rounds with the spread (min-max), in CPU time:

- a log line (`node.get_logger().info(...)` to a stream that discards it) of a node that
  publishes it on /rosout (every node now, as in ROS 2) over one that does not
  (`enable_rosout=False`), in process under the sim clock, with no /rosout reader and with one;
- a publish on the DDS transport that no other process reads (a Twist): llfsm now asks DDS
  whether a reader has matched since the run last polled before it drops the message (the
  first message of a publisher that appears while `bag record` runs is no longer lost), over
  the same publish without that question (the code as it was);
- `llfsm check` of a tree of machines whose Includes.py import messages and helper modules:
  with the import rules (LF042, LF043, LF109: folder listings, never an import) over the same
  check without them.
"""

from __future__ import annotations

import argparse
import io
import os
import shutil
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

HERE = Path(__file__).resolve()
sys.path.insert(0, str(HERE.parent.parent))

Table = tuple[str, list[str], list[list[str]]]


def interleaved(
    a: Callable[[], float], b: Callable[[], float], rounds: int
) -> tuple[float, float, float, float, float]:
    """(median a, median b, median of a/b, and the spread of a/b as min, max) over `rounds`."""
    ta, tb, ratios = [], [], []
    for i in range(rounds):
        first, second = (a, b) if i % 2 == 0 else (b, a)
        x = first()
        y = second()
        xa, xb = (x, y) if i % 2 == 0 else (y, x)
        ta.append(xa)
        tb.append(xb)
        ratios.append(xa / xb)
    return statistics.median(ta), statistics.median(tb), statistics.median(ratios), min(ratios), max(ratios)


def cpu(fn: Callable[[], None]) -> float:
    t0 = time.process_time()
    fn()
    return time.process_time() - t0


# -- a log line ---------------------------------------------------------------------------------------


def _log_case(reader: bool, n: int, rounds: int) -> list[str]:
    """One row: a log line with and without /rosout, with or without a /rosout reader."""
    from llfsm import ros
    from llfsm.msgs.rcl_interfaces.msg import Log
    from llfsm.ros.bus import bus_of
    from llfsm.runtime import RunContext, SimClock
    from llfsm.runtime.context import activate

    ctx = RunContext(SimClock())
    activate(ctx)
    bus = bus_of(ctx)
    bus.log_stream = io.StringIO()
    ros.init()
    with_rosout = ros.Node("talker")
    without = ros.Node("quiet", enable_rosout=False)
    got: list[int] = []
    if reader:
        ros.Node("listener").create_subscription(Log, "/rosout", lambda m: got.append(1), 1000)

    def run(node: ros.Node) -> float:
        logger = node.get_logger()

        def go() -> None:
            for _ in range(n):
                logger.info("tick")
            bus.log_stream = io.StringIO()
            bus.spin_some()
            got.clear()

        return cpu(go) / n

    a, b, ratio, lo, hi = interleaved(lambda: run(with_rosout), lambda: run(without), rounds)
    case = "one /rosout subscription" if reader else "nobody reads /rosout"
    return [case, f"{a * 1e6:.2f}", f"{b * 1e6:.2f}", f"{ratio:.2f} ({lo:.2f}-{hi:.2f})"]


def log_lines(n: int, rounds: int) -> Table:
    rows = [_log_case(reader, n, rounds) for reader in (False, True)]
    title = f"A log line, in process, sim clock: µs of CPU per call; median of {rounds} interleaved rounds of {n:,}"
    return title, ["case", "with /rosout", "enable_rosout=False", "ratio"], rows


# -- a publish nobody elsewhere reads -----------------------------------------------------------------


def dds_publish(n: int, rounds: int) -> Table:
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "OFF"  # this process only: nothing on the network
    from llfsm import ros
    from llfsm.msgs.geometry_msgs.msg import Twist
    from llfsm.ros.bus import bus_of
    from llfsm.ros.transports import dds
    from llfsm.runtime import RunContext, WallClock
    from llfsm.runtime.context import activate

    ctx = RunContext(WallClock())
    ctx.transport = dds.DdsTransport(96)
    activate(ctx)
    bus_of(ctx).initialised = True
    pub = ros.Node("talker", enable_rosout=False).create_publisher(Twist, "/cmd", 10)
    msg = Twist()
    now = dds._Writer.write

    def before(self: dds._Writer, m: object) -> None:  # the code as it was: `matched` as last polled
        if (self.matched or self.keeps) and not self.t.closed:
            dds._write(self.writer, self.cdr(m))

    def run(write: Callable[..., None]) -> float:
        dds._Writer.write = write  # type: ignore[method-assign]
        try:
            return cpu(lambda: [pub.publish(msg) for _ in range(n)]) / n
        finally:
            dds._Writer.write = now  # type: ignore[method-assign]

    a, b, ratio, lo, hi = interleaved(lambda: run(now), lambda: run(before), rounds)
    ctx.transport.close()
    title = (
        f"A publish on the DDS transport that no other process reads (Twist): µs of CPU per publish; "
        f"median of {rounds} interleaved rounds of {n:,}"
    )
    row = [f"{a * 1e6:.2f}", f"{b * 1e6:.2f}", f"{ratio:.2f} ({lo:.2f}-{hi:.2f})"]
    return title, ["asks DDS before dropping (now)", "as last polled (before)", "ratio"], [row]


# -- llfsm check ------------------------------------------------------------------------------------


def check_imports(machines: int, rounds: int) -> Table:
    from llfsm.lang import check as check_package
    from llfsm.lang.check import code, diagnose, includes

    root = Path(tempfile.mkdtemp(prefix="llfsm-bench-"))
    try:
        (root / "helpers.py").write_text("X = 1\n")
        for i in range(machines):
            d = root / f"m{i}.machine"
            d.mkdir()
            (d / "machine.yaml").write_text("states:\n  - name: A\n    transitions: [END]\n  - name: END\n")
            (d / "Includes.py").write_text(
                "from llfsm import ros\nfrom llfsm.msgs.geometry_msgs.msg import Twist, Pose\n"
                "from llfsm.msgs.std_msgs.msg import String\nfrom llfsm.msgs.sensor_msgs.msg import LaserScan\n"
                "import helpers\nimport math\n"
            )
            (d / "State_A_OnEntry.py").write_text("t = Twist()\nprint(t, Pose(), String(), LaserScan(), helpers.X)\n")
            (d / "State_A_Transition_0.expr").write_text("after_ms(10)\n")
        real_includes, real_code = includes.imports, code.imports

        def run(with_rules: bool) -> float:
            if not with_rules:
                includes.imports = code.imports = lambda *a: None  # type: ignore[assignment]
            try:
                return cpu(lambda: diagnose([root], jobs=1)) / machines
            finally:
                includes.imports, code.imports = real_includes, real_code

        assert check_package  # (the package under test)
        a, b, ratio, lo, hi = interleaved(lambda: run(True), lambda: run(False), rounds)
    finally:
        shutil.rmtree(root)
    title = (
        f"`llfsm check`, {machines} machines each importing 4 message modules and a helper: ms of CPU per "
        f"machine; median of {rounds} interleaved rounds"
    )
    row = [f"{a * 1e3:.3f}", f"{b * 1e3:.3f}", f"{ratio:.2f} ({lo:.2f}-{hi:.2f})"]
    return title, ["with the import rules", "without them", "ratio"], [row]


def show(table: Table) -> None:
    title, head, rows = table
    print(f"### {title}\n")
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for r in rows:
        print("| " + " | ".join(r) + " |")
    print()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smaller sizes (a smoke run)")
    args = parser.parse_args()
    q = args.quick
    show(log_lines(2_000 if q else 20_000, 3 if q else 9))
    show(dds_publish(5_000 if q else 100_000, 3 if q else 9))
    show(check_imports(20 if q else 200, 3 if q else 9))


if __name__ == "__main__":
    main()
