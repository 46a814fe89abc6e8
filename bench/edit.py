"""Writing machines (issue 29): what the editor and the structure commands cost, in tables.

    python bench/edit.py [--repeats N] [--quick]

- layout: llfsm's layered layout (llfsm.diagram.layout, through llfsm.diagram.svg.layout, the
  page's) of whole machines of 50 to 300 states, of two shapes: a chain with random shortcuts
  (each state one or two transitions more to anywhere) and the how-to's habit (every state also
  goes to END on `not ros.ok()`).  Goal: a 300-state machine in at most 1 s.
- edit: each structure operation of llfsm.edit planned and applied on a copy of a 300-state
  machine (planning reads and parses machine.yaml with its comments; applying writes the files).

CPU time of this process (time.process_time), the median over interleaved repeats (min-max
beside it): the machine is shared.  The frontend's numbers (diagnostics after a keystroke, a
folder of machines opened, the server's memory) are added to this file by the editor's branch.
"""

from __future__ import annotations

import argparse
import random
import shutil
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from gen import write_big  # noqa: E402

from llfsm import edit  # noqa: E402
from llfsm.diagram.svg import layout  # noqa: E402


def description(n: int, shape: str, seed: int = 1) -> dict[str, Any]:
    """A machine's description (the web view's shape) of n states."""
    rnd = random.Random(seed)
    names = [f"S{i}" for i in range(n - 1)] + ["END"]
    states = []
    for i, s in enumerate(names):
        if s == "END":
            targets: list[str] = []
        elif shape == "shortcuts":
            targets = [names[i + 1]] + [names[rnd.randrange(n)] for _ in range(rnd.randint(1, 2))]
        else:  # "to END": the how-to's `not ros.ok()` first, then the next state
            targets = ["END", names[i + 1]]
        states.append(
            {
                "name": s,
                "transitions": [
                    {"index": k, "target": t, "guard": f"after_ms({100 * k})"} for k, t in enumerate(targets)
                ],
                "accepting": not targets,
            }
        )
    return {"name": "big", "description": "", "states": states, "initial": "S0", "suspend": None}


def cpu(fn: Callable[[], object]) -> float:
    t = time.process_time()
    fn()
    return time.process_time() - t


def cell(times: list[float]) -> str:
    return f"{statistics.median(times) * 1000:,.0f} ms ({min(times) * 1000:,.0f}-{max(times) * 1000:,.0f})"


def table(title: str, head: list[str], rows: list[list[str]]) -> None:
    print(f"\n### {title}\n")
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for r in rows:
        print("| " + " | ".join(r) + " |")


def bench_layout(sizes: list[int], repeats: int) -> None:
    cases = [(n, shape, description(n, shape)) for n in sizes for shape in ("shortcuts", "to END")]
    times: dict[tuple[int, str], list[float]] = {(n, s): [] for n, s, _ in cases}
    for r in range(repeats):
        for n, shape, desc in cases[r % len(cases) :] + cases[: r % len(cases)]:  # rotated: interleaved
            times[(n, shape)].append(cpu(lambda desc=desc: layout(desc)))
    rows = []
    for n, shape, desc in cases:
        transitions = sum(len(s["transitions"]) for s in desc["states"])
        rows.append(
            [
                str(n),
                shape,
                str(transitions),
                cell(times[(n, shape)]),
                "yes" if n < 300 or statistics.median(times[(n, shape)]) <= 1 else "NO",
            ]
        )
    table("Layered layout of a whole machine (CPU)", ["states", "shape", "transitions", "layout", "within 1 s"], rows)


def bench_edit(states: int, repeats: int) -> None:
    ops: list[tuple[str, Callable[[Path], edit.Change]]] = [
        ("state add", lambda m: edit.state_add(m, "NEW")),
        ("state rename", lambda m: edit.state_rename(m, "S10", "RENAMED")),
        ("state remove", lambda m: edit.state_remove(m, "S10")),
        ("transition add", lambda m: edit.transition_add(m, "S10", "S20", guard="after(1)", priority=0)),
        ("transition move", lambda m: edit.transition_move(m, "S10", 1, 0)),
        ("transition remove", lambda m: edit.transition_remove(m, "S10", 0)),
        ("set guard", lambda m: edit.set_guard(m, "S10", 0, "x > 1")),
    ]
    plan_t: dict[str, list[float]] = {name: [] for name, _ in ops}
    apply_t: dict[str, list[float]] = {name: [] for name, _ in ops}
    files: dict[str, int] = {}
    with tempfile.TemporaryDirectory() as tmp:
        master = write_big(Path(tmp), "big", states)
        for r in range(repeats):
            for name, op in ops[r % len(ops) :] + ops[: r % len(ops)]:
                work = Path(tmp) / f"w{r}" / "big.machine"
                shutil.copytree(master, work)
                t = time.process_time()
                change = op(work)
                plan_t[name].append(time.process_time() - t)
                apply_t[name].append(cpu(lambda change=change: edit.apply(change)))
                files[name] = len(change.writes)
                shutil.rmtree(work)
    rows = [[name, str(files[name]), cell(plan_t[name]), cell(apply_t[name])] for name, _ in ops]
    table(f"Structure operations on a {states}-state machine (CPU)", ["operation", "files", "plan", "apply"], rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--quick", action="store_true", help="smaller sizes (a smoke run)")
    args = ap.parse_args()
    bench_layout([50, 100] if args.quick else [50, 100, 200, 300], args.repeats)
    bench_edit(50 if args.quick else 300, args.repeats)


if __name__ == "__main__":
    main()
