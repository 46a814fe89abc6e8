"""What `llfsm run --monitor` costs (SPEC 16, issue 32): every number printed in a table, never
asserted.

    python bench/monitor.py            the table (about a minute)
    python bench/monitor.py --quick    smaller sizes (a smoke run)

The toggle of bench/run.py (two states, guards True, OnEntry `count += 1`: one fired transition
per ringlet, about 100 ns), with one more variable, `limit`, that no ringlet assigns, under the
sim clock; ringlets per CPU second, each contestant once per round in a rotated order, the ratio
to the toggle without a monitor taken in each round, median (min-max) over the rounds.  The
arrangement and the monitor are made before the timer starts.  Rows:

- a property the toggle touches every ringlet (`always: toggle.count >= 0`: count changes in
  every ringlet; it only grows, by `count += 1`, so a lower bound cannot fail there and the check
  is left out, llfsm.monitor.variant) and one it touches in none (`always: toggle.limit > 0`: no
  ringlet can change limit, so no check is compiled in at all); one and ten of each;
- a property every ringlet could falsify (`always: toggle.count < 1000000000`: an upper bound
  of what grows, compared after every ringlet), one and ten (ten bounds of one number: tested
  as one comparison first, llfsm.monitor.variant `_merge_bounds`), and ten different properties
  of the toggle's state and variables (MIXED: comparisons with constants and with the other
  variable, arithmetic, the state; `limit` pinned to its value, terms the bounds decide left out
  and the residue `count % 1` kept by `count += 1`, llfsm.monitor.bounds and variant): the rows
  SPEC 16's targets are read for, since a check runs at every ringlet there;
- `state(toggle)`, which every ringlet changes, in a property whose check folds away at each
  return (`always: state(toggle) in ("A", "B")`) and in one that cannot (`never: state(toggle) ==
  "B" and toggle.count < 0`: the count is compared after each ringlet that enters B);
- the same one safety property judged at every boundary by a watcher (what a monitor costs
  where a property's value can change anywhere: a variable handed to a helper module, a native
  build, an `ltl` with X), and a watcher that judges nothing, the scheduler's watched round
  alone (a Python loop over a round with a call after each ringlet, where the plain loop is a
  bare call);
- an `ltl` formula with X, which only a watcher judges (it counts boundaries), alone and with the
  ten falsifiable properties beside it: those stay compiled into the ringlets.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from gen import write_toggle  # noqa: E402
from run import render  # noqa: E402  (bench/run.py's tables)

from llfsm.monitor import Monitor  # noqa: E402
from llfsm.props.file import PropertySource  # noqa: E402
from llfsm.runtime import SimClock  # noqa: E402
from llfsm.runtime.scheduler import Arrangement  # noqa: E402
from llfsm.targets import load  # noqa: E402

Table = tuple[str, list[str], list[list[str]]]
TOUCHED = "always: toggle.count >= {k}"
UNTOUCHED = "always: toggle.limit > {k}"
FALSIFIABLE = "always: toggle.count < {k}"
NEXT = "ltl: G (toggle.count >= 0 -> X toggle.count > 0)"
#: ten different properties of the toggle's state and variables, as a user might write them
MIXED = [
    "always: toggle.count < 1000000000",
    "always: toggle.count >= 0",
    "never: toggle.count == -1",
    'always: state(toggle) in ("A", "B")',
    'never: state(toggle) == "B" and toggle.count < 0',
    "always: toggle.limit > 0",
    "always: toggle.count < toggle.limit * 100000000",
    "always: toggle.count % 1 == 0",
    "always: toggle.count <= 2000000000",
    'always: state(toggle) != "B" or toggle.count > 0',
]


def contestant(
    cls: type, properties: list[str], targeted: bool = True, idle_watcher: bool = False
) -> Callable[[int], tuple[int, float]]:
    def timed(n: int) -> tuple[int, float]:
        arr = Arrangement([cls], clock=SimClock(1))
        if idle_watcher:
            arr.watcher = lambda _m: 0
        if properties:
            sources = [PropertySource(*p.split(": ", 1)) for p in properties]
            Monitor(sources, [cls], "log", lambda _line: None, targeted=targeted).attach(arr)
        t = time.process_time()
        arr.run(duration_ns=n)
        return arr.ringlets, time.process_time() - t

    return timed


def table(cls: type, n: int, rounds: int) -> Table:
    rows_spec = [
        ("no monitor", []),
        ("1 property the toggle touches every ringlet", [TOUCHED.format(k=0)]),
        ("1 property it touches in none", [UNTOUCHED.format(k=0)]),
        ("10 properties it touches every ringlet", [TOUCHED.format(k=-k) for k in range(10)]),
        ("10 properties it touches in none", [UNTOUCHED.format(k=-k) for k in range(10)]),
        ("1 property every ringlet could falsify", [FALSIFIABLE.format(k=1_000_000_000)]),
        ("10 properties every ringlet could falsify", [FALSIFIABLE.format(k=1_000_000_000 + k) for k in range(10)]),
        ("10 different properties of its state and variables (bench/monitor.py MIXED)", MIXED),
        ('state(toggle), folded away: always: state(toggle) in ("A", "B")', ['always: state(toggle) in ("A", "B")']),
        (
            'state(toggle), not folded: never: state(toggle) == "B" and toggle.count < 0',
            ['never: state(toggle) == "B" and toggle.count < 0'],
        ),
    ]
    named = {name: contestant(cls, props) for name, props in rows_spec}
    named["an ltl with X (a watcher judges it at every boundary)"] = contestant(cls, [NEXT])
    ten = [FALSIFIABLE.format(k=1_000_000_000 + k) for k in range(10)]
    named["the ltl with X and the 10 properties every ringlet could falsify"] = contestant(cls, [NEXT, *ten])
    watcher = "1 property it touches every ringlet, judged by a watcher at every boundary"
    named[watcher] = contestant(cls, [TOUCHED.format(k=0)], targeted=False)
    idle = "a watcher that judges nothing (the scheduler's watched round alone)"
    named[idle] = contestant(cls, [], idle_watcher=True)
    rates: dict[str, list[float]] = {k: [] for k in named}
    names = list(named)
    for r in range(rounds):
        k = r % len(names)
        for name in names[k:] + names[:k]:
            work, t = named[name](n)
            rates[name].append(work / t)
    base = "no monitor"
    # SPEC 16's targets are read as the cost of properties the toggle's ringlets can falsify (a
    # check that runs at every ringlet); the others cost what is left when no check runs
    targets = {
        "1 property every ringlet could falsify": "≤ 1.10",
        "10 properties every ringlet could falsify": "≤ 1.30",
        "10 different properties of its state and variables (bench/monitor.py MIXED)": "≤ 1.30",
        "1 property the toggle touches every ringlet": "(≤ 1.10)",
        "1 property it touches in none": "(≤ 1.10)",
        "10 properties it touches every ringlet": "(≤ 1.30)",
        "10 properties it touches in none": "(≤ 1.30)",
    }
    rows = []
    for name in names:
        cost = [b / x for x, b in zip(rates[name], rates[base], strict=True)]  # time with / time without
        spread = f"{statistics.median(cost):.2f} ({min(cost):.2f}-{max(cost):.2f})"
        rows.append([name, f"{statistics.median(rates[name]):,.0f}", spread, targets.get(name, "")])
    return (
        f"The monitor's cost on the toggle (sim clock): ringlets per CPU second and time per ringlet against no "
        f"monitor, median (min-max) of {rounds} interleaved rounds; {n:,} ringlets a run",
        ["run", "ringlets/s", "time ÷ no monitor", "target (SPEC 16)"],
        rows,
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="smaller sizes, for a smoke run")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="llfsm-bench-monitor-") as tmp_s:
        tmp = Path(tmp_s)
        os.environ["LLFSM_CACHE_DIR"] = str(tmp / "cache")
        d = write_toggle(tmp, "toggle")
        (d / "Variables.py").write_text("count: int = 0\nlimit: int = 10\n")
        cls = load(str(d))
        n, rounds = (100_000, 5) if args.quick else (400_000, 15)
        print(render([table(cls, n, rounds)]), flush=True)
        print(f"load average: {' '.join(f'{x:.1f}' for x in os.getloadavg())} on {os.cpu_count()} cores")


if __name__ == "__main__":
    main()
