"""Soak: a long run must not grow.  Memory is measured with tracemalloc after a warm-up, so the
one-time costs (compiling, caches, the first message of each type) do not count.

    python bench/soak.py                 10 million ringlets, 1 million bus messages
    python bench/soak.py --quick         a tenth of that

The test suite runs a small version of the same workload (tests/test_soak.py).
"""

from __future__ import annotations

import argparse
import gc
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from gen import write_idle, write_toggle  # noqa: E402

from llfsm import ros  # noqa: E402
from llfsm.msgs.geometry_msgs.msg import Twist  # noqa: E402
from llfsm.ros.bus import bus_of  # noqa: E402
from llfsm.runtime import Arrangement, RunContext, SimClock  # noqa: E402
from llfsm.runtime.context import activate  # noqa: E402
from llfsm.targets import load  # noqa: E402


def write_boss(root: Path, target: str) -> Path:
    """Suspends and resumes `target` every few milliseconds: commands, hooks and entries churn."""
    d = root / "boss.machine"
    d.mkdir(parents=True, exist_ok=True)
    (d / "machine.yaml").write_text(
        "states:\n  - name: STOP\n    transitions: [GO]\n  - name: GO\n    transitions: [STOP]\n"
    )
    (d / "State_STOP_OnEntry.py").write_text(f"suspend({target!r})\n")
    (d / "State_GO_OnEntry.py").write_text(f"resume({target!r})\nlog.append(state_name())\ndel log[:-8]\n")
    (d / "State_STOP_Transition_0.expr").write_text("after_ms(3) and is_suspended('toggle_0')\n")
    (d / "State_GO_Transition_0.expr").write_text("after_ms(5)\n")
    (d / "Variables.py").write_text("log: list = []\n")
    return d


def ten_machines(root: Path) -> list[type]:
    paths = [write_toggle(root, f"toggle_{i}") for i in range(6)]
    paths += [write_idle(root, f"idle_{i}") for i in range(3)]
    paths.append(write_boss(root, "toggle_0"))
    return [load(str(p)) for p in paths]


def _mib(n: int) -> str:
    return f"{n / 1024:,.1f} KiB"


def soak_ringlets(classes: list[type], ringlets: int) -> dict[str, float]:
    """Run `ringlets` ringlets of the arrangement (1 ms sim rounds), all traced, after a warm-up
    of another 10% that fills the caches a long run would have filled anyway."""
    arr = Arrangement(classes, clock=SimClock())
    rounds = ringlets // len(classes)
    warm = rounds // 10
    arr.run(duration_ns=warm * 1_000_000)
    gc.collect()
    tracemalloc.start()
    before = tracemalloc.get_traced_memory()[0]
    t = time.perf_counter()
    arr.run(duration_ns=(warm + rounds) * 1_000_000)  # the clock is absolute: warm-up + traced
    elapsed = time.perf_counter() - t
    gc.collect()
    after, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    done = (arr.rounds - warm) * len(classes)
    return {"ringlets": done, "seconds": elapsed, "growth": after - before, "peak": peak - before}


def soak_messages(messages: int) -> dict[str, float]:
    """Publish `messages` Twists to a PULL reader and a PUSH subscriber, spinning as between rounds."""
    ctx = RunContext(SimClock())
    prev = activate(ctx)
    try:
        ros.init()
        bus = bus_of(ctx)
        node = ros.Node("soak")
        pub = node.create_publisher(Twist, "/turtle1/cmd_vel", 10)
        reader = node.create_subscription(Twist, "/turtle1/cmd_vel", None, 10)
        heard = [0]

        def on(msg: Twist) -> None:
            heard[0] += 1

        node.create_subscription(Twist, "/turtle1/cmd_vel", on, 10)
        msg = Twist()

        def burst(n: int) -> None:
            for i in range(n):
                msg.linear.x = float(i % 7)
                pub.publish(msg)
                reader.take()
                if i % 10 == 9:
                    bus.spin_some()

        burst(messages // 10)
        gc.collect()
        tracemalloc.start()
        before = tracemalloc.get_traced_memory()[0]
        t = time.perf_counter()
        burst(messages)
        elapsed = time.perf_counter() - t
        gc.collect()
        after, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        return {
            "messages": messages,
            "seconds": elapsed,
            "growth": after - before,
            "peak": peak - before,
            "heard": heard[0],
        }
    finally:
        activate(prev)


def table(ringlets: int, messages: int) -> list[list[str]]:
    with tempfile.TemporaryDirectory(prefix="llfsm-soak-") as tmp:
        r = soak_ringlets(ten_machines(Path(tmp)), ringlets)
    m = soak_messages(messages)
    return [
        [
            f"{r['ringlets']:,} ringlets, 10 machines",
            f"{r['seconds']:.1f}",
            _mib(int(r["growth"])),
            _mib(int(r["peak"])),
            "< 1 MiB",
        ],
        [
            f"{m['messages']:,} bus messages (PULL + PUSH)",
            f"{m['seconds']:.1f}",
            _mib(int(m["growth"])),
            _mib(int(m["peak"])),
            "< 1 MiB",
        ],
    ]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    scale = 10 if args.quick else 1
    rows = table(10_000_000 // scale, 1_000_000 // scale)
    print("| workload | seconds (traced) | memory growth | peak above start | target |")
    print("|---|---|---|---|---|")
    for row in rows:
        print("| " + " | ".join(row) + " |")


if __name__ == "__main__":
    main()
