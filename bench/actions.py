"""Actions benchmark: a goal's round trip, llfsm to llfsm over Cyclone DDS beside rclpy to rclpy
over Fast DDS, between two processes.

    .venv/bin/python bench/actions.py [--quick]

Prints one table: the time from `send_goal_async` to the result in hand (the goal accepted, its
result asked for and received), one goal at a time, with an empty execution (the server
succeeds at once); p50 and p99 over the goals of a run, each the median of interleaved runs
(llfsm, rclpy, llfsm, rclpy...).  Both sides serve the same action, Fibonacci as test_msgs
defines it (llfsm compiles the same definition from a package of its own).  Both clients spin
as their own `spin_until_future_complete` does.  rclpy comes from `.venv-ros` (make
.venv-ros/.installed); without it its column says so.  Everything runs inside a private network
namespace (unshare -n), so nothing leaves the machine.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve()
REPO = HERE.parent.parent
ROS_PYTHON = REPO / ".venv-ros" / "bin" / "python"
NETNS_SETUP = "ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo"
ACTION = "/bench_fibonacci"
FIBONACCI = "int32 order\n---\nint32[] sequence\n---\nint32[] sequence\n"
WARM_UP = 30


# -- roles (each runs in a process of its own) -----------------------------------------------------


def _stack(stack: str, name: str) -> tuple[Any, Any, Any]:
    """(ros module, node, the Fibonacci action class) of one stack."""
    if stack == "llfsm":
        from llfsm import ros
        from llfsm.ros.transports import make
        from llfsm.runtime import RunContext, WallClock
        from llfsm.runtime.context import activate

        ctx = RunContext(WallClock())
        ctx.transport = make("dds")
        activate(ctx)
        ros.init()
        from llfsm.msgs.llfsm_bench_msgs.action import Fibonacci

        return ros, ros.Node(name), Fibonacci
    import rclpy
    from test_msgs.action import Fibonacci  # type: ignore[import-not-found]

    rclpy.init()
    return rclpy, rclpy.create_node(name), Fibonacci


def role_server(stack: str, seconds: float) -> None:
    """Serve the action for `seconds`: every goal accepted and succeeded at once."""
    ros, node, fibonacci = _stack(stack, "bench_action_server")

    def execute(goal_handle: Any) -> Any:
        goal_handle.succeed()
        return fibonacci.Result()

    if stack == "llfsm":
        ros.ActionServer(node, fibonacci, ACTION, execute)
    else:
        from rclpy.action import ActionServer

        ActionServer(node, fibonacci, ACTION, execute)
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        ros.spin_once(node, timeout_sec=0.1)


def role_client(stack: str, count: int) -> None:
    """`count` goals, one at a time, after WARM_UP more: p50 and p99 of the round trips (µs)."""
    ros, node, fibonacci = _stack(stack, "bench_action_client")
    if stack == "llfsm":
        client = ros.ActionClient(node, fibonacci, ACTION)
    else:
        from rclpy.action import ActionClient

        client = ActionClient(node, fibonacci, ACTION)
    if not client.wait_for_server(timeout_sec=20.0):
        print(json.dumps({"n": 0}), flush=True)
        return
    time.sleep(0.5)  # the server's side matches this client's endpoints too
    times: list[float] = []
    goal = fibonacci.Goal()
    for i in range(count + WARM_UP):
        t0 = time.perf_counter()
        sent = client.send_goal_async(goal)
        ros.spin_until_future_complete(node, sent, timeout_sec=5.0)
        handle = sent.result()
        if handle is None or not handle.accepted:
            continue
        result = handle.get_result_async()
        ros.spin_until_future_complete(node, result, timeout_sec=5.0)
        if result.done() and i >= WARM_UP:
            times.append((time.perf_counter() - t0) * 1e6)
    times.sort()
    out: dict[str, float] = {"n": len(times)}
    if times:
        out |= {"p50": times[len(times) // 2], "p99": times[min(len(times) - 1, int(len(times) * 0.99))]}
    print(json.dumps(out), flush=True)


ROLES = {"server": role_server, "client": role_client}


# -- the orchestration (inside the namespace) ---------------------------------------------------------


def _env(stack: str, interfaces: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("ROS_", "CYCLONEDDS", "FASTDDS", "FASTRTPS"))}
    env["PYTHONPATH"] = str(REPO)
    env["LLFSM_INTERFACE_PATH"] = interfaces
    if stack == "rclpy":
        env["RMW_IMPLEMENTATION"] = "rmw_fastrtps_cpp"
        env.pop("VIRTUAL_ENV", None)
    return env


def _start(stack: str, role: str, arg: float, interfaces: str) -> subprocess.Popen[str]:
    python = str(ROS_PYTHON) if stack == "rclpy" else sys.executable
    return subprocess.Popen(
        [python, str(HERE), "--role", role, stack, str(arg)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=_env(stack, interfaces),
    )


def _result(p: subprocess.Popen[str], timeout: float) -> dict[str, float]:
    try:
        out, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        p.kill()
        out, err = p.communicate()
    for line in reversed(out.splitlines()):
        if line.startswith("{"):
            return json.loads(line)
    raise RuntimeError(f"a benchmark process failed: {err.strip()[-600:]}")


def round_trips(stack: str, count: int, interfaces: str) -> tuple[float, float]:
    server = _start(stack, "server", 120, interfaces)
    client = _start(stack, "client", count, interfaces)
    r = _result(client, 150)
    server.kill()
    server.communicate()
    if not r.get("n"):
        raise RuntimeError(f"{stack}: no goal came back")
    return r["p50"], r["p99"]


def inside(quick: bool) -> None:
    reps = 1 if quick else 5
    count = 200 if quick else 1000
    stacks = ["llfsm"] + (["rclpy"] if ROS_PYTHON.exists() else [])
    with tempfile.TemporaryDirectory() as tmp:
        package = Path(tmp) / "llfsm_bench_msgs" / "action"
        package.mkdir(parents=True)
        (package / "Fibonacci.action").write_text(FIBONACCI)
        os.environ["LLFSM_CACHE_DIR"] = str(Path(tmp) / "cache")
        measured: dict[str, list[tuple[float, float]]] = {s: [] for s in stacks}
        for _ in range(reps):  # interleaved: each repetition measures every stack once
            for s in stacks:
                measured[s].append(round_trips(s, count, tmp))

    def cell(stack: str, i: int) -> str:
        if stack not in stacks:
            return "(no .venv-ros)"
        return f"{statistics.median(m[i] for m in measured[stack]):,.0f}"

    def ratio(i: int) -> str:
        if "rclpy" not in stacks:
            return ""
        llfsm = statistics.median(m[i] for m in measured["llfsm"])
        rclpy = statistics.median(m[i] for m in measured["rclpy"])
        return f"{llfsm / rclpy:.2f}"

    print(
        f"llfsm actions benchmark: Python {sys.version.split()[0]}, {os.cpu_count()} CPUs, "
        f"{count} goals a run, medians of {reps} interleaved runs\n"
    )
    print("| goal round trip (send_goal -> accepted -> result, empty execution) | llfsm ↔ llfsm (Cyclone DDS) "
          "| rclpy ↔ rclpy (Fast DDS) | llfsm / rclpy | target |")  # fmt: skip
    print("|---|---|---|---|---|")
    for i, what in enumerate(("p50 (µs)", "p99 (µs)")):
        print(f"| {what} | {cell('llfsm', i)} | {cell('rclpy', i)} | {ratio(i)} | ≤ 1.00 |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="fewer goals, one repetition")
    ap.add_argument("--inside", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--role", nargs=3, metavar=("ROLE", "STACK", "ARG"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.role:
        role, stack, arg = args.role
        ROLES[role](stack, int(float(arg)) if role == "client" else float(arg))
        return
    if args.inside:
        inside(args.quick)
        return
    cmd = [sys.executable, str(HERE), "--inside"] + (["--quick"] if args.quick else [])
    r = subprocess.run(["unshare", "-n", "sh", "-c", f'{NETNS_SETUP} && exec "$@"', "sh", *cmd], check=False)
    sys.exit(r.returncode)


if __name__ == "__main__":
    main()
