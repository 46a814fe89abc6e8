"""llfsm benchmarks: every number is printed in a table, never asserted.

    python bench/run.py              all sections, also written to bench/results.md
    python bench/run.py speed build  one or more sections
    python bench/run.py --quick      smaller sizes (a smoke run)

The machines are shared and noisy, so speed is compared, not quoted: every contestant of the
`speed` section (the plain-Python bounds, llfsm's pure-Python path, llfsm's native build, other
libraries) runs once per round, the rounds interleave them in a rotated order, and a ratio is
the median over the rounds of (contestant / its bound in the same round), printed with the
spread (min-max).  One plain-Python bound per workload serves every table that uses it.  Times
are CPU time of the process doing the work (time.process_time), which other processes on the
machine disturb far less than wall time.  Arrangements, clocks and buses are made before the
timer starts.  The native contestants run in a worker process started with LLFSM_NATIVE (the
compiled runtime can only be imported by a process of its own), driven round by round from here.

Every cache (compiled modules, native builds, mypy's cache) goes to a temporary folder.
"""

from __future__ import annotations

import argparse
import io
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from gen import write_big, write_bus_toggle, write_idle, write_toggle  # noqa: E402

Table = tuple[str, list[str], list[list[str]]]
QUICK = False
#: (work done, CPU seconds) for a workload of size n
Timed = Callable[[int], tuple[int, float]]


def fmt_rate(x: float) -> str:
    return f"{x:,.0f}"


def llfsm_cmd() -> list[str]:
    exe = Path(sys.executable).parent / "llfsm"
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "llfsm"]


# -- the contestants of the speed section ----------------------------------------------------------


def best_rate(fn: Callable[[int], None], n: int, repeats: int = 3) -> float:
    """Operations per second: the best of `repeats` timed runs of fn(n) (the bus section)."""
    best = float("inf")
    for _ in range(repeats):
        t = time.perf_counter()
        fn(n)
        best = min(best, time.perf_counter() - t)
    return n / best


def cpu(fn: Callable[[], object]) -> float:
    t = time.process_time()
    fn()
    return time.process_time() - t


def plain_toggle(n: int) -> tuple[int, float]:
    """The CPython bound: a hand-written two-state toggle, one function call per step."""

    class T:
        count = 0

    t = T()

    def a(t: T) -> Callable:
        t.count += 1
        return b

    def b(t: T) -> Callable:
        t.count += 1
        return a

    def run() -> None:
        s = a
        for _ in range(n):
            s = s(t)

    return n, cpu(run)


def plain_arrangement(machines: int, fired: bool) -> Timed:
    """The plain-Python bound for n ringlets: a list of objects, each with a current state
    function called once per round.  Fired: every call increments a counter and switches state
    (the toggle).  Idle: every call tests a false guard and returns."""

    class T:
        __slots__ = ("count", "state", "stop")

        def __init__(self) -> None:
            self.count, self.stop = 0, False

    def a(t: T) -> None:
        t.count += 1
        t.state = b

    def b(t: T) -> None:
        t.count += 1
        t.state = a

    def idle(t: T) -> int | None:
        if t.stop:
            return 0
        return None

    def timed(n: int) -> tuple[int, float]:
        objs = [T() for _ in range(machines)]
        for o in objs:
            o.state = a if fired else idle

        def run() -> None:
            for _ in range(n // machines):
                for o in objs:
                    o.state(o)

        return n // machines * machines, cpu(run)

    return timed


def llfsm_timed(classes: list[type], clock: str = "sim") -> Timed:
    """n ringlets of an arrangement of `classes`: the sim clock (1 us rounds), or the wall clock
    (rounds back to back: every machine here fires)."""
    from llfsm.runtime import Arrangement, RunContext, SimClock, WallClock

    def timed(n: int) -> tuple[int, float]:
        ctx = RunContext(SimClock(1_000) if clock == "sim" else WallClock(idle_ns=0))
        arr = Arrangement(classes, context=ctx)
        rounds = n // len(classes)
        if clock == "sim":
            t = cpu(lambda: arr.run(duration_ns=rounds * 1_000))
            return arr.rounds * len(classes), t
        # the wall clock: run for about as long as the sim run takes, count the rounds
        t = cpu(lambda: arr.run(duration_ns=rounds * 150))
        return arr.rounds * len(classes), t

    return timed


def transitions_toggle(n: int) -> tuple[int, float]:
    from transitions import Machine as TMachine

    class Model:
        count = 0

        def inc(self) -> None:
            self.count += 1

    m = Model()
    TMachine(
        m,
        states=["A", "B"],
        initial="A",
        transitions=[
            {"trigger": "go", "source": "A", "dest": "B", "after": "inc"},
            {"trigger": "go", "source": "B", "dest": "A", "after": "inc"},
        ],
    )

    def run() -> None:
        for _ in range(n):
            m.go()  # type: ignore[attr-defined]

    return n, cpu(run)


def statemachine_toggle(n: int) -> tuple[int, float]:
    from statemachine import State, StateMachine

    class Toggle(StateMachine):
        a = State(initial=True)
        b = State()
        go = a.to(b) | b.to(a)

        def __init__(self) -> None:
            self.count = 0
            super().__init__()

        def on_enter_state(self) -> None:
            self.count += 1

    s = Toggle()

    def run() -> None:
        for _ in range(n):
            s.go()

    return n, cpu(run)


SISMIC_YAML = """
statechart:
  name: toggle
  preamble: count = 0
  root state:
    name: root
    initial: A
    states:
      - name: A
        on entry: count += 1
        transitions:
          - {target: B, event: go}
      - name: B
        on entry: count += 1
        transitions:
          - {target: A, event: go}
"""


def sismic_toggle(n: int) -> tuple[int, float]:
    from sismic.interpreter import Interpreter
    from sismic.io import import_from_yaml

    it = Interpreter(import_from_yaml(SISMIC_YAML))
    it.execute_once()

    def run() -> None:
        for _ in range(n):
            it.queue("go")
            it.execute_once()

    return n, cpu(run)


def arrangement_sizes() -> tuple[int, int]:
    """How many machines the arrangements of the ringlet table hold.  --quick stops at 30: the
    native build compiles every machine module in one mypyc run, about 2 s a module here (200
    modules took 451 s on the shared 2-core machine)."""
    return (10, 30) if QUICK else (10, 100)


def machine_paths(tmp: Path) -> list[Path]:
    """The toggle that uses the bus, then as many toggles and idle machines as the largest
    arrangement, each its own module, built into tmp/out."""
    count = max(arrangement_sizes())
    write_bus_toggle(tmp / "src")
    for i in range(count):
        write_toggle(tmp / "src", f"toggle_{i}")
        write_idle(tmp / "src", f"idle_{i}")
    out = tmp / "out"
    subprocess.run([*llfsm_cmd(), "build", "-q", str(tmp / "src"), "-o", str(out)], check=True)
    return [
        out / "bus_toggle.py",
        *(out / f"toggle_{i}.py" for i in range(count)),
        *(out / f"idle_{i}.py" for i in range(count)),
    ]


def contestants(paths: list[Path], prefix: str = "") -> dict[str, Timed]:
    """llfsm's contestants, by name, from `machine_paths`; `prefix` tells the pure ones from the
    native ones."""
    from llfsm.targets import load

    bus_toggle, rest = load(str(paths[0])), [load(str(p)) for p in paths[1:]]
    tog, idl = rest[: len(rest) // 2], rest[len(rest) // 2 :]
    out: dict[str, Timed] = {
        f"{prefix}toggle sim": llfsm_timed(tog[:1]),
        f"{prefix}toggle wall": llfsm_timed(tog[:1], "wall"),
        f"{prefix}toggle bus": llfsm_timed([bus_toggle]),
    }
    for k in arrangement_sizes():
        out[f"{prefix}fired {k}"] = llfsm_timed(tog[:k])
        out[f"{prefix}idle {k}"] = llfsm_timed(idl[:k])
    return out


def bounds() -> dict[str, Timed]:
    out: dict[str, Timed] = {"plain toggle": plain_toggle}
    for k in arrangement_sizes():
        out[f"plain fired {k}"] = plain_arrangement(k, True)
        out[f"plain idle {k}"] = plain_arrangement(k, False)
    return out


def worker() -> None:
    """`run.py --worker` in a process with LLFSM_NATIVE set: reads the module paths (as
    `machine_paths` gives them) on its first line, then times the native contestants it is
    asked for ("name n"), one line back each ("work seconds")."""
    mine = contestants([Path(p) for p in sys.stdin.readline().split()], "native ")
    import llfsm.runtime.scheduler as sched

    print("compiled" if (sched.__file__ or "").endswith(".so") else "plain", flush=True)
    for line in sys.stdin:
        name, _, n = line.strip().rpartition(" ")
        work, t = mine[name](int(n))
        print(f"{work} {t}", flush=True)


class Native:
    """The native contestants, timed by a worker process that runs the compiled runtime."""

    def __init__(self, paths: list[Path]) -> None:
        from llfsm.cachedir import cache_root

        self.proc: subprocess.Popen[str] | None = None
        self.cached, self.build_seconds = False, 0.0
        try:
            from llfsm.compiler.native import ENV, available, native_build
        except ImportError:  # an llfsm from before native builds (measuring a baseline)
            self.why: str | None = "this llfsm has no native builds"
            return
        self.why = available()
        if self.why is not None:
            return
        t = time.perf_counter()
        nb = native_build([p.resolve() for p in paths], cache_root())
        self.build_seconds = time.perf_counter() - t
        self.cached = nb.cached
        env = dict(os.environ, **{ENV: str(nb.folder)})
        self.proc = subprocess.Popen(
            [sys.executable, __file__, "--worker", *(["--quick"] if QUICK else [])],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            env=env,
        )
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.proc.stdin.write(" ".join(str(p) for p in paths) + "\n")
        self.proc.stdin.flush()
        kind = self.proc.stdout.readline().strip()
        if kind != "compiled":
            self.close()
            self.why = "the native build did not compile the runtime"

    def timed(self, name: str) -> Timed:
        def run(n: int) -> tuple[int, float]:
            assert self.proc is not None and self.proc.stdin and self.proc.stdout
            self.proc.stdin.write(f"{name} {n}\n")
            self.proc.stdin.flush()
            work, t = self.proc.stdout.readline().split()
            return int(work), float(t)

        return run

    def close(self) -> None:
        if self.proc is not None:
            assert self.proc.stdin is not None
            self.proc.stdin.close()
            self.proc.wait(timeout=60)
            self.proc = None


def interleaved(named: dict[str, Timed], sizes: dict[str, int], rounds: int) -> dict[str, list[float]]:
    """Rates (work per CPU second) of every contestant, `rounds` times, in rotated order."""
    names = list(named)
    rates: dict[str, list[float]] = {n: [] for n in names}
    for r in range(rounds):
        k = r % len(names)
        for name in names[k:] + names[:k]:
            work, t = named[name](sizes[name])
            rates[name].append(work / t)
    return rates


def ratio(rates: dict[str, list[float]], name: str, bound: str) -> tuple[float, float, float]:
    """Median, min and max over the rounds of contestant / bound in the same round."""
    rs = [a / b for a, b in zip(rates[name], rates[bound], strict=True)]
    return statistics.median(rs), min(rs), max(rs)


def fmt_ratio(r: tuple[float, float, float], digits: int = 2) -> str:
    return f"{r[0]:.{digits}f} ({r[1]:.{digits}f}-{r[2]:.{digits}f})"


def section_speed(tmp: Path) -> list[Table]:
    paths = machine_paths(tmp)
    n = 200_000 if QUICK else 1_000_000
    rounds = 7 if QUICK else 9
    named: dict[str, Timed] = {**bounds(), **contestants(paths)}
    native = Native(paths)
    if native.proc is not None:
        for name in list(named):  # the same workloads, compiled
            if not name.startswith("plain"):
                named[f"native {name}"] = native.timed(f"native {name}")
    others = {"transitions": (transitions_toggle, 20_000), "python-statemachine": (statemachine_toggle, 5_000)}
    others["sismic"] = (sismic_toggle, 2_000)
    missing = []
    for name, (fn, _m) in others.items():
        try:
            fn(10)
        except ImportError:
            missing.append(name)
            continue
        named[name] = fn
    sizes = {name: n for name in named}
    for name, (_fn, m) in others.items():
        sizes[name] = m // (5 if QUICK else 1)
    try:
        rates = interleaved(named, sizes, rounds)
    finally:
        native.close()
    med = {k: statistics.median(v) for k, v in rates.items()}

    def row(label: str, name: str, bound: str, target: str) -> list[str]:
        if name not in rates:
            return [label, f"not measured ({native.why})", "", target]
        return [label, fmt_rate(med[name]), fmt_ratio(ratio(rates, name, bound)), target]

    toggle_rows = [
        ["plain Python (the bound)", fmt_rate(med["plain toggle"]), "1.00", ""],
        row("llfsm, sim clock", "toggle sim", "plain toggle", "≥ 0.5"),
        row("llfsm, wall clock", "toggle wall", "plain toggle", "≥ 0.4"),
        row("llfsm, sim clock, a machine using a live bus", "toggle bus", "plain toggle", "≥ 0.45"),
        row("llfsm --native, sim clock", "native toggle sim", "plain toggle", "≥ 1.0"),
        row("llfsm --native, wall clock", "native toggle wall", "plain toggle", "≥ 1.0"),
        row("llfsm --native, sim clock, a machine using a live bus", "native toggle bus", "plain toggle", "≥ 1.0"),
    ]
    for name in others:
        if name in missing:
            toggle_rows.append([name, "not installed (pip install -e '.[bench]')", "", ""])
        else:
            r = ratio(rates, name, "plain toggle")
            toggle_rows.append(
                [name, fmt_rate(med[name]), fmt_ratio(r, 4), f"llfsm is {med['toggle sim'] / med[name]:,.0f}x"]
            )
    ring_rows = []
    for k in arrangement_sizes():
        for kind, target in (("fired", "≥ 1/3"), ("idle", "≥ 0.6")):
            bound = f"plain {kind} {k}"
            ring_rows.append(
                [
                    f"{'fired transitions' if kind == 'fired' else 'idle ringlets'}",
                    str(k),
                    fmt_rate(med[bound]),
                    row("", f"{kind} {k}", bound, "")[1],
                    row("", f"{kind} {k}", bound, "")[2],
                    row("", f"native {kind} {k}", bound, "")[2] or "not measured",
                    f"{target}; native ≥ 1.0",
                ]
            )
    note = f"median of {rounds} interleaved rounds (min-max); CPU time; n = {n:,} ringlets"
    build_note = (
        f"native build: {'found in the cache' if native.cached else f'{native.build_seconds:.0f} s, one compile'}"
        if native.why is None
        else f"native: {native.why}"
    )
    return [
        (
            f"Fired transitions per second: two-state toggle (guards True, OnEntry count += 1); {note}",
            ["implementation", "transitions/s", "ratio to plain", "target"],
            toggle_rows,
        ),
        (
            f"Ringlets per second, sim clock, against the plain-Python bound of the same size; {note}; {build_note}",
            ["kind", "machines", "plain Python /s", "llfsm /s", "llfsm ratio", "native ratio", "target"],
            ring_rows,
        ),
    ]


# -- start-up ------------------------------------------------------------------------------------


def wall(cmd: list[str], env: dict[str, str]) -> float:
    """Wall seconds of the command, waited for with a blocking waitpid.  (subprocess.run with a
    timeout polls with sleeps that double from 0.5 ms to 50 ms, which rounds a 20 ms command up
    to 31.5 ms: start-up times came out as 16, 32 or 64 ms.)  A timer kills a command that
    hangs, so the benchmark still ends by itself."""
    import threading

    t = time.perf_counter()
    p = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    watchdog = threading.Timer(600, p.kill)
    watchdog.start()
    try:
        p.wait()
    finally:
        watchdog.cancel()
    return time.perf_counter() - t


def wheel_venv(tmp: Path) -> Path:
    """llfsm installed from a wheel into a fresh virtual environment (pip compiles the bytecode
    at install, as for any user); its dependencies come from this environment's site-packages
    through a .pth file, so nothing is downloaded.  Returns the venv's `llfsm` script."""
    repo = HERE.parent
    venv = tmp / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    wheels = tmp / "wheel"
    pip = [sys.executable, "-m", "pip", "--disable-pip-version-check", "--no-cache-dir", "-q"]  # nothing in ~/.cache
    subprocess.run([*pip, "wheel", "--no-deps", "-w", str(wheels), str(repo)], check=True, stderr=subprocess.DEVNULL)
    py = venv / "bin" / "python"
    subprocess.run([*pip, "--python", str(py), "install", "--no-deps", *map(str, wheels.glob("*.whl"))], check=True)
    site = next(venv.glob("lib/python*/site-packages"))
    import sysconfig

    (site / "_llfsm_bench_deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    return venv / "bin" / "llfsm"


def _load_average() -> str:
    """The 1-minute load average (how busy the shared machine was), or "unknown"."""
    try:
        return Path("/proc/loadavg").read_text().split()[0]
    except (OSError, IndexError):
        return "unknown"


def section_startup(tmp: Path) -> list[Table]:
    m = tmp / "hello.machine"
    m.mkdir()
    (m / "machine.yaml").write_text("states:\n  - name: INITIAL\n")
    (m / "State_INITIAL_OnEntry.py").write_text("print('hello')\n")
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # as for a user: bytecode is written and reused
    llfsm = wheel_venv(tmp)
    python = str(llfsm.parent / "python")
    subprocess.run([str(llfsm), "build", str(m), "-o", str(tmp / "out"), "-q"], check=True, env=env)
    hashing = "llfsm run hello.machine (warm cache, no stat record: hashes the files)"
    runs = {
        "python -c pass": [python, "-c", "pass"],
        "llfsm run build/hello.py": [str(llfsm), "run", "--clock", "sim", str(tmp / "out" / "hello.py")],
        "llfsm run hello.machine (warm cache)": [str(llfsm), "run", "--clock", "sim", str(m)],
        hashing: [str(llfsm), "run", "--clock", "sim", str(m)],
    }
    for cmd in runs.values():
        wall(cmd, env)  # the first run writes the caches (bytecode of the compiled module)
    # A warm run stats the machine's files (and llfsm's compiler) instead of hashing them once
    # a stat record says they are as they were; a record is written only for files that have
    # not changed for 2 s (llfsm.fingerprint.RACY_NS): llfsm was installed a moment ago.
    time.sleep(2.1)
    for cmd in runs.values():
        wall(cmd, env)
    records = list(Path(env["LLFSM_CACHE_DIR"]).rglob("hello.py.stat"))
    reps = 7 if QUICK else 15
    times: dict[str, list[float]] = {k: [] for k in runs}
    names = list(runs)
    load_before = _load_average()
    for r in range(reps):
        k = r % len(names)
        for name in names[k:] + names[:k]:
            if name == hashing:  # outside the timed region: this run finds no record (and writes it)
                for record in records:
                    record.unlink(missing_ok=True)
            times[name].append(wall(runs[name], env))
    bare = times["python -c pass"]
    rows = [["python -c pass (the interpreter alone)", f"{statistics.median(bare) * 1000:.0f}", "1.00", ""]]
    for name in names[1:]:
        rs = [a / b for a, b in zip(times[name], bare, strict=True)]
        ms = statistics.median(times[name]) * 1000
        target = "" if name == hashing else "≤ 2.5"
        rows.append([name, f"{ms:.0f}", fmt_ratio((statistics.median(rs), min(rs), max(rs))), target])
    load = f"load average {load_before} before, {_load_average()} after, on {os.cpu_count()} cores"
    shutil.rmtree(Path(env["LLFSM_CACHE_DIR"]), ignore_errors=True)
    t = wall([str(llfsm), "run", "--clock", "sim", str(m)], env)
    rows.append(["llfsm run hello.machine (cold: compiles first)", f"{t * 1000:.0f}", "", ""])
    return [
        (
            f"`llfsm run` start-up to exit, from a wheel installed by pip (bytecode compiled at install); "
            f"wall time, median of {reps} interleaved runs (ratio min-max); {load}",
            ["command", "ms", "ratio to python -c pass", "target"],
            rows,
        )
    ]


# -- check and build -----------------------------------------------------------------------------


def wall_cpu(cmd: list[str], env: dict[str, str]) -> tuple[float, float]:
    """(wall seconds, CPU seconds: user + system of the command and every process it started).
    CPU time hardly depends on what else the machine runs; wall time does."""
    import resource

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    w = wall(cmd, env)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return w, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def _med(runs: list[tuple[float, float]]) -> tuple[str, str]:
    walls, cpus = [w for w, _ in runs], [c for _, c in runs]
    spread = f" ({min(walls):.2f}-{max(walls):.2f})" if len(walls) > 1 else ""
    return f"{statistics.median(walls):.2f}{spread}", f"{statistics.median(cpus):.2f}"


def section_build(tmp: Path, sizes: tuple[int, ...] = (10, 100, 1000)) -> list[Table]:
    rows = []
    env = dict(os.environ)
    targets = {100: ("< 1.5", "< 3", "< 0.3"), 1000: ("< 5", "< 8", "< 1")}
    if QUICK:
        sizes = tuple(x for x in sizes if x <= 100)
    loads = [os.getloadavg()[0]]
    for count in sizes:
        root = tmp / f"m{count}"
        for i in range(count):
            write_big(root, f"machine_{i:04d}", 10)
        check = [wall_cpu([*llfsm_cmd(), "check", "-q", str(root)], env) for _ in range(3)]
        colds = []
        for k in range(3):
            colds.append(wall_cpu([*llfsm_cmd(), "build", "-q", str(root), "-o", str(tmp / f"out{count}-{k}")], env))
        out = tmp / f"out{count}-0"
        warm = [wall_cpu([*llfsm_cmd(), "build", "-q", str(root), "-o", str(out)], env) for _ in range(5)]
        loads.append(os.getloadavg()[0])
        tc, tb, tw = targets.get(count, ("", "", ""))
        rows += [
            [f"check {count} machines", *_med(check), tc],
            [f"cold build {count}", *_med(colds), tb],
            [f"warm build {count} (nothing changed)", *_med(warm), tw],
        ]
    return [
        (
            f"`llfsm check` and `llfsm build` of generated 10-state machines (whole command; median, wall min-max; "
            f"{os.cpu_count()} cores; load average {min(loads):.1f}-{max(loads):.1f} while measuring)",
            ["what", "wall s", "CPU s (user+sys)", "target (wall)"],
            rows,
        )
    ]


# -- the bus and the simulator ----------------------------------------------------------------


def section_bus(tmp: Path) -> list[Table]:
    from llfsm import ros
    from llfsm.msgs.geometry_msgs.msg import Twist
    from llfsm.msgs.std_msgs.msg import String
    from llfsm.ros.bus import bus_of
    from llfsm.runtime import RunContext, SimClock
    from llfsm.runtime.context import activate

    ctx = RunContext(SimClock())
    prev = activate(ctx)
    rows = []
    try:
        ros.init()
        bus = bus_of(ctx)
        node = ros.Node("bench")
        n = 100_000 if QUICK else 500_000
        for name, make in (("std_msgs/String", lambda: String(data="The count is 0")), ("geometry_msgs/Twist", Twist)):
            topic = "/" + name.replace("/", "_")
            pub = node.create_publisher(type(make()), topic, 10)
            reader = node.create_subscription(type(make()), topic, None, 10)
            msg = make()

            def pull(k: int, pub: object = pub, reader: object = reader, msg: object = msg) -> None:
                for _ in range(k):
                    pub.publish(msg)  # type: ignore[attr-defined]
                    reader.take()  # type: ignore[attr-defined]

            rows.append([f"publish -> PULL take(), {name}", fmt_rate(best_rate(pull, n)), "≥ 1,000,000"])
            topic2 = topic + "_push"
            pub2 = node.create_publisher(type(make()), topic2, 10)
            node.create_subscription(type(make()), topic2, lambda m: None, 10)

            def push(k: int, pub2: object = pub2, msg: object = msg) -> None:
                for _ in range(k):
                    pub2.publish(msg)  # type: ignore[attr-defined]
                    bus.spin_some()

            rows.append([f"publish -> callback, {name}", fmt_rate(best_rate(push, n)), "≥ 300,000"])
    finally:
        activate(prev)
    return [
        (
            "Bus messages per second (each publish copies the message for each reader)",
            ["path", "messages/s", "target"],
            rows,
        )
    ]


def turtlesim_rtf(turtles: int, seconds: float) -> float:
    """Real-time factor of `--node turtlesim` with moving turtles and no drawing: simulated
    seconds per wall second, through the bus exactly as in a run (16 ms timer, pose topics)."""
    from llfsm import ros
    from llfsm.msgs.geometry_msgs.msg import Twist
    from llfsm.nodes import NodeOptions
    from llfsm.nodes.turtlesim import Turtlesim
    from llfsm.ros.bus import bus_of
    from llfsm.runtime import RunContext, SimClock
    from llfsm.runtime.context import activate

    ctx = RunContext(SimClock())
    prev = activate(ctx)
    try:
        ros.init()
        bus = bus_of(ctx)
        bus.log_stream = io.StringIO()  # a wall warning would be timed as terminal output
        sim = Turtlesim(ctx, NodeOptions())
        for i in range(1, turtles):  # circles of radius 2 that stay inside the 11 m arena
            sim.world.spawn(2.5 + (i % 7) * 1.0, 3.0 + (i // 7) * 1.0, 0.0, "")
        sim._sync()
        driver = ros.Node("driver")
        pubs = [driver.create_publisher(Twist, f"/{name}/cmd_vel", 1) for name in sim.world.names()]
        cmd = Twist()
        cmd.linear.x, cmd.angular.z = 1.0, 0.5
        step = 16_000_000
        t = time.perf_counter()
        for k in range(int(seconds * 1e9) // step):
            if k % 30 == 0:  # a command twice a second keeps every turtle moving
                for p in pubs:
                    p.publish(cmd)
            ctx.clock.now += step
            bus.spin_some()
        return seconds / (time.perf_counter() - t)
    finally:
        activate(prev)


def section_turtlesim(tmp: Path) -> list[Table]:
    seconds = 60.0 if QUICK else 300.0
    rows = [
        [f"{n} turtle{'s' if n > 1 else ''}", f"{turtlesim_rtf(n, seconds):,.0f}x", "≥ 500x" if n == 1 else ""]
        for n in (1, 10)
    ]
    return [
        (
            "turtlesim real-time factor, no drawing (simulated seconds per wall second)",
            ["world", "real-time factor", "target"],
            rows,
        )
    ]


def section_soak(tmp: Path) -> list[Table]:
    from soak import table

    scale = 10 if QUICK else 1
    rows = table(10_000_000 // scale, 1_000_000 // scale)
    return [
        (
            "Soak: memory growth after a warm-up, measured with tracemalloc",
            ["workload", "seconds (traced)", "memory growth", "peak above start", "target"],
            rows,
        )
    ]


SECTIONS: dict[str, Callable[[Path], list[Table]]] = {
    "speed": section_speed,
    "startup": section_startup,
    "build": section_build,
    "bus": section_bus,
    "turtlesim": section_turtlesim,
    "soak": section_soak,
}


def render(tables: list[Table]) -> str:
    out = []
    for title, header, rows in tables:
        out.append(f"### {title}\n")
        out.append("| " + " | ".join(header) + " |")
        out.append("|" + "|".join("---" for _ in header) + "|")
        out += ["| " + " | ".join(r) + " |" for r in rows]
        out.append("")
    return "\n".join(out)


def machine_description() -> str:
    model = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    bytecode = (
        "not written (PYTHONDONTWRITEBYTECODE)" if sys.dont_write_bytecode else "cached (.pyc files written and reused)"
    )
    return (
        f"- machine: {os.cpu_count()} CPUs (nproc), {model}, {platform.system()} {platform.release()}\n"
        f"- Python: {platform.python_implementation()} {platform.python_version()} ({sys.executable})\n"
        f"- bytecode: {bytecode}; start-up is measured from a wheel that pip installed (bytecode compiled at install)\n"
        f"- run on {time.strftime('%Y-%m-%d %H:%M %Z')}{' (quick)' if QUICK else ''}; the machine is shared with other "
        "jobs, so compare ratios, not rates\n"
    )


def main() -> None:
    global QUICK
    if sys.argv[1:2] == ["--worker"]:
        QUICK = "--quick" in sys.argv[2:]  # the same arrangement sizes as the process that started it
        worker()
        return
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("sections", nargs="*", choices=[*SECTIONS, []], help="default: all")
    ap.add_argument("--quick", action="store_true", help="smaller sizes, for a smoke run")
    ap.add_argument("--no-write", action="store_true", help="do not write bench/results.md")
    args = ap.parse_args()
    QUICK = args.quick
    chosen = args.sections or list(SECTIONS)
    header = machine_description()
    print(header)
    tables: list[Table] = []
    with tempfile.TemporaryDirectory(prefix="llfsm-bench-cache-") as cache:
        # every cache of the benchmark (compiled modules, native builds, mypy) is temporary
        os.environ["LLFSM_CACHE_DIR"] = cache
        for name in chosen:
            with tempfile.TemporaryDirectory(prefix=f"llfsm-bench-{name}-") as tmp:
                new = SECTIONS[name](Path(tmp))
            print(render(new), flush=True)
            tables += new
    if not args.no_write and not QUICK and set(chosen) == set(SECTIONS):
        (HERE / "results.md").write_text("# Benchmark results\n\n" + header + "\n" + render(tables))


if __name__ == "__main__":
    main()
