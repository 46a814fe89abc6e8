"""The debugger's requests from the page (llfsm.web.debugging, docs/debug.md "The page"), over
HTTP against a run in this process: pause, step, read and set, breakpoints, history frames;
and a replay's frames.  The page's controls themselves are tested in Chromium."""

from __future__ import annotations

import asyncio
import http.client
import json
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from helpers import MACHINES, llfsm

pytest.importorskip("aiohttp")

from llfsm import ros
from llfsm.debug.debugger import Debugger
from llfsm.ros.control import enable
from llfsm.runtime import Arrangement, RunContext, SimClock
from llfsm.runtime.context import activate
from llfsm.targets import load
from llfsm.web.debugging import ReplayDebug, RunDebug
from llfsm.web.replay import read
from llfsm.web.server import WebServer
from llfsm.web.source import RunSource


class _Served:
    """The counter run in a thread of its own (as the scheduler's), its page served."""

    def __init__(self) -> None:
        self.ctx = RunContext(SimClock(1_000_000))
        prev = activate(self.ctx)
        try:
            self.arr = Arrangement([load(str(MACHINES / "counter.machine"))], context=self.ctx)
            ros.init()
            enable(self.ctx)
            self.debugger = Debugger(self.arr, history=1000)
            source = RunSource(self.arr, ros.bus_of())
            source.debug = RunDebug(self.debugger)
            self.debugger.attach_bus(ros.bus_of(), lambda: None)
        finally:
            activate(prev)
        self.arr.end_when_suspended = False
        self.debugger.pause("--paused")
        self.server = WebServer(source, "127.0.0.1", 0)
        self.server.start()
        self.thread = threading.Thread(target=self.arr.run, kwargs={"duration_ns": 10**12}, daemon=True)
        self.thread.start()

    def post(self, what: str, **data: Any) -> tuple[int, dict[str, Any]]:
        conn = http.client.HTTPConnection("127.0.0.1", self.server.port, timeout=10)
        conn.request("POST", f"/api/debug/{what}", body=json.dumps(data), headers={"Content-Type": "application/json"})
        resp = conn.getresponse()
        body = resp.read()
        conn.close()
        return resp.status, json.loads(body) if resp.getheader("Content-Type", "").startswith(
            "application/json"
        ) else {}

    def paused(self, timeout: float = 10) -> dict[str, Any]:
        """The debug part of a snapshot, once the run is paused."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            state = self.server.source.debug.state()  # type: ignore[union-attr]
            if state["paused"]:
                return state
            time.sleep(0.01)
        raise AssertionError("the run did not pause")

    def stop(self) -> None:
        self.arr.interrupt(0)
        if self.debugger.paused:
            self.debugger.inbox.put(lambda: None)
        self.thread.join(10)
        self.server.stop()


@pytest.fixture
def served() -> Iterator[_Served]:
    s = _Served()
    try:
        yield s
    finally:
        s.stop()


def test_the_page_pauses_steps_reads_sets_and_continues_the_run(served: _Served) -> None:
    state = served.paused()
    assert state["where"] == "paused before the first round (0.000 s): --paused"
    assert state["variables"] == {"counter": {"count": 0, "limit": 5}}
    status, answer = served.post("step")
    assert status == 200 and answer["message"] == "stepping one ringlet"
    state = served.paused()
    assert state["reason"] == "step" and state["machine"] == "counter"
    status, answer = served.post("set", machine="counter", name="count", value="3")
    assert status == 200 and answer["message"] == "counter.count = 3"
    status, answer = served.post("set", machine="counter", name="count", value="three")
    assert status == 400 and answer["message"] == "counter.count is int: 'three' is a string, not an int"
    status, answer = served.post("breakpoint", expression="counter.count == 5", enable=True)
    assert status == 200 and answer["message"] == "breakpoint 1: counter.count == 5"
    status, answer = served.post("breakpoint", expression="counter.nope == 5", enable=True)
    assert status == 400 and "counter has no variable or input nope" in answer["message"]
    assert served.post("continue")[1]["message"] == "continuing"
    time.sleep(0.05)
    state = served.paused()
    assert state["reason"] == "break 1: counter.count == 5" and state["variables"]["counter"]["count"] == 5
    status, frame = served.post("frame", back=state["records"] - 1)  # the first record: the first ringlet
    assert status == 200 and frame["record"]["ringlet"] == 1 and frame["machines"][0]["state"] == "COUNT"
    assert frame["machines"][0]["values"]["count"] == 0  # COUNT entered: its OnEntry runs in the next ringlet
    status, hist = served.post("history", n=2)
    assert [r["changed"].get("count") for r in hist["records"]] == [None, [4, 5]]
    assert served.post("frame", back=10_000)[0] == 400
    assert served.post("pause")[1]["message"] == "pausing at the next ringlet boundary"
    assert served.post("nonsense")[0] == 404


def test_a_replay_answers_frames_and_refuses_to_run(tmp_path: Path) -> None:
    trace = tmp_path / "t.jsonl"
    assert llfsm("run", "--clock", "sim", MACHINES / "counter.machine", "--trace", trace).status == 0
    debug = ReplayDebug(read(trace))
    frame = asyncio.run(debug.request("frame", {"at": 1}))
    assert frame["machines"][0]["state"] == "COUNT" and frame["record"]["after"] == "COUNT"
    with pytest.raises(Exception, match="a replay cannot step round: it is a recorded run"):
        asyncio.run(debug.request("step_round", {}))
    assert debug.state()["replay"] == "trace" and debug.state()["records"] == len(read(trace).records)
