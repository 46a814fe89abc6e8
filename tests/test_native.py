"""Native builds (`--native`, docs/native.md): the same machines compiled with mypyc behave
exactly as the plain-Python ones, and a machine mypyc refuses runs as plain Python with one
warning.

Native compiles are slow (tens of seconds), so one session fixture builds every machine these
tests use in ONE `llfsm build --native`; each test then runs `llfsm run --native` on them, which
finds that build in the cache.  That build holds one shipped machine that uses the bus
(ros2_ping_pong: a node, a publisher, the lifetimes walk over compiled variables); every
shipped machine under --native, and the whole semantics suite, are the slow tests at the end.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest
from helpers import MACHINES, REPO, Run, write_machine

from llfsm.compiler.native import available

WHY = available()
pytestmark = pytest.mark.skipif(WHY is not None, reason=f"no native builds here: {WHY}")


@dataclass
class Corpus:
    out: Path  # the built modules
    cache: Path
    build: Run  # the `llfsm build --native` that compiled them all


def _corpus_machines(root: Path) -> None:
    """Machines that exercise SPEC section 2 rule by rule, plus one that mypyc refuses."""
    write_machine(
        root,
        "order",
        {"A": [("B", 'print("guard A0") or False'), ("B", 'print("guard A1") or True')], "B": None},
        {"A_OnEntry": 'print("A entry")', "A_OnExit": 'print("A exit")', "A_Internal": 'print("A internal")'}
        | {"B_OnEntry": 'print("B entry")'},
    )
    write_machine(
        root,
        "internal",
        {"A": [("END", "n >= 3")], "END": None},
        {"A_OnEntry": 'print("entry")', "A_Internal": 'n += 1\nprint("internal", n)', "A_OnExit": 'print("exit")'},
        variables="n: int = 0\n",
    )
    for name in ("first", "second"):
        write_machine(
            root, name, {"S": [("S", "True")]}, {"S_OnEntry": f'print("{name}", n)\nn += 1'}, variables="n: int = 0\n"
        )
    write_machine(
        root,
        "selfloop",
        {"A": [("END", "k == 3"), ("A", "after_ms(5)")], "END": None},
        {"A_OnEntry": "k += 1\nprint('entry', k, 'at', current().clock.now // 1_000_000)", "A_OnExit": "print('exit')"},
        variables="k: int = 0\n",
        includes="from llfsm.runtime import current\n",
    )
    write_machine(
        root,
        "worker",
        {"RUN": [("END", "n >= 8")], "END": None, "SUSPENDED": None},
        {
            "RUN_OnEntry": "print('worker entry', n)",
            "RUN_Internal": "n += 1\nprint('worker tick', n)",
            "RUN_OnSuspend": "print('worker suspended')",
            "RUN_OnResume": "print('worker resumed')",
            "SUSPENDED_OnEntry": "print('worker in SUSPENDED')",
            "END_OnEntry": "print('worker done', n)",
        },
        variables="n: int = 0\n",
        yaml_extra="suspended: SUSPENDED",
    )
    write_machine(
        root,
        "boss",
        {"S0": [("S1", "after_ms(2)")], "S1": [("S2", "after_ms(2)")], "S2": [("S3", "after_ms(1)")]}
        | {"S3": [("S4", "True")], "S4": [("END", "not is_running('worker')")], "END": None},
        {
            "S1_OnEntry": "suspend('worker')\nprint('boss: worker suspended?', is_suspended('worker'))",
            "S2_OnEntry": "resume('worker')",
            "S3_OnEntry": "restart('worker')",
            "S4_OnEntry": "print('boss sees worker in', state_name_of('worker'))",
            "END_OnEntry": "print('boss done')",
        },
    )
    write_machine(
        root,
        "lonely",
        {"A": [("END", "False")], "END": None},
        {"A_OnEntry": "print('going to sleep')\nsuspend_self()"},
    )
    write_machine(
        root,
        "napper",
        {"A": [("SUSPENDED", "after_ms(3)")], "SUSPENDED": None, "END": None},
        {"A_OnEntry": "print('napping at', state_name())", "SUSPENDED_OnEntry": "print('asleep')"},
        yaml_extra="suspended: SUSPENDED",
    )
    write_machine(
        root,
        "faulty",
        {"A": [("A", "after_ms(2)")]},
        {"A_OnEntry": "print('about to fail', n)\nn += 1\nif n == 3:\n    print(1 // (n - 3))"},
        variables="n: int = 0\n",
    )
    # mypyc refuses this one: x is declared an int and gets a string (line 2 of its OnEntry)
    write_machine(
        root,
        "untyped",
        {"A": [("END", "True")], "END": None},
        {"A_OnEntry": "print('untyped runs', x)\nx = 'text'\nprint('now', x)"},
        variables="x: int = 0\n",
    )
    # a node held in a variable, dropped when the machine finishes (llfsm.ros.lifetimes reads the
    # variables of a native class, which has no __slots__)
    write_machine(
        root,
        "talker",
        {"A": [("END", "after_ms(3)")], "END": None},
        {"A_OnEntry": 'ros.init()\nnode = ros.Node("talker")\ncount = 1', "END_OnEntry": "print('talked', count)"},
        variables="node: ros.Node | None = None\ncount: int = 0\n",
        includes="from llfsm import ros\n",
    )
    # tells whether its module is the compiled one
    write_machine(
        root,
        "probe",
        {"A": [("END", "True")], "END": None},
        {"A_OnEntry": "print('compiled:', __file__.endswith('.so'))"},
    )
    # the lifetimes walk over a compiled machine's variables: the node it drops leaves the graph
    write_machine(
        root,
        "dropper",
        {"A": [("B", "after_ms(2)")], "B": [("B", "False")]},
        {
            "A_OnEntry": "ros.init()\nkept = ros.Node('kept')\ngone = ros.Node('gone')",
            # making something has the bus look at what the variables hold
            "B_OnEntry": "gone = None\nkept.create_timer(1.0, lambda: None)\nprint('let go')",
        },
        variables="kept: ros.Node = None\ngone: ros.Node = None\n",
        includes="from llfsm import ros\n",
    )
    # a machine that uses the bus (issue 27, item 0: every one of them crashed under --native)
    shutil.copytree(MACHINES / "ros2_ping_pong.machine", root / "ros2_ping_pong.machine")


@pytest.fixture(scope="session")
def corpus(tmp_path_factory: pytest.TempPathFactory) -> Corpus:
    root = tmp_path_factory.mktemp("native")
    _corpus_machines(root / "src")
    cache = root / "cache"
    out = root / "out"
    env = dict(os.environ, LLFSM_CACHE_DIR=str(cache))
    env.pop("LLFSM_NATIVE", None)
    proc = subprocess.run(
        [sys.executable, "-m", "llfsm", "build", "--native", str(root / "src"), "-o", str(out)],
        capture_output=True,
        text=True,
        env=env,
        timeout=900,
    )
    return Corpus(out, cache, Run(proc.returncode, proc.stdout, proc.stderr))


def run(corpus: Corpus, *args: str | Path, native: bool, cwd: Path | None = None) -> Run:
    env = dict(os.environ, LLFSM_CACHE_DIR=str(corpus.cache))
    env.pop("LLFSM_NATIVE", None)
    cmd = [sys.executable, "-m", "llfsm", "run", *(["--native"] if native else []), "--clock", "sim"]
    proc = subprocess.run(
        [*cmd, *map(str, args)], capture_output=True, text=True, env=env, timeout=120, cwd=cwd or corpus.out
    )
    return Run(proc.returncode, proc.stdout, proc.stderr)


def test_one_native_build_compiles_every_machine_but_the_one_mypyc_refuses(corpus: Corpus) -> None:
    assert corpus.build.status == 0, corpus.build.stderr
    warnings = [line for line in corpus.build.stderr.splitlines() if "warning:" in line]
    assert len(warnings) == 1, corpus.build.stderr
    # named by the user's own file and line, not the generated module
    assert warnings[0].endswith("runs as plain Python")
    assert "untyped.machine/State_A_OnEntry.py:2: warning: mypyc cannot compile this machine" in warnings[0]
    machines = len(list(corpus.out.glob("*.py")))
    assert f"native: {machines - 1} of {machines} machines compiled" in corpus.build.stderr
    assert len(list((corpus.cache / "native").glob("*/manifest.json"))) == 1  # one build, one compile


def test_a_native_run_uses_the_compiled_modules_and_finds_the_build_in_the_cache(corpus: Corpus) -> None:
    builds = sorted((corpus.cache / "native").glob("*/manifest.json"))
    native = run(corpus, "probe.py", native=True)
    assert native.stdout == "compiled: True\n", native.stderr
    assert run(corpus, "probe.py", native=False).stdout == "compiled: False\n"
    assert sorted((corpus.cache / "native").glob("*/manifest.json")) == builds  # nothing compiled again


ARRANGEMENTS = {
    "guards then OnExit, entry on the next ringlet": (["order.py"], []),
    "Internal only when nothing fires": (["internal.py"], []),
    "round robin in load order": (["first.py", "second.py", "--duration", "3ms"], []),
    "self-transition restarts the timer": (["selfloop.py"], []),
    "suspend, resume, restart from another machine": (["worker.py", "boss.py", "--duration", "40ms"], []),
    "suspend_self ends the run when all are suspended": (["lonely.py"], []),
    "a transition into the suspend state": (["napper.py", "--duration", "10ms"], []),
    "--suspended and --keep-accepting": (
        ["worker.py", "order.py", "--suspended", "worker", "--keep-accepting", "--duration", "5ms"],
        [],
    ),
    "an exception in machine code": (["faulty.py", "--duration", "50ms"], []),
    "a machine mypyc refused beside compiled ones": (["untyped.py", "internal.py"], []),
    "a node dropped by a compiled machine leaves the graph": (["dropper.py", "--duration", "10ms", "--introspect"], []),
    "a machine that uses the bus": (["ros2_ping_pong.py", "--duration", "3.5s", "--echo", "/pingpong"], []),
}


@pytest.mark.parametrize("case", list(ARRANGEMENTS))
def test_pure_and_native_runs_give_the_same_output_verbose_trace_and_trace_file(corpus: Corpus, case: str) -> None:
    args, _ = ARRANGEMENTS[case]
    runs = {}
    for native in (False, True):
        trace = corpus.out.parent / f"trace-{case.replace(' ', '_')}-{native}.jsonl"
        r = run(corpus, *args, "-v", "--trace", trace, native=native)
        runs[native] = (r, trace.read_text().splitlines())
    (pure, pure_trace), (native, native_trace) = runs[False], runs[True]
    assert pure.stdout and pure_trace
    assert native.stdout == pure.stdout
    warning = "warning: mypyc cannot compile"
    assert [ln for ln in native.stderr.splitlines() if warning not in ln] == pure.stderr.splitlines()
    assert native.status == pure.status
    assert [json.loads(x) for x in native_trace] == [json.loads(x) for x in pure_trace]


def test_a_monitor_and_the_bus_under_native_say_what_they_say_in_pure_python(corpus: Corpus) -> None:
    # a native class's ringlets cannot be rewritten: the monitor judges every boundary, with the
    # same verdicts; its variables are found all the same
    args = ["worker.py", "boss.py", "talker.py", "--duration", "40ms"]
    args += ["--monitor-property", "never: worker.n >= 5", "--monitor-property", "reachable: suspended(worker)"]
    args += ["--monitor-property", "always: talker.count < 1"]
    pure, native = run(corpus, *args, native=False), run(corpus, *args, native=True)
    assert pure.status == 0 and "talked 1" in pure.stdout, pure.stderr
    lines = [x for x in pure.stderr.splitlines() if x.startswith("llfsm: monitor:")]
    assert len(lines) == 3 and "worker.n=5" in lines[0] + lines[1] + lines[2]
    assert (native.status, native.stdout, native.stderr) == (pure.status, pure.stdout, pure.stderr)


def test_native_runs_keep_the_semantics(corpus: Corpus) -> None:
    """The same expectations as tests/test_semantics.py, under --native."""
    assert run(corpus, "order.py", native=True).stdout.splitlines() == [
        "A entry",
        "guard A0",
        "guard A1",
        "A exit",
        "B entry",
    ]
    assert run(corpus, "internal.py", native=True).stdout.splitlines() == [
        "entry",
        "internal 1",
        "internal 2",
        "internal 3",
        "exit",
    ]
    rr = run(corpus, "first.py", "second.py", "--duration", "3ms", native=True).stdout.splitlines()
    assert rr == ["first 0", "second 0", "first 1", "second 1", "first 2", "second 2"]
    sl = run(corpus, "selfloop.py", native=True).stdout.splitlines()
    assert sl == ["entry 1 at 0", "exit", "entry 2 at 7", "exit", "entry 3 at 14", "exit"]
    lonely = run(corpus, "lonely.py", native=True)
    assert lonely.status == 0 and lonely.stdout == "going to sleep\n"
    faulty = run(corpus, "faulty.py", "--duration", "50ms", native=True)
    assert faulty.status == 1
    assert "faulty.machine/State_A_OnEntry.py:4: error: ZeroDivisionError" in faulty.stderr
    assert "(machine faulty, state A, OnEntry)" in faulty.stderr
    dropper = run(corpus, "dropper.py", "--duration", "10ms", "--introspect", native=True)
    assert dropper.status == 0 and "/kept" in dropper.stderr and "/gone" not in dropper.stderr, dropper.stderr
    untyped = run(corpus, "untyped.py", native=True)
    assert untyped.stdout.splitlines() == ["untyped runs 0", "now text"]
    assert untyped.stderr.count("warning: mypyc cannot compile this machine") == 1


#: How each shipped machine runs (its nodes, as the demos and docs/tutorial.md run it), for
#: the comparison of every shipped machine under --native.
SHIPPED = {
    "counter": [],
    "ros2_ping_pong": ["--duration", "3.5s", "--echo", "/pingpong"],
    "ros2_blind_turtle_bot": ["--node", "turtlesim", "--duration", "3s", "--echo", "/turtle1/pose"],
    "ros2_turtle_suspend_resume": ["ros2_blind_turtle_bot", "--node", "turtlesim", "--duration", "8s"],
    "ros2_wall_turtle_bot": ["--node", "turtlesim", "--node", "turtle_sensor_poster", "--duration", "8s"],
    "turtle_follower": ["--node", "turtlesim", "--duration", "4s", "--echo", "/turtle2/cmd_vel"],
    "turtle_rotator": ["--node", "turtlesim", "--duration", "6s"],
    "wall_follower": ["--node", "turtlesim", "--node", "wall_sensor", "--duration", "4s"],
}


@pytest.fixture(scope="session")
def shipped(corpus: Corpus) -> Path:
    """Every shipped machine in one native build (the corpus's cache: mypy's cache is shared)."""
    out = corpus.out.parent / "shipped"
    env = dict(os.environ, LLFSM_CACHE_DIR=str(corpus.cache))
    env.pop("LLFSM_NATIVE", None)
    proc = subprocess.run(
        [sys.executable, "-m", "llfsm", "build", "--native", str(MACHINES), "-o", str(out)],
        capture_output=True,
        text=True,
        env=env,
        timeout=900,
    )
    assert proc.returncode == 0, proc.stderr
    return out


@pytest.mark.slow
@pytest.mark.parametrize("machine", sorted(SHIPPED))
def test_every_shipped_machine_runs_the_same_under_native(corpus: Corpus, shipped: Path, machine: str) -> None:
    """Issue 27, item 0: the machines that use the bus crashed under --native."""
    assert sorted(SHIPPED) == sorted(p.stem for p in MACHINES.glob("*.machine"))  # none left out
    args = [f"{a}.py" if a in SHIPPED else a for a in SHIPPED[machine]]
    pure = run(corpus, f"{machine}.py", *args, "-v", native=False, cwd=shipped)
    native = run(corpus, f"{machine}.py", *args, "-v", native=True, cwd=shipped)
    assert pure.status == 0 and pure.stderr, pure.stderr
    # every shipped machine compiles (an input is declared for mypyc), and runs as the pure one does
    assert (native.status, native.stdout, native.stderr) == (pure.status, pure.stdout, pure.stderr)


@pytest.mark.slow
def test_the_semantics_suite_passes_under_native(tmp_path: Path) -> None:
    """Every test of tests/test_semantics.py with `llfsm run` switched to --native (helpers.llfsm
    reads LLFSM_TEST_NATIVE): one compile per test, hence slow."""
    env = dict(os.environ, LLFSM_TEST_NATIVE="1", LLFSM_CACHE_DIR=str(tmp_path / "cache"))
    env.pop("LLFSM_NATIVE", None)
    proc = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-x", "-p", "no:cacheprovider", "tests/test_semantics.py"],
        capture_output=True,
        text=True,
        env=env,
        cwd=REPO,
        timeout=3600,
    )
    assert proc.returncode == 0, proc.stdout[-3000:]
