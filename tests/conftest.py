"""Fixtures and hooks of the whole suite.  What tests import lives in helpers.py (and the other
helper modules it names); nothing is imported from here.

The markers (declared in pyproject.toml, strict): `dds` (Cyclone DDS participants, in a private
network namespace where they talk across processes), `browser` (Chromium, headless), `interop`
(real ROS 2 from .venv-ros), `slow` (left out unless the `-m` expression names it: `-m slow`,
`-m "slow or not slow"`; any other `-m`, such as the quick run's `-m "not dds and not browser"`,
still leaves it out).  A test that uses the `netns` fixture talks DDS, so it must carry `dds`:
collection stops saying which do not.
"""

from __future__ import annotations

import re
from collections.abc import Iterator

import pytest

from llfsm import ros
from llfsm.ros.bus import Bus, bus_of
from llfsm.runtime import RunContext, SimClock
from llfsm.runtime.context import activate

pytest_plugins = ["dds_netns"]  # the `netns` fixture


@pytest.fixture(autouse=True)
def _isolated_cache(tmp_path_factory: pytest.TempPathFactory, monkeypatch: pytest.MonkeyPatch) -> None:
    """Every test compiles into its own cache, never into ~/.cache."""
    monkeypatch.setenv("LLFSM_CACHE_DIR", str(tmp_path_factory.mktemp("cache")))


@pytest.fixture
def bus() -> Iterator[Bus]:
    """A fresh run context with a sim clock, active for the test."""
    ctx = RunContext(SimClock())
    prev = activate(ctx)
    ros.init()
    try:
        yield bus_of(ctx)
    finally:
        activate(prev)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """`slow` tests are left out unless `-m` names them (a `-m` on the command line replaces the
    one of addopts, so addopts cannot do it); `-m "not dds"` must leave out every test that
    talks DDS across processes."""
    if not re.search(r"\bslow\b", config.option.markexpr or ""):
        slow = [item for item in items if item.get_closest_marker("slow")]
        if slow:
            config.hook.pytest_deselected(items=slow)
            items[:] = [item for item in items if not item.get_closest_marker("slow")]
    unmarked = [
        item.nodeid
        for item in items
        if "netns" in getattr(item, "fixturenames", ()) and not item.get_closest_marker("dds")
    ]
    if unmarked:
        raise pytest.UsageError("tests that use the netns fixture need the dds marker:\n  " + "\n  ".join(unmarked))
