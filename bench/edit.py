"""`llfsm edit`'s speed and memory (issue 29), measured through the real page in Chromium and
the real server process, printed as a table (docs/edit.md has the figures).

- diagnostics: from the last key of a typo in a state's OnEntry (a 50-state machine) to the
  state's mark on the diagram; and from the key that fixes it to the mark gone (p50, p95);
- opening a folder of 20 machines of 30 states: the server's start to its printed address,
  and the page's load to the first diagram drawn;
- the edit server with 100 machines open (each read, checked and drawn): resident memory.

    .venv/bin/python bench/edit.py [--rounds N]

Needs Chromium (/usr/bin/chromium) and the page built (`make web`).
"""

from __future__ import annotations

import argparse
import http.client
import json
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from edit_machines import ring
from playwright.sync_api import sync_playwright

ROOT = Path(__file__).resolve().parent.parent
CHROMIUM = "/usr/bin/chromium"


def serve(folder: Path) -> tuple[subprocess.Popen[str], str, float]:
    t0 = time.perf_counter()
    proc = subprocess.Popen(
        [sys.executable, "-m", "llfsm", "edit", str(folder), "--web", "127.0.0.1:0"],
        stderr=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        text=True,
        cwd=ROOT,
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
        ring(Path(t), "fifty", 50)
        proc, url, _ = serve(Path(t))
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 900})  # type: ignore[attr-defined]
            page.goto(url)
            state = page.locator('.state[data-state="S010"]')
            state.click()
            page.wait_for_selector('.state[data-state="S010"][aria-selected="true"]')
            page.get_by_role("textbox", name="OnEntry", exact=True).click()
            page.keyboard.press("Control+End")
            marked, cleared = [], []
            for _ in range(rounds):
                t0 = time.perf_counter()
                page.keyboard.press(":")  # a line holding `:`: a syntax error
                page.wait_for_selector('.state[data-state="S010"][data-problem="error"]', timeout=10_000)
                marked.append(time.perf_counter() - t0)
                t0 = time.perf_counter()
                page.keyboard.press("Backspace")
                page.wait_for_selector('.state[data-state="S010"]:not([data-problem])', timeout=10_000)
                cleared.append(time.perf_counter() - t0)
            page.close()
            return marked, cleared
        finally:
            stop(proc)


def first_diagram(browser: object, rounds: int) -> tuple[list[float], list[float]]:
    starts, draws = [], []
    with tempfile.TemporaryDirectory() as t:
        for i in range(20):
            ring(Path(t), f"m{i:02d}", 30)
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
            ring(Path(t), f"m{i:03d}", 30)
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


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=30)
    a = ap.parse_args()
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=["--headless", "--no-sandbox", "--disable-gpu"])
        marked, cleared = diagnostics(browser, a.rounds)
        starts, draws = first_diagram(browser, max(3, a.rounds // 6))
        browser.close()
    rss = resident()
    ms = 1000

    def row(what: str, a: float, b: float | None, target: str = "") -> None:
        print(f"| {what} | {a:.0f} | {'' if b is None else f'{b:.0f}'} | {target} |")

    print("| measure | p50 (median) | p95 (worst) | target |")
    print("|---|---:|---:|---|")
    row("typo to its mark on the diagram (50 states), ms", pct(marked, 0.5) * ms, pct(marked, 0.95) * ms, "p95 <= 300")
    row("fix to the mark gone, ms", pct(cleared, 0.5) * ms, pct(cleared, 0.95) * ms)
    row("20 x 30 states: server start to its address, ms", statistics.median(starts) * ms, max(starts) * ms)
    row("20 x 30 states: page load to first diagram, ms", statistics.median(draws) * ms, max(draws) * ms, "<= 1000")
    row("100 machines of 30 states open: resident, MB", rss, None, "<= 150")


if __name__ == "__main__":
    main()
