"""The debugger's page in a real browser (SPEC 14, docs/debug.md "The page"): Debian's Chromium,
headless, driven by Playwright, over a real `llfsm run ... --web` (its /debug page), a replay,
and `llfsm edit`'s Run: pause at a breakpoint set on the diagram, read a variable, set it, step,
move the History slider back and see the old state highlighted, continue."""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from browser import TIMEOUT_MS, Served, chromium, page_not_built, playwright_or_skip, until
from helpers import MACHINES, llfsm

pytestmark = pytest.mark.browser

sync_api = playwright_or_skip()


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    assert page_not_built() is None, page_not_built()
    yield from chromium(sync_api)


def _state(page: Any, state: str, current: bool = True) -> Any:
    mark = '[aria-current="true"]' if current else ""
    return page.locator(f'.state[data-machine="counter"][data-state="{state}"]{mark}')


def _variable(page: Any, name: str) -> str:
    cell = page.get_by_role("table", name="Variables of counter").locator(f'tr[data-variable="{name}"] td')
    field = cell.locator("input")
    return str(field.input_value() if field.count() else cell.inner_text())


def test_the_page_pauses_at_a_breakpoint_reads_sets_steps_goes_back_and_continues(browser: Any, tmp_path: Path) -> None:
    run = Served(
        "run", "--clock", "wall", str(MACHINES / "counter.machine"), "--paused", "--keep-accepting",
        "--duration", "120", env={"LLFSM_CACHE_DIR": str(tmp_path / "cache")},
    )  # fmt: skip
    page = browser.new_page(viewport={"width": 1280, "height": 860})
    page.set_default_timeout(TIMEOUT_MS)
    try:
        page.goto(run.url.rstrip("/") + "/debug")
        status = page.get_by_role("status", name="debugger status")
        sync_api.expect(status).to_have_text("paused")
        sync_api.expect(page.locator(".debug .where")).to_contain_text("paused before the first round")
        _state(page, "INITIAL").wait_for()
        # a breakpoint on COUNT, toggled on the diagram (Alt+click)
        _state(page, "COUNT", current=False).click(modifiers=["Alt"])
        page.locator('.state[data-state="COUNT"][data-breakpoint="true"]').wait_for()
        page.get_by_role("button", name="Continue").click()
        sync_api.expect(page.locator(".debug .where")).to_contain_text('break 1: state(counter) == "COUNT"')
        sync_api.expect(status).to_have_text("paused")
        _state(page, "COUNT").wait_for()
        until(lambda: _variable(page, "count") == "0", what="count read as 0")  # COUNT's OnEntry still to run
        # set it
        field = page.get_by_role("textbox", name="count of counter")
        field.fill("3")
        field.press("Enter")
        sync_api.expect(page.locator("header .status")).to_have_text("counter.count = 3")
        # step: COUNT's OnEntry runs (4)
        page.get_by_role("button", name="Step ringlet").click()
        until(lambda: _variable(page, "count") == "4", what="count 4 after a step")
        sync_api.expect(page.locator(".debug .where")).to_contain_text("step")
        # the History slider back to before the first ringlet: INITIAL highlighted, count 0 there
        slider = page.get_by_role("slider", name="History")
        slider.focus()
        slider.press("Home")
        _state(page, "INITIAL").wait_for()
        until(lambda: _variable(page, "count") == "0", what="count 0 in the history")
        slider.press("End")
        _state(page, "COUNT").wait_for()
        # the breakpoint off, and on: the run reaches END
        _state(page, "COUNT").click(modifiers=["Alt"])
        until(lambda: page.locator('.state[data-breakpoint="true"]').count() == 0, what="breakpoint off")
        page.get_by_role("button", name="Continue").click()
        sync_api.expect(status).to_have_text("running")
        _state(page, "END").wait_for()
        until(lambda: "count = 5 at state COUNT\n" in run.stdout, what="the run counted on")
        assert "count = 4 at state COUNT\n" in run.stdout and "count = 1 at state COUNT\n" not in run.stdout
    finally:
        page.close()
        run.stop()


def test_a_replay_steps_through_a_trace_on_the_diagram(browser: Any, tmp_path: Path) -> None:
    trace = tmp_path / "t.jsonl"
    assert llfsm("run", "--clock", "sim", MACHINES / "counter.machine", "--trace", trace).status == 0
    served = Served("replay", str(trace), "--duration", "120")
    page = browser.new_page(viewport={"width": 1280, "height": 860})
    page.set_default_timeout(TIMEOUT_MS)
    try:
        page.goto(served.url)
        sync_api.expect(page.locator("h1")).to_have_text("llfsm replay")
        assert page.get_by_role("button", name="Pause").count() == 0  # nothing runs in a replay
        _state(page, "END").wait_for()  # a replay opens at its end
        slider = page.get_by_role("slider", name="History")
        slider.focus()
        slider.press("Home")
        _state(page, "INITIAL").wait_for()
        slider.press("ArrowRight")
        _state(page, "COUNT").wait_for()
        until(lambda: _variable(page, "count") == "0", what="count 0 at the first ringlet")
        for _ in range(3):
            slider.press("ArrowRight")
        until(lambda: _variable(page, "count") == "2", what="count 2 further on")
    finally:
        page.close()
        served.stop()


def test_edit_runs_with_the_debugger_in_its_run_bar(browser: Any, tmp_path: Path) -> None:
    # the counter counting far (its five counts end the run in a second: under load the page saw
    # it ended, never running, before it could pause it)
    counter = tmp_path / "counter.machine"
    shutil.copytree(MACHINES / "counter.machine", counter)
    (counter / "Variables.py").write_text(
        (counter / "Variables.py").read_text().replace("limit: int = 5", "limit: int = 10**6")
    )
    served = Served("edit", str(counter), env={"LLFSM_CACHE_DIR": str(tmp_path / "cache")})
    page = browser.new_page(viewport={"width": 1280, "height": 860})
    page.set_default_timeout(TIMEOUT_MS)
    try:
        page.goto(served.url)
        page.get_by_role("button", name="Run").click()
        status = page.get_by_role("status", name="debugger status")
        sync_api.expect(status).to_have_text("running")
        page.get_by_role("button", name="Pause").click()
        sync_api.expect(status).to_have_text("paused")
        page.get_by_role("table", name="Variables of counter").wait_for()
        page.get_by_role("button", name="Step ringlet").click()
        sync_api.expect(page.locator(".debug .where")).to_contain_text("step")
        page.get_by_role("button", name="Continue").click()
        sync_api.expect(status).to_have_text("running")
        page.get_by_role("button", name="Stop").click()
    finally:
        page.close()
        served.stop()
