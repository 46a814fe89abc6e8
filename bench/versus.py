"""This checkout against another one, side by side: did a change make llfsm slower?

    .venv/bin/python bench/versus.py OTHER [--quick] [--sections speed startup build verify dds]

OTHER is another checkout of llfsm (a `git worktree add /tmp/base <commit>` with its own
`make .venv/.installed-dev`).  Each figure is measured in both checkouts in the same run,
alternating (this, other, other, this, ...), and the table gives the median of the per-round
ratios this / other with their spread, beside each side's median.  Ratios are the point: the
machines are shared and noisy, so a figure alone says little, and two figures taken minutes
apart say less.  Each side runs with its own interpreter and its own code and benchmark
helpers (bench/run.py's contestants, bench/dds.py's roles), so what differs is the change.

- speed: rates (work per CPU second) of the `speed` section's llfsm contestants and of the
  plain-Python bound, each side in a worker process of its own.  The bound runs the same code
  on both sides: its ratio is the control (how far apart two identical things come out).
- startup: wall time of `llfsm run --clock sim hello.machine` with a warm cache, and of a
  built module.
- build: CPU time (user + system) of a cold `llfsm build` of 10 and 100 generated machines.
- verify: `llfsm verify`'s exploration speed (configurations per CPU second, exact storage) on
  bench/verify.py's counter and mutex arrangements, each side with its own bench/verify.py.
- dds: Twist round trip p50 and an idle machine's rounds per second on the DDS transport,
  inside a private network namespace.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import textwrap
from collections.abc import Callable, Iterator
from pathlib import Path

HERE = Path(__file__).resolve().parent
THIS = HERE.parent
sys.path.insert(0, str(HERE))

import run  # noqa: E402  (bench/run.py: its timers, which this file shares)

NETNS_SETUP = "ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo"
Row = list[str]

#: The worker of the speed section: builds the contestants with its own checkout's bench/run.py,
#: then times the one asked for on each line ("name n"), answering "work seconds".
SPEED_WORKER = textwrap.dedent(
    """
    import sys, tempfile
    from pathlib import Path
    sys.path.insert(0, sys.argv[1] + "/bench")
    import run
    tmp = Path(tempfile.mkdtemp(prefix="llfsm-versus-"))
    paths = run.machine_paths(tmp)  # one list; (toggles, idles) in a bench/run.py before issue 27's
    mine = run.contestants(*paths) if isinstance(paths, tuple) else run.contestants(paths)
    named = {**run.bounds(), **mine}
    print(" ".join(n.replace(" ", "_") for n in named), flush=True)
    for line in sys.stdin:
        name, _, n = line.strip().rpartition(" ")
        work, t = named[name.replace("_", " ")](int(n))
        print(work, t, flush=True)
    """
)

#: What the dds section measures on one side: each side's own bench/dds.py roles.
DDS_PROBE = textwrap.dedent(
    """
    import json, sys
    sys.path.insert(0, sys.argv[1] + "/bench")
    import dds
    p50, _p99 = dds.latency("llfsm", int(sys.argv[2]))
    idle = dds.idle_rate("dds", float(sys.argv[3]))
    print(json.dumps({"Twist round trip p50 (µs)": p50, "idle rounds/s on dds": idle}))
    """
)


#: The verify section's probe: one exploration with the side's own bench/verify.py, answering
#: "configurations cpu_seconds".
VERIFY_PROBE = textwrap.dedent(
    """
    import sys
    from pathlib import Path
    sys.path.insert(0, sys.argv[1] + "/bench")
    import verify as bench
    root = Path(sys.argv[3])
    if sys.argv[2] == "counter":
        paths, prop = [bench.write_counter(root, int(sys.argv[4]))], "always: counter.count >= 0"
    else:
        n = int(sys.argv[4])
        paths, prop = bench.write_mutex(root, n), bench.mutex_property(n)
    v, t = bench.explore(paths, prop, False)
    print(v.configurations, t)
    """
)


def python_of(checkout: Path) -> str:
    py = checkout / ".venv" / "bin" / "python"
    return str(py) if py.exists() else sys.executable


def env_of(checkout: Path, cache: Path) -> dict[str, str]:
    """The side's environment: its llfsm first on the path.  PYTHONSAFEPATH: `python -c` and
    `python -m` would otherwise put the working directory first, and run from this checkout's
    root (as the docstring says) the other side imported this checkout's llfsm too."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONDONTWRITEBYTECODE")}
    env["PYTHONPATH"] = str(checkout)
    env["PYTHONSAFEPATH"] = "1"
    env["LLFSM_CACHE_DIR"] = str(cache)
    return env


def row(label: str, mine: list[float], theirs: list[float], fmt: Callable[[float], str]) -> Row:
    """Each side's median, and the median (min-max) of the per-round ratios this / other."""
    rs = [a / b for a, b in zip(mine, theirs, strict=True)]
    ratio = f"{statistics.median(rs):.2f} ({min(rs):.2f}-{max(rs):.2f})"
    return [label, fmt(statistics.median(mine)), fmt(statistics.median(theirs)), ratio]


def alternate(
    rounds: int, sides: tuple[Path, Path], measure: Callable[[Path], float]
) -> tuple[list[float], list[float]]:
    """`measure` on both sides, `rounds` times, the order swapped every round."""
    out: dict[Path, list[float]] = {s: [] for s in sides}
    for r in range(rounds):
        for side in sides if r % 2 == 0 else sides[::-1]:
            out[side].append(measure(side))
    return out[sides[0]], out[sides[1]]


def section_speed(other: Path, quick: bool, tmp: Path) -> list[Row]:
    workers = {}
    for side in (THIS, other):
        p = subprocess.Popen(
            [python_of(side), "-c", SPEED_WORKER, str(side)],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            env=env_of(side, tmp / f"cache-{side.name}"),
        )
        assert p.stdout is not None
        names = [n.replace("_", " ") for n in p.stdout.readline().split()]
        workers[side] = (p, names)
    wanted = [n for n in workers[THIS][1] if n in workers[other][1] and "wall" not in n]
    n = 200_000 if quick else 1_000_000

    def timed(side: Path, name: str) -> float:
        p = workers[side][0]
        assert p.stdin is not None and p.stdout is not None
        p.stdin.write(f"{name.replace(' ', '_')} {n}\n")
        p.stdin.flush()
        work, t = p.stdout.readline().split()
        return int(work) / float(t)

    rows = []
    rounds = 5 if quick else 9
    results = {name: ([], []) for name in wanted}
    for r in range(rounds):  # every contestant once per round, each on both sides back to back
        k = r % len(wanted)
        for name in wanted[k:] + wanted[:k]:
            for side in (THIS, other) if r % 2 == 0 else (other, THIS):
                results[name][0 if side == THIS else 1].append(timed(side, name))
    for p, _ in workers.values():
        assert p.stdin is not None
        p.stdin.close()
        p.wait(timeout=60)
    for name in wanted:
        mine, theirs = results[name]
        label = f"{name} (control: the same code on both sides)" if name.startswith("plain") else name
        rows.append(row(f"speed: {label}", mine, theirs, lambda x: f"{x:,.0f}/s"))
    return rows


def section_startup(other: Path, quick: bool, tmp: Path) -> list[Row]:
    m = tmp / "hello.machine"
    m.mkdir()
    (m / "machine.yaml").write_text("states:\n  - name: INITIAL\n")
    (m / "State_INITIAL_OnEntry.py").write_text("print('hello')\n")
    rows = []
    for label, built in (("llfsm run hello.machine (warm cache)", False), ("llfsm run build/hello.py", True)):

        def once(side: Path, built: bool = built) -> float:
            env = env_of(side, tmp / f"cache-{side.name}")
            target = m
            if built:
                target = tmp / f"out-{side.name}" / "hello.py"
                if not target.exists():
                    subprocess.run([python_of(side), "-m", "llfsm", "build", "-q", str(m), "-o", str(target.parent)],
                                   env=env, check=True)  # fmt: skip
            return run.wall([python_of(side), "-m", "llfsm", "run", "--clock", "sim", str(target)], env)

        for side in (THIS, other):
            once(side)  # caches and bytecode written outside the timed runs
        mine, theirs = alternate(9 if quick else 21, (THIS, other), once)
        rows.append(row(f"startup: {label}", mine, theirs, lambda x: f"{x * 1000:.0f} ms"))
    return rows


def section_build(other: Path, quick: bool, tmp: Path) -> list[Row]:
    from gen import write_big

    rows = []
    for count in (10,) if quick else (10, 100):
        root = tmp / f"m{count}"
        for i in range(count):
            write_big(root, f"machine_{i:04d}", 10)
        fresh = iter(range(10**6))

        def once(side: Path, root: Path = root, fresh: Iterator[int] = fresh) -> float:
            i = next(fresh)  # a fresh cache and output folder: a cold build every time
            env = env_of(side, tmp / f"bcache-{i}")
            cmd = [python_of(side), "-m", "llfsm", "build", "-q", str(root), "-o", str(tmp / f"bout-{i}")]
            return run.wall_cpu(cmd, env)[1]

        mine, theirs = alternate(3 if quick else 5, (THIS, other), once)
        rows.append(row(f"build: cold build of {count} machines (CPU)", mine, theirs, lambda x: f"{x:.2f} s"))
    return rows


def section_verify(other: Path, quick: bool, tmp: Path) -> list[Row]:
    rows = []
    for kind, size in (("counter", 20_000 if quick else 100_000), ("mutex", 4 if quick else 5)):

        def once(side: Path, kind: str = kind, size: int = size) -> float:
            folder = tmp / f"{kind}-{side.name}"
            cmd = [python_of(side), "-c", VERIFY_PROBE, str(side), kind, str(folder), str(size)]
            r = subprocess.run(cmd, capture_output=True, text=True, env=env_of(side, tmp / f"cache-{side.name}"),
                               timeout=600, check=True)  # fmt: skip
            configurations, seconds = r.stdout.split()
            return int(configurations) / float(seconds)

        mine, theirs = alternate(3 if quick else 7, (THIS, other), once)
        label = f"verify: {kind} {size:,}" if kind == "counter" else f"verify: {size} mutex machines"
        rows.append(row(f"{label} (configurations per CPU s)", mine, theirs, lambda x: f"{x:,.0f}/s"))
    return rows


def section_dds(other: Path, quick: bool, tmp: Path) -> list[Row]:
    cmd = [sys.executable, str(Path(__file__)), str(other), "--dds-inside"] + (["--quick"] if quick else [])
    r = subprocess.run(
        ["unshare", "-n", "sh", "-c", f'{NETNS_SETUP} && exec "$@"', "sh", *cmd],
        capture_output=True,
        text=True,
        check=False,
    )
    if r.returncode != 0:
        return [["dds: not measured", r.stderr.strip().splitlines()[-1] if r.stderr.strip() else "", "", ""]]
    return [json.loads(line) for line in r.stdout.splitlines() if line.startswith("[")]


def dds_inside(other: Path, quick: bool) -> None:
    count, seconds = (200, 2.0) if quick else (1000, 4.0)
    got: dict[Path, list[dict[str, float]]] = {THIS: [], other: []}
    for r in range(2 if quick else 5):
        for side in (THIS, other) if r % 2 == 0 else (other, THIS):
            p = subprocess.run(
                [python_of(side), "-c", DDS_PROBE, str(side), str(count), str(seconds)],
                capture_output=True,
                text=True,
                env=env_of(side, Path(tempfile.gettempdir()) / f"llfsm-versus-dds-{side.name}"),
                timeout=300,
                check=True,
            )
            got[side].append(json.loads(p.stdout.strip().splitlines()[-1]))
    for key in got[THIS][0]:
        mine, theirs = [g[key] for g in got[THIS]], [g[key] for g in got[other]]
        print(json.dumps(row(f"dds: {key}", mine, theirs, lambda x: f"{x:.3g}")))


SECTIONS = {
    "speed": section_speed,
    "startup": section_startup,
    "build": section_build,
    "verify": section_verify,
    "dds": section_dds,
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("other", type=Path, help="the other checkout (with its own .venv)")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--sections", nargs="*", choices=list(SECTIONS), default=list(SECTIONS))
    ap.add_argument("--dds-inside", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    other = args.other.resolve()
    if args.dds_inside:
        dds_inside(other, args.quick)
        return
    if not (other / "llfsm" / "__init__.py").exists():
        sys.exit(f"versus: {other} is not a checkout of llfsm")
    rev = {s: subprocess.run(["git", "-C", str(s), "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                             check=False).stdout.strip() or "?" for s in (THIS, other)}  # fmt: skip
    rows: list[Row] = []
    with tempfile.TemporaryDirectory(prefix="llfsm-versus-") as tmp:
        for name in args.sections:
            (Path(tmp) / name).mkdir()
            rows += SECTIONS[name](other, args.quick, Path(tmp) / name)
    head = ["what", f"this ({rev[THIS]})", f"other ({rev[other]})", "this / other: median (min-max)"]
    load = os.getloadavg()[0]
    print(f"llfsm {rev[THIS]} against {rev[other]}, interleaved; {os.cpu_count()} cores, load average {load:.1f}\n")
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for row in rows:
        print("| " + " | ".join(row) + " |")
    print("\nA rate's ratio above 1 is faster; a time's ratio below 1 is faster.")


if __name__ == "__main__":
    main()
