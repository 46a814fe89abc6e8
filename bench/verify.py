"""`llfsm verify` benchmarks (issue 20): every number printed in a table, never asserted.

    python bench/verify.py            all tables (a few minutes)
    python bench/verify.py --quick    smaller sizes (a smoke run)

- exploration speed (configurations per CPU second) and memory (bytes per stored configuration,
  measured with tracemalloc in a run of its own) on a counter arrangement of 10^6 configurations
  and on N mutex machines, N = 2..6, exact and with hash compaction (the chance of a collision
  printed), and with `--native` (the ringlets compiled by mypyc, the explorer plain Python) where
  a native build can be made;
- side by side with SPIN on the Promela export of the same structure: SPIN's own time to
  compile and search, the same verdict, and the ratio;
- verify with an environment (a service of three responses) against the same machine with an
  input of three values instead: configurations per CPU second, interleaved;
- the cost of inputs at run time: the toggle of bench/run.py without an input, with one bound
  input and no message, and with one bound input and a message every round, interleaved,
  medians of CPU time.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from gen import write_toggle  # noqa: E402

Table = tuple[str, list[str], list[list[str]]]


def write_counter(root: Path, modulo: int) -> Path:
    """One state re-entered at every ringlet, counting modulo `modulo`: `modulo` configurations."""
    d = root / "counter.machine"
    d.mkdir(parents=True, exist_ok=True)
    (d / "machine.yaml").write_text("states:\n  - name: COUNT\n    transitions: [COUNT]\n")
    (d / "State_COUNT_OnEntry.py").write_text(f"count = (count + 1) % {modulo}\n")
    (d / "State_COUNT_Transition_0.expr").write_text("True\n")
    (d / "Variables.py").write_text("count: int = 0\n")
    return d


def write_mutex(root: Path, n: int) -> list[Path]:
    """n machines m0..m{n-1}: IDLE -> TRY when its input `want` says so, TRY -> CRIT when no other
    machine is in CRIT, back to IDLE after 10 ms (abstract time: at most or more than 10 ms): a
    state space that grows about sixfold per machine (97 configurations for 2, 172,063 for 6)."""
    out = []
    names = [f"m{i}" for i in range(n)]
    for name in names:
        d = root / f"{name}.machine"
        d.mkdir(parents=True, exist_ok=True)
        (d / "machine.yaml").write_text(
            "inputs:\n  want:\n    type: bool\n"
            "states:\n  - name: IDLE\n    transitions: [TRY]\n  - name: TRY\n    transitions: [CRIT]\n"
            "  - name: CRIT\n    transitions: [IDLE]\n"
        )
        others = tuple(x for x in names if x != name)
        (d / "Variables.py").write_text(f"others: tuple = {others!r}\n")
        (d / "State_IDLE_Transition_0.expr").write_text("want\n")
        (d / "State_TRY_Transition_0.expr").write_text('all(state_name_of(o) != "CRIT" for o in others)\n')
        (d / "State_CRIT_Transition_0.expr").write_text("after_ms(10)\n")
        out.append(d)
    return out


def mutex_property(n: int) -> str:
    pairs = [f'(state(m{i}) == "CRIT" and state(m{j}) == "CRIT")' for i in range(n) for j in range(i + 1, n)]
    return "never: " + " or ".join(pairs)


def explore(paths: list[Path], prop: str, hash_compact: bool, graph: bool = False) -> tuple[object, float]:
    """(the verification, CPU seconds of the exploration)."""
    from llfsm.verify.explorer import Options
    from llfsm.verify.judge import verify
    from llfsm.verify.load import PropertySource, load_arrangement

    kind, _, text = prop.partition(":")
    loaded = load_arrangement([str(p) for p in paths])
    t = time.process_time()
    v = verify(loaded, [PropertySource(kind, text.strip())], Options(hash_compact=hash_compact), keep_graph=graph)
    return v, time.process_time() - t


def memory_per_config(paths: list[Path], prop: str, hash_compact: bool) -> float:
    """Bytes held per stored configuration once the exploration is done (tracemalloc)."""
    explore(paths, prop, hash_compact)  # imports and caches warm
    tracemalloc.start()
    before = tracemalloc.get_traced_memory()[0]
    v, _t = explore(paths, prop, hash_compact)
    after = tracemalloc.get_traced_memory()[0]
    tracemalloc.stop()
    return (after - before) / v.configurations  # type: ignore[attr-defined]


def rate_rows(
    label: str, paths: list[Path], prop: str, rounds: int, native: dict[str, float] | None = None
) -> list[list[str]]:
    rows = []
    for hc in (False, True):
        rates, v = [], None
        for _ in range(rounds):
            v, t = explore(paths, prop, hc)
            rates.append(v.configurations / t)  # type: ignore[attr-defined]
        assert v is not None
        n = v.configurations  # type: ignore[attr-defined]
        mem = memory_per_config(paths, prop, hc)
        storage = f"hash compaction (collision chance {n * n / 2**65:.0e})" if hc else "exact"
        verdict = v.outcomes[0].verdict  # type: ignore[attr-defined]
        rows.append(
            [label, storage, f"{n:,}", f"{statistics.median(rates):,.0f}", f"{min(rates):,.0f}-{max(rates):,.0f}",
             f"{mem:,.0f}", verdict]
        )  # fmt: skip
    if native is not None:
        configs, rate = f"{int(native['configs']):,}", f"{native['rate']:,.0f}"
        rows.append([label, "exact, --native ringlets", configs, rate, "", "", str(native["verdict"])])
    return rows


# -- native: the explorer in a process whose runtime and machines are compiled ---------------------


def native_rates(paths: list[Path], prop: str, rounds: int) -> dict[str, float] | str:
    """Configurations/s of exact exploration in a worker with LLFSM_NATIVE, or why not."""
    try:
        from llfsm.cachedir import cache_root
        from llfsm.compiler.native import ENV, available, native_build
        from llfsm.targets import compiled_module_for
    except ImportError:
        return "this llfsm has no native builds"
    why = available()
    if why is not None:
        return why
    modules = [compiled_module_for(p.resolve()) for p in paths]
    nb = native_build(modules, cache_root())
    env = dict(os.environ, **{ENV: str(nb.folder)})
    code = (
        "import sys, time, statistics\n"
        f"sys.path.insert(0, {str(HERE)!r})\n"
        "from verify import explore\n"
        "from pathlib import Path\n"
        f"paths = [Path(p) for p in {[str(p) for p in paths]!r}]\n"
        "import llfsm.runtime.scheduler as s\n"
        "print('compiled' if s.__file__.endswith('.so') else 'plain', flush=True)\n"
        "rates = []\n"
        f"for _ in range({rounds}):\n"
        f"    v, t = explore(paths, {prop!r}, False)\n"
        "    rates.append(v.configurations / t)\n"
        "print(v.configurations, statistics.median(rates), v.outcomes[0].verdict)\n"
    )
    run = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=3600)
    if run.returncode != 0:
        last = run.stderr.strip().splitlines()[-1] if run.stderr.strip() else f"status {run.returncode}"
        return f"the explorer did not run natively: {last}"
    lines = run.stdout.split("\n")
    if lines[0] != "compiled":
        return "the native build did not compile the runtime"
    configs, rate, verdict = lines[1].split()
    return {"configs": float(configs), "rate": float(rate), "verdict": verdict}  # type: ignore[dict-item]


# -- SPIN ------------------------------------------------------------------------------------------------


def spin_side_by_side(label: str, paths: list[Path], prop: str, folder: Path) -> list[str]:
    """llfsm's exploration time and SPIN's (compile of pan.c + search) on the same structure."""
    from llfsm.verify.export import promela

    spin, gcc = shutil.which("spin"), shutil.which("gcc") or shutil.which("cc")
    v, t_llfsm = explore(paths, prop, False, graph=True)
    n = v.configurations  # type: ignore[attr-defined]
    if spin is None or gcc is None:
        return [label, f"{n:,}", f"{t_llfsm:.3f}", "no spin (apt-get install spin)", "", "", "", ""]
    (folder / "m.pml").write_text(promela(v))  # type: ignore[arg-type]
    t0 = time.perf_counter()
    cc = [gcc, "-O2", "-w", "-DNOREDUCE", "-DVECTORSZ=4096", "-o", "pan", "pan.c"]
    for cmd in ([spin, "-a", "m.pml"], cc):
        done = subprocess.run(cmd, cwd=folder, capture_output=True, text=True, timeout=3600)
        if done.returncode != 0:
            why = (done.stdout + done.stderr).strip().splitlines()
            return [label, f"{n:,}", f"{t_llfsm:.3f}", f"{Path(cmd[0]).name} failed: {why[-1] if why else ''}"]
    t_compile = time.perf_counter() - t0
    t1 = time.perf_counter()
    pan = ["./pan", "-a", "-m10000000", "-N", "p0"]
    run = subprocess.run(pan, cwd=folder, capture_output=True, text=True, timeout=3600)
    t_search = time.perf_counter() - t1
    spin_states = next((line.split()[0] for line in run.stdout.splitlines() if "states, stored" in line), "?")
    # pan's own time for the search (its wall time from start to end, as it prints it), rather than
    # the process's, which also counts allocating its hash table
    own = [line for line in run.stdout.splitlines() if "pan: elapsed time" in line]
    if own:
        t_search = max(float(own[0].split()[3]), 0.001)
    errors = int(run.stdout.split("errors: ")[1].split()[0]) if "errors: " in run.stdout else -1
    spin_verdict = "fails" if errors > 0 else "holds"
    ours = v.outcomes[0].verdict  # type: ignore[attr-defined]
    same = "same" if spin_verdict == ours else f"DIFFERENT ({spin_verdict})"
    times = [f"{t_llfsm:.3f}", f"{t_compile:.2f}", f"{t_search:.3f}"]
    return [label, f"{n:,}", *times, spin_states, f"{t_llfsm / t_search:.1f}x", f"{ours}, {same}"]


# -- inputs at run time -----------------------------------------------------------------------------------


def write_input_toggle(root: Path) -> Path:
    d = write_toggle(root, "itoggle")
    text = (d / "machine.yaml").read_text()
    (d / "machine.yaml").write_text(
        text + "inputs:\n  go:\n    type: bool\n    topic: /go\n    msg: std_msgs/msg/Bool\n    field: data\n"
    )
    return d


def toggle_timed(path: Path, messages: bool, reader: bool = False) -> object:
    """n ringlets of the toggle (sim clock, 1 us rounds) on a live bus; with an input bound to
    /go when the machine has one, with `messages` a node publishing /go every round, and with
    `reader` a PULL subscription of that node's own on /go (what a bound input's reader costs the
    bus, without the input: the delivery the input row pays too)."""
    from llfsm import ros
    from llfsm.msgs.std_msgs.msg import Bool
    from llfsm.ros.inputs import bind
    from llfsm.runtime import Arrangement, RunContext, SimClock
    from llfsm.runtime.context import activate
    from llfsm.targets import load

    cls = load(str(path))

    def timed(n: int) -> tuple[int, float]:
        ctx = RunContext(SimClock(1_000))
        prev = activate(ctx)
        try:
            ros.init()
            node = ros.Node("bench")
            pub = node.create_publisher(Bool, "/go", 10)
            if messages:
                msg = Bool(data=True)
                node.create_timer(1e-6, lambda: pub.publish(msg))
            if reader:
                node.create_subscription(Bool, "/go", None, 1)
            arr = Arrangement([cls], context=ctx)
            if cls.INPUTS:
                bind(arr, ros.bus_of(ctx))
        finally:
            activate(prev)
        t = time.process_time()
        arr.run(duration_ns=n * 1_000)
        return arr.rounds, time.process_time() - t

    return timed


NO_INPUT = "no input"
QUIET = "one bound input, no message"
BUSY = "one bound input, a message every round"
BUS = "no input, a message every round (the bus alone)"
READ = "no input, a message every round to a subscription of its own"


def inputs_table(tmp: Path, n: int, rounds: int) -> Table:
    plain = write_toggle(tmp, "toggle")
    with_input = write_input_toggle(tmp)
    named = {
        NO_INPUT: toggle_timed(plain, False),
        QUIET: toggle_timed(with_input, False),
        BUSY: toggle_timed(with_input, True),
        BUS: toggle_timed(plain, True),
        READ: toggle_timed(plain, True, reader=True),
    }
    rates: dict[str, list[float]] = {k: [] for k in named}
    names = list(named)
    for r in range(rounds):
        k = r % len(names)
        for name in names[k:] + names[:k]:
            work, t = named[name](n)  # type: ignore[operator]
            rates[name].append(work / t)

    def ratio(a: str, b: str) -> str:
        rs = [x / y for x, y in zip(rates[a], rates[b], strict=True)]
        return f"{statistics.median(rs):.2f} ({min(rs):.2f}-{max(rs):.2f})"

    def rate(name: str) -> str:
        return f"{statistics.median(rates[name]):,.0f}"

    rows = [
        [NO_INPUT, rate(NO_INPUT), "1.00", ""],
        [QUIET, rate(QUIET), ratio(QUIET, NO_INPUT), "≥ 0.9"],
        [BUS, rate(BUS), ratio(BUS, NO_INPUT), ""],
        [READ, rate(READ), ratio(READ, BUS) + " of the bus alone", "(a delivery each round)"],
        [BUSY, rate(BUSY), ratio(BUSY, READ) + " of the row above", "(a delivery and a snapshot each round)"],
    ]
    return (
        f"The cost of inputs at run time: the toggle of bench/run.py (guards True, OnEntry count += 1), sim clock, "
        f"a live bus; ringlets per CPU second, median of {rounds} interleaved rounds (ratio min-max); n = {n:,}",
        ["toggle", "ringlets/s", "ratio", "target"],
        rows,
    )


# -- the environment against inputs -----------------------------------------------------------------

ASK_STATES = "states:\n  - name: INIT\n    transitions: [ASK]\n  - name: ASK\n    transitions: [ASK]\n"


def write_asker(root: Path, modulo: int, environment: bool, handles: bool = False) -> Path:
    """One machine asking for a value at every ringlet and counting modulo `modulo`: from a
    service of the environment (three responses: call_async, spin_until_future_complete,
    result()), or from an input of three values (with `handles`, holding the same node and
    client, never called): 3 x `modulo` configurations either way."""
    name = "asker" if environment else "holder" if handles else "reader"
    d = root / f"{name}.machine"
    d.mkdir(parents=True, exist_ok=True)
    if environment or handles:
        (d / "Includes.py").write_text(
            "from llfsm import ros\nfrom llfsm.msgs.turtle_sensor_interface.srv import TurtlePosition\n"
        )
        (d / "State_INIT_OnEntry.py").write_text(
            f'ros.init()\nnode = ros.Node("{name}")\nclient = node.create_client(TurtlePosition, "/where")\n'
        )
        (d / "Variables.py").write_text(
            "node: object = None\nclient: object = None\nvalue: float = 0.0\ncount: int = 0\n"
        )
    else:
        (d / "Variables.py").write_text("value: float = 0.0\ncount: int = 0\n")
    if environment:
        (d / "machine.yaml").write_text(ASK_STATES)
        (d / "State_ASK_OnEntry.py").write_text(
            "future = client.call_async(TurtlePosition.Request())\n"
            "ros.spin_until_future_complete(node, future)\n"
            f"value = future.result().x\ncount = (count + 1) % {modulo}\n"
        )
    else:
        (d / "machine.yaml").write_text(
            "inputs:\n  x:\n    type: float\n    default: 1.0\n    domain: [1.0, 2.0, 3.0]\n" + ASK_STATES
        )
        (d / "State_ASK_OnEntry.py").write_text(f"value = x\ncount = (count + 1) % {modulo}\n")
    for s in ("INIT", "ASK"):
        (d / f"State_{s}_Transition_0.expr").write_text("True\n")
    return d


def environment_table(tmp: Path, modulo: int, rounds: int) -> Table:
    """Configurations/s with an environment of three responses against the same machine with an
    input of three values instead, interleaved."""
    from llfsm.props.file import Environment, ServiceDecl
    from llfsm.verify.explorer import Options
    from llfsm.verify.judge import verify
    from llfsm.verify.load import PropertySource, load_arrangement

    env = Environment(
        services={
            "/where": ServiceDecl(
                "turtle_sensor_interface/srv/TurtlePosition", [{"x": 1.0}, {"x": 2.0}, {"x": 3.0}], False
            )
        }
    )
    asker, reader = write_asker(tmp, modulo, True), write_asker(tmp, modulo, False)
    holder = write_asker(tmp, modulo, False, handles=True)
    base = "an input of 3 values instead"
    cases = {
        "an environment of 3 responses": (asker, env, "asker"),
        base: (reader, None, "reader"),
        "an input of 3 values, holding the asker's node and client (never called)": (holder, env, "holder"),
    }
    rates: dict[str, list[float]] = {k: [] for k in cases}
    sizes: dict[str, int] = {}
    names = list(cases)
    for r in range(rounds):
        k = r % len(names)
        for name in names[k:] + names[:k]:
            path, environment, machine = cases[name]
            loaded = load_arrangement([str(path)], environment)
            t = time.process_time()
            v = verify(loaded, [PropertySource("always", f"{machine}.count < {modulo}")], Options())
            rates[name].append(v.configurations / (time.process_time() - t))  # type: ignore[attr-defined]
            sizes[name] = v.configurations  # type: ignore[attr-defined]
    rows = []
    for name in names:
        ratio = [a / b for a, b in zip(rates[name], rates[base], strict=True)]
        rows.append(
            [name, f"{sizes[name]:,}", f"{statistics.median(rates[name]):,.0f}",
             f"{statistics.median(ratio):.2f} ({min(ratio):.2f}-{max(ratio):.2f})",
             "≥ 0.80" if name == names[0] else ""]
        )  # fmt: skip
    return (
        f"verify with an environment against inputs: one machine asking for a value every ringlet (a service "
        f"call answered with each of 3 responses, or an input of 3 values), counting modulo {modulo:,}; "
        f"configurations per CPU second, median of {rounds} interleaved runs, ratio to inputs (min-max)",
        ["the values come from", "configurations", "configurations/s", "ratio to inputs", "target (issue 32)"],
        rows,
    )


def render(tables: list[Table]) -> str:
    out = []
    for title, header, rows in tables:
        out.append(f"### {title}\n")
        out.append("| " + " | ".join(header) + " |")
        out.append("|" + "|".join("---" for _ in header) + "|")
        out += ["| " + " | ".join(r) + " |" for r in rows]
        out.append("")
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="smaller sizes, for a smoke run")
    ap.add_argument("--no-native", action="store_true", help="skip the --native rows (a native build takes minutes)")
    ap.add_argument(
        "--only",
        choices=("explore", "spin", "inputs", "environment"),
        action="append",
        help="only these tables (repeatable)",
    )
    args = ap.parse_args()
    only = set(args.only or ("explore", "spin", "inputs", "environment"))
    quick = args.quick
    rounds = 3 if quick else 5
    with tempfile.TemporaryDirectory(prefix="llfsm-bench-verify-") as tmp_s:
        tmp = Path(tmp_s)
        os.environ["LLFSM_CACHE_DIR"] = str(tmp / "cache")
        tables: list[Table] = []
        if "explore" in only:
            explore_table(tmp, quick, rounds, args.no_native, tables)
        if "spin" in only:
            spin_table(tmp, quick, tables)
        if "inputs" in only:
            tables.append(inputs_table(tmp, 200_000 if quick else 1_000_000, rounds + 2))
            print(render(tables[-1:]), flush=True)
        if "environment" in only:
            tables.append(environment_table(tmp, 2_000 if quick else 20_000, rounds + 2))
            print(render(tables[-1:]), flush=True)


def explore_table(tmp: Path, quick: bool, rounds: int, no_native: bool, tables: list[Table]) -> None:
    """Speed and memory on the counter and the mutex machines, exact and hash-compacted."""
    size = 100_000 if quick else 1_000_000
    counter = write_counter(tmp / "counter", size)
    prop = f"always: counter.count < {size}"
    native = None if no_native else native_rates([counter], prop, rounds)
    rows = rate_rows(f"counter, {size:,}", [counter], prop, rounds, native if isinstance(native, dict) else None)
    if isinstance(native, str):
        rows.append([f"counter, {size:,}", "exact, --native ringlets", "", f"not measured: {native}", "", "", ""])
    for n in range(2, 5 if quick else 7):
        paths = write_mutex(tmp / f"mutex{n}", n)
        rows += rate_rows(f"{n} mutex machines", paths, mutex_property(n), rounds)
    tables.append(
        (
            f"Exploration: configurations per CPU second (median of {rounds} runs, min-max) and bytes per stored "
            "configuration (tracemalloc, after the exploration, everything it keeps); a safety property judged "
            "on the fly. Goals: ≥ 200,000/s pure and ≥ 1,000,000/s native on the counter; ≤ 100 bytes",
            ["arrangement", "storage", "configurations", "configurations/s", "min-max", "bytes/configuration",
             "verdict"],
            rows,
        )
    )  # fmt: skip
    print(render(tables[-1:]), flush=True)


def spin_table(tmp: Path, quick: bool, tables: list[Table]) -> None:
    """The same structures searched by SPIN from the Promela export."""
    spin_rows = []
    folder = tmp / "spin"
    folder.mkdir()
    for size_c in (1_000, 10_000) if quick else (1_000, 10_000, 100_000, 1_000_000):
        c = write_counter(tmp / f"spin-counter{size_c}", size_c)
        prop_c = f"always: counter.count < {size_c}"
        spin_rows.append(spin_side_by_side(f"counter, {size_c:,}", [c], prop_c, folder))
    for n in range(2, 4 if quick else 7):
        paths = write_mutex(tmp / f"spin-mutex{n}", n)
        spin_rows.append(spin_side_by_side(f"{n} mutex machines", paths, mutex_property(n), folder))
    tables.append(
        (
            "Side by side with SPIN on the Promela export of the same structure (llfsm: CPU seconds of the "
            "exploration, the graph kept; SPIN: wall seconds of spin -a + gcc -O2, then pan's own elapsed time "
            "searching the exported structure, at least 0.001 s, pan -a for the claim). Goal: llfsm within "
            "10x of SPIN's search",
            ["arrangement", "configurations", "llfsm s", "SPIN compile s", "SPIN search s", "SPIN states",
             "llfsm / SPIN search", "verdict"],
            spin_rows,
        )
    )  # fmt: skip
    print(render(tables[-1:]), flush=True)


if __name__ == "__main__":
    main()
