"""`llfsm import` benchmarks (issue 31): tables, never asserts.

    python bench/import.py                 time to import generated clfsm machines of 30 to 3000 files
    python bench/import.py --quick         fewer rounds
    python bench/import.py --share DIR     the share of code lines translated, per machine, for
                                           every clfsm machine below DIR (a checkout of MiPal's
                                           gufsm, say), with the constructs left, most common first

The machines are written by the tests' clfsm writer (tests/clfsm_writer.py) with a few lines
of C++ in each section of the kinds the how-to's machines hold (assignments, `cout`, an `if`,
rclcpp calls), guards of CLMacros, so every file goes through the reader, the parser and the
translator.  Each size is timed as the whole command (`llfsm import`, a process: start-up
included) and as the library call alone, interleaved, medians of wall and CPU time.
"""

from __future__ import annotations

import argparse
import collections
import json
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "tests"))

import run  # noqa: E402  (bench/run.py: its timers)
from clfsm_writer import ClfsmState, write_clfsm  # noqa: E402

ENTRY = """int n = count + {i};
if (n > 10 && ok) {{
    cout << "state {i}: " << n << endl;
}} else {{
    count++;
}}
msg.linear.x = {i}.5;
publisher_->publish(msg);
"""
VARIABLES = (
    "int\tcount;\t///< how many\nbool\tok;\t///<\ngeometry_msgs::msg::Twist\tmsg;\t///<\n"
    "rclcpp::Publisher<geometry_msgs::msg::Twist>::SharedPtr\tpublisher_;\t///<\n"
)
INCLUDES = '#include "rclcpp/rclcpp.hpp"\n#include "geometry_msgs/msg/twist.hpp"\n#include "CLMacros.h"\n'


def machine(root: Path, states: int) -> tuple[Path, int]:
    """A clfsm machine of `states` states (MiEditLLFSM writes 14 files for each, with two
    transitions, and 9 for the machine), and its number of files."""
    ss = [
        ClfsmState(
            f"S{i}",
            [(f"S{(i + 1) % states}", "after_ms(100) && count > 2"), (f"S{(i + 2) % states}", "!ok")],
            {"OnEntry": ENTRY.format(i=i), "OnExit": "ok = !ok;\n", "Internal": "count += 2;\n"},
        )
        for i in range(states)
    ]
    d = write_clfsm(root, f"gen{states}", ss, includes=INCLUDES, variables=VARIABLES)
    return d, sum(1 for _ in d.iterdir())


def timings(rounds: int) -> list[list[str]]:
    # deferred: start-up (the library is imported once, after the machines are written)
    from llfsm.importer import import_machines

    rows = []
    tmp = Path(tempfile.mkdtemp(prefix="llfsm-bench-import-"))
    try:
        for states in (2, 21, 214):
            src, files = machine(tmp / "src", states)
            cmd_wall, cmd_cpu, lib_wall = [], [], []
            for k in range(rounds):
                out = tmp / f"out{states}-{k}"
                w, c = run.wall_cpu([sys.executable, "-m", "llfsm", "import", str(src), "-o", str(out)], {})
                cmd_wall.append(w)
                cmd_cpu.append(c)
                shutil.rmtree(out)
                out.mkdir()
                t = time.perf_counter()
                [report] = import_machines([src], out)
                lib_wall.append(time.perf_counter() - t)
                assert report.error is None and report.left_lines == 0, report
                shutil.rmtree(out)
            rows.append(
                [
                    str(files),
                    str(report.code),
                    f"{statistics.median(cmd_wall):.3f}",
                    f"{statistics.median(cmd_cpu):.3f}",
                    f"{statistics.median(lib_wall):.3f}",
                    f"{statistics.median(lib_wall) / files * 1000:.2f}",
                ]
            )
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return rows


def share(root: Path) -> None:
    """The share of translated lines of every clfsm machine below `root`, and why lines were left."""
    out = Path(tempfile.mkdtemp(prefix="llfsm-share-"))
    try:
        r = subprocess.run(
            [sys.executable, "-m", "llfsm", "import", str(root), "-o", str(out), "--format", "json"],
            capture_output=True,
            text=True,
            check=False,
        )
    finally:
        shutil.rmtree(out, ignore_errors=True)
    reports = json.loads(r.stdout)
    rows, reasons, total = [], collections.Counter(), [0, 0]
    for rep in reports:
        name = str(Path(rep["source"]).relative_to(root))
        if rep["error"]:
            rows.append([name, "-", "-", "not imported: " + rep["error"].split(": ", 1)[-1]])
            continue
        code, done = rep["lines"]["code"], rep["lines"]["translated"]
        total[0] += code
        total[1] += done
        rows.append([name, f"{done} of {code}", f"{100 * done / code:.0f}%" if code else "-", ""])
        for x in rep["left"]:
            reasons[re.sub(r"^\S+ (is not a (function|name)|is of a type)", r"a name that \1", x["reason"])] += 1
    rows.append(["all", f"{total[1]} of {total[0]}", f"{100 * total[1] / max(total[0], 1):.0f}%", ""])
    left = [[str(n), why] for why, n in reasons.most_common(25)]
    print(run.render([("Translated share", ["machine", "code lines translated", "share", ""], rows),
                      ("Why statements were left", ["statements", "why"], left)]))  # fmt: skip


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--quick", action="store_true")
    p.add_argument("--share", type=Path, help="report the translated share of the clfsm machines below DIR")
    args = p.parse_args()
    if args.share:
        share(args.share.resolve())
        return
    rows = timings(3 if args.quick else 7)
    head = ["files", "code lines", "llfsm import: wall s", "CPU s", "library: wall s", "ms per file"]
    print(run.render([("Importing a generated clfsm machine (medians)", head, rows)]))


if __name__ == "__main__":
    main()
