"""The web view in a real browser (SPEC §10): Debian's Chromium, headless, driven by Playwright.

The run is a real `llfsm run --clock wall machines/ros2_ping_pong.machine --web 127.0.0.1:0`
subprocess; the test reads the page's address from its stderr.  Playwright never downloads a
browser here: it is pointed at /usr/bin/chromium (`apt-get install chromium`; `make test`
installs it where it can), and these tests skip, saying why, when it is absent.
"""

from __future__ import annotations

import os
import re
import shutil
import struct
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from dds_netns import NetNamespace, finish
from helpers import MACHINES, REPO

pytestmark = pytest.mark.browser

pytest.importorskip("aiohttp")
sync_api = pytest.importorskip("playwright.sync_api", reason="playwright is not installed (pip install -e '.[dev]')")

CHROMIUM = os.environ.get("LLFSM_CHROMIUM", "/usr/bin/chromium")
if not (Path(CHROMIUM).exists() or shutil.which(CHROMIUM)):
    pytest.skip(
        f"no Chromium at {CHROMIUM}: `apt-get install chromium` (make test does it as root)", allow_module_level=True
    )

ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
MACHINE = "ros2_ping_pong"
TIMEOUT_MS = 15_000


class LiveRun:
    """`llfsm run ... --web` in a subprocess: its URL, and its stdout collected as it comes."""

    def __init__(self, cache: Path, *extra: str, machines: tuple[str, ...] = (MACHINE,)) -> None:
        env = {**os.environ, "LLFSM_CACHE_DIR": str(cache), "PYTHONUNBUFFERED": "1"}
        self.proc = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "llfsm",
                "run",
                "--clock",
                "wall",
                *(str(MACHINES / f"{m}.machine") for m in machines),
                "--web",
                "127.0.0.1:0",
                "--duration",
                "120",
                *extra,
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            cwd=REPO,
            env=env,
        )
        self.stdout: list[str] = []
        self.url = ""
        deadline = time.monotonic() + 60
        assert self.proc.stderr is not None
        for line in self.proc.stderr:
            m = re.search(r"http://\S+", line)
            if m:
                self.url = m.group(0)
                break
            if time.monotonic() > deadline:
                break
        assert self.url, "the run printed no http:// address"
        threading.Thread(target=self._drain, args=(self.proc.stdout, self.stdout), daemon=True).start()
        threading.Thread(target=self._drain, args=(self.proc.stderr, []), daemon=True).start()

    @staticmethod
    def _drain(stream: Any, into: list[str]) -> None:
        for line in stream:
            into.append(line)

    def stop(self) -> None:
        self.proc.terminate()
        try:
            self.proc.wait(15)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait(5)


@pytest.fixture(scope="module")
def live(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LiveRun]:
    run = LiveRun(tmp_path_factory.mktemp("cache"), "--echo", "/from_the_page")
    try:
        yield run
    finally:
        run.stop()


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    with sync_api.sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        try:
            yield b
        finally:
            b.close()


@pytest.fixture
def page(live: LiveRun, browser: Any) -> Iterator[Any]:
    p = browser.new_page(viewport={"width": 1280, "height": 860})
    p.set_default_timeout(TIMEOUT_MS)
    p.goto(live.url)
    p.wait_for_selector(f'article.machine[data-machine="{MACHINE}"][data-status="running"]')
    try:
        yield p
    finally:
        p.close()


def _current(state: str) -> str:
    return f'.state[data-machine="{MACHINE}"][data-state="{state}"][aria-current="true"]'


def _count(page: Any, topic: str) -> int:
    text = page.locator(f'#topics tr[data-topic="{topic}"] td.count').inner_text()
    return int(text) if text.strip().isdigit() else -1


def _until(condition: Any, timeout: float = TIMEOUT_MS / 1000) -> None:
    """Poll from Python: the page's Content-Security-Policy forbids evaluating strings, and so
    Playwright's wait_for_function, which the tests do not get around."""
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.1)


def _command(page: Any, verb: str) -> None:
    page.locator(f'article[data-machine="{MACHINE}"] button[data-command="{verb}"]').click()


def test_the_highlight_follows_the_machine(page: Any) -> None:
    for _ in range(2):  # PUBLISH lasts 1 s, WAIT_AND_COUNT 0.5 s
        page.wait_for_selector(_current("PUBLISH"))
        page.wait_for_selector(_current("WAIT_AND_COUNT"))
    assert page.locator('.state[aria-current="true"]').count() == 1
    assert page.locator(f'article[data-machine="{MACHINE}"] .transitions li').count() >= 3
    # the diagram shows the guards as written, in priority order
    labels = page.locator(".guard text").all_text_contents()
    assert "1: after_ms(1000)" in labels and "0: not ros.ok()" in labels


def test_suspend_stops_the_machine_and_its_publishing_and_resume_goes_on(page: Any) -> None:
    page.wait_for_selector('#topics tr[data-topic="/pingpong"]')
    _command(page, "suspend")
    page.wait_for_selector(f'article[data-machine="{MACHINE}"][data-status="suspended"]')
    page.wait_for_selector(_current("SUSPENDED"))
    assert "suspend of ros2_ping_pong pending" in page.locator(".command-result").inner_text()
    before = _count(page, "/pingpong")
    time.sleep(2.5)  # across processes: ping-pong would have published twice by now
    assert _count(page, "/pingpong") == before
    _command(page, "suspend")
    sync_api.expect(page.locator(".command-result")).to_contain_text("already suspended")
    _command(page, "resume")
    page.wait_for_selector(f'article[data-machine="{MACHINE}"][data-status="running"]')
    _until(lambda: _count(page, "/pingpong") > before)


def test_a_message_published_from_the_form_is_echoed(page: Any, live: LiveRun) -> None:
    form = page.locator("#publish-form")
    form.locator('input[name="topic"]').fill("/from_the_page")
    form.locator('input[name="type"]').fill("std_msgs/msg/String")
    form.locator('textarea[name="values"]').fill("{data: 'hello: from the page'}")
    form.locator('button[type="submit"]').click()
    page.wait_for_selector('#publish-result[data-ok="true"]')
    page.wait_for_selector('#topics tr.last[data-topic="/from_the_page"] pre:has-text("hello: from the page")')
    deadline = time.monotonic() + 10
    while "data: 'hello: from the page'\n" not in live.stdout and time.monotonic() < deadline:
        time.sleep(0.1)
    assert "data: 'hello: from the page'\n" in live.stdout  # --echo printed it, quoted as ros2 topic echo does
    # not a number: `{data: 3.5}` is the string '3.5' here, as in topic pub (rosidl writes str(value))
    form.locator('textarea[name="values"]').fill("{data: [1, 2]}")
    form.locator('button[type="submit"]').click()
    page.wait_for_selector('#publish-result[data-ok="false"]')
    assert "must be of type 'str'" in page.locator("#publish-result").inner_text()


def test_calling_the_suspend_service_from_the_service_form_and_the_page_follows(page: Any) -> None:
    form = page.locator("#call-form")
    form.locator('input[name="service"]').fill(f"/llfsm/{MACHINE}/suspend")
    form.locator('button[type="submit"]').click()
    page.wait_for_selector('#call-result[data-ok="true"]')
    assert "success: true" in page.locator("#call-result").inner_text()
    page.wait_for_selector(f'article[data-machine="{MACHINE}"][data-status="suspended"]')
    form.locator('input[name="service"]').fill(f"/llfsm/{MACHINE}/resume")
    form.locator('button[type="submit"]').click()
    page.wait_for_selector(f'article[data-machine="{MACHINE}"][data-status="running"]')


def test_screenshot_of_the_page(browser: Any, tmp_path: Path) -> None:
    """A picture of the page (look at it after a change): the seed's suspend/resume pair driving
    the blind turtle bot in turtlesim.  It is written under tmp_path; with
    LLFSM_UPDATE_DOC_IMAGES=1 it is also copied to docs/images/view.png, the picture docs/view.md
    shows (a test run never changes the repository otherwise)."""
    run = LiveRun(tmp_path, "--node", "turtlesim", machines=("ros2_turtle_suspend_resume", "ros2_blind_turtle_bot"))
    out = tmp_path / "view.png"
    try:
        p = browser.new_page(viewport={"width": 1400, "height": 900})
        p.set_default_timeout(TIMEOUT_MS)
        p.goto(run.url)
        p.wait_for_selector("#world svg .turtle")
        p.wait_for_selector('article[data-machine="ros2_blind_turtle_bot"][data-status="suspended"]')
        p.wait_for_selector('article[data-machine="ros2_blind_turtle_bot"][data-status="running"]')
        _until(lambda: p.locator('article[data-machine="ros2_blind_turtle_bot"] .transitions li').count() >= 5)
        p.screenshot(path=str(out), full_page=True)
        p.close()
    finally:
        run.stop()
    data = out.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and data[12:16] == b"IHDR" and len(data) > 20_000
    width, height = struct.unpack(">II", data[16:24])
    assert width == 1400 and 900 <= height <= 10_000, (width, height)  # the viewport's width, the whole page
    if os.environ.get("LLFSM_UPDATE_DOC_IMAGES") == "1":
        shutil.copyfile(out, REPO / "docs" / "images" / "view.png")


def test_the_turtle_world_is_drawn_live(browser: Any, tmp_path: Path) -> None:
    run = LiveRun(tmp_path, "--node", "turtlesim")
    try:
        p = browser.new_page(viewport={"width": 1280, "height": 860})
        p.set_default_timeout(TIMEOUT_MS)
        p.goto(run.url)
        p.wait_for_selector("#world svg .turtle")
        assert p.locator("#world-panel").is_visible()
        form = p.locator("#call-form")
        form.locator('input[name="service"]').fill("/spawn")
        form.locator('textarea[name="values"]').fill("{x: 2.0, y: 2.0, name: leo}")
        form.locator('button[type="submit"]').click()
        p.wait_for_selector('#world svg .turtle[id="leo"]')
        p.close()
    finally:
        run.stop()


# -- the page follows `llfsm service call` from another process, over DDS ------------------------

#: The browser's side, run inside the test's network namespace (where the run's 127.0.0.1 is):
#: Chromium driven by Playwright sees the machine run, says "ready", then waits for the page to
#: show it suspended, which only a call from outside can do.
WATCH_PAGE = r"""
import sys, time
from playwright.sync_api import sync_playwright
url, chromium, args, machine = sys.argv[1], sys.argv[2], sys.argv[3].split(), sys.argv[4]
card = f'article.machine[data-machine="{machine}"]'
with sync_playwright() as pw:
    b = pw.chromium.launch(executable_path=chromium, args=args)
    p = b.new_page(viewport={"width": 1280, "height": 860})
    p.set_default_timeout(30_000)
    p.goto(url)
    for state in ("PUBLISH", "WAIT_AND_COUNT"):
        p.wait_for_selector(f'{card}[data-status="running"] .state[data-state="{state}"][aria-current="true"]')
    print("ready", flush=True)
    p.wait_for_selector(f'{card}[data-status="suspended"]', timeout=45_000)
    p.wait_for_selector(f'.state[data-machine="{machine}"][data-state="SUSPENDED"][aria-current="true"]')
    print("suspended", flush=True)
    b.close()
"""


@pytest.mark.dds
def test_the_page_follows_a_suspend_called_with_llfsm_service_call(netns: NetNamespace) -> None:
    """Issue 9: `llfsm service call /llfsm/M/suspend` from another process, over DDS, and the
    page (in Chromium, in the same private network) shows M suspended.  The call's output is
    ros2's, word for word (the reprs checked against rclpy 9.1.2's std_srvs)."""
    run = netns.llfsm(
        "run", "--transport", "dds", MACHINES / f"{MACHINE}.machine", "--web", "127.0.0.1:0", "--duration", "90"
    )
    assert run.stderr is not None
    url = ""
    for line in run.stderr:
        m = re.search(r"http://\S+", line)
        if m:
            url = m.group(0)
            break
    assert url, "the run printed no http:// address"
    threading.Thread(target=LiveRun._drain, args=(run.stderr, []), daemon=True).start()
    threading.Thread(target=LiveRun._drain, args=(run.stdout, []), daemon=True).start()
    watcher = netns.popen([sys.executable, "-c", WATCH_PAGE, url, CHROMIUM, " ".join(ARGS), MACHINE])
    assert watcher.stdout is not None
    ready = watcher.stdout.readline()  # ends with the watcher: it prints or it dies within 30 s
    assert ready == "ready\n", ready + (watcher.stderr.read() if watcher.stderr else "")
    call = netns.llfsm("service", "call", f"/llfsm/{MACHINE}/suspend", "std_srvs/srv/Trigger")
    c_status, c_out, c_err = finish(call, 60)
    w_status, w_out, w_err = finish(watcher, 60)
    run.terminate()
    finish(run, 20)
    assert c_status == 0, c_err
    answer = (
        "requester: making request: std_srvs.srv.Trigger_Request()\n\n"
        "response:\n"
        "std_srvs.srv.Trigger_Response(success=True, "
        f"message='suspend of {MACHINE} pending until its next ringlet')\n\n"
    )
    assert c_out in (answer, "waiting for service to become available...\n" + answer), c_out
    assert w_status == 0 and w_out == "suspended\n", w_out + w_err
