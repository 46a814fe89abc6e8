"""DDS benchmark: llfsm over Cyclone DDS beside rclpy over Fast DDS, between two processes.

    .venv/bin/python bench/dds.py [--quick]

Prints one table:
- Twist messages per second from a publisher process to a subscriber process (reliable, keep
  last 100, volatile: the same QoS for both stacks), counted at the subscriber;
- round-trip latency (p50, p99) of a Twist sent to an echo process and back;
- rounds per second of an idle machine (nothing fires, no idle sleep: `--idle 0`) with the DDS
  transport beside the in-process bus (one process, the machine holds a publisher and a PULL
  reader, so the DDS run really polls its wait set after every round).
Each figure is the median of interleaved repetitions (llfsm, rclpy, llfsm, rclpy...).  rclpy
comes from `.venv-ros` (make .venv-ros/.installed); without it its column says so.  Everything
runs inside a private network namespace (unshare -n), so nothing leaves the machine.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve()
REPO = HERE.parent.parent
ROS_PYTHON = REPO / ".venv-ros" / "bin" / "python"
NETNS_SETUP = "ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo"
DEPTH = 100
TOPIC, PING, PONG = "/bench_twist", "/bench_ping", "/bench_pong"


# -- roles (each runs in a process of its own) -----------------------------------------------------


def _llfsm_node(name: str):
    from llfsm import ros
    from llfsm.ros.transports import make
    from llfsm.runtime import RunContext, WallClock
    from llfsm.runtime.context import activate

    ctx = RunContext(WallClock())
    ctx.transport = make("dds")
    activate(ctx)
    ros.init()
    return ros, ros.Node(name)


def _rclpy_node(name: str):
    import rclpy

    rclpy.init()
    return rclpy, rclpy.create_node(name)


def _twist(stack: str) -> type:
    if stack == "llfsm":
        from llfsm.msgs.geometry_msgs.msg import Twist
    else:
        from geometry_msgs.msg import Twist  # type: ignore[no-redef]
    return Twist


def _node(stack: str, name: str):
    return _llfsm_node(name) if stack == "llfsm" else _rclpy_node(name)


def role_source(stack: str, seconds: float) -> None:
    """Publish Twist as fast as the stack allows for `seconds` once a subscriber is matched."""
    ros, node = _node(stack, "bench_source")
    pub = node.create_publisher(_twist(stack), TOPIC, DEPTH)
    msg = _twist(stack)()
    deadline = time.monotonic() + 20
    while pub.get_subscription_count() == 0 and time.monotonic() < deadline:
        ros.spin_once(node, timeout_sec=0.05)
    time.sleep(0.5)  # let the subscriber's side see the match too
    end = time.monotonic() + seconds
    sent = 0
    while time.monotonic() < end:
        for _ in range(100):
            msg.linear.x = float(sent)
            pub.publish(msg)
            sent += 1
        ros.spin_once(node, timeout_sec=0)
    print(json.dumps({"sent": sent}), flush=True)


def role_sink(stack: str, seconds: float) -> None:
    """Count messages received during `seconds` after the first one."""
    ros, node = _node(stack, "bench_sink")
    times: list[float] = []
    node.create_subscription(_twist(stack), TOPIC, lambda m: times.append(time.monotonic()), DEPTH)
    deadline = time.monotonic() + 25
    while not times and time.monotonic() < deadline:
        ros.spin_once(node, timeout_sec=0.05)
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        ros.spin_once(node, timeout_sec=0.01)
    window = [t for t in times if t <= end]
    span = (window[-1] - window[0]) if len(window) > 1 else 0.0
    print(json.dumps({"received": len(window), "rate": (len(window) - 1) / span if span else 0.0}), flush=True)


def role_echo(stack: str, seconds: float) -> None:
    """Send every /bench_ping back on /bench_pong."""
    ros, node = _node(stack, "bench_echo")
    pub = node.create_publisher(_twist(stack), PONG, DEPTH)
    node.create_subscription(_twist(stack), PING, pub.publish, DEPTH)
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        ros.spin_once(node, timeout_sec=0.1)


def role_ping(stack: str, count: int) -> None:
    """Round trips through the echo process, one at a time: p50 and p99 in microseconds."""
    ros, node = _node(stack, "bench_ping")
    pub = node.create_publisher(_twist(stack), PING, DEPTH)
    got: list[float] = []
    node.create_subscription(_twist(stack), PONG, lambda m: got.append(m.linear.x), DEPTH)
    deadline = time.monotonic() + 20
    while pub.get_subscription_count() == 0 and time.monotonic() < deadline:
        ros.spin_once(node, timeout_sec=0.05)
    msg = _twist(stack)()
    rtts: list[float] = []
    for i in range(count + 50):  # the first 50 warm up
        msg.linear.x = float(i)
        t0 = time.perf_counter()
        pub.publish(msg)
        limit = t0 + 1.0
        while (not got or got[-1] != float(i)) and time.perf_counter() < limit:
            ros.spin_once(node, timeout_sec=0.001)
        if i >= 50 and got and got[-1] == float(i):
            rtts.append((time.perf_counter() - t0) * 1e6)
    rtts.sort()
    out = {"n": len(rtts)}
    if rtts:
        out |= {"p50": rtts[len(rtts) // 2], "p99": rtts[min(len(rtts) - 1, int(len(rtts) * 0.99))]}
    print(json.dumps(out), flush=True)


def role_idle(transport: str, seconds: float) -> None:
    """Rounds per second of one idle machine (no transition fires, no idle sleep)."""
    import tempfile

    from llfsm.ros.bus import bus_of
    from llfsm.ros.transports import make
    from llfsm.runtime import Arrangement, RunContext, WallClock
    from llfsm.targets import load

    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp) / "idle.machine"
        d.mkdir()
        (d / "machine.yaml").write_text("states:\n  - name: INITIAL\n    transitions: [END]\n  - name: END\n")
        (d / "State_INITIAL_Transition_0.expr").write_text("not ros.ok()\n")
        (d / "Includes.py").write_text("from llfsm import ros\nfrom llfsm.msgs.geometry_msgs.msg import Twist\n")
        (d / "State_INITIAL_OnEntry.py").write_text(
            'ros.init()\nnode = ros.Node("idle")\n'
            'pub = node.create_publisher(Twist, "/idle_out", 10)\n'
            'reader = node.create_subscription(Twist, "/idle_in", None, 10)\n'
        )
        os.environ.setdefault("LLFSM_CACHE_DIR", str(Path(tmp) / "cache"))
        cls = load(str(d))
        ctx = RunContext(WallClock(idle_ns=0))
        ctx.transport = make(transport)
        bus_of(ctx)  # the bus's executor runs between rounds, as in `llfsm run`
        arr = Arrangement([cls], context=ctx)
        # the scheduler counts rounds itself (between-round hooks run only when the bus has work)
        t0 = time.perf_counter()
        result = arr.run(round(seconds * 1e9))
        rate = result.rounds / (time.perf_counter() - t0)  # includes making the DDS entities once
        print(json.dumps({"rate": rate}), flush=True)


ROLES = {"source": role_source, "sink": role_sink, "echo": role_echo, "ping": role_ping, "idle": role_idle}


# -- the orchestration (inside the namespace) ---------------------------------------------------------


def _python(stack: str) -> str:
    return str(ROS_PYTHON) if stack == "rclpy" else sys.executable


def _env(stack: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("ROS_", "CYCLONEDDS", "FASTDDS", "FASTRTPS"))}
    env["PYTHONPATH"] = str(REPO)
    if stack == "rclpy":
        env["RMW_IMPLEMENTATION"] = "rmw_fastrtps_cpp"
        env.pop("VIRTUAL_ENV", None)
    return env


def _start(stack: str, role: str, arg: float) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [_python(stack), str(HERE), "--role", role, stack, str(arg)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=_env(stack),
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
    raise RuntimeError(f"a benchmark process failed: {err.strip()[-400:]}")


def throughput(stack: str, seconds: float) -> float:
    sink = _start(stack, "sink", seconds)
    source = _start(stack, "source", seconds + 1.5)
    rate = _result(sink, seconds + 40)["rate"]
    _result(source, seconds + 40)
    return rate


def latency(stack: str, count: int) -> tuple[float, float]:
    echo = _start(stack, "echo", 60)
    ping = _start(stack, "ping", count)
    r = _result(ping, 90)
    echo.kill()
    echo.communicate()
    return r.get("p50", float("nan")), r.get("p99", float("nan"))


def idle_rate(transport: str, seconds: float) -> float:
    return _result(_start(transport, "idle", seconds), seconds + 60)["rate"]


def inside(quick: bool) -> None:
    reps = 1 if quick else 3
    seconds = 1.5 if quick else 3.0
    count = 300 if quick else 2000
    stacks = ["llfsm"] + (["rclpy"] if ROS_PYTHON.exists() else [])
    tp: dict[str, list[float]] = {s: [] for s in stacks}
    lat: dict[str, list[tuple[float, float]]] = {s: [] for s in stacks}
    idle: dict[str, list[float]] = {"inproc": [], "dds": []}
    for _ in range(reps):  # interleaved: each repetition measures every stack once
        for s in stacks:
            tp[s].append(throughput(s, seconds))
        for s in stacks:
            lat[s].append(latency(s, count))
        for t in ("inproc", "dds"):
            idle[t].append(idle_rate(t, seconds))

    def med(xs: list[float]) -> float:
        return statistics.median(xs)

    def col(stack: str, fmt: str, fn) -> str:
        return fmt.format(fn(stack)) if stack in stacks else "(no .venv-ros)"

    rows = [
        (
            "Twist messages/s, process to process",
            col("llfsm", "{:,.0f}", lambda s: med(tp[s])),
            col("rclpy", "{:,.0f}", lambda s: med(tp[s])),
        ),
        (
            "round trip p50 (µs)",
            col("llfsm", "{:,.0f}", lambda s: med([a for a, _ in lat[s]])),
            col("rclpy", "{:,.0f}", lambda s: med([a for a, _ in lat[s]])),
        ),
        (
            "round trip p99 (µs)",
            col("llfsm", "{:,.0f}", lambda s: med([b for _, b in lat[s]])),
            col("rclpy", "{:,.0f}", lambda s: med([b for _, b in lat[s]])),
        ),
    ]
    print(f"llfsm DDS benchmark: Python {sys.version.split()[0]}, {os.cpu_count()} CPUs, medians of {reps}\n")
    print("| measure | llfsm (Cyclone DDS) | rclpy (Fast DDS) |")
    print("|---|---|---|")
    for r in rows:
        print(f"| {r[0]} | {r[1]} | {r[2]} |")
    ratio = med(idle["dds"]) / med(idle["inproc"])
    print()
    print("| idle machine, rounds/s (--idle 0) | in-process bus | DDS transport | DDS / in-process |")
    print("|---|---|---|---|")
    inproc_rate, dds_rate = med(idle["inproc"]), med(idle["dds"])
    print(f"| one machine, a publisher and a PULL reader | {inproc_rate:,.0f} | {dds_rate:,.0f} | {ratio:.2f} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="shorter runs, one repetition")
    ap.add_argument("--inside", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--role", nargs=3, metavar=("ROLE", "STACK", "ARG"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.role:
        role, stack, arg = args.role
        ROLES[role](stack, int(arg) if role == "ping" else float(arg))
        return
    if args.inside:
        inside(args.quick)
        return
    cmd = [sys.executable, str(HERE), "--inside"] + (["--quick"] if args.quick else [])
    r = subprocess.run(["unshare", "-n", "sh", "-c", f'{NETNS_SETUP} && exec "$@"', "sh", *cmd], check=False)
    sys.exit(r.returncode)


if __name__ == "__main__":
    main()
