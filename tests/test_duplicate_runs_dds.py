"""Two runs of the same machine on one domain (issue 22, item 13): each run says so when it
sees the other, and `llfsm view`'s data keeps them as two machines, each with its own
transitions, not one machine with the two runs' transitions merged.

The two machines share a name (so topics and services) but not their states: a run's states
in the other's history would show the merge.  Every process runs in a private network
namespace (tests/dds_netns.py).
"""

# ruff: noqa: F811  (the netns fixture is imported, and test arguments name it)
from __future__ import annotations

import json
from pathlib import Path

import pytest
from dds_netns import NetNamespace, finish, netns  # noqa: F401  (the fixture)
from helpers import write_machine

pytestmark = pytest.mark.dds  # every test talks DDS across processes


def _twins(tmp_path: Path) -> tuple[Path, Path]:
    """Two machines named twin (a machine is on the graph once it uses the bus: ros.init())."""
    blink = write_machine(
        tmp_path / "a",
        "twin",
        {"ON": [("OFF", "after_ms(300)")], "OFF": [("ON", "after_ms(300)")]},
        {"ON_OnEntry": "ros.init()"},
        includes="from llfsm import ros\n",
    )
    slow = write_machine(
        tmp_path / "b",
        "twin",
        {"IDLE": [("WAITING", "after_ms(1500)")], "WAITING": [("IDLE", "after_ms(1500)")]},
        {"IDLE_OnEntry": "ros.init()"},
        includes="from llfsm import ros\n",
    )
    return blink, slow


def test_each_run_warns_that_another_runs_the_same_machine(netns: NetNamespace, tmp_path: Path) -> None:
    blink, slow = _twins(tmp_path)
    first = netns.llfsm("run", "--transport", "dds", blink, "--duration", "12")
    second = netns.llfsm("run", "--transport", "dds", slow, "--duration", "8")
    _s2, _out2, err2 = finish(second, 60)
    _s1, _out1, err1 = finish(first, 60)
    for err in (err1, err2):
        lines = [line for line in err.splitlines() if "runs a machine named twin too" in line]
        assert len(lines) == 1, err  # once, not once per look
        assert lines[0].startswith("[WARN]") and "/llfsm/twin/suspend" in lines[0] and "llfsm view" in lines[0]


CLIENT = r"""
import asyncio, json, aiohttp
from llfsm.web.channel import Mirror
async def main(url):
    rows = {}
    mirror = Mirror()
    async with aiohttp.ClientSession() as s:
        async with s.ws_connect(url.replace("http://", "ws://") + "ws") as ws:
            loop = asyncio.get_running_loop()
            end = loop.time() + 9
            while loop.time() < end:
                try:
                    msg = await asyncio.wait_for(ws.receive(), end - loop.time())
                except asyncio.TimeoutError:
                    break
                data = json.loads(msg.data)
                if data["type"] == "hello":
                    names = [m["name"] for m in data["machines"]]
                data = mirror.apply(data)
                if data is None:  # the graph of nodes and topics
                    continue
                for m in data["machines"]:
                    rows[m["name"]] = m
            answer = None
            if len(rows) == 2:
                other = next(n for n in rows if n != "twin")
                r = await s.post(url + "api/command", json={"machine": other, "command": "suspend"})
                answer = await r.json()
    print(json.dumps({"names": names, "rows": rows, "answer": answer}))
asyncio.run(main(URL))
"""


def test_the_view_keeps_two_runs_of_a_machine_apart(netns: NetNamespace, tmp_path: Path) -> None:
    pytest.importorskip("aiohttp")
    blink, slow = _twins(tmp_path)
    a = netns.llfsm("run", "--transport", "dds", blink, "--duration", "30")
    b = netns.llfsm("run", "--transport", "dds", slow, "--duration", "30")
    view = netns.llfsm("view", "--web", "127.0.0.1:0", "--duration", "30")
    assert view.stderr is not None
    url = ""
    for line in view.stderr:
        if "http://" in line:
            url = line.split("web view at ", 1)[1].strip()
            break
    assert url, "llfsm view printed no address"
    client = netns.python(CLIENT.replace("URL", repr(url)))
    c_status, out, c_err = finish(client, 60)
    for p in (a, b, view):
        p.terminate()
        finish(p, 20)
    assert c_status == 0, c_err
    got = json.loads(out)
    rows = got["rows"]
    assert len(rows) == 2, rows
    assert "twin" in rows
    other = next(n for n in rows if n != "twin")
    assert other.startswith("twin@") and rows[other]["machine"] == "twin"
    assert rows["twin"]["participant"] != rows[other]["participant"]
    assert sorted(got["names"]) == sorted(rows)  # each drawn, under its own name
    states = {
        name: {s for t in row["transitions"] for s in (t["from"], t["to"])} | {row["state"]}
        for name, row in rows.items()
    }
    kinds = sorted(states.values(), key=lambda s: sorted(s))
    # each machine's history holds its own run's states only
    assert kinds[0] <= {"IDLE", "WAITING"} or kinds[0] <= {"ON", "OFF"}, states
    assert not (states["twin"] & states[other]), states
    assert {"ON", "OFF"} in [s & {"ON", "OFF"} for s in states.values()], states
    # a command to one reaches both runs (their services share the name), and says so
    assert got["answer"] is not None and "2 runs of twin" in got["answer"]["message"], got["answer"]
