"""Machines on the graph across processes (SPEC §8 over DDS) and `llfsm view` (SPEC §10).

Every process runs in a private network namespace (tests/dds_netns.py): nothing leaves this
machine, and the processes find each other as ROS 2 nodes on one host do.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from dds_netns import NetNamespace, finish
from helpers import MACHINES, write_machine

pytestmark = pytest.mark.dds

WATCHER = {
    "INITIAL": [("JOIN", "after_ms(3000)")],
    "JOIN": [("ASK", "after_ms(1000)")],
    "ASK": [("LOOK", "after_ms(1500)")],
    "LOOK": [("END", "True")],
    "END": None,
}
WATCHER_CODE = {
    "INITIAL_OnEntry": "ros.init()\nnode = ros.Node('watcher')",
    "JOIN_OnEntry": (
        "latched = ros.QoSProfile(depth=1, durability=ros.DurabilityPolicy.TRANSIENT_LOCAL)\n"
        "sub = node.create_subscription(String, '/llfsm/ros2_ping_pong/state', None, latched)"
    ),
    "ASK_OnEntry": (
        "node.get_logger().info(f'joined: {sub.latest.data if sub.latest is not None else None}')\n"
        "cli = node.create_client(Trigger, '/llfsm/ros2_ping_pong/suspend')\n"
        "cli.wait_for_service(timeout_sec=5.0)\n"
        "fut = cli.call_async(Trigger.Request())\n"
        "code = ros.spin_until_future_complete(node, fut, timeout_sec=5.0)\n"
        "node.get_logger().info(f'suspend: {code} {fut.result().success if fut.done() else None}')"
    ),
    "LOOK_OnEntry": "node.get_logger().info(f'now: {sub.latest.data if sub.latest is not None else None}')",
}


def test_state_and_control_of_a_machine_in_another_process(netns: NetNamespace, tmp_path: Path) -> None:
    watcher = write_machine(
        tmp_path,
        "watcher",
        WATCHER,
        WATCHER_CODE,
        variables="node: ros.Node\nsub: ros.Subscription\n",
        includes=(
            "from llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import String\n"
            "from llfsm.msgs.std_srvs.srv import Trigger\n"
        ),
    )
    pp = netns.llfsm("run", "--transport", "dds", MACHINES / "ros2_ping_pong.machine", "--duration", "9")
    w = netns.llfsm("run", "--transport", "dds", watcher, "--duration", "15")
    w_status, _, w_err = finish(w, 40)
    p_status, _, p_err = finish(pp, 40)
    assert w_status == 0 and p_status == 0, w_err + p_err
    joined = [line for line in w_err.splitlines() if "joined:" in line]
    assert joined and joined[0].split("joined: ")[1] in ("PUBLISH", "WAIT_AND_COUNT"), w_err  # the current state
    assert "suspend: SUCCESS True" in w_err
    assert "now: SUSPENDED" in w_err
    # suspended from outside, the run waited (it could be resumed) until its --duration
    assert p_err.count("Publishing:") <= 5


CLIENT = r"""
import asyncio, json, sys, aiohttp
from llfsm.web.channel import Mirror
async def main(url):
    out = {"machines": [], "states": [], "statuses": []}
    mirror = Mirror()
    async with aiohttp.ClientSession() as s:
        async with s.ws_connect(url.replace("http://", "ws://") + "ws") as ws:
            loop = asyncio.get_running_loop()
            end = loop.time() + 25
            asked = False
            while loop.time() < end:
                msg = await asyncio.wait_for(ws.receive(), end - loop.time())
                data = json.loads(msg.data)
                if data["type"] == "hello":
                    out["machines"] = [m["name"] for m in data["machines"]]
                    out["svg"] = any('data-state="WAIT_AND_COUNT"' in m["svg"] for m in data["machines"])
                data = mirror.apply(data)
                if data is None:  # the graph of nodes and topics
                    continue
                for m in data["machines"]:
                    if m["name"] == "ros2_ping_pong":
                        if not out["states"] or out["states"][-1] != m["state"]:
                            out["states"].append(m["state"])
                        out["statuses"].append(m["status"])
                if {"PUBLISH", "WAIT_AND_COUNT"} <= set(out["states"]) and not asked:
                    asked = True
                    r = await s.post(url + "api/command", json={"machine": "ros2_ping_pong", "command": "suspend"})
                    out["answer"] = await r.json()
                if out["statuses"] and out["statuses"][-1] == "suspended":
                    break
    print(json.dumps(out))
asyncio.run(main(sys.argv[1]))
"""


def test_llfsm_view_finds_shows_and_steers_a_machine_of_another_run(netns: NetNamespace) -> None:
    pytest.importorskip("aiohttp")
    pp = netns.llfsm("run", "--transport", "dds", MACHINES / "ros2_ping_pong.machine", "--duration", "30")
    view = netns.llfsm("view", "--web", "127.0.0.1:0", "--duration", "30")
    assert view.stderr is not None
    url = ""
    for line in view.stderr:
        if "http://" in line:
            url = line.split("web view at ", 1)[1].strip()
            break
    assert url, "llfsm view printed no address"
    client = netns.python(CLIENT.replace("sys.argv[1]", repr(url)))
    c_status, out, c_err = finish(client, 60)
    pp.terminate()
    view.terminate()
    finish(pp, 20)
    finish(view, 20)
    assert c_status == 0, c_err
    got = json.loads(out)
    assert "ros2_ping_pong" in got["machines"] and got["svg"]
    assert {"PUBLISH", "WAIT_AND_COUNT"} <= set(got["states"])  # the page follows the other run's state
    assert got["answer"]["success"] is True and "pending" in got["answer"]["message"]
    assert got["statuses"][-1] == "suspended" and got["states"][-1] == "SUSPENDED"


VIEW_CLIENT = r"""
import asyncio, json, sys, aiohttp
from llfsm.web.channel import Mirror
async def main(url):
    out = {"machines": {}, "graph": None, "first": None}
    mirror = Mirror()
    async with aiohttp.ClientSession() as s:
        async with s.ws_connect(url.replace("http://", "ws://") + "ws") as ws:
            loop = asyncio.get_running_loop()
            end = loop.time() + 40
            while loop.time() < end:
                data = json.loads((await asyncio.wait_for(ws.receive(), end - loop.time())).data)
                if data["type"] == "hello":
                    out["graph"] = data["graph"]
                elif data["type"] == "graph":
                    out["graph"] = data
                    continue
                data = mirror.apply(data)
                rows = [m for m in data["machines"] if m["transitions"]]
                if out["first"] is None and rows:
                    out["first"] = {"t": data["t"], "source": data["source"], "rows": rows}
                for m in data["machines"]:
                    out["machines"][m["name"]] = m
                nodes = set((out["graph"] or {}).get("nodes", []))
                if len(out["machines"]) >= 2 and {"/turtlesim", "/ros_ping_pong"} <= nodes and out["first"]:
                    break
        api = url + "api/"
        out["params"] = await (await s.post(api + "parameters", json={"node": "/turtlesim"})).json()
        for key, value in (("bad", "abc"), ("good", "10")):
            ask = {"node": "/turtlesim", "name": "background_r", "value": value}
            out[key] = await (await s.post(api + "parameter", json=ask)).json()
        out["after"] = await (await s.post(api + "parameters", json={"node": "turtlesim"})).json()
    print(json.dumps(out))
asyncio.run(main(sys.argv[1]))
"""


def test_llfsm_view_shows_two_runs_their_own_times_the_graph_and_parameters_over_dds(netns: NetNamespace) -> None:
    """Issue 22 and 21 in `llfsm view`: two runs of ping-pong (one with turtlesim) started before
    the view: two machines, each saying its run; times are the runs' own (they started seconds
    before the view did); the graph shows the runs' nodes; turtlesim's parameters are read and
    set through its parameter services over DDS, a bad value refused with the node's reason."""
    pytest.importorskip("aiohttp")
    one = netns.llfsm(
        "run", "--transport", "dds", MACHINES / "ros2_ping_pong.machine", "--node", "turtlesim", "--duration", "60"
    )
    two = netns.llfsm("run", "--transport", "dds", MACHINES / "ros2_ping_pong.machine", "--duration", "60")
    # The runs' clocks must be seconds ahead of the view's: wait until each has run 4 s by its own
    # clock (its fifth count), however long a loaded machine took to start it.
    for run in (one, two):
        assert run.stderr is not None
        for line in run.stderr:
            if "'The count is 4'" in line:
                break
        else:
            raise AssertionError(f"a run ended before its fifth count: {finish(run, 5)}")
    view = netns.llfsm("view", "--web", "127.0.0.1:0", "--duration", "60")
    assert view.stderr is not None
    url = ""
    for line in view.stderr:
        if "http://" in line:
            url = line.split("web view at ", 1)[1].strip()
            break
    assert url, "llfsm view printed no address"
    client = netns.python(VIEW_CLIENT.replace("sys.argv[1]", repr(url)))
    c_status, out, c_err = finish(client, 90)
    for p in (one, two, view):
        p.terminate()
    for p in (one, two, view):
        finish(p, 20)
    assert c_status == 0, c_err
    got = json.loads(out)
    rows = got["machines"]
    assert len(rows) == 2 and "ros2_ping_pong" in rows, rows
    other = next(k for k in rows if k != "ros2_ping_pong")
    assert other.startswith("ros2_ping_pong@") and len(other) == len("ros2_ping_pong@") + 8
    assert {r["machine"] for r in rows.values()} == {"ros2_ping_pong"}
    assert all(r["runs"] == 2 for r in rows.values())
    assert len({r["participant"] for r in rows.values()}) == 2 and all(r["participant"] for r in rows.values())
    assert other.endswith(rows[other]["participant"][8:16])
    first = got["first"]
    assert first["source"] == "view"
    newest = max(t["t"] for r in first["rows"] for t in r["transitions"])
    assert newest > first["t"] + 2.5, first  # the run's time, seconds ahead of the view's
    assert all(r["run_time"] for r in first["rows"])
    assert {"/turtlesim", "/ros_ping_pong"} <= set(got["graph"]["nodes"])
    # turtlesim's action, found over DDS by the names and types of its services
    assert {
        "name": "/turtle1/rotate_absolute",
        "type": "turtlesim/action/RotateAbsolute",
        "servers": ["/turtlesim"],
        "clients": [],
    } in got["graph"]["actions"]
    params = {p["name"]: p for p in got["params"]["parameters"]}
    assert got["params"]["success"] and params["background_r"]["type"] == "integer"
    assert not got["bad"]["success"]
    assert got["bad"]["message"].startswith("Setting parameter failed: Wrong parameter type")
    assert got["good"] == {"success": True, "message": "Set parameter successful"}
    assert {p["name"]: p["value"] for p in got["after"]["parameters"]}["background_r"] == "10"


GONE_CLIENT = r"""
import asyncio, json, sys, aiohttp
from llfsm.web.channel import Mirror
async def main(url):
    seen = []
    mirror = Mirror()
    async with aiohttp.ClientSession() as s:
        async with s.ws_connect(url.replace("http://", "ws://") + "ws") as ws:
            loop = asyncio.get_running_loop()
            end = loop.time() + 40
            while loop.time() < end:
                data = json.loads((await asyncio.wait_for(ws.receive(), end - loop.time())).data)
                data = mirror.apply(data)
                if data is None:
                    continue
                for m in data["machines"]:
                    if not seen or seen[-1] != m["ended"]:
                        seen.append(m["ended"])
                if seen[-1:] == [True]:
                    break
    print(json.dumps(seen))
asyncio.run(main(sys.argv[1]))
"""


def test_llfsm_view_says_when_a_run_has_gone(netns: NetNamespace) -> None:
    """Issue 22: after its run ends, a machine's card in `llfsm view` no longer says running (the
    page shows `run gone` and disables its buttons when `ended` is true)."""
    pytest.importorskip("aiohttp")
    run = netns.llfsm("run", "--transport", "dds", MACHINES / "ros2_ping_pong.machine", "--duration", "8")
    view = netns.llfsm("view", "--web", "127.0.0.1:0", "--duration", "60")
    assert view.stderr is not None
    url = ""
    for line in view.stderr:
        if "http://" in line:
            url = line.split("web view at ", 1)[1].strip()
            break
    assert url, "llfsm view printed no address"
    client = netns.python(GONE_CLIENT.replace("sys.argv[1]", repr(url)))
    c_status, out, c_err = finish(client, 60)
    r_status, _, r_err = finish(run, 30)
    view.terminate()
    finish(view, 20)
    assert c_status == 0 and r_status == 0, c_err + r_err
    assert json.loads(out) == [False, True]
