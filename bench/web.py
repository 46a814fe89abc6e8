"""The web view's cost to the scheduler: rounds per second of a machine that changes state every
ringlet, on the wall clock, without and with `--web` and a connected page.

    python bench/web.py [--seconds S] [--repeats N]

Variants, interleaved, each run for S seconds of wall time, N times; the table gives medians
and the ratio to the run without --web (goal: >= 0.9 with a page connected):
- plain:        the toggle machine alone (no bus);
- bus:          the same with the bus up (state topics and control services on the graph);
- web, no page: --web serving, no page connected;
- web + page:   --web with a WebSocket client in another process reading every snapshot
                (what a browser tab does).
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from gen import write_toggle  # noqa: E402

from llfsm import ros  # noqa: E402
from llfsm.ros.control import enable  # noqa: E402
from llfsm.runtime import Arrangement, RunContext, WallClock  # noqa: E402
from llfsm.runtime.context import activate  # noqa: E402
from llfsm.targets import load  # noqa: E402

CLIENT = textwrap.dedent(
    """
    import asyncio, sys, aiohttp
    async def main(url, seconds):
        got = 0
        async with aiohttp.ClientSession() as s:
            async with s.ws_connect(url.replace("http://", "ws://") + "ws") as ws:
                print("connected", flush=True)
                loop = asyncio.get_running_loop()
                end = loop.time() + seconds
                while loop.time() < end:
                    try:
                        msg = await asyncio.wait_for(ws.receive(), max(0.01, end - loop.time()))
                    except asyncio.TimeoutError:
                        break
                    if msg.type != aiohttp.WSMsgType.TEXT:
                        break
                    got += 1
        print(got, flush=True)
    asyncio.run(main(sys.argv[1], float(sys.argv[2])))
    """
)


def rounds_per_second(cls: type, seconds: float, bus: bool, web: bool, page: bool) -> tuple[float, int]:
    """Run the toggle for `seconds` of wall time; (rounds/s, snapshots the page received)."""
    ctx = RunContext(WallClock(10_000_000, None))
    prev = activate(ctx)
    server = client = None
    try:
        arr = Arrangement([cls], context=ctx)
        if bus or web:
            ros.init()
            enable(ctx)
        if web:
            from llfsm.web.server import WebServer
            from llfsm.web.source import RunSource

            arr.end_when_suspended = False
            server = WebServer(RunSource(arr, ros.bus_of()), "127.0.0.1", 0)
            server.rate = float(os.environ.get("LLFSM_WEB_RATE", server.rate))
            url = server.start()
            if page:
                client = subprocess.Popen(
                    [sys.executable, "-c", CLIENT, url, str(seconds + 30)], stdout=subprocess.PIPE, text=True
                )
                assert client.stdout is not None
                assert client.stdout.readline().strip() == "connected"
                time.sleep(0.3)  # the hello and first snapshots are out
        t = time.perf_counter()
        result = arr.run(duration_ns=int(seconds * 1e9))
        elapsed = time.perf_counter() - t
        snapshots = 0
        if server is not None:
            server.stop()
        if client is not None:
            out, _ = client.communicate(timeout=60)
            snapshots = int(out.strip().splitlines()[-1])
        return result.rounds / elapsed, snapshots
    finally:
        if client is not None and client.poll() is None:
            client.kill()
        activate(prev)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=3.0)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        cls = load(str(write_toggle(Path(tmp))))
        variants = {
            "plain (no bus)": dict(bus=False, web=False, page=False),
            "bus (state topics, no reader)": dict(bus=True, web=False, page=False),
            "--web, no page": dict(bus=True, web=True, page=False),
            "--web + connected page": dict(bus=True, web=True, page=True),
        }
        rates: dict[str, list[float]] = {k: [] for k in variants}
        pushed: list[int] = []
        for _ in range(args.repeats):  # interleaved: drift in the machine's load hits every variant alike
            for name, kw in variants.items():
                rate, snaps = rounds_per_second(cls, args.seconds, **kw)
                rates[name].append(rate)
                if kw["page"]:
                    pushed.append(snaps)
    base = statistics.median(rates["plain (no bus)"])
    bus = statistics.median(rates["bus (state topics, no reader)"])
    print(
        f"### Round rate with the web view: a machine changing state every ringlet, wall clock, "
        f"{args.seconds:g} s x {args.repeats}, medians"
    )
    print("| variant | rounds/s | vs plain | vs bus |")
    print("|---|---|---|---|")
    for name, values in rates.items():
        m = statistics.median(values)
        print(f"| {name} | {m:,.0f} | {m / base:.2f} | {m / bus:.2f} |")
    per_s = statistics.median(pushed) / args.seconds if pushed else 0
    print(f"\nsnapshots the page received: about {per_s:.1f} per second (bounded at 20)")


if __name__ == "__main__":
    main()
