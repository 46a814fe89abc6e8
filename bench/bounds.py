"""What a peer can cost (SPEC §18, issue 28): two tables.

    .venv/bin/python bench/bounds.py actions [--against DIR] [--quick]
    .venv/bin/python bench/bounds.py view [--quick]
    .venv/bin/python bench/bounds.py verify [--quick]

`actions`: an action server in process (the PULL form) holding n unfinished goals, with a
subscriber of its status array (as a client of the same run is), and one cancel of every goal:
the time the executor's turn that answers it takes, for n from 250 to 2,000; with `--against
DIR` the same in another checkout (`git worktree add /tmp/base main`), interleaved.  Each cell is
the median of interleaved repetitions, each in a fresh process.

`view`: `llfsm view` in a private network namespace beside a peer with 2,000 live nodes (each
publishing on a topic of its own, a tenth of them every second), then beside a peer that made
10,000 topics and dropped them: the page's first message (the hello), what it is sent per second
afterwards, and, in Chromium when it is installed, how long the page takes to apply a message
(the page's own `window.llfsmStats`).

`verify`: `llfsm verify` of a machine whose variable grows at every step (bytes by 200 kB a
step; a list by one item a step, as in the issue), each with `--max-memory` from 50 MB to
800 MB, and once without it under a 1 GiB address-space limit (the default bound: half of what
the process may use): the exit status, the memory verify said it was using when it stopped, the
process's peak resident set (the kernel's, `wait4`), and the configurations explored.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import textwrap
import threading
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve()
REPO = HERE.parent.parent
NETNS_SETUP = "ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo"
CHROMIUM = os.environ.get("LLFSM_CHROMIUM", "/usr/bin/chromium")

# -- actions ---------------------------------------------------------------------------------------

#: One measurement, in a process of its own whose llfsm is the checkout it runs in (argv: n).
CANCEL = textwrap.dedent(
    """
    import json, sys, time
    from llfsm import ros
    from llfsm.msgs.action_msgs.msg import GoalStatusArray
    from llfsm.msgs.action_msgs.srv import CancelGoal
    from llfsm.msgs.turtlesim.action import RotateAbsolute
    from llfsm.ros.bus import bus_of
    from llfsm.runtime import RunContext, SimClock
    from llfsm.runtime.context import activate
    n = int(sys.argv[1])
    ctx = RunContext(SimClock()); activate(ctx); ros.init(); bus = bus_of(ctx)
    node = ros.Node("bench")
    kw = {"max_goals": n} if "max_goals" in ros.ActionServer.__init__.__code__.co_varnames else {}
    ros.ActionServer(node, RotateAbsolute, "t", None, cancel_callback=lambda h: ros.CancelResponse.ACCEPT, **kw)
    client = ros.ActionClient(node, RotateAbsolute, "t")
    node.create_subscription(GoalStatusArray, "/t/_action/status", lambda m: None, 10)
    goals = [client.send_goal_async(RotateAbsolute.Goal(theta=1.0)) for _ in range(n)]
    for _ in range(3):
        bus.clock.now += 1_000_000
        bus.spin_some()
    assert all(g.done() and g.result().accepted for g in goals)
    cancel = client._cancel_client.call_async(CancelGoal.Request())
    t0 = time.perf_counter()
    bus.clock.now += 1_000_000
    bus.spin_some()
    took = time.perf_counter() - t0
    assert len(cancel.result().goals_canceling) == n
    print(json.dumps({"ms": took * 1e3}))
    """
)
SIZES = (250, 500, 1000, 2000)


def _cancel_ms(checkout: Path, n: int) -> float:
    env = {**os.environ, "PYTHONPATH": str(checkout)}
    r = subprocess.run(
        [sys.executable, "-c", CANCEL, str(n)], cwd=checkout, env=env, capture_output=True, text=True, timeout=900
    )
    if r.returncode != 0:
        raise RuntimeError(f"{checkout}: {r.stderr.strip()[-600:]}")
    return float(json.loads(r.stdout.strip().splitlines()[-1])["ms"])


def actions(against: Path | None, quick: bool) -> None:
    reps = 1 if quick else 5
    checkouts = [REPO] + ([against] if against is not None else [])
    sizes = SIZES[:3] if quick else SIZES
    got: dict[tuple[Path, int], list[float]] = {}
    for _ in range(reps):  # interleaved: every checkout and size once a repetition
        for n in sizes:
            for c in checkouts:
                got.setdefault((c, n), []).append(_cancel_ms(c, n))
    print(
        f"### A cancel of every goal: the executor's turn that answers it, an action server holding n goals "
        f"(PULL form, a status subscriber in process); median of {reps} interleaved fresh processes; "
        f"Python {sys.version.split()[0]}, {os.cpu_count()} CPUs\n"
    )
    head = "| goals | this checkout (ms) | µs per goal |"
    rule = "|---|---|---|"
    if against is not None:
        head += f" {against} (ms) | ratio |"
        rule += "---|---|"
    print(head)
    print(rule)
    for n in sizes:
        mine = statistics.median(got[(REPO, n)])
        row = f"| {n:,} | {mine:,.1f} | {mine * 1e3 / n:,.1f} |"
        if against is not None:
            other = statistics.median(got[(against, n)])
            row += f" {other:,.1f} | {other / mine:,.0f}x |"
        print(row)


# -- the view ----------------------------------------------------------------------------------------

#: The peer of the view's cases (argv: "nodes" N, or "dead" N): cyclonedds alone, llfsm's types.
PEER = textwrap.dedent(
    """
    import sys, time
    from cyclonedds._clayer import ddspy_write
    from cyclonedds.core import Policy, Qos
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.topic import Topic
    from llfsm.msgs import _dds
    from llfsm.msgs.rmw_dds_common.msg import Gid, NodeEntitiesInfo, ParticipantEntitiesInfo
    from llfsm.msgs.std_msgs.msg import String
    kind, n = sys.argv[1], int(sys.argv[2])
    dp = DomainParticipant(0)
    xcdr1 = Policy.DataRepresentation(use_cdrv0_representation=True)
    qos = Qos(Policy.Reliability.Reliable(max_blocking_time=10**8), xcdr1)
    wire = _dds.dds_type(String)
    writers = [DataWriter(dp, Topic(dp, f"rt/bench/n{i:05d}/out", wire), qos=qos) for i in range(n)]
    if kind == "nodes":  # every writer a node's, as rmw says it
        latched = Qos(Policy.Reliability.Reliable(max_blocking_time=10**8), Policy.Durability.TransientLocal,
                      Policy.History.KeepLast(1), xcdr1)
        info = DataWriter(dp, Topic(dp, "ros_discovery_info", _dds.dds_type(ParticipantEntitiesInfo)), qos=latched)
        nodes = [NodeEntitiesInfo(node_namespace="/bench", node_name=f"n{i:05d}", reader_gid_seq=[],
                                  writer_gid_seq=[Gid(data=list(w.guid.bytes))]) for i, w in enumerate(writers)]
        message = ParticipantEntitiesInfo(gid=Gid(data=list(dp.guid.bytes)), node_entities_info_seq=nodes)
        ddspy_write(info._ref, _dds.codec(ParticipantEntitiesInfo).cdr(message))
    cdr = _dds.codec(String).cdr
    print("up", flush=True)
    if kind == "dead":
        time.sleep(3)
        for w in writers:
            w.__del__()
        writers = []
        print("dropped", flush=True)
    i = 0
    while True:  # a tenth of the nodes publish every second
        for w in writers[i % 10 :: 10]:
            ddspy_write(w._ref, cdr(String(data=str(i))))
        i += 1
        time.sleep(0.1)
    """
)

#: A page's WebSocket for `seconds` after its hello: sizes and counts (llfsm.web.channel.Mirror).
CLIENT = textwrap.dedent(
    """
    import asyncio, json, sys, aiohttp
    from llfsm.web.channel import Mirror
    async def main(url, seconds, wanted):
        mirror, out = Mirror(), {"hello": 0, "bytes": 0, "messages": 0, "rows": 0, "total": 0}
        async with aiohttp.ClientSession() as s:
            async with s.ws_connect(url.replace("http://", "ws://") + "ws", max_msg_size=64 << 20) as ws:
                loop = asyncio.get_running_loop()
                start = None
                while True:
                    timeout = 60 if start is None else start + seconds - loop.time()
                    if timeout <= 0:
                        break
                    try:
                        msg = await asyncio.wait_for(ws.receive(), timeout)
                    except asyncio.TimeoutError:
                        break
                    state = mirror.apply(json.loads(msg.data))
                    if start is None:
                        if state is not None and wanted[0] <= state["topics_total"] <= wanted[1]:
                            start, out["hello"] = loop.time(), len(msg.data)
                        continue
                    out["bytes"] += len(msg.data)
                    out["messages"] += 1
                    if state is not None:
                        out["rows"], out["total"] = len(state["topics"]), state["topics_total"]
        out["seconds"] = seconds
        print(json.dumps(out), flush=True)
    asyncio.run(main(sys.argv[1], float(sys.argv[2]), [int(x) for x in sys.argv[3].split(",")]))
    """
)

#: Chromium on the page for `seconds`: the page's own statistics (messages, bytes, apply times).
PAGE = textwrap.dedent(
    """
    import json, sys, time
    from playwright.sync_api import expect, sync_playwright
    url, chromium, seconds = sys.argv[1], sys.argv[2], float(sys.argv[3])
    args = ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-background-networking"]
    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=chromium, args=args)
        p = b.new_page(viewport={"width": 1280, "height": 860})
        p.on("pageerror", lambda e: print("page error:", e, file=sys.stderr, flush=True))
        p.goto(url)
        expect(p.locator("#run-time")).not_to_have_text("connecting…", timeout=60_000)  # the hello came
        time.sleep(seconds)
        print(json.dumps(p.locator("html").evaluate("e => window.llfsmStats")), flush=True)
        b.close()
    """
)


def _view_case(kind: str, n: int, seconds: float) -> dict[str, Any]:
    """(inside the namespace) One case: the view, the peer, the page's client and Chromium."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("ROS_", "CYCLONEDDS"))}
    env["PYTHONPATH"] = str(REPO)
    view = subprocess.Popen(
        [sys.executable, "-m", "llfsm", "view", "--web", "127.0.0.1:0"],
        stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True, env=env, cwd=REPO,
    )  # fmt: skip
    peer = subprocess.Popen([sys.executable, "-c", PEER, kind, str(n)], stdout=subprocess.PIPE, text=True, env=env)
    procs = [view, peer]
    try:
        assert view.stderr is not None and peer.stdout is not None
        url = ""
        while not url:
            line = view.stderr.readline()
            if not line:
                raise RuntimeError("llfsm view ended")
            if "http://" in line:
                url = line.split("web view at ", 1)[1].strip()
        threading.Thread(target=view.stderr.read, daemon=True).start()  # never let its log fill the pipe
        assert peer.stdout.readline() == "up\n"
        if kind == "dead":
            assert peer.stdout.readline() == "dropped\n"
        wanted = f"{n},{10**9}" if kind == "nodes" else "0,50"  # the peer's topics seen, or forgotten
        client = subprocess.Popen(
            [sys.executable, "-c", CLIENT, url, str(seconds), wanted], stdout=subprocess.PIPE, text=True, env=env
        )
        procs.append(client)
        page: subprocess.Popen[str] | None = None
        if Path(CHROMIUM).exists():
            page = subprocess.Popen(
                [sys.executable, "-c", PAGE, url, CHROMIUM, str(seconds)],
                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
            )  # fmt: skip
            procs.append(page)
        out, _ = client.communicate(timeout=seconds + 240)
        got: dict[str, Any] = json.loads(out.strip().splitlines()[-1])
        if page is not None:
            p_out, p_err = page.communicate(timeout=seconds + 240)
            if not p_out.strip():
                raise RuntimeError(f"the page in Chromium failed: {p_err.strip()[-1500:]}")
            got["page"] = json.loads(p_out.strip().splitlines()[-1])
        return got
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
                p.communicate()


def view_inside(quick: bool) -> None:
    seconds = 5.0 if quick else 15.0
    cases = [("nodes", 500 if quick else 2000), ("dead", 2000 if quick else 10_000)]
    print(
        f"### `llfsm view` beside a peer: what a page is sent and how long it takes to apply it; {seconds:g} s "
        f"after the hello; Python {sys.version.split()[0]}, {os.cpu_count()} CPUs\n"
    )
    print("| case | hello (KB) | KB/s to a page | messages/s | topic rows shown / known | page apply ms, mean (max) |")
    print("|---|---|---|---|---|---|")
    for kind, n in cases:
        g = _view_case(kind, n, seconds)
        what = (
            f"{n:,} live nodes, a tenth publishing each second"
            if kind == "nodes"
            else f"{n:,} topics made, then dropped"
        )
        page = g.get("page")
        apply = "(no Chromium)"
        if page and page.get("messages"):
            apply = f"{page['totalApplyMs'] / page['messages']:.1f} ({page['maxApplyMs']:.0f})"
        print(
            f"| {what} | {g['hello'] / 1024:,.0f} | {g['bytes'] / 1024 / g['seconds']:,.1f} | "
            f"{g['messages'] / g['seconds']:,.1f} | {g['rows']:,} / {g['total']:,} | {apply} |"
        )


# -- verify's memory ---------------------------------------------------------------------------------

#: The machines whose values grow at every step: (its variable, its state's OnEntry).
GROWING = {
    "bytes": ('blob: bytes = b""\n', 'blob = blob + b"x" * 200_000'),
    "list": ("items: list = []\n", "items.append(len(items))"),
}
#: (machine, --max-memory or None for the default under an address-space limit of 1 GiB).
VERIFY_CASES = [("bytes", "100MB"), ("bytes", "200MB"), ("bytes", "400MB"), ("bytes", "800MB"), ("bytes", None),
                ("list", "50MB"), ("list", "100MB")]  # fmt: skip


def _growing_machine(root: Path, kind: str) -> Path:
    variables, entry = GROWING[kind]
    d = root / f"grow_{kind}.machine"
    d.mkdir(parents=True, exist_ok=True)
    (d / "machine.yaml").write_text("states:\n  - name: A\n    transitions: [A]\n")
    (d / "State_A_Transition_0.expr").write_text("True\n")
    (d / "State_A_OnEntry.py").write_text(entry + "\n")
    (d / "Variables.py").write_text(variables)
    return d


def _limit_address_space() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (1 << 30, 1 << 30))


def _verify_case(machine: Path, max_memory: str | None) -> dict[str, Any]:
    """One `llfsm verify` in a fresh process: status, what it said, its peak resident set."""
    cmd = [sys.executable, "-m", "llfsm", "verify", str(machine)] + (["--max-memory", max_memory] if max_memory else [])
    started = time.monotonic()
    with tempfile.TemporaryFile("w+") as out:
        p = subprocess.Popen(
            cmd, cwd=REPO, stdout=out, stderr=subprocess.DEVNULL, text=True,
            preexec_fn=None if max_memory else _limit_address_space,
        )  # fmt: skip
        _pid, status, usage = os.wait4(p.pid, 0)
        p.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        text = out.read()
    said = re.search(
        r"stopped at the memory bound \(([\d,]+) MB in use, --max-memory ([\d,]+) MB; ([\d,]+) configurations", text
    )
    return {
        "status": p.returncode,
        "in_use": int(said.group(1).replace(",", "")) if said else None,
        "bound": int(said.group(2).replace(",", "")) if said else None,
        "configurations": int(said.group(3).replace(",", "")) if said else None,
        "peak_mb": usage.ru_maxrss * 1024 / 1e6,  # KiB on Linux; MB as verify says them
        "seconds": time.monotonic() - started,
    }


def verify_memory(quick: bool) -> None:
    reps = 1 if quick else 3
    got: dict[tuple[str, str | None], list[dict[str, Any]]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        machines = {kind: _growing_machine(Path(tmp), kind) for kind in GROWING}
        for _ in range(reps):  # interleaved
            for kind, bound in VERIFY_CASES:
                got.setdefault((kind, bound), []).append(_verify_case(machines[kind], bound))
    print(
        f"### llfsm verify of a value growing at every step: peak memory against --max-memory; median of "
        f"{reps} interleaved fresh processes; Python "
        f"{sys.version.split()[0]}, {os.cpu_count()} CPUs\n"
    )
    print(
        "| value growing | --max-memory | exit | in use when stopped (MB) | peak resident (MB) | peak / bound |", end=""
    )
    print(" configurations | wall s |")
    print("|---|---|---|---|---|---|---|---|")
    for (kind, bound), runs in got.items():
        exits = "/".join(str(s) for s in sorted({r["status"] for r in runs}))
        peak = statistics.median(r["peak_mb"] for r in runs)
        wall = statistics.median(r["seconds"] for r in runs)
        said = [r for r in runs if r["in_use"] is not None]
        what = "200 kB of bytes a step" if kind == "bytes" else "a list, one item a step"
        if not said:  # it did not stop at the memory bound: the row says so
            print(f"| {what} | {bound or 'default'} | {exits} | - | {peak:,.0f} | - | - | {wall:,.1f} |")
            continue
        limit = said[0]["bound"]
        in_use = statistics.median(r["in_use"] for r in said)
        configs = statistics.median(r["configurations"] for r in said)
        shown = bound or f"default: {limit} MB under a 1 GiB limit"
        print(
            f"| {what} | {shown} | {exits} | {in_use:,.0f} | {peak:,.0f} | {peak / limit:.2f} | {configs:,.0f} | "
            f"{wall:,.1f} |"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("what", choices=("actions", "view", "verify"))
    ap.add_argument("--against", type=Path, help="another checkout to measure beside this one (actions)")
    ap.add_argument("--quick", action="store_true", help="smaller cases, one repetition")
    ap.add_argument("--inside", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.what == "actions":
        actions(args.against.resolve() if args.against else None, args.quick)
        return
    if args.what == "verify":
        verify_memory(args.quick)
        return
    if args.inside:
        with tempfile.TemporaryDirectory() as tmp:
            os.environ["LLFSM_CACHE_DIR"] = tmp
            view_inside(args.quick)
        return
    cmd = [sys.executable, str(HERE), "view", "--inside"] + (["--quick"] if args.quick else [])
    started = time.monotonic()
    r = subprocess.run(["unshare", "-n", "sh", "-c", f'{NETNS_SETUP} && exec "$@"', "sh", *cmd], check=False)
    print(f"\n(took {time.monotonic() - started:.0f} s)", file=sys.stderr)
    sys.exit(r.returncode)


if __name__ == "__main__":
    main()
