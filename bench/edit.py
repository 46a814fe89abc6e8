"""Writing machines (issue 29): what the editor and the structure commands cost, in tables.

    python bench/edit.py [--repeats N] [--quick]

- layout: llfsm's layered layout (llfsm.diagram.layout, through llfsm.diagram.svg.layout, the
  page's) of whole machines of 50 to 300 states, of two shapes: a chain with random shortcuts
  (each state one or two transitions more to anywhere) and the how-to's habit (every state also
  goes to END on `not ros.ok()`).  Goal: a 300-state machine in at most 1 s.
- edit: each structure operation of llfsm.edit planned and applied on a copy of a 300-state
  machine (planning reads and parses machine.yaml with its comments; applying writes the files).
- page (`llfsm edit` through the real page in Chromium and the real server process, wall time):
  from the last key of a typo in a state's OnEntry (a 50-state machine) to the state's mark on
  the diagram, and from the key that fixes it to the mark gone (p50, p95); a folder of 20
  machines of 30 states: the server's start to its printed address, the page's load to the
  first diagram; the server with 100 machines open (each read, checked and drawn): resident
  memory.  Needs /usr/bin/chromium and the page built (`make web`); `--no-page` leaves it out.

CPU time of this process (time.process_time), the median over interleaved repeats (min-max
beside it): the machine is shared.  The page's figures are wall time (what a user waits).
"""

from __future__ import annotations

import argparse
import http.client
import json
import random
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
CHROMIUM = "/usr/bin/chromium"
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


def serve(folder: Path) -> tuple[subprocess.Popen[str], str, float]:
    t0 = time.perf_counter()
    proc = subprocess.Popen(
        [sys.executable, "-m", "llfsm", "edit", str(folder), "--web", "127.0.0.1:0"],
        stderr=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        text=True,
        cwd=HERE.parent,
    )
    assert proc.stderr is not None
    for line in proc.stderr:
        m = re.search(r"http://\S+", line)
        if m:
            return proc, m.group(0), time.perf_counter() - t0
    raise SystemExit("the editor printed no address")


def stop(proc: subprocess.Popen[str]) -> None:
    proc.terminate()
    proc.wait(15)


def pct(values: list[float], q: float) -> float:
    s = sorted(values)
    return s[min(len(s) - 1, round(q * (len(s) - 1)))]


def diagnostics(browser: object, rounds: int) -> tuple[list[float], list[float]]:
    with tempfile.TemporaryDirectory() as t:
        write_big(Path(t), "fifty", 50)
        proc, url, _ = serve(Path(t))
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 900})  # type: ignore[attr-defined]
            page.goto(url)
            state = page.locator('.state[data-state="S10"]')
            state.click()
            page.wait_for_selector('.state[data-state="S10"][aria-selected="true"]')
            page.get_by_role("textbox", name="OnEntry", exact=True).click()
            page.keyboard.press("Control+End")
            marked, cleared = [], []
            for _ in range(rounds):
                t0 = time.perf_counter()
                page.keyboard.press(":")  # a line holding `:`: a syntax error
                page.wait_for_selector('.state[data-state="S10"][data-problem="error"]', timeout=10_000)
                marked.append(time.perf_counter() - t0)
                t0 = time.perf_counter()
                page.keyboard.press("Backspace")
                page.wait_for_selector('.state[data-state="S10"]:not([data-problem])', timeout=10_000)
                cleared.append(time.perf_counter() - t0)
            page.close()
            return marked, cleared
        finally:
            stop(proc)


def first_diagram(browser: object, rounds: int) -> tuple[list[float], list[float]]:
    starts, draws = [], []
    with tempfile.TemporaryDirectory() as t:
        for i in range(20):
            write_big(Path(t), f"m{i:02d}", 30)
        for _ in range(rounds):
            proc, url, started = serve(Path(t))
            try:
                page = browser.new_page(viewport={"width": 1280, "height": 900})  # type: ignore[attr-defined]
                t0 = time.perf_counter()
                page.goto(url)
                page.wait_for_selector(".diagram-box .state", timeout=20_000)
                draws.append(time.perf_counter() - t0)
                starts.append(started)
                page.close()
            finally:
                stop(proc)
    return starts, draws


def resident(n: int = 100) -> float:
    with tempfile.TemporaryDirectory() as t:
        for i in range(n):
            write_big(Path(t), f"m{i:03d}", 30)
        proc, url, _ = serve(Path(t))
        try:
            port = int(url.rsplit(":", 1)[1].strip("/"))
            for i in range(n):
                conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
                body = json.dumps({"machine": f"m{i:03d}"})
                conn.request("POST", "/api/machine", body=body, headers={"Content-Type": "application/json"})
                assert conn.getresponse().status == 200
                conn.close()
            time.sleep(1.5)  # a look at the disk or two
            status = Path(f"/proc/{proc.pid}/status").read_text()
            return int(re.search(r"VmRSS:\s+(\d+)", status).group(1)) / 1024  # type: ignore[union-attr]
        finally:
            stop(proc)


def bench_page(rounds: int) -> None:
    # deferred: the page's measures alone need Playwright (and Chromium)
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=["--headless", "--no-sandbox", "--disable-gpu"])
        marked, cleared = diagnostics(browser, rounds)
        starts, draws = first_diagram(browser, max(3, rounds // 6))
        browser.close()
    rss = resident()

    def ms(a: float, b: float) -> list[str]:
        return [f"{a * 1000:,.0f} ms", f"{b * 1000:,.0f} ms"]

    rows = [
        ["a typo to its mark on the diagram (50 states)", *ms(pct(marked, 0.5), pct(marked, 0.95)), "p95 <= 300 ms"],
        ["the fix to the mark gone", *ms(pct(cleared, 0.5), pct(cleared, 0.95)), ""],
        ["20 x 30 states: the server's start to its address", *ms(statistics.median(starts), max(starts)), ""],
        ["20 x 30 states: the page's load to the first diagram", *ms(statistics.median(draws), max(draws)), "<= 1 s"],
        ["100 machines of 30 states open: resident memory", f"{rss:.0f} MB", "", "<= 150 MB"],
    ]
    table(f"llfsm edit through the page (wall time, {rounds} rounds)", ["measure", "p50", "p95 or worst", "goal"], rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--quick", action="store_true", help="smaller sizes (a smoke run)")
    ap.add_argument("--rounds", type=int, default=20, help="keystrokes and page loads measured")
    ap.add_argument("--no-page", action="store_true", help="leave out the page's measures (no Chromium)")
    args = ap.parse_args()
    bench_layout([50, 100] if args.quick else [50, 100, 200, 300], args.repeats)
    bench_edit(50 if args.quick else 300, args.repeats)
    if not args.no_page:
        bench_page(args.rounds)


if __name__ == "__main__":
    main()
