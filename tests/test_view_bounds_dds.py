"""`llfsm view` beside a peer that makes a thousand topics then drops them, and floods
/parameter_events with long node names (SPEC §18, issue 28 items 4 and 10).  The page is sent
at most 200 topic rows, the rest counted and said; once the peer's topics have no endpoints
the view forgets them and deletes its readers of them (before, `topic list` showed them for as
long as the view ran, and the table grew without end); Ctrl-C ends the view cleanly (status 0).  A
WebSocket client that applies the channel's messages, and Chromium, watch.  Real DDS processes
in a private network namespace."""

from __future__ import annotations

import json
import re
import signal
import sys
import textwrap
import time

import pytest
from browser import ARGS, CHROMIUM, playwright_or_skip
from dds_netns import RAW_PEER, NetNamespace, finish, start_view
from helpers import REPO

pytestmark = pytest.mark.dds
pytest.importorskip("aiohttp")

TOPICS = 1000

#: The peer: TOPICS topics, one sample each, and events on /parameter_events whose node names are
#: long (100,000 characters) or many (a new one each time), until told on stdin; then its
#: topics' writers go (their endpoints leave the graph) while it stays.
PEER = RAW_PEER + textwrap.dedent(
    """
    import itertools, select
    from llfsm.msgs import _dds
    from llfsm.msgs.rcl_interfaces.msg import ParameterEvent, Parameter
    n = int(sys.argv[1])
    writers = [writer(f"rt/churn/t{i:05d}", String) for i in range(n)]
    for w in writers:
        write(w, HEAD + string(b"x"))
    events = writer("rt/parameter_events", ParameterEvent)
    cdr = _dds.codec(ParameterEvent).cdr
    long_name = cdr(ParameterEvent(node="/" + "n" * 100_000, new_parameters=[Parameter(name="p" * 1000)] * 100))
    print("up", flush=True)
    for i in itertools.count():
        if select.select([sys.stdin], [], [], 0.02)[0]:
            break
        write(events, long_name)
        for j in range(20):
            write(events, cdr(ParameterEvent(node=f"/ghost_{i}_{j}")))
    for w in writers:
        w.__del__()
    print("gone", flush=True)
    time.sleep(300)
    """
)

#: A page's WebSocket: applies every message (llfsm.web.channel.Mirror) and reports what it held
#: while the topics lived, and after they went, and the largest message it was sent.
CLIENT = textwrap.dedent(
    """
    import asyncio, json, sys, aiohttp
    from llfsm.web.channel import Mirror
    async def main(url, topics):
        mirror, out = Mirror(), {"largest": 0, "up": None, "after": None}
        async with aiohttp.ClientSession() as s:
            async with s.ws_connect(url.replace("http://", "ws://") + "ws", max_msg_size=64 << 20) as ws:
                loop = asyncio.get_running_loop()
                end = loop.time() + 120
                while loop.time() < end:
                    msg = await asyncio.wait_for(ws.receive(), end - loop.time())
                    out["largest"] = max(out["largest"], len(msg.data))
                    state = mirror.apply(json.loads(msg.data))
                    if state is None:
                        continue
                    churn = [r["name"] for r in state["topics"] if r["name"].startswith("/churn/")]
                    summary = {"rows": len(state["topics"]), "total": state["topics_total"], "churn_rows": len(churn),
                               "events": len(state["param_events"])}
                    if out["up"] is None and state["topics_total"] >= topics:
                        out["up"] = summary
                        print("seen", flush=True)
                    elif out["up"] is not None and state["topics_total"] < 50:
                        # the endpoints leave one by one: keep watching until the last has gone
                        out["after"] = summary
                        if not churn:
                            break
        print(json.dumps(out), flush=True)
    asyncio.run(main(sys.argv[1], int(sys.argv[2])))
    """
)


def topic_list(ns: NetNamespace) -> list[str]:
    _status, out, _err = finish(ns.popen([sys.executable, "-m", "llfsm", "topic", "list"], cwd=REPO), 60)
    return out.split()


def test_the_view_bounds_its_table_and_forgets_topics_that_have_gone(netns: NetNamespace) -> None:
    view, url, err = start_view(netns)
    peer = netns.popen([sys.executable, "-c", PEER, str(TOPICS)], cwd=REPO, stdin=-1)
    assert peer.stdout is not None and peer.stdout.readline() == "up\n"
    client = netns.popen([sys.executable, "-c", CLIENT, url, str(TOPICS)], cwd=REPO)
    assert client.stdout is not None and client.stdout.readline() == "seen\n"
    # a fresh `topic list` may end its discovery before it has seen a thousand writers (under
    # load it did): asked again until it lists them all, or a minute
    deadline = time.monotonic() + 60
    while (listed := sum(t.startswith("/churn/") for t in topic_list(netns))) < TOPICS and time.monotonic() < deadline:
        pass
    assert listed == TOPICS
    assert peer.stdin is not None
    peer.stdin.write("go\n")
    peer.stdin.flush()
    assert peer.stdout.readline() == "gone\n"
    status, out, c_err = finish(client, 120)
    assert status == 0, c_err
    got = json.loads(out.strip().splitlines()[-1])
    assert got["up"]["rows"] == 200 and got["up"]["total"] >= TOPICS, got  # bounded, the rest counted
    assert got["after"] is not None and got["after"]["churn_rows"] == 0, got  # forgotten
    assert got["up"]["events"] <= 1, got  # the ghosts' events are not sent (the view's own node only)
    assert got["largest"] < 200_000, got  # a hello of 200 rows, not a thousand
    # the view's readers of the peer's topics were deleted: no other tool sees them any more
    deadline = time.monotonic() + 30
    while (left := [t for t in topic_list(netns) if t.startswith("/churn/")]) and time.monotonic() < deadline:
        time.sleep(1)
    assert left == []
    view.send_signal(signal.SIGINT)
    status, _out, _err = finish(view, 60)
    text = "".join(err)
    assert status == 0, text[-3000:]  # a view ends by Ctrl-C, as `ros2 run` does; never the watchdog's 137
    assert "killed" not in text and "Traceback" not in text, text[-3000:]
    peer.kill()


#: Chromium on the view's page while the peer's topics live, then after they went.
WATCH = textwrap.dedent(
    """
    import json, sys
    from playwright.sync_api import expect, sync_playwright
    url, chromium, args = sys.argv[1], sys.argv[2], sys.argv[3].split()
    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=chromium, args=args)
        p = b.new_page(viewport={"width": 1280, "height": 860})
        p.set_default_timeout(60_000)
        p.goto(url)
        churn = p.locator('#topics tbody[data-topic^="/churn/"]')
        churn.nth(99).wait_for()
        p.locator("#topics-more").wait_for()
        up = {"rows": p.locator("#topics tbody").count(), "more": p.locator("#topics-more").inner_text()}
        print("seen", flush=True)
        sys.stdin.readline()
        expect(churn).to_have_count(0, timeout=60_000)
        stats = p.locator("html").evaluate("e => window.llfsmStats")
        print(json.dumps({"up": up, "after": p.locator("#topics tbody").count(), "stats": stats}), flush=True)
        b.close()
    """
)


@pytest.mark.browser
def test_the_page_in_chromium_shows_the_bounded_table_and_follows_the_topics_going(netns: NetNamespace) -> None:
    playwright_or_skip()
    view, url, err = start_view(netns)
    peer = netns.popen([sys.executable, "-c", PEER, str(TOPICS)], cwd=REPO, stdin=-1)
    assert peer.stdout is not None and peer.stdout.readline() == "up\n"
    watcher = netns.popen([sys.executable, "-c", WATCH, url, CHROMIUM, " ".join(ARGS)], cwd=REPO, stdin=-1)
    assert watcher.stdout is not None and watcher.stdin is not None and peer.stdin is not None
    seen = watcher.stdout.readline()
    assert seen == "seen\n", seen + (watcher.stderr.read() if watcher.stderr else "")
    peer.stdin.write("go\n")
    peer.stdin.flush()
    watcher.stdin.write("go\n")
    watcher.stdin.flush()
    status, out, w_err = finish(watcher, 120)
    view.send_signal(signal.SIGINT)
    v_status = finish(view, 60)[0]
    peer.kill()
    assert status == 0, w_err
    got = json.loads(out.strip().splitlines()[-1])
    assert got["up"]["rows"] == 200 and re.match(r"[\d,]+ more topics not listed", got["up"]["more"]), got
    assert got["after"] < 50, got
    print("page statistics:", got["stats"])
    assert v_status == 0 and "killed" not in "".join(err)
