"""Launch benchmark: from `llfsm launch` to the wall bot's first /turtle1/cmd_vel, and the
launcher's memory.

    .venv/bin/python bench/launch.py [--quick] [--rounds N]

Starts machines/ros2_wall_turtle_bot.launch.xml (turtlesim, the pose service, the wall bot) and
times, from the moment the command is started to the moment a subscriber that was already
listening receives the first Twist on /turtle1/cmd_vel, beside the same three processes started
at once by hand (three `llfsm run --transport dds ...` commands, no launcher), interleaved
(launch, by hand, launch, ...), medians.  The bot publishes its first command after its INITIAL
state's `after_ms(1000)`, so a second of every figure is the machine waiting, as written.
The launcher's memory is its peak resident size (VmHWM of /proc/PID/status, read just before
its Ctrl-C).  Everything runs inside a private network namespace (unshare -n), and the
machine's compiled module is warm (one run first, not counted).
"""

from __future__ import annotations

import argparse
import os
import signal
import statistics
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve()
REPO = HERE.parent.parent
LAUNCH_FILE = REPO / "machines" / "ros2_wall_turtle_bot.launch.xml"
MACHINE = REPO / "machines" / "ros2_wall_turtle_bot.machine"
NETNS_SETUP = "ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo"
LLFSM = [sys.executable, "-m", "llfsm"]
BY_HAND = [
    [*LLFSM, "run", "--transport", "dds", "--node", "turtlesim"],
    [*LLFSM, "run", "--transport", "dds", "--node", "turtle_sensor_poster"],
    [*LLFSM, "run", "--transport", "dds", str(MACHINE)],
]
TARGET_S, TARGET_MB = 3.0, 60.0


class Listener:
    """A subscriber to /turtle1/cmd_vel in this process, matched before anything starts."""

    def __init__(self) -> None:
        from llfsm import ros
        from llfsm.msgs.geometry_msgs.msg import Twist
        from llfsm.ros.transports import make
        from llfsm.runtime import RunContext, WallClock
        from llfsm.runtime.context import activate

        ctx = RunContext(WallClock())
        ctx.transport = make("dds")
        activate(ctx)
        ros.init()
        self.ros = ros
        self.node = ros.Node("bench_launch_listener")
        self.first: float | None = None
        self.node.create_subscription(Twist, "/turtle1/cmd_vel", self._heard, 10)

    def _heard(self, msg: object) -> None:
        if self.first is None:
            self.first = time.monotonic()

    def wait(self, timeout: float) -> float | None:
        """Seconds until the first message (from now), None past `timeout`."""
        self.first = None
        end = time.monotonic() + timeout
        while self.first is None and time.monotonic() < end:
            self.ros.spin_once(self.node, timeout_sec=0.005)
        return self.first


def _stop(procs: list[subprocess.Popen[bytes]]) -> None:
    for p in procs:
        if p.poll() is None:
            p.send_signal(signal.SIGINT)
    for p in procs:
        try:
            p.wait(timeout=30)
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)
            p.wait()


def _peak_mb(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def one(how: str, listener: Listener, logs: Path) -> tuple[float | None, float | None]:
    """(seconds to the first cmd_vel, the launcher's peak MB) for one start."""
    env = {**os.environ, "ROS_LOG_DIR": str(logs)}
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "env": env, "process_group": 0}
    t0 = time.monotonic()
    if how == "launch":
        procs = [subprocess.Popen([*LLFSM, "launch", str(LAUNCH_FILE)], **quiet)]  # type: ignore[call-overload]
    else:
        procs = [subprocess.Popen(cmd, **quiet) for cmd in BY_HAND]  # type: ignore[call-overload]
    first = listener.wait(30)
    peak = _peak_mb(procs[0].pid) if how == "launch" and procs[0].poll() is None else None
    _stop(procs)
    return (first - t0 if first is not None else None), peak


def inside(rounds: int) -> None:
    import tempfile

    listener = Listener()
    logs = Path(tempfile.mkdtemp(prefix="llfsm-bench-launch-"))
    one("launch", listener, logs)  # warm: the machine's module compiled, the files in the page cache
    times: dict[str, list[float]] = {"launch": [], "hand": []}
    peaks: list[float] = []
    missed = 0
    for _ in range(rounds):
        for how in ("launch", "hand"):
            seconds, peak = one(how, listener, logs)
            if seconds is None:
                missed += 1
                continue
            times[how].append(seconds)
            if peak is not None:
                peaks.append(peak)
    med = statistics.median
    load = os.getloadavg()[0]
    print(
        f"### `llfsm launch` of the wall bot: median of {rounds} interleaved rounds (min-max); "
        f"load average {load:.2f} on {os.cpu_count()} cores"
    )
    print()
    print("| start | first /turtle1/cmd_vel, s | target |")
    print("|---|---|---|")
    for how, label, target in (
        ("launch", f"`llfsm launch {LAUNCH_FILE.relative_to(REPO)}`", f"≤ {TARGET_S:.0f}"),
        ("hand", "the same three `llfsm run` started at once, no launcher", ""),
    ):
        xs = times[how]
        cell = f"{med(xs):.2f} ({min(xs):.2f}-{max(xs):.2f})" if xs else "never"
        print(f"| {label} | {cell} | {target} |")
    if times["launch"] and times["hand"]:
        print(f"| launch / by hand | {med(times['launch']) / med(times['hand']):.2f} |  |")
    print()
    print("| launcher | peak resident memory, MB | target |")
    print("|---|---|---|")
    cell = f"{med(peaks):.1f} ({min(peaks):.1f}-{max(peaks):.1f})" if peaks else "not measured"
    print(f"| `llfsm launch` (VmHWM) | {cell} | ≤ {TARGET_MB:.0f} |")
    if missed:
        print(f"\n{missed} start(s) saw no /turtle1/cmd_vel within 30 s")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="three rounds")
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--inside", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    rounds = 3 if args.quick else args.rounds
    if args.inside:
        inside(rounds)
        return
    cmd = [sys.executable, str(HERE), "--inside", "--rounds", str(rounds)]
    r = subprocess.run(["unshare", "-n", "sh", "-c", f'{NETNS_SETUP} && exec "$@"', "sh", *cmd], check=False)
    sys.exit(r.returncode)


if __name__ == "__main__":
    main()
