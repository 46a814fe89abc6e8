"""The web view in a real browser (SPEC §10): Debian's Chromium, headless, driven by Playwright.

The run is a real `llfsm run --clock wall machines/ros2_ping_pong.machine --web 127.0.0.1:0`
subprocess; the test reads the page's address from its stderr.  Playwright never downloads a
browser here: it is pointed at /usr/bin/chromium (`apt-get install chromium`; `make test`
installs it where it can), and these tests skip, saying why, when it is absent.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import struct
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from browser import ARGS, CHROMIUM, TIMEOUT_MS, Served, chromium, playwright_or_skip, until
from dds_netns import NetNamespace, finish
from helpers import MACHINES, REPO

from llfsm.web.channel import state_of

pytestmark = pytest.mark.browser

sync_api = playwright_or_skip()
MACHINE = "ros2_ping_pong"


class LiveRun(Served):
    """`llfsm run --clock wall MACHINE... --web` in a subprocess, stopped by the test (the 15
    minutes are a net, not a window: a module's tests can take minutes under load, and a run
    shared by them must not end under the later ones, as 120 s could): its URL, and its stdout
    collected as it comes."""

    def __init__(self, cache: Path, *extra: str, machines: tuple[str, ...] = (MACHINE,)) -> None:
        paths = (str(MACHINES / f"{m}.machine") for m in machines)
        super().__init__(
            "run", "--clock", "wall", *paths, "--duration", "900", *extra, env={"LLFSM_CACHE_DIR": str(cache)}
        )


@pytest.fixture(scope="module")
def live(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LiveRun]:
    run = LiveRun(tmp_path_factory.mktemp("cache"), "--echo", "/from_the_page")
    try:
        yield run
    finally:
        run.stop()


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    yield from chromium(sync_api)


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
    # the run's answer ("pending until its next ringlet") gives way once the page sees it applied
    sync_api.expect(page.locator(".command-result")).to_contain_text("suspend applied")
    assert "pending" not in page.locator(".command-result").inner_text()
    # the table reads a topic's row again at most every ROW_PERIOD (0.5 s): when the status turns,
    # its count may still be catching up with the last message sent before the suspension (under
    # load it was). A rate of 0 Hz is a row read again after two seconds without a message.
    rate = page.locator('#topics tr[data-topic="/pingpong"] td.rate')
    sync_api.expect(rate).to_have_text("0.0 Hz", timeout=30_000)
    before = _count(page, "/pingpong")
    time.sleep(2.5)  # across processes: ping-pong would have published twice by now
    assert _count(page, "/pingpong") == before
    _command(page, "suspend")
    sync_api.expect(page.locator(".command-result")).to_contain_text("already suspended")
    _command(page, "resume")
    page.wait_for_selector(f'article[data-machine="{MACHINE}"][data-status="running"]')
    until(lambda: _count(page, "/pingpong") > before)


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


# -- issue 22: the page's rough edges, each at both widths ------------------------------------------

WIDTHS = (1280, 800)


def _shot(p: Any, tmp_path: Path, name: str) -> Path:
    """A picture of the whole page, checked to be one (look at it after a change)."""
    out = tmp_path / f"{name}.png"
    p.screenshot(path=str(out), full_page=True)
    data = out.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and data[12:16] == b"IHDR" and len(data) > 10_000
    width, height = struct.unpack(">II", data[16:24])
    assert width == p.viewport_size["width"] and 600 <= height <= 12_000, (width, height)
    return out


@pytest.fixture(params=WIDTHS, ids=lambda w: f"{w}px")
def wide_page(request: pytest.FixtureRequest, live: LiveRun, browser: Any) -> Iterator[Any]:
    p = browser.new_page(viewport={"width": request.param, "height": 860})
    p.set_default_timeout(TIMEOUT_MS)
    p.goto(live.url)
    p.wait_for_selector(f'article.machine[data-machine="{MACHINE}"][data-status="running"]')
    try:
        yield p
    finally:
        p.close()


def test_underscores_show_in_the_monospace_inputs(wide_page: Any, tmp_path: Path) -> None:
    """`/turtle1/cmd_vel` must not read `cmd vel`: the field with its underscore drawn differs
    from the same field with a space where the underscore is."""
    field = wide_page.locator('#publish-form input[name="topic"]')
    assert field.get_attribute("placeholder") == "/turtle1/cmd_vel"
    with_underscore = field.screenshot()
    field.evaluate("(e) => { e.placeholder = '/turtle1/cmd vel'; }")
    with_space = field.screenshot()
    field.evaluate("(e) => { e.placeholder = '/turtle1/cmd_vel'; }")
    assert with_underscore != with_space
    field.fill("/turtle1/cmd_vel")  # a value typed is drawn whole too
    typed = field.screenshot()
    field.fill("/turtle1/cmd vel")
    assert field.screenshot() != typed
    _shot(wide_page, tmp_path, "inputs")


def test_the_buttons_stay_put_as_the_state_name_changes(wide_page: Any, tmp_path: Path) -> None:
    """PUBLISH and WAIT_AND_COUNT (and the `since` time) differ in length: the buttons do not move."""
    buttons = wide_page.locator(f'article[data-machine="{MACHINE}"] button[data-command]')
    seen: dict[str, set[tuple[float, ...]]] = {}
    deadline = time.monotonic() + 60  # until both are seen: a loaded page follows late
    while time.monotonic() < deadline and len(seen) < 2:
        state = wide_page.locator(f'article[data-machine="{MACHINE}"] .state-name').inner_text()
        boxes = tuple(round(v, 1) for i in range(3) for v in buttons.nth(i).bounding_box().values())
        seen.setdefault(state, set()).add(boxes)
        time.sleep(0.05)
    assert set(seen) == {"PUBLISH", "WAIT_AND_COUNT"}, seen
    assert len(set().union(*seen.values())) == 1, seen
    _shot(wide_page, tmp_path, "buttons")


#: For each cell of the topics' type column: the characters a line ends with (from the page).
LINE_ENDS = """(cells) => cells.map((td) => {
  const chars = [];
  const walk = document.createTreeWalker(td, NodeFilter.SHOW_TEXT);
  for (let n = walk.nextNode(); n; n = walk.nextNode()) {
    for (let i = 0; i < n.length; i++) {
      const r = document.createRange(); r.setStart(n, i); r.setEnd(n, i + 1);
      const rect = r.getClientRects()[0];
      if (rect) chars.push([n.data[i], Math.round(rect.top)]);
    }
  }
  const ends = [];
  for (let i = 1; i < chars.length; i++) if (chars[i][1] > chars[i - 1][1]) ends.push(chars[i - 1][0]);
  return [td.textContent, ends];
})"""


def test_the_type_column_breaks_only_between_words(wide_page: Any, tmp_path: Path) -> None:
    """A type wraps after a slash (or an underscore), never inside a word."""
    wide_page.wait_for_selector('#topics tr[data-topic="/rosout"]')
    cells = wide_page.locator("#topics tbody tr.topic td.type").evaluate_all(LINE_ENDS)
    assert any(text == "rcl_interfaces/msg/Log" for text, _ in cells), cells
    assert all(end in "/_" for _, ends in cells for end in ends), cells
    _shot(wide_page, tmp_path, "types")


def test_a_machines_state_topic_shows_its_count(page: Any) -> None:
    row = f"/llfsm/{MACHINE}/state"
    page.wait_for_selector(f'#topics tr[data-topic="{row}"]')
    assert _count(page, row) >= 1  # the initial state at least, not "—"
    assert _count(page, f"/llfsm/{MACHINE}/description") == 1


@pytest.fixture(scope="module")
def turtle(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LiveRun]:
    """The blind turtle bot driving llfsm's turtlesim, with the seed's suspend/resume pair."""
    run = LiveRun(
        tmp_path_factory.mktemp("turtle"),
        "--node",
        "turtlesim",
        machines=("ros2_turtle_suspend_resume", "ros2_blind_turtle_bot"),
    )
    try:
        yield run
    finally:
        run.stop()


def _open(browser: Any, run: LiveRun, width: int = 1280) -> Any:
    p = browser.new_page(viewport={"width": width, "height": 900})
    p.set_default_timeout(TIMEOUT_MS)
    p.goto(run.url)
    p.wait_for_selector("#world svg .turtle")
    return p


def test_the_graph_of_nodes_and_topics_as_rqt_graph_draws_it_live(turtle: LiveRun, browser: Any) -> None:
    p = _open(browser, turtle)
    try:
        graph = p.locator("#graph svg.rosgraph")
        graph.locator('g.ros-node[data-node="/turtlesim"] ellipse').wait_for()
        graph.locator('g.ros-topic[data-topic="/turtle1/cmd_vel"] rect').wait_for()
        # publisher -> topic -> subscriber
        graph.locator('path.link.pub[data-node="/ros2_blind_turtle_bot"][data-topic="/turtle1/cmd_vel"]').wait_for(
            state="attached"
        )
        graph.locator('path.link.sub[data-node="/turtlesim"][data-topic="/turtle1/cmd_vel"]').wait_for(state="attached")
        graph.locator('path.link.pub[data-node="/turtlesim"][data-topic="/turtle1/pose"]').wait_for(state="attached")
        assert graph.locator('[data-topic="/rosout"]').count() == 0  # rqt_graph hides debug names
        assert graph.locator('[data-node^="/llfsm_web"]').count() == 0  # and the page's own node
        # live: a turtle spawned from the page brings its topics onto the graph
        form = p.locator("#call-form")
        form.locator('input[name="service"]').fill("/spawn")
        form.locator('textarea[name="values"]').fill("{x: 2.0, y: 2.0, name: leo}")
        form.locator('button[type="submit"]').click()
        graph.locator('path.link.pub[data-node="/turtlesim"][data-topic="/leo/pose"]').wait_for(state="attached")
        graph.locator('path.link.sub[data-node="/turtlesim"][data-topic="/leo/cmd_vel"]').wait_for(state="attached")
        # turtlesim's action, found by the names of its services, with its type and server
        row = p.locator('#actions tr[data-action="/turtle1/rotate_absolute"]')
        row.wait_for()
        assert row.locator("td").all_inner_texts() == [
            "/turtle1/rotate_absolute",
            "turtlesim/action/RotateAbsolute",
            "/turtlesim",
            "—",
        ]
        assert p.locator("#no-actions").is_hidden()
        # its _action/ topics are hidden from the topics, as `ros2 topic list` hides them
        p.locator('#topics tr[data-topic="/turtle1/pose"]').first.wait_for()
        assert p.locator('#topics tr[data-topic="/turtle1/rotate_absolute/_action/feedback"]').count() == 0
        # long types wrap between words, within their column
        wide = p.locator("#topics td.type, #actions td.type").evaluate_all(
            "(cells) => cells.filter((td) => td.scrollWidth > td.clientWidth + 1).map((td) => td.textContent)"
        )
        assert wide == []
        # a click on a node opens its parameters
        graph.locator('g.ros-node[data-node="/turtlesim"]').click()
        p.locator('#nodes details[data-node="/turtlesim"][open] form.param[data-param="background_g"]').wait_for()
    finally:
        p.close()


def _background(p: Any) -> str:
    return p.locator("#world svg rect").first.get_attribute("fill") or ""


def test_a_parameter_set_from_the_page_changes_the_background_and_a_bad_one_says_why(
    turtle: LiveRun, browser: Any
) -> None:
    p = _open(browser, turtle)
    try:
        p.locator('#nodes details[data-node="/turtlesim"] summary').click()
        row = p.locator('#nodes details[data-node="/turtlesim"] form.param[data-param="background_r"]')
        row.wait_for()
        assert row.locator(".param-type").inner_text() == "integer"
        before = _background(p)
        row.locator("input").fill("abc")
        row.locator("button").click()
        out = p.locator('#nodes details[data-node="/turtlesim"] form.param[data-param="background_r"] output')
        sync_api.expect(out).to_contain_text("Setting parameter failed: Wrong parameter type")
        assert out.get_attribute("data-ok") == "false"
        assert _background(p) == before
        row = p.locator('#nodes details[data-node="/turtlesim"] form.param[data-param="background_r"]')
        row.locator("input").fill("255")
        row.locator("button").click()
        sync_api.expect(out).to_contain_text("Set parameter successful")
        until(lambda: _background(p).lower().startswith("#ff"))
        assert _background(p) != before
        # the rows are read again after the node's parameter event: the value shown is the new one
        until(lambda: row.locator("input").input_value() == "255")
        # a value of the right type but out of the node's range is refused with the node's reason
        row = p.locator('#nodes details[data-node="/turtlesim"] form.param[data-param="background_g"]')
        row.locator("input").fill("300")
        row.locator("button").click()
        out_g = p.locator('#nodes details[data-node="/turtlesim"] form.param[data-param="background_g"] output')
        sync_api.expect(out_g).to_contain_text("Setting parameter failed")
    finally:
        p.close()


@pytest.mark.parametrize("width", WIDTHS)
def test_screenshot_of_the_page(turtle: LiveRun, browser: Any, tmp_path: Path, width: int) -> None:
    """The page docs/view.md shows (look at it after a change): the seed's suspend/resume pair
    driving the blind turtle bot in turtlesim, the graph and turtlesim's parameters open.  With
    LLFSM_UPDATE_DOC_IMAGES=1 it is copied to docs/images/view-WIDTH.png (a test run never
    changes the repository otherwise)."""
    p = _open(browser, turtle, width)
    try:
        p.wait_for_selector('article[data-machine="ros2_blind_turtle_bot"][data-status="suspended"]')
        p.wait_for_selector('article[data-machine="ros2_blind_turtle_bot"][data-status="running"]')
        until(lambda: p.locator('article[data-machine="ros2_blind_turtle_bot"] .transitions li').count() >= 5)
        p.locator('#nodes details[data-node="/turtlesim"] summary').click()
        p.locator('#nodes details[data-node="/turtlesim"] form.param[data-param="background_b"]').wait_for()
        out = _shot(p, tmp_path, f"view-{width}")
    finally:
        p.close()
    if os.environ.get("LLFSM_UPDATE_DOC_IMAGES") == "1":
        shutil.copyfile(out, REPO / "docs" / "images" / f"view-{width}.png")


def test_after_the_run_ends_the_cards_say_so_and_the_buttons_are_disabled(browser: Any, tmp_path: Path) -> None:
    run = LiveRun(tmp_path)
    try:
        p = browser.new_page(viewport={"width": 1280, "height": 860})
        p.set_default_timeout(TIMEOUT_MS)
        p.goto(run.url)
        card = p.locator(f'article.machine[data-machine="{MACHINE}"]')
        p.wait_for_selector(f'article.machine[data-machine="{MACHINE}"][data-status="running"]')
        assert card.locator('button[data-command="suspend"]').is_enabled()
        # Ctrl-C ends it once the page has seen it run (a --duration of 6 s could end it before a
        # page loaded under load had); the machine takes its `not ros.ok()` to END
        run.proc.send_signal(signal.SIGINT)
        p.wait_for_selector(f'article.machine[data-machine="{MACHINE}"][data-status="ended"]')
        assert card.locator(".status").inner_text() == "run ended"
        for verb in ("suspend", "resume", "restart"):
            assert card.locator(f'button[data-command="{verb}"]').is_disabled()
        assert p.locator("#publish-form button").is_disabled()
        assert "the run has ended" in p.locator("#run-time").inner_text()
        _shot(p, tmp_path, "ended")
        p.close()
    finally:
        run.stop()


# -- two runs of one machine, and actions, as `llfsm view` sends them -------------------------------


class TwoRuns:
    """What `llfsm view` sends for two runs of ping-pong on one domain (llfsm/web/machines.py
    keys the second NAME@xxxxxxxx), and an action on the graph, served by the real server."""

    ended = False

    def __init__(self) -> None:
        import json as _json

        from llfsm.ros.control import description
        from llfsm.targets import load

        desc = _json.loads(_json.dumps(description(load(str(MACHINES / f"{MACHINE}.machine")))))
        self.descs = [
            {**desc, "name": MACHINE, "machine": MACHINE, "participant": "01100b7fc3313630a1b2c3d4000001c1"},
            {**desc, "name": f"{MACHINE}@5e0f9a21", "machine": MACHINE, "participant": "01100b7f5e0f9a21e5f6"},
        ]

    def machines(self) -> list[Any]:
        return self.descs

    def graph(self) -> Any:
        from llfsm.web.rosgraph import Action, RosGraph

        return RosGraph(
            ("/teleop", "/turtlesim"),
            (("/turtle1/cmd_vel", "geometry_msgs/msg/Twist"),),
            (("/teleop", "/turtle1/cmd_vel", "pub"), ("/turtlesim", "/turtle1/cmd_vel", "sub")),
            (Action("/turtle1/rotate_absolute", "turtlesim/action/RotateAbsolute", ("/turtlesim",), ("/teleop",)),),
        )

    def state(self) -> dict[str, Any]:
        rows = [
            {
                "name": d["name"],
                "machine": MACHINE,
                "participant": d["participant"],
                "runs": 2,
                "ended": False,
                "state": state,
                "status": "running",
                "pending": None,
                "since": 1.5,
                "run_time": True,
                "transitions": [],
            }
            for d, state in zip(self.descs, ("PUBLISH", "WAIT_AND_COUNT"), strict=True)
        ]
        return state_of(t=2.0, source="view", machines=rows)


def test_two_runs_of_one_machine_are_two_cards_saying_which_run_and_that_commands_reach_both(
    browser: Any, tmp_path: Path
) -> None:
    from llfsm.web.server import WebServer

    srv = WebServer(TwoRuns(), "127.0.0.1", 0)
    url = srv.start()
    try:
        for width in WIDTHS:
            p = browser.new_page(viewport={"width": width, "height": 900})
            p.set_default_timeout(TIMEOUT_MS)
            p.goto(url)
            first = p.locator(f'article.machine[data-machine="{MACHINE}"]')
            second = p.locator(f'article.machine[data-machine="{MACHINE}@5e0f9a21"]')
            second.wait_for()
            assert first.locator(".machine-name").inner_text() == second.locator(".machine-name").inner_text()
            assert first.locator(".run-label").inner_text() == "run c3313630"
            assert second.locator(".run-label").inner_text() == "run 5e0f9a21"
            for card in (first, second):
                twins = card.locator(".twins").inner_text()
                assert "One of 2 runs of ros2_ping_pong" in twins and "reaches every one of them" in twins
                assert card.locator(".run-label").inner_text() in twins
            # each card follows its own run
            p.wait_for_selector(f'.state[data-machine="{MACHINE}"][data-state="PUBLISH"][aria-current="true"]')
            p.wait_for_selector(
                f'.state[data-machine="{MACHINE}@5e0f9a21"][data-state="WAIT_AND_COUNT"][aria-current="true"]'
            )
            # the actions, from the graph's names and types
            row = p.locator('#actions tr[data-action="/turtle1/rotate_absolute"]')
            assert row.locator("td").all_inner_texts() == [
                "/turtle1/rotate_absolute",
                "turtlesim/action/RotateAbsolute",
                "/turtlesim",
                "/teleop",
            ]
            assert p.locator("#no-actions").is_hidden()
            p.locator('#graph g.ros-node[data-node="/teleop"] ellipse').wait_for()
            _shot(p, tmp_path, f"two-runs-{width}")
            p.close()
    finally:
        srv.stop()


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


#: The browser's side of `llfsm view` over DDS (in the test's network namespace): the graph of
#: another process's nodes, and turtlesim's parameters read and set from the page.
VIEW_PAGE = r"""
import json, sys
from playwright.sync_api import sync_playwright
url, chromium, args, shot = sys.argv[1], sys.argv[2], sys.argv[3].split(), sys.argv[4]
out = {}
with sync_playwright() as pw:
    b = pw.chromium.launch(executable_path=chromium, args=args)
    p = b.new_page(viewport={"width": 1280, "height": 900})
    p.set_default_timeout(30_000)
    p.goto(url)
    g = p.locator("#graph svg.rosgraph")
    g.locator('g.ros-node[data-node="/turtlesim"] ellipse').wait_for()
    link = 'path.link.pub[data-node="/ros2_blind_turtle_bot"][data-topic="/turtle1/cmd_vel"]'
    g.locator(link).wait_for(state="attached")
    g.locator('path.link.sub[data-node="/turtlesim"][data-topic="/turtle1/cmd_vel"]').wait_for(state="attached")
    g.locator('g.ros-node[data-node="/turtlesim"]').click()
    form = '#nodes details[data-node="/turtlesim"][open] form.param[data-param="background_r"]'
    p.locator(form).wait_for()
    out["type"] = p.locator(form + " .param-type").inner_text()
    for value in ("abc", "255"):
        p.locator(form + " input").fill(value)
        p.locator(form + " button").click()
        o = p.locator(form + " output")
        for _ in range(300):
            if o.inner_text() not in ("", "…"):
                break
            p.wait_for_timeout(100)
        out[value] = o.inner_text()
    for _ in range(300):  # the rows are read again after turtlesim's parameter event
        if p.locator(form + " input").input_value() == "255":
            break
        p.wait_for_timeout(100)
    out["shown"] = p.locator(form + " input").input_value()
    p.screenshot(path=shot, full_page=True)
    b.close()
print(json.dumps(out))
"""


@pytest.mark.dds
def test_llfsm_view_in_chromium_draws_another_processs_graph_and_sets_its_parameters(
    netns: NetNamespace, tmp_path: Path
) -> None:
    run = netns.llfsm(
        "run",
        "--transport",
        "dds",
        MACHINES / "ros2_blind_turtle_bot.machine",
        "--node",
        "turtlesim",
        "--duration",
        "90",
    )
    view = netns.llfsm("view", "--web", "127.0.0.1:0", "--duration", "90")
    assert view.stderr is not None
    url = ""
    for line in view.stderr:
        m = re.search(r"http://\S+", line)
        if m:
            url = m.group(0)
            break
    assert url, "llfsm view printed no address"
    threading.Thread(target=LiveRun._drain, args=(view.stderr, []), daemon=True).start()
    shot = tmp_path / "view-dds.png"
    page = netns.popen([sys.executable, "-c", VIEW_PAGE, url, CHROMIUM, " ".join(ARGS), str(shot)])
    status, out, err = finish(page, 120)
    for p in (run, view):
        p.terminate()
    for p in (run, view):
        finish(p, 20)
    assert status == 0, err
    got = json.loads(out)
    assert got["type"] == "integer"
    assert got["abc"].startswith("Setting parameter failed: Wrong parameter type"), got
    assert got["255"] == "Set parameter successful" and got["shown"] == "255", got
    assert shot.stat().st_size > 10_000


def test_a_monitored_violation_marks_the_machine_and_is_listed(browser: Any, tmp_path: Path) -> None:
    run = LiveRun(tmp_path, "--monitor-property", f"never: {MACHINE}.count >= 1")
    p = browser.new_page(viewport={"width": 1280, "height": 860})
    p.set_default_timeout(TIMEOUT_MS)
    try:
        p.goto(run.url)
        card = p.wait_for_selector(f'article.machine[data-machine="{MACHINE}"][data-violated="true"]')
        assert card is not None
        badge = p.locator(f'article[data-machine="{MACHINE}"] .badge.violation').inner_text()
        assert badge == f"violated: never: {MACHINE}.count >= 1"
        item = p.locator('#verdicts li[data-verdict="violated"]').inner_text()
        assert re.match(rf"never: {MACHINE}\.count >= 1 at \d+\.\d{{3}} s, ringlet \d+: {MACHINE} \w+; ", item), item
        assert f"{MACHINE}.count=1" in item
        assert "1 verdict on /llfsm/monitor" in p.locator("#monitor-count").inner_text()
    finally:
        p.close()
        run.stop()
