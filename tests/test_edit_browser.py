"""`llfsm edit` in a real browser (SPEC 13, issue 29): Debian's Chromium through Playwright,
driving the page only, as a user would, and then looking at the files on disk and running
them with `llfsm check` and `llfsm run`.

One browser for the module; each test opens its own editor process on its own folder.
"""

from __future__ import annotations

import os
import re
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml
from browser import TIMEOUT_MS, Served, chromium, page_not_built, playwright_or_skip, until
from helpers import MACHINES, llfsm, llfsm_process

pytestmark = pytest.mark.browser

sync_api = playwright_or_skip()


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    why = page_not_built()
    if why:
        pytest.fail(why, pytrace=False)
    yield from chromium(sync_api)


class Editor:
    """An editor process on a folder and a page of it."""

    def __init__(self, browser: Any, folder: Path, width: int = 1280, height: int = 900) -> None:
        self.folder = folder
        self.server = Served("edit", str(folder))
        self.page = browser.new_page(viewport={"width": width, "height": height})
        self.page.set_default_timeout(TIMEOUT_MS)
        self.errors: list[str] = []
        self.page.on("pageerror", lambda e: self.errors.append(str(e)))
        self.page.on("console", lambda m: m.type == "error" and self.errors.append(m.text))
        self.page.goto(self.server.url)
        self.page.wait_for_selector('.badge.connection[data-status="live"]')

    def close(self) -> None:
        self.page.close()
        self.server.stop()

    # -- what a user does ------------------------------------------------------------------------------
    def button(self, name: str) -> Any:
        return self.page.get_by_role("button", name=name, exact=True)

    def code(self, label: str) -> Any:
        return self.page.get_by_role("textbox", name=label, exact=True)

    def type_code(self, label: str, text: str) -> None:
        """Replace a code editor's text as typing would (one insertion: no auto-indent)."""
        box = self.code(label)
        box.click()
        self.page.keyboard.press("Control+A")
        self.page.keyboard.insert_text(text)

    def state(self, name: str) -> Any:
        return self.page.locator(f'.state[data-state="{name}"]')

    def select_state(self, name: str) -> None:
        self.state(name).click()
        self.page.wait_for_selector(f'.state[data-state="{name}"][aria-selected="true"]')

    def select_transition(self, source: str, index: int) -> None:
        self.select_state(source)
        self.page.locator(".panel ul.transitions li button").nth(index).click()
        self.page.wait_for_selector(f'.panel[aria-label="transition {index} of {source}"]')

    def add_state(self, name: str) -> None:
        self.button("Add state").click()
        dialog = self.page.get_by_role("dialog")
        dialog.get_by_role("textbox", name="Name", exact=True).fill(name)
        dialog.get_by_role("button", name="Add").click()
        self.state(name).wait_for()

    def add_transition(self, source: str, target: str, guard: str) -> None:
        self.button("Add transition").click()
        dialog = self.page.get_by_role("dialog")
        dialog.get_by_label("Source").select_option(source)
        dialog.get_by_label("Target").select_option(target)
        dialog.get_by_role("textbox", name="Guard").click()
        self.page.keyboard.insert_text(guard)
        dialog.get_by_role("button", name="Add").click()
        dialog.wait_for(state="detached")

    def saved(self) -> None:
        """Every edit is on disk (the header counts what is not)."""
        until(lambda: self.page.locator(".unsaved").count() == 0, what="unsaved edits")

    def problems(self) -> list[str]:
        return self.page.get_by_role("list", name="Problems").locator("li").all_inner_texts()


@pytest.fixture
def editor(browser: Any, tmp_path: Path) -> Iterator[Editor]:
    folder = tmp_path / "machines"
    folder.mkdir()
    e = Editor(browser, folder)
    try:
        yield e
    finally:
        e.close()


def _text(path: Path) -> str:
    return path.read_text() if path.exists() else ""


def _copy_ping_pong(folder: Path) -> Path:
    return Path(shutil.copytree(MACHINES / "ros2_ping_pong.machine", folder / "ros2_ping_pong.machine"))


@pytest.fixture
def ping_pong(browser: Any, tmp_path: Path) -> Iterator[Editor]:
    folder = tmp_path / "machines"
    folder.mkdir()
    _copy_ping_pong(folder)
    e = Editor(browser, folder)
    e.state("PUBLISH").wait_for()
    try:
        yield e
    finally:
        e.close()


INCLUDES = "from llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import String\n"
VARIABLES = "count: int = 0\npublisher_: ros.Publisher\nnode: ros.Node\n"
INITIAL = (
    'ros.init()\nnode = ros.Node("ros_ping_pong")\npublisher_ = node.create_publisher(String, "pingpong", 10)\n'
    "count = 0\n"
)
PUBLISH = 'message = String()\nmessage.data = f"The count is {count}"\npublisher_.publish(message)\n'


def test_the_how_tos_ping_pong_built_from_an_empty_folder_checks_clean_and_runs(editor: Editor) -> None:
    e = editor
    e.button("New machine").click()
    e.page.get_by_role("dialog").get_by_role("textbox", name="Name", exact=True).fill("ping_pong")
    e.page.get_by_role("dialog").get_by_role("button", name="Make").click()
    e.state("INITIAL").wait_for()
    for name in ("PUBLISH", "WAIT_AND_COUNT"):
        e.add_state(name)
    if e.state("END").count() == 0:
        e.add_state("END")
    # the skeleton's INITIAL -> END keeps its place (priority 0); its guard becomes the how-to's
    structure = (e.folder / "ping_pong.machine" / "machine.yaml").read_text()
    assert "INITIAL" in structure
    e.select_transition("INITIAL", 0)
    guard = e.code("Guard")
    guard.click()
    e.page.keyboard.press("Control+A")
    e.page.keyboard.insert_text("not ros.ok()")
    e.page.keyboard.press("Enter")
    e.page.wait_for_selector('.guard[data-source="INITIAL"][data-index="0"]:has-text("not ros.ok()")')
    e.add_transition("INITIAL", "PUBLISH", "after_ms(1000)")
    e.add_transition("PUBLISH", "END", "not ros.ok()")
    e.add_transition("PUBLISH", "WAIT_AND_COUNT", "after_ms(500)")
    e.add_transition("WAIT_AND_COUNT", "END", "not ros.ok()")
    e.add_transition("WAIT_AND_COUNT", "PUBLISH", "after_ms(500)")
    e.type_code("Description", "Publishes the count on /pingpong.")
    e.type_code("Includes", INCLUDES)
    e.type_code("Variables", VARIABLES)
    e.select_state("INITIAL")
    e.type_code("OnEntry", INITIAL)
    e.select_state("PUBLISH")
    e.type_code("OnEntry", PUBLISH)
    e.select_state("WAIT_AND_COUNT")
    e.type_code("OnEntry", "count += 1\n")
    e.saved()
    until(lambda: e.page.locator(".problems .clean").count() == 1, what=f"a clean check: {e.problems()}")
    assert not e.errors

    machine = e.folder / "ping_pong.machine"
    assert yaml.safe_load((machine / "machine.yaml").read_text())["description"] == "Publishes the count on /pingpong."
    assert llfsm("check", str(machine)).status == 0
    ran = llfsm_process("run", "--clock", "sim", str(machine), "--duration", "2.6s", "--echo", "/pingpong")
    assert ran.status == 0, ran.stderr
    assert "data: The count is 0" in ran.stdout and "data: The count is 1" in ran.stdout
    # every guard file written by the editor names its target (SPEC 13)
    for guard_file in machine.glob("State_*_Transition_*.expr"):
        assert guard_file.read_text().startswith("# -> "), guard_file.name


def test_a_typo_shows_in_problems_and_on_the_diagram_and_leaves_when_fixed(ping_pong: Editor) -> None:
    e = ping_pong
    e.select_state("WAIT_AND_COUNT")
    e.type_code("OnEntry", "count +=\n")
    e.page.wait_for_selector('.state[data-state="WAIT_AND_COUNT"][data-problem="error"]')
    problems = e.problems()
    assert any("State_WAIT_AND_COUNT_OnEntry.py:1" in p for p in problems), problems
    e.page.wait_for_selector('[data-file="State_WAIT_AND_COUNT_OnEntry.py"] .cm-lint-marker-error')
    # the problem leads to its place: another state selected first, then the problem clicked
    e.select_state("INITIAL")
    e.page.get_by_role("list", name="Problems").get_by_role("button").first.click()
    e.page.wait_for_selector('.state[data-state="WAIT_AND_COUNT"][aria-selected="true"]')
    e.page.wait_for_selector('[data-file="State_WAIT_AND_COUNT_OnEntry.py"] .cm-editor.cm-focused')
    e.type_code("OnEntry", "count += 1\n")
    e.page.wait_for_selector('.state[data-state="WAIT_AND_COUNT"]:not([data-problem])')
    until(lambda: e.page.locator(".problems .clean").count() == 1, what="problems gone")
    assert (e.folder / "ros2_ping_pong.machine" / "State_WAIT_AND_COUNT_OnEntry.py").read_text() == "count += 1\n"


def test_a_dragged_state_stays_where_it_was_dropped_and_layout_yaml_says_so(ping_pong: Editor) -> None:
    e = ping_pong
    rect = e.state("END").locator("rect").first
    before = float(rect.get_attribute("x") or 0)
    box = rect.bounding_box()
    assert box is not None
    x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    e.page.mouse.move(x, y)
    e.page.mouse.down()
    e.page.mouse.move(x + 60, y + 10, steps=6)
    e.page.mouse.move(x + 120, y + 20, steps=6)
    e.page.mouse.up()
    layout = e.folder / "ros2_ping_pong.machine" / "layout.yaml"
    until(layout.exists, what="layout.yaml written")
    assert "END" in layout.read_text()
    until(lambda: float(e.state("END").locator("rect").first.get_attribute("x") or 0) > before + 20, what="redrawn")
    # the same place after the page is opened again (the server drew it from layout.yaml)
    e.page.reload()
    e.state("END").wait_for()
    assert float(e.state("END").locator("rect").first.get_attribute("x") or 0) > before + 20
    # a transition's label too
    label = e.page.locator('.guard[data-source="INITIAL"][data-index="1"]')
    box = label.bounding_box()
    assert box is not None
    e.page.mouse.move(box["x"] + 5, box["y"] + 5)
    e.page.mouse.down()
    e.page.mouse.move(box["x"] + 45, box["y"] + 45, steps=6)
    e.page.mouse.up()
    until(lambda: "labels:" in layout.read_text(), what="the label's place written")
    assert re.search(r"INITIAL:\n\s+1: \{x: ", layout.read_text()), layout.read_text()


def test_a_reorder_of_priorities_keeps_each_guard_with_its_target(ping_pong: Editor) -> None:
    e = ping_pong
    machine = e.folder / "ros2_ping_pong.machine"
    e.select_transition("PUBLISH", 1)
    priority = e.page.get_by_role("spinbutton", name="Priority")
    priority.fill("0")
    priority.press("Enter")
    e.page.wait_for_selector('.transition[data-source="PUBLISH"][data-index="0"][data-target="WAIT_AND_COUNT"]')
    assert re.search(
        r"- name: PUBLISH\n\s+transitions: \[WAIT_AND_COUNT, END\]", (machine / "machine.yaml").read_text()
    )
    assert "after_ms(500)" in (machine / "State_PUBLISH_Transition_0.expr").read_text()
    assert "not ros.ok()" in (machine / "State_PUBLISH_Transition_1.expr").read_text()
    assert llfsm("check", "--strict", str(machine)).status == 0


def test_a_file_changed_by_another_program_appears(ping_pong: Editor) -> None:
    e = ping_pong
    variables = e.folder / "ros2_ping_pong.machine" / "Variables.py"
    variables.write_text(variables.read_text() + "extra: int = 7\n")
    e.page.wait_for_selector('[data-file="Variables.py"] .cm-content:has-text("extra: int = 7")')


def test_a_conflict_with_unsaved_edits_shows_both_and_loses_neither(ping_pong: Editor) -> None:
    e = ping_pong
    variables = e.folder / "ros2_ping_pong.machine" / "Variables.py"
    theirs = variables.read_text() + "theirs: int = 1\n"

    def meanwhile(route: Any) -> None:
        # another program writes the file after the page's edit and before its save lands
        variables.write_text(theirs)
        route.continue_()

    e.page.route("**/api/write", meanwhile)
    e.code("Variables").click()
    e.page.keyboard.press("Control+End")
    e.page.keyboard.insert_text("mine: int = 2\n")
    conflict = e.page.get_by_role("alert", name="Conflict in Variables.py")
    conflict.wait_for()
    e.page.unroute("**/api/write")
    assert "mine: int = 2" in conflict.get_by_role("textbox", name="Your version").inner_text()
    assert "theirs: int = 1" in conflict.get_by_role("textbox", name="Version on disk").inner_text()
    assert variables.read_text() == theirs  # nothing written over theirs until the user chooses
    conflict.get_by_role("button", name="Keep mine").click()
    until(lambda: "mine: int = 2" in variables.read_text(), what="mine written")
    assert "theirs: int = 1" not in variables.read_text()


def test_undo_and_redo_across_structure_and_text(ping_pong: Editor) -> None:
    e = ping_pong
    machine = e.folder / "ros2_ping_pong.machine"
    e.add_state("PAUSE")
    assert "PAUSE" in (machine / "machine.yaml").read_text()
    e.type_code("Includes", "import math\n")
    e.saved()
    until(lambda: (machine / "Includes.py").read_text() == "import math\n")
    e.button("Undo").click()
    until(lambda: "from llfsm import ros" in (machine / "Includes.py").read_text(), what="text undone")
    e.page.wait_for_selector('[data-file="Includes.py"] .cm-content:has-text("from llfsm import ros")')
    e.button("Undo").click()
    e.state("PAUSE").wait_for(state="detached")
    assert "PAUSE" not in (machine / "machine.yaml").read_text()
    e.button("Redo").click()
    e.state("PAUSE").wait_for()
    assert "PAUSE" in (machine / "machine.yaml").read_text()


def test_structure_by_keyboard_alone(ping_pong: Editor) -> None:
    e = ping_pong
    machine = e.folder / "ros2_ping_pong.machine"
    e.button("Add state").focus()
    e.page.keyboard.press("Enter")
    e.page.wait_for_selector("dialog[open] input[name=name]:focus")  # the dialog's first field has the focus
    e.page.keyboard.type("IDLE")
    e.page.keyboard.press("Enter")
    e.state("IDLE").wait_for()
    e.state("PUBLISH").focus()
    e.page.keyboard.press("Enter")
    e.page.wait_for_selector('.state[data-state="PUBLISH"][aria-selected="true"]')
    # Alt+arrows move the focused state: a layout without a pointer
    e.state("PUBLISH").focus()
    e.page.keyboard.press("Alt+ArrowRight")
    until(lambda: "PUBLISH" in _text(machine / "layout.yaml"), what="moved by the keyboard")
    suspend = e.page.get_by_role("checkbox", name="Suspend state")
    suspend.focus()
    e.page.keyboard.press("Space")
    until(lambda: "suspended: PUBLISH" in (machine / "machine.yaml").read_text(), what="suspend state set")


def test_run_turns_the_diagram_into_the_live_view_and_stop_ends_it(ping_pong: Editor) -> None:
    e = ping_pong
    e.button("Run").click()
    e.page.wait_for_selector('.state[data-state="PUBLISH"][aria-current="true"]', timeout=30_000)
    e.page.wait_for_selector('.state[data-state="WAIT_AND_COUNT"][aria-current="true"]')
    e.button("Stop").click()
    until(lambda: e.page.get_by_role("status", name="run status").inner_text() == "stopped", what="stopped")


@pytest.mark.parametrize("width", [1280, 800])
def test_the_page_fits_its_width_with_a_problem_marked(browser: Any, tmp_path: Path, width: int) -> None:
    """What docs/edit.md shows (the screenshots are taken here: LLFSM_SCREENSHOTS=DIR keeps them)."""
    folder = tmp_path / "machines"
    folder.mkdir()
    machine = _copy_ping_pong(folder)
    shutil.copytree(MACHINES / "ros2_wall_turtle_bot.machine", folder / "ros2_wall_turtle_bot.machine")
    (machine / "State_WAIT_AND_COUNT_OnEntry.py").write_text("count += \n")
    # tall enough to show the whole page: CodeMirror measures the editors it can see
    e = Editor(browser, folder, width=width, height=1100 if width > 1000 else 1800)
    try:
        e.page.locator('nav.machines button[data-machine="ros2_ping_pong"]').click()
        e.select_state("PUBLISH")
        e.page.wait_for_selector('.state[data-state="WAIT_AND_COUNT"][data-problem="error"]')
        assert e.page.evaluate("() => document.documentElement.scrollWidth") <= width
        assert not e.errors
        keep = os.environ.get("LLFSM_SCREENSHOTS")
        e.page.screenshot(path=str(Path(keep or tmp_path) / f"edit-{width}.png"), full_page=True)
    finally:
        e.close()
