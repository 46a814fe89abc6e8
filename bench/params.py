"""Parameters benchmark: what serving parameters costs a run, and a `param get` round trip.

    .venv/bin/python bench/params.py [--quick]

Prints one table:
- rounds per CPU second of an idle run (a machine that never fires, three nodes beside it, every
  node serving its six parameter services and its /parameter_events publisher) over rounds
  per second of the same run with no parameter services, in process (`--clock sim`) and over
  DDS (wall clock, `--idle 0`): the target is >= 0.95;
- the round-trip latency (p50, p99) of a GetParameters call from a client process to a node
  in another process, llfsm to llfsm over Cyclone DDS beside rclpy to rclpy over Fast DDS
  (`.venv-ros`; without it its column says so).
Each figure is the median of interleaved repetitions (with, without, with, without...), each in
a fresh process; DDS runs inside a private network namespace (unshare -n).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve()
REPO = HERE.parent.parent
ROS_PYTHON = REPO / ".venv-ros" / "bin" / "python"
NETNS_SETUP = "ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo"

IDLE_MACHINE = {
    "machine.yaml": "states:\n  - name: INITIAL\n    transitions: [END]\n  - name: END\n",
    "Includes.py": "from llfsm import ros\nfrom llfsm.msgs.std_msgs.msg import String\n",
    "Variables.py": "nodes: list = []\n",
    "State_INITIAL_OnEntry.py": "ros.init()\nfor i in range(3):\n"
    "    n = ros.Node(f'idle_{i}')\n    n.declare_parameter('gain', 1.0)\n"
    "    n.create_publisher(String, 'out', 10)\n    n.create_subscription(String, 'in', None, 10)\n"
    "    nodes.append(n)\n",
    "State_INITIAL_Transition_0.expr": "after(10000)\n",
}


# -- roles, each in a process of its own ---------------------------------------------------------------


def role_idle(transport: str, services: bool, seconds: float) -> None:
    """Print rounds per second of the idle machine's run."""
    from llfsm.ros import node as node_module
    from llfsm.session import RunOptions, Session

    if not services:

        class NoServices:
            def __init__(self, node: object) -> None:
                pass

        node_module.ParameterService = NoServices  # type: ignore[assignment, misc]
    tmp = Path(tempfile.mkdtemp())
    m = tmp / "idle.machine"
    m.mkdir()
    for name, text in IDLE_MACHINE.items():
        (m / name).write_text(text)
    ns = int(seconds * 1e9)
    if transport == "inproc":
        options = RunOptions((str(m),), clock="sim", period=1_000, duration=ns)
    else:
        options = RunOptions((str(m),), transport="dds", idle=0, duration=ns)
    from llfsm.runtime import Arrangement

    timed: list[float] = []
    real_run = Arrangement.run

    def run(self: Arrangement, *a: object, **kw: object) -> object:  # the rounds alone, not the start-up
        # CPU time of the thread that runs the rounds: other processes on a shared machine
        # disturb it far less than wall time (which swung by 2x between runs), and it leaves out
        # Cyclone's own threads, busy for the first second with discovering 18 more services.
        start = time.thread_time()
        try:
            return real_run(self, *a, **kw)  # type: ignore[arg-type]
        finally:
            timed.append(time.thread_time() - start)

    Arrangement.run = run  # type: ignore[method-assign]
    outcome = Session(options, say=lambda _: None).run()
    shutil.rmtree(tmp)
    print(json.dumps(outcome.result.rounds / timed[0]))


def role_llfsm_server() -> None:
    """A run with a node of its own, as `llfsm run --transport dds --node ...` serves one."""
    from llfsm.session import RunOptions, Session

    tmp = Path(tempfile.mkdtemp())
    m = tmp / "server.machine"
    m.mkdir()
    (m / "machine.yaml").write_text("states:\n  - name: INITIAL\n    transitions: [END]\n  - name: END\n")
    (m / "Includes.py").write_text("from llfsm import ros\n")
    (m / "Variables.py").write_text("node: object = None\n")
    (m / "State_INITIAL_OnEntry.py").write_text(
        "ros.init()\nnode = ros.Node('bench_server')\nnode.declare_parameter('gain', 1.5)\n"
    )
    (m / "State_INITIAL_Transition_0.expr").write_text("not ros.ok()\n")
    Session(RunOptions((str(m),), transport="dds", duration=120_000_000_000), say=lambda _: None).run()


def role_llfsm_client(n: int) -> None:
    from llfsm import ros
    from llfsm.msgs.rcl_interfaces.srv import GetParameters
    from llfsm.ros.transports import make
    from llfsm.runtime import RunContext, WallClock
    from llfsm.runtime.context import activate

    ctx = RunContext(WallClock())
    ctx.transport = make("dds")
    activate(ctx)
    ros.init()
    node = ros.Node("bench_client", start_parameter_services=False)
    client = node.create_client(GetParameters, "/bench_server/get_parameters")
    client.wait_for_service(timeout_sec=30.0)
    times = []
    for _ in range(n):
        t = time.perf_counter()
        future = client.call_async(GetParameters.Request(names=["gain"]))
        ros.spin_until_future_complete(node, future, timeout_sec=5.0)
        assert future.result() is not None and future.result().values[0].double_value == 1.5
        times.append(time.perf_counter() - t)
    print(json.dumps(times))


RCLPY_SERVER = """
import rclpy
rclpy.init()
node = rclpy.create_node("bench_server")
node.declare_parameter("gain", 1.5)
rclpy.spin(node)
"""
RCLPY_CLIENT = """
import json, sys, time, rclpy
from rclpy.parameter_client import AsyncParameterClient
rclpy.init()
node = rclpy.create_node("bench_client")
client = AsyncParameterClient(node, "/bench_server")
client.wait_for_services(timeout_sec=30.0)
times = []
for _ in range(int(sys.argv[1])):
    t = time.perf_counter()
    future = client.get_parameters(["gain"])
    rclpy.spin_until_future_complete(node, future, timeout_sec=5.0)
    assert future.result().values[0].double_value == 1.5
    times.append(time.perf_counter() - t)
print(json.dumps(times))
"""


# -- the driver -----------------------------------------------------------------------------------------


def _in_netns() -> bool:
    return os.environ.get("LLFSM_BENCH_NETNS") == "1"


def _run(args: list[str], env: dict[str, str] | None = None, timeout: float = 120) -> str:
    full = {**os.environ, **(env or {})}
    return subprocess.run(args, capture_output=True, text=True, timeout=timeout, env=full, check=True).stdout


def idle_ratio(transport: str, repeats: int, seconds: float) -> tuple[float, float, float, float, float]:
    """(median rounds/s with services, without, the median of the per-pair ratios, their min, max),
    each pair run back to back in alternating order."""
    with_, without = [], []
    for r in range(repeats):
        order = ((True, with_), (False, without))
        for services, out in order if r % 2 == 0 else order[::-1]:
            text = _run([sys.executable, str(HERE), "--role", "idle", transport, str(int(services)), str(seconds)])
            out.append(json.loads(text))
    ratios = [a / b for a, b in zip(with_, without, strict=True)]
    return statistics.median(with_), statistics.median(without), statistics.median(ratios), min(ratios), max(ratios)


def round_trip(stack: str, n: int) -> tuple[float, float] | None:
    """(p50, p99) in ms of a GetParameters call, server and client in two processes."""
    if stack == "rclpy":
        if not ROS_PYTHON.exists():
            return None
        env = {"RMW_IMPLEMENTATION": "rmw_fastrtps_cpp"}
        server = subprocess.Popen(  # its stderr: rclpy's traceback when it is stopped, not ours
            [str(ROS_PYTHON), "-c", RCLPY_SERVER], env={**os.environ, **env}, stderr=subprocess.DEVNULL
        )
        client = [str(ROS_PYTHON), "-c", RCLPY_CLIENT, str(n)]
    else:
        env = {}
        server = subprocess.Popen([sys.executable, str(HERE), "--role", "llfsm_server"])
        client = [sys.executable, str(HERE), "--role", "llfsm_client", str(n)]
    try:
        times = sorted(json.loads(_run(client, env)))
    finally:
        server.terminate()
        server.wait(10)
    return times[len(times) // 2] * 1e3, times[min(len(times) - 1, int(len(times) * 0.99))] * 1e3


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--role", nargs="+")
    args = parser.parse_args()
    if args.role:
        role, *rest = args.role
        if role == "idle":
            role_idle(rest[0], rest[1] == "1", float(rest[2]))
        elif role == "llfsm_server":
            role_llfsm_server()
        elif role == "llfsm_client":
            role_llfsm_client(int(rest[0]))
        return
    if not _in_netns():
        if shutil.which("unshare") is None:
            sys.exit("bench/params.py needs unshare(1) for a private network namespace")
        cmd = ["unshare", "-n", "sh", "-c", f'{NETNS_SETUP} && exec "$@"', "sh", sys.executable, str(HERE)]
        os.execvpe("unshare", cmd + (["--quick"] if args.quick else []), {**os.environ, "LLFSM_BENCH_NETNS": "1"})
    repeats, seconds, calls = (3, 0.5, 200) if args.quick else (7, 1.0, 1000)
    rows = []
    # Over DDS a short run also pays for start-up: for about its first second Cyclone's threads
    # announce and match the 18 services' endpoints, beside the rounds. A run three times as
    # long shows what serving them costs each round once that is over.
    for transport, secs in (("inproc", seconds), ("dds", seconds), ("dds", 3 * seconds)):
        a, b, r, lo, hi = idle_ratio(transport, repeats, secs)
        label = f"idle run, {transport}, {secs:g} s: rounds per CPU second with / without parameter services"
        rows.append((label, f"{a:,.0f} / {b:,.0f}", f"{r:.3f} ({lo:.3f}-{hi:.3f})"))
    llfsm_rt, rclpy_rt = round_trip("llfsm", calls), round_trip("rclpy", calls)

    def ms(rt: tuple[float, float] | None) -> str:
        return "no .venv-ros" if rt is None else f"{rt[0]:.2f} / {rt[1]:.2f}"

    print("| measure | value | ratio: median of pairs (min-max), target >= 0.95 |\n|---|---|---|")
    for name, value, ratio in rows:
        print(f"| {name} | {value} | {ratio} |")
    print()
    print("| `param get` round trip (GetParameters), p50 / p99 ms | llfsm (Cyclone DDS) | rclpy (Fast DDS) |")
    print("|---|---|---|")
    print(f"| client process -> node process, {calls} calls | {ms(llfsm_rt)} | {ms(rclpy_rt)} |")


if __name__ == "__main__":
    main()
