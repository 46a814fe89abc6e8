"""A step from the debugger's page to the newly highlighted state (docs/debug.md, "What it
costs"): a table, never an assert.

    .venv/bin/python bench/debug_page.py [--steps N]
    .venv/bin/python bench/debug_page.py --shots     # docs/images/debug-1280.png and -800.png

`llfsm run --clock wall` of a toggle (A <-> B, one transition a ringlet) starts paused with its
page (`--web`); Chromium (headless, Playwright) opens /debug and clicks "Step ringlet" N times,
each time timing from the click to the diagram highlighting the other state (what a person
sees: the page's request, the run's step, its snapshot pushed and drawn).  Measured in the page
itself: a listener notes the click's time, a MutationObserver the moment the other state gets
`aria-current`, and the next animation frame after it (the highlight painted) ends the step; so
Playwright's own round trips are not counted.  Needs Chromium and the web and dev extras.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "tests"))

from browser import ARGS, CHROMIUM, Served  # noqa: E402
from gen import write_toggle  # noqa: E402

#: In the page: the time of each click on Step ringlet, and of the frame painted after the
#: other state got aria-current.
PROBE = """() => {
  window.__steps = [];
  let clicked = 0;
  document.addEventListener("click", (e) => {
    if (e.target.closest && e.target.closest("button")?.textContent === "Step ringlet") clicked = performance.now();
  }, true);
  new MutationObserver((records) => {
    for (const r of records) {
      if (clicked && r.target.getAttribute("aria-current") === "true") {
        const at = clicked;
        clicked = 0;
        requestAnimationFrame(() => window.__steps.push(performance.now() - at));
      }
    }
  }).observe(document.querySelector("main"), { attributes: true, subtree: true, attributeFilter: ["aria-current"] });
}"""


def shots() -> None:
    """docs/debug.md's pictures: the how-to pair with turtlesim, paused at a breakpoint on the
    blind bot's TURN_RIGHT, at 1280 px and at 800 px (the whole page)."""
    from playwright.sync_api import sync_playwright

    machines = HERE.parent / "machines"
    run = Served(
        "run", "--clock", "wall", str(machines / "ros2_turtle_suspend_resume.machine"),
        str(machines / "ros2_blind_turtle_bot.machine"), "--node", "turtlesim",
        "--break", 'state(ros2_blind_turtle_bot) == "TURN_RIGHT"', "--duration", "300",
    )  # fmt: skip
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            for w, h in ((1280, 860), (800, 1100)):
                page = browser.new_page(viewport={"width": w, "height": h})
                page.goto(run.url.rstrip("/") + "/debug")
                page.get_by_role("status", name="debugger status").filter(has_text="paused").wait_for(timeout=30_000)
                bot = '.state[data-machine="ros2_blind_turtle_bot"][data-state="TURN_RIGHT"][aria-current="true"]'
                page.locator(bot).wait_for()
                time.sleep(0.5)  # the variables' snapshot after the pause
                page.screenshot(path=str(HERE.parent / "docs" / "images" / f"debug-{w}.png"), full_page=w == 800)
                page.close()
            browser.close()
    finally:
        run.stop()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--shots", action="store_true", help="make docs/debug.md's pictures instead")
    args = ap.parse_args()
    if args.shots:
        shots()
        return
    from playwright.sync_api import sync_playwright

    tmp = Path(tempfile.mkdtemp(prefix="llfsm-bench-debug-page-"))
    machine = write_toggle(tmp, "toggle")
    run = Served("run", "--clock", "wall", str(machine), "--paused", "--duration", "600")
    times: list[float] = []
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            page = browser.new_page(viewport={"width": 1280, "height": 860})
            page.goto(run.url.rstrip("/") + "/debug")
            step = page.get_by_role("button", name="Step ringlet")
            page.locator('.state[data-machine="toggle"][aria-current="true"]').wait_for()
            page.evaluate(PROBE)
            for k in range(args.steps):
                step.click()
                until = time.monotonic() + 10
                while page.evaluate("window.__steps.length") <= k and time.monotonic() < until:
                    time.sleep(0.005)
                page.locator('button:has-text("Step ringlet"):enabled').wait_for()
            times = [float(x) for x in page.evaluate("window.__steps")]
            browser.close()
    finally:
        run.stop()
    times.sort()
    p = lambda q: times[min(len(times) - 1, int(q * len(times)))]  # noqa: E731
    print("| steps | median | p95 | max |")
    print("|---|---|---|---|")
    print(f"| {len(times)} | {statistics.median(times):.0f} ms | {p(0.95):.0f} ms | {times[-1]:.0f} ms |")
    print(f"\n(from the click on Step ringlet to the other state highlighted, {time.strftime('%Y-%m-%d')})")


if __name__ == "__main__":
    main()
