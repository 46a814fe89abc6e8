"""What the debugger costs a run (docs/debug.md, "What it costs"): tables, never asserts.

    .venv/bin/python bench/debug.py [--quick]

Each workload of bench/run.py's speed section (a toggle, 10 and 100 of them firing every
ringlet, 10 and 100 idle machines), and the how-to's suspend/resume pair driving turtlesim,
runs under the sim clock in five ways: plain (no debugger),
with a debugger attached and nothing asked of it (what every `--transport dds` run has), with
`--break` on a state that is never reached, with `--history 10000`, and with both.  The ways
alternate inside each round, and a ratio is the median over the rounds of (way / plain in the
same round), with its spread; times are CPU time of the process.  The toggles here have a third
state C, behind a guard that never holds, so that a breakpoint on a state can be set without
ever pausing (`state(toggle_0) == "C"`; idle machines: their END).
"""

from __future__ import annotations

import argparse
import io
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from gen import write_idle  # noqa: E402
from run import cpu, llfsm_cmd  # noqa: E402

WAYS = ("plain", "debugger", "break on a state", "history 10000", "break + history")
#: The how-to's suspend/resume pair with turtlesim on the bus: machines that do a robot's work.
HOW_TO = "how-to pair + turtlesim"


def write_exit_toggle(root: Path, name: str) -> Path:
    """bench/gen.py's toggle (A <-> B, OnEntry counts, one fired transition per ringlet) with a
    state C that A leads to first, behind a guard that never holds."""
    d = root / f"{name}.machine"
    d.mkdir(parents=True, exist_ok=True)
    (d / "machine.yaml").write_text(
        "states:\n  - name: A\n    transitions: [C, B]\n  - name: B\n    transitions: [A]\n  - name: C\n"
    )
    (d / "State_A_Transition_0.expr").write_text("count < 0\n")
    (d / "State_A_Transition_1.expr").write_text("True\n")
    (d / "State_B_Transition_0.expr").write_text("True\n")
    for s in "AB":
        (d / f"State_{s}_OnEntry.py").write_text("count += 1\n")
    (d / "Variables.py").write_text("count: int = 0\n")
    return d


def build(tmp: Path) -> tuple[list[type], list[type]]:
    from llfsm.targets import load

    for i in range(100):
        write_exit_toggle(tmp / "src", f"toggle_{i}")
        write_idle(tmp / "src", f"idle_{i}")
    out = tmp / "out"
    subprocess.run([*llfsm_cmd(), "build", "-q", str(tmp / "src"), "-o", str(out)], check=True)
    return [load(str(out / f"toggle_{i}.py")) for i in range(100)], [
        load(str(out / f"idle_{i}.py")) for i in range(100)
    ]


def timed(classes: list[type], way: str, n: int, turtlesim: bool = False) -> float:
    """Ringlets per CPU second of `classes` run for about n ringlets, debugged `way` (with
    turtlesim on the bus: rounds of 1 ms, as `llfsm run --clock sim --node turtlesim`)."""
    from llfsm.debug.debugger import Debugger
    from llfsm.runtime import Arrangement, RunContext, SimClock

    period = 1_000_000 if turtlesim else 1_000
    ctx = RunContext(SimClock(period))
    if turtlesim:
        from llfsm.nodes import NodeOptions, start
        from llfsm.ros.bus import bus_of
        from llfsm.runtime.context import activate

        prev = activate(ctx)
        try:
            bus = bus_of(ctx)
            bus.log_stream = io.StringIO()  # turtlesim's start-up lines are not the table's
            bus.init()
            start("turtlesim", ctx, NodeOptions())
        finally:
            activate(prev)
    arr = Arrangement(classes, context=ctx)
    if way != "plain":
        history = 10_000 if "history" in way else None
        d = Debugger(arr, history=history)
        if "break" in way:
            first = classes[0]
            unreached = "C" if "C" in first.STATES else "END"
            d.add_break(f'state({first.NAME}) == "{unreached}"')
    rounds = max(1, n // len(classes))
    t = cpu(lambda: arr.run(duration_ns=rounds * period))
    return arr.rounds * len(classes) / t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="llfsm-bench-debug-"))
    toggles, idles = build(tmp)
    from llfsm.targets import load

    machines = HERE.parent / "machines"
    pair = [load(str(machines / f"{name}.machine")) for name in ("ros2_turtle_suspend_resume", "ros2_blind_turtle_bot")]
    workloads: dict[str, list[type]] = {
        "toggle": toggles[:1],
        "fired 10": toggles[:10],
        "fired 100": toggles[:100],
        "idle 10": idles[:10],
        "idle 100": idles[:100],
        HOW_TO: pair,
    }
    n = 100_000 if args.quick else 400_000
    rounds = 3 if args.quick else 9
    rates: dict[tuple[str, str], list[float]] = {(w, way): [] for w in workloads for way in WAYS}
    for r in range(rounds):
        for w, classes in workloads.items():
            order = WAYS if r % 2 == 0 else WAYS[::-1]
            for way in order:
                size = n // 20 if w == HOW_TO else n  # 1 ms rounds, turtlesim's timer in most of them
                rates[(w, way)].append(timed(classes, way, size, turtlesim=w == HOW_TO))
    print("Ringlets per CPU second, and each way's ratio to plain (median over rounds, min-max):\n")
    head = "| workload | plain | " + " | ".join(WAYS[1:]) + " |"
    print(head)
    print("|" + "---|" * (len(WAYS) + 1))
    for w in workloads:
        plain = rates[(w, "plain")]
        cells = [f"{statistics.median(plain):,.0f}/s"]
        for way in WAYS[1:]:
            ratios = [p / q for p, q in zip(plain, rates[(w, way)], strict=True)]
            cells.append(f"{statistics.median(ratios):.3f} ({min(ratios):.2f}-{max(ratios):.2f})")
        print(f"| {w} | " + " | ".join(cells) + " |")
    print(
        f"\n(ratio = time with the way / time plain: 1.05 is 5% slower; {rounds} rounds, {time.strftime('%Y-%m-%d')})"
    )


if __name__ == "__main__":
    main()
