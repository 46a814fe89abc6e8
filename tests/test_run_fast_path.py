"""`llfsm run`'s start-up fast path (llfsm.cli.main without click) against the click command.

The fast parser (llfsm.cli.run_args.parse) must either give exactly the keyword arguments that
click gives for the same command line, or hand the command line to click (None).  Whichever
way a command goes, the user sees the same output and exit status.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import click
import pytest
from click.testing import CliRunner
from helpers import MACHINES, llfsm_process, write_machine

from llfsm.cli import cli
from llfsm.cli.run_args import COMPLETE_VAR, RUN_OPTIONS, TARGETS, parse

RUN = cli.commands["run"]


def click_params(args: list[str]) -> dict[str, object]:
    """What the click command would call the run with (or raises click's error)."""
    parent = click.Context(cli, info_name="llfsm", **cli.context_settings)
    with RUN.make_context("run", list(args), parent=parent) as ctx:
        return dict(ctx.params)


def test_every_option_of_the_click_command_is_in_the_table() -> None:
    options = {p.name: p for p in RUN.params if isinstance(p, click.Option)}
    assert set(options) == {o.dest for o in RUN_OPTIONS}
    for o in RUN_OPTIONS:
        assert tuple(options[o.dest].opts + options[o.dest].secondary_opts) == o.flags
        assert options[o.dest].multiple == o.multiple
    arguments = [p.name for p in RUN.params if isinstance(p, click.Argument)]
    assert arguments == [TARGETS]


ACCEPTED = [
    [],
    ["a.machine"],
    ["--clock", "sim", "a.machine", "b.py"],
    ["a.machine", "--clock=sim", "-v"],
    ["-v", "--verbose", "--keep-accepting", "--introspect", "--view", "--native", "x"],
    ["--period", "5ms", "--idle", "0.5", "--duration=2s", "--grace", "0", "x"],
    ["--suspended", "A", "--suspended=B", "--node", "turtlesim", "--node", "teleop", "x"],
    ["--remap", "a:=b", "--param", "turtlesim:background_r:=10", "--echo", "/t", "--echo", "/u"],
    ["--trace", "out.jsonl", "--image", "pic.png", "--web", "127.0.0.1:0"],
    ["--transport", "dds", "--record", "bag", "--record-topic", "/a", "--storage", "sqlite3"],
    ["--play", "bag", "--play-topic", "/a", "--play-rate", "2.5", "--play-rate", "1e-3"],
    ["--trace=", "x"],
    ["--duration", "100ms", "x"],
    ["PKG/NAME", "--clock", "wall"],
    # ROS arguments, as `ros2 run` takes them (issue 27, item 9)
    [
        "x",
        "--ros-args",
        "-r",
        "a:=b",
        "--remap",
        "c:=d",
        "-p",
        "n:=1",
        "--params-file",
        "f.yaml",
        "--log-level",
        "debug",
        "--log-level",
        "talker:=warn",
        "--",
        "--clock",
        "sim",
    ],
    ["--ros-args", "--enable-external-lib-logs", "--disable-external-lib-logs", "--", "x", "--log-file"],
    ["--log-level", "info", "-r", "a:=b", "x", "--ros-args", "-p", "n:=1"],
]


@pytest.mark.parametrize("args", ACCEPTED, ids=lambda a: " ".join(a) or "(none)")
def test_the_fast_parser_gives_what_click_gives(args: list[str], monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("LLFSM_TRANSPORT", raising=False)
    fast = parse(args, os.environ)
    assert fast is not None, "the fast path should take this command line itself"
    assert fast == click_params(args)


def test_the_transport_variable_is_read_as_click_reads_it(monkeypatch: pytest.MonkeyPatch) -> None:
    for value in ("dds", "", "inproc"):
        monkeypatch.setenv("LLFSM_TRANSPORT", value)
        assert parse(["x"], os.environ) == click_params(["x"])
    monkeypatch.setenv("LLFSM_TRANSPORT", "carrier-pigeon")
    assert parse(["x"], os.environ) is None  # click reports the bad value
    with pytest.raises(click.BadParameter):
        click_params(["x"])


DELEGATED = [
    ["--help"],
    ["-h"],
    ["x", "--help"],
    ["--bogus", "x"],
    ["--verb", "x"],  # click has no abbreviations: an error there
    ["-vv", "x"],
    ["--", "-x.machine"],
    ["-"],
    ["--clock", "sims", "x"],
    ["--clock"],
    ["--period", "soon", "x"],
    ["--duration", "1e308min", "x"],
    ["--play-rate", "fast", "x"],
    ["--play-rate", "-1", "x"],
    ["--trace", "--verbose", "x"],
    ["--verbose=yes", "x"],
    ["x", "--ros-args", "--enclave", "/e"],  # a ROS argument llfsm does not take: click says so
]


@pytest.mark.parametrize("args", DELEGATED, ids=" ".join)
def test_what_the_fast_parser_does_not_take_goes_to_click(args: list[str]) -> None:
    assert parse(args, {}) is None


def test_a_directory_as_an_output_file_goes_to_click(tmp_path: Path) -> None:
    assert parse(["--trace", str(tmp_path), "x"], {}) is None
    assert parse(["--image", str(tmp_path / "new.png"), "x"], {}) is not None


def test_shell_completion_goes_to_click() -> None:
    assert parse(["x"], {COMPLETE_VAR: "bash_complete"}) is None


def in_process(*args: str | os.PathLike[str]) -> tuple[int, str, str]:
    res = CliRunner().invoke(cli, [str(a) for a in args], catch_exceptions=False, prog_name="llfsm")
    return res.exit_code, res.stdout, res.stderr


def as_command(*args: str | os.PathLike[str], cwd: Path) -> tuple[int, str, str]:
    r = llfsm_process(*args, cwd=cwd)
    return r.status, r.stdout, r.stderr


def test_the_command_gives_what_the_click_command_gives(tmp_path: Path) -> None:
    """The real entry point (fast path where it can) against click, in process, for runs that
    succeed, fail in machine code, fail validation, and command lines click must handle."""
    write_machine(tmp_path, "ok", {"A": [("END", "True")], "END": None}, {"A_OnEntry": "print('hi')"})
    write_machine(tmp_path, "boom", {"A": None}, {"A_OnEntry": "x = 1 / 0"})
    write_machine(tmp_path, "bad", {"A": [("Z", "True")]})
    cases = [
        ["run", "--clock", "sim", "-v", "ok.machine"],
        ["run", "--clock=sim", "ok.machine", "--duration", "5ms"],
        ["run", "--clock", "sim", "boom.machine"],
        ["run", "--clock", "sim", "bad.machine"],
        ["run", "--clock", "sim", "nothing.machine"],
        ["run"],
        ["run", "--bogus", "ok.machine"],
        ["run", "--clock", "sims", "ok.machine"],
        ["run", "--period", "0", "ok.machine"],
        ["run", "--help"],
    ]
    cwd = os.getcwd()
    os.chdir(tmp_path)  # the messages name files relative to the current folder
    try:
        expected = [in_process(*c) for c in cases]
    finally:
        os.chdir(cwd)
    for case, want in zip(cases, expected, strict=True):
        got = as_command(*case, cwd=tmp_path)
        if "--help" in case:  # wrapped to the terminal's width: compare the words
            got, want = (tuple(" ".join(str(x).split()) for x in r) for r in (got, want))
        assert got == want, case
    assert expected[0][0] == 0 and "hi" in expected[0][1]
    assert expected[2][0] == 1 and "ZeroDivisionError" in expected[2][2]
    assert expected[6][0] == 2 and "No such option" in expected[6][2]
    assert expected[9][0] == 0 and "Usage: llfsm run" in expected[9][1]


def test_a_warm_run_imports_neither_click_nor_the_bus(tmp_path: Path) -> None:
    """What the start-up target rests on: a plain run of a machine directory with a fresh cache,
    or of a built module, imports nothing of the command-line library, the compiler, the bus or
    the messages, and hashes nothing."""
    m = MACHINES / "counter.machine"
    built = tmp_path / "build"
    assert in_process("build", m, "-o", built, "-q")[0] == 0

    def probe(target: Path) -> str:
        return (
            "import atexit, sys\n"
            "heavy = ('click', 'yaml', 'jinja2', 'pydantic', 'llfsm.compiler', 'llfsm.lang', 'llfsm.ros', 'llfsm.msgs',"
            " 'hashlib')\n"
            "atexit.register(lambda: sys.stderr.write('HEAVY %s\\n' % sorted(m for m in heavy if m in sys.modules)))\n"
            "import llfsm.fingerprint\n"
            "llfsm.fingerprint.RACY_NS = 0  # a stat record even for files just checked out or merged\n"
            "from llfsm.__main__ import main\n"
            f"sys.argv = ['llfsm', 'run', '--clock', 'sim', {str(target)!r}]\n"
            "main()\n"
        )

    env = dict(os.environ, LLFSM_CACHE_DIR=str(tmp_path / "cache"))
    run = [sys.executable, "-c", probe(m)]
    cold = subprocess.run(run, capture_output=True, text=True, env=env, timeout=120)
    warm = subprocess.run(run, capture_output=True, text=True, env=env, timeout=120)
    assert "click" not in cold.stderr.split("HEAVY")[1]  # compiling does not need click either
    assert "HEAVY []" in warm.stderr, warm.stderr
    assert warm.stdout == cold.stdout and "done" in warm.stdout
    module = subprocess.run(
        [sys.executable, "-c", probe(built / "counter.py")], capture_output=True, text=True, env=env, timeout=120
    )
    assert "HEAVY []" in module.stderr, module.stderr
    assert module.stdout == warm.stdout


def test_a_warm_run_trusts_its_stat_record_and_sees_changes(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A warm run of a machine directory stats its files instead of hashing them, once a stat
    record says how they looked when the module was last found fresh; an edit that keeps the
    size and puts the modification time back, a new file, a removed file: each is seen."""
    import llfsm.fingerprint as fingerprint

    monkeypatch.setattr(fingerprint, "RACY_NS", 0)  # record files however recently they changed
    m = write_machine(tmp_path, "rec", {"A": None}, {"A_OnEntry": "print('one')"})
    assert in_process("run", "--clock", "sim", m)[1] == "one\n"
    records = list(Path(os.environ["LLFSM_CACHE_DIR"]).rglob("rec.py.stat"))
    assert len(records) == 1

    real_fingerprint = fingerprint.machine_fingerprint

    def no_hashing(*args: object, **kw: object) -> str:
        raise AssertionError("a warm run with a stat record hashed the machine's files")

    monkeypatch.setattr(fingerprint, "machine_fingerprint", no_hashing)
    assert in_process("run", "--clock", "sim", m)[1] == "one\n"
    monkeypatch.setattr(fingerprint, "machine_fingerprint", real_fingerprint)

    f = m / "State_A_OnEntry.py"
    st = f.stat()
    f.write_text("print('two')\n")  # same size
    os.utime(f, ns=(st.st_atime_ns, st.st_mtime_ns))  # and the same modification time
    assert in_process("run", "--clock", "sim", m)[1] == "two\n"
    (m / "State_A_OnExit.py").write_text("print('bye')\n")
    assert in_process("run", "--clock", "sim", m)[1] == "two\n"  # A is accepting: no OnExit
    (m / "State_A_OnExit.py").unlink()
    (m / "Variables.py").write_text("x: int = 1\n")
    f.write_text("print(x)\n")
    assert in_process("run", "--clock", "sim", m)[1] == "1\n"


def test_no_stat_record_for_files_that_just_changed(tmp_path: Path) -> None:
    """A file changed within the last two seconds could change again in the same clock tick
    without its stat changing: such a machine is hashed on every run until it settles."""
    from llfsm.fingerprint import record_fresh, unchanged_since_record

    m = write_machine(tmp_path, "new", {"A": None})
    module = tmp_path / "new.py"
    module.write_text("# Fingerprint: abc\n")
    record_fresh(str(m), str(module), "abc")
    assert not (tmp_path / "new.py.stat").exists()
    assert not unchanged_since_record(str(m), str(module))
