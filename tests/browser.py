"""Shared by the page's browser tests: Debian's Chromium driven by Playwright (never a browser
Playwright downloads), a server of llfsm started as a process with its printed address, and
the rule that the page's build (frontend/, `make`) must be there: its absence fails these
tests with a clear message instead of skipping them (docs/architecture.md, "The front end")."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from helpers import REPO

CHROMIUM = os.environ.get("LLFSM_CHROMIUM", "/usr/bin/chromium")
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
TIMEOUT_MS = 15_000
APP = REPO / "llfsm" / "web" / "static" / "app" / "app.js"


def have_chromium() -> bool:
    return Path(CHROMIUM).exists() or shutil.which(CHROMIUM) is not None


def page_not_built() -> str | None:
    """Why the page cannot be tested (its build is missing), or None."""
    if APP.exists():
        return None
    return f"the page is not built ({APP.relative_to(REPO)} is missing): run `make web` (make test does it)"


def until(condition: Callable[[], object], timeout: float = TIMEOUT_MS / 1000, what: str = "") -> None:
    """Poll from Python: the page's Content-Security-Policy forbids evaluating strings, and so
    Playwright's wait_for_function."""
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, f"timed out{': ' + what if what else ''}"
        time.sleep(0.05)


def playwright_or_skip() -> Any:
    """Playwright's sync API; the calling test module is skipped, saying why, without it, the
    web extra or Chromium."""
    pytest.importorskip("aiohttp")
    sync_api = pytest.importorskip(
        "playwright.sync_api", reason="playwright is not installed (pip install -e '.[dev]')"
    )
    if not have_chromium():
        pytest.skip(
            f"no Chromium at {CHROMIUM}: `apt-get install chromium` (make test does it as root)",
            allow_module_level=True,
        )
    # `expect` does not take the page's default timeout: its own is 5 s, which a loaded machine
    # overran (a run's debugger status, a command's answer); the same wait as every other here
    sync_api.expect.set_options(timeout=TIMEOUT_MS)
    return sync_api


def chromium(sync_api: Any) -> Iterator[Any]:
    """A headless Chromium for a test module's tests (a generator for a fixture to yield from)."""
    with sync_api.sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        try:
            yield b
        finally:
            b.close()


class Served:
    """`llfsm VERB ... --web 127.0.0.1:0` as a process: its URL (from the line holding
    `http://`), its standard output and error kept as they come."""

    def __init__(self, *args: str, cwd: Path = REPO, env: dict[str, str] | None = None) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "llfsm", *args, "--web", "127.0.0.1:0"],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            cwd=cwd,
            env={**os.environ, "PYTHONUNBUFFERED": "1", **(env or {})},
        )
        self.stdout: list[str] = []
        self.stderr: list[str] = []
        self.url = ""
        assert self.proc.stderr is not None
        deadline = time.monotonic() + 60
        for line in self.proc.stderr:
            self.stderr.append(line)
            m = re.search(r"http://\S+", line)
            if m:
                self.url = m.group(0)
                break
            if time.monotonic() > deadline:
                break
        assert self.url, f"no http:// address printed: {''.join(self.stderr)}"
        threading.Thread(target=self._drain, args=(self.proc.stdout, self.stdout), daemon=True).start()
        threading.Thread(target=self._drain, args=(self.proc.stderr, self.stderr), daemon=True).start()

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
