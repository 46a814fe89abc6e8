"""The web view's server without a browser (SPEC §10): the diagram, security (token, Origin,
Host), message values, and `--web` usage errors."""

from __future__ import annotations

import base64
import http.client
import json
import logging
import os
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from browser import until
from helpers import MACHINES, llfsm, llfsm_process

pytest.importorskip("aiohttp")

from llfsm import ros
from llfsm.diagram import svg as diagram
from llfsm.msgs.geometry_msgs.msg import PoseStamped, Twist
from llfsm.msgs.std_msgs.msg import String
from llfsm.ros.control import description, enable
from llfsm.runtime import Arrangement, RunContext, SimClock
from llfsm.runtime.context import activate
from llfsm.targets import load
from llfsm.web.server import WebServer, parse_address
from llfsm.web.source import CommandError, RunSource, parse_values, type_class

PING_PONG = MACHINES / "ros2_ping_pong.machine"


# -- the diagram ---------------------------------------------------------------------------------


def test_the_diagram_has_every_state_and_guard_and_marks_the_current_one() -> None:
    desc = description(load(str(PING_PONG)))
    svg = diagram.svg(desc, current="PUBLISH")
    for state in ("INITIAL", "PUBLISH", "WAIT_AND_COUNT", "END", "SUSPENDED"):
        assert f'data-machine="ros2_ping_pong" data-state="{state}"' in svg
    assert svg.count('aria-current="true"') == 1
    assert 'data-state="PUBLISH" aria-current="true"' in svg
    assert "1: after_ms(1000)" in svg and "0: not ros.ok()" in svg  # guards as written, with their priority
    assert svg.count('class="transition"') == 6  # the six transitions of the seed machine
    assert "http://" not in svg.replace('xmlns="http://www.w3.org/2000/svg"', "")  # nothing fetched


def test_guard_text_is_escaped_in_the_diagram() -> None:
    desc = {
        "name": "m",
        "initial": "A",
        "suspend": "A",
        "states": [
            {"name": "A", "accepting": False, "transitions": [{"index": 0, "target": "A", "guard": "x < 1 and '<b>'"}]}
        ],
    }
    svg = diagram.svg(desc)
    assert "<b>" not in svg and "x &lt; 1" in svg


def test_a_layout_keeps_states_apart() -> None:
    desc = description(load(str(MACHINES / "turtle_follower.machine")))
    placed = diagram.layout(desc)
    boxes = []
    for s in desc["states"]:
        (x, y), w = placed.centres[s["name"]], diagram._state_w(s["name"])
        boxes.append((x - w / 2, y - diagram.STATE_H / 2, x + w / 2, y + diagram.STATE_H / 2))
    for i, a in enumerate(boxes):
        for b in boxes[i + 1 :]:
            assert a[2] <= b[0] or b[2] <= a[0] or a[3] <= b[1] or b[3] <= a[1], (a, b)


# -- values typed into the page ---------------------------------------------------------------------


def test_values_are_yaml_checked_by_the_message_types_never_evaluated() -> None:
    """The page's values go through `llfsm topic pub`'s parsing (llfsm.msgs._yaml) and its TYPE
    reading (llfsm.ros2cli.interfaces); every mistake is a CommandError of one line."""
    t, _ = parse_values(Twist, "{linear: {x: 2}, angular: {z: -1.5}}")
    assert t.linear.x == 2.0 and t.angular.z == -1.5
    assert parse_values(String, "")[0].data == ""
    stamped, stamps = parse_values(PoseStamped, "{header: auto, pose: {position: {x: 1.5}}}")  # as topic pub takes it
    assert stamped.pose.position.x == 1.5 and len(stamps) == 1
    with pytest.raises(CommandError, match="float"):
        parse_values(Twist, "{linear: {x: \"__import__('os').system('true')\"}}")
    with pytest.raises(CommandError, match="no field 'linar'"):
        parse_values(Twist, "{linar: {x: 1}}")
    with pytest.raises(CommandError, match="not valid YAML"):
        parse_values(Twist, "{linear: {x: 1}")
    with pytest.raises(CommandError, match="mapping"):
        parse_values(String, "- a list")
    assert type_class("std_msgs/String", "msg") is String
    with pytest.raises(CommandError, match="unknown message type"):
        type_class("nope_msgs/msg/Thing", "msg")
    with pytest.raises(CommandError, match="invalid type"):
        type_class("../../etc/msg/x", "msg")
    with pytest.raises(CommandError, match="is a message type"):
        type_class("std_msgs/msg/String", "srv")


# -- the server --------------------------------------------------------------------------------------


@pytest.fixture
def server(request: pytest.FixtureRequest) -> Iterator[WebServer]:
    """A page over a ping-pong arrangement that is not running (HTTP-level checks only)."""
    ctx = RunContext(SimClock())
    prev = activate(ctx)
    try:
        arr = Arrangement([load(str(PING_PONG))], context=ctx)
        ros.init()
        enable(ctx)
        srv = WebServer(RunSource(arr, ros.bus_of()), "127.0.0.1", 0, token=getattr(request, "param", None))
        srv.start()
        yield srv
        srv.stop()
    finally:
        activate(prev)


def _get(
    srv: WebServer, path: str, headers: dict[str, str] | None = None, method: str = "GET", body: str | None = None
) -> http.client.HTTPResponse:
    conn = http.client.HTTPConnection("127.0.0.1", srv.port, timeout=10)
    conn.request(method, path, body=body, headers=headers or {})
    resp = conn.getresponse()
    resp.read()
    conn.close()
    return resp


def _upgrade(srv: WebServer, path: str = "/ws", headers: dict[str, str] | None = None) -> int:
    key = base64.b64encode(os.urandom(16)).decode()
    h = {"Upgrade": "websocket", "Connection": "Upgrade", "Sec-WebSocket-Key": key, "Sec-WebSocket-Version": "13"}
    return _get(srv, path, {**h, **(headers or {})}).status


def test_the_page_and_its_assets_are_served_from_the_package(server: WebServer) -> None:
    assert server.url == f"http://127.0.0.1:{server.port}/"
    assert _get(server, "/").status == 200
    for name in ("app.js", "style.css"):
        assert _get(server, f"/static/{name}").status == 200
    assert _get(server, "/static/../server.py").status == 404
    assert "default-src 'self'" in _get(server, "/").getheader("Content-Security-Policy", "")


@pytest.mark.parametrize("server", ["s3cret-token"], indirect=True)
def test_a_wrong_or_missing_token_is_refused(server: WebServer) -> None:
    assert server.url.endswith("/?token=s3cret-token")
    assert _get(server, "/").status == 403
    assert _get(server, "/?token=wrong").status == 403
    assert _upgrade(server, "/ws?token=wrong") == 403
    ok = _get(server, "/?token=s3cret-token")
    assert ok.status == 200
    cookie = ok.getheader("Set-Cookie", "")
    assert "llfsm_token=s3cret-token" in cookie and "HttpOnly" in cookie and "SameSite=Strict" in cookie
    assert _get(server, "/static/app.js", {"Cookie": "llfsm_token=s3cret-token"}).status == 200
    assert _upgrade(server, "/ws", {"Cookie": "llfsm_token=s3cret-token"}) == 101


def test_any_address_but_loopback_gets_a_token() -> None:
    srv = WebServer(source=None, host="0.0.0.0", port=0)
    assert srv.token is not None and len(srv.token) >= 20
    assert WebServer(source=None).token is None
    assert parse_address("8080") == ("127.0.0.1", 8080)
    assert parse_address("0.0.0.0:0") == ("0.0.0.0", 0)
    assert parse_address("[::1]:9000") == ("::1", 9000)


def test_a_foreign_origin_is_refused(server: WebServer) -> None:
    own = f"http://127.0.0.1:{server.port}"
    assert _upgrade(server, headers={"Origin": "http://evil.example"}) == 403
    assert _upgrade(server, headers={"Origin": own}) == 101
    body = json.dumps({"machine": "ros2_ping_pong", "command": "suspend"})
    json_h = {"Content-Type": "application/json"}
    assert _get(server, "/api/command", {**json_h, "Origin": "http://evil.example"}, "POST", body).status == 403
    # a cross-site form cannot send JSON, and a form is what a foreign page could send without asking
    form_h = {"Content-Type": "application/x-www-form-urlencoded", "Origin": own}
    assert _get(server, "/api/command", form_h, "POST", "machine=x").status == 415


def test_a_foreign_host_name_is_refused_without_a_token(server: WebServer) -> None:
    """DNS rebinding: a page of evil.example that resolves to 127.0.0.1 is its own origin."""
    assert _get(server, "/", {"Host": f"evil.example:{server.port}"}).status == 403


def test_bad_values_from_the_page_are_refused_with_a_reason(server: WebServer) -> None:
    own = {"Content-Type": "application/json", "Origin": f"http://127.0.0.1:{server.port}"}
    conn = http.client.HTTPConnection("127.0.0.1", server.port, timeout=10)
    body = json.dumps({"topic": "/pingpong", "type": "std_msgs/msg/String", "values": "{data: [1, 2]}"})
    conn.request("POST", "/api/publish", body=body, headers=own)
    resp = conn.getresponse()
    answer = json.loads(resp.read())
    assert resp.status == 400 and answer["success"] is False and "'data' field" in answer["message"]
    conn.request("POST", "/api/command", body=json.dumps({"machine": "nope", "command": "suspend"}), headers=own)
    resp = conn.getresponse()
    assert resp.status == 400 and "no machine named 'nope'" in json.loads(resp.read())["message"]
    conn.close()


# -- usage errors ------------------------------------------------------------------------------------


def test_web_without_aiohttp_says_what_to_install(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "aiohttp", None)
    r = llfsm("run", "--clock", "sim", str(PING_PONG), "--web", "0", "--duration", "1ms")
    assert r.status == 2
    assert "pip install 'llfsm[web]'" in r.stderr


def test_a_bad_web_address_is_a_usage_error(tmp_path: Path) -> None:
    r = llfsm("run", "--clock", "sim", str(PING_PONG), "--web", "localhost:http", "--duration", "1ms")
    assert r.status == 2 and "expected [HOST:]PORT" in r.stderr


def test_the_run_is_sampled_only_while_a_page_is_connected(server: WebServer) -> None:
    """A closed tab costs the run nothing: no page, no sampling (the scheduler never does any)."""
    import asyncio
    import time

    import aiohttp

    calls = {"n": 0}
    sample = server.source.state

    def counting() -> dict:
        calls["n"] += 1
        return sample()

    server.source.state = counting  # type: ignore[method-assign]

    async def visit() -> list[str]:
        kinds = []
        async with aiohttp.ClientSession() as s, s.ws_connect(f"ws://127.0.0.1:{server.port}/ws") as ws:
            kinds.append(json.loads((await ws.receive()).data)["type"])
            await asyncio.sleep(0.3)  # sampled meanwhile: a delta only if something changed
        return kinds

    assert asyncio.run(visit())[0] == "hello"
    assert calls["n"] > 1
    # the server notices the page has gone in its own time (0.3 s was not enough under load)
    until(lambda: not server.clients, 30, "the server still counts the page that left")
    after_close = calls["n"]
    time.sleep(0.6)  # a dozen push periods
    assert calls["n"] == after_close
    assert not server.clients


def test_a_page_that_leaves_right_after_the_handshake_costs_no_traceback(
    server: WebServer, caplog: pytest.LogCaptureFixture
) -> None:
    """Issue 27, item 4: a tab closed (or a headless browser exiting) just after the WebSocket
    handshake printed aiohttp's 25-line "Cannot write to closing transport" traceback."""
    import socket
    import struct
    import time

    for _ in range(10):
        with socket.create_connection(("127.0.0.1", server.port), timeout=10) as s:
            key = base64.b64encode(os.urandom(16)).decode()
            s.sendall(
                f"GET /ws HTTP/1.1\r\nHost: 127.0.0.1:{server.port}\r\nUpgrade: websocket\r\n"
                f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n".encode()
            )
            assert s.recv(12) == b"HTTP/1.1 101"
            s.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))  # close with a reset
    time.sleep(0.5)  # the server's thread handles the resets, and drops the pages (under load, later)
    until(lambda: not server.clients, 30, "the server's thread never handled the resets")
    assert [r.getMessage() for r in caplog.records if r.levelno >= logging.WARNING] == []
    assert not server.clients
    assert _upgrade(server) == 101  # and it still serves


def test_each_pages_node_has_a_name_of_its_own() -> None:
    """Issue 27, item 8: two `--web` runs on one domain were both /llfsm_web, and `node list`
    warned about llfsm's own nodes."""
    names = []
    for _ in range(2):
        r = llfsm_process("run", "--clock", "sim", PING_PONG, "--web", "0", "--duration", "5ms", "--introspect")
        assert r.status == 0, r.stderr
        names += [line.strip() for line in r.stderr.split("topics:")[0].splitlines() if "/llfsm_web" in line]
    assert len(names) == 2 and names[0] != names[1], names


def test_the_page_tells_running_suspended_and_finished_machines_apart(tmp_path: Path) -> None:
    from helpers import write_machine

    quick = write_machine(tmp_path, "quick", {"A": [("END", "after_ms(2)")], "END": None})
    slow = write_machine(tmp_path, "slow", {"A": [("B", "after_ms(1)")], "B": [("A", "after_ms(1)")]})
    idle = write_machine(tmp_path, "idle", {"A": [("END", "False")], "END": None})
    ctx = RunContext(SimClock())
    prev = activate(ctx)
    try:
        arr = Arrangement([load(str(m)) for m in (quick, slow, idle)], context=ctx, suspended=["idle"])
        ros.init()
        enable(ctx)
        source = RunSource(arr, ros.bus_of())
        arr.run(duration_ns=10_000_000)
        rows = {r["name"]: r for r in source.machine_rows()}
    finally:
        activate(prev)
    assert (rows["quick"]["status"], rows["quick"]["state"]) == ("finished", "END")
    assert (rows["idle"]["status"], rows["idle"]["state"]) == ("suspended", "SUSPENDED")
    assert rows["slow"]["status"] == "running" and rows["slow"]["state"] in ("A", "B")
