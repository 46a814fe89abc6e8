"""Hardening of the run time, the caches and the command line (issue 12): runs that must stop,
caches that must not be trusted, and failures that must be one clear line, not a traceback or a
silent success.  Signal tests cross processes, so they (only they) wait in real time, briefly
and under timeouts."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from helpers import REPO, llfsm, llfsm_process, write_machine

PY = sys.executable


def _spawn(args: list[str], cwd: Path = REPO, **env: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [PY, "-m", "llfsm", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=dict(os.environ, PYTHONUNBUFFERED="1", **env),
        cwd=cwd,
    )


def _wait_for_go(p: subprocess.Popen[str]) -> None:
    assert p.stdout is not None
    assert p.stdout.readline().strip() == "go", "the machine did not start"


def _finish(p: subprocess.Popen[str], timeout: float = 20) -> tuple[str, str]:
    try:
        return p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        p.kill()
        p.communicate()
        raise


# -- 1. a run that cannot be stopped -------------------------------------------------------------

STUCK = {
    # section code, the line (of State_A_OnEntry.py) where it is stopped
    "loop": ("print('go', flush=True)\nwhile True:\n    pass\n", 2, "while True:"),
    "sleep": ("print('go', flush=True)\ntime.sleep(600)\n", 2, "time.sleep(600)"),
    "wait": ("print('go', flush=True)\nthreading.Event().wait()\n", 2, "threading.Event().wait()"),
}
SIGNALS = {"SIGINT": (signal.SIGINT, 130), "SIGTERM": (signal.SIGTERM, 143), "SIGHUP": (signal.SIGHUP, 129)}


def _stuck_machine(root: Path, kind: str) -> Path:
    code, _line, _text = STUCK[kind]
    return write_machine(
        root, kind, {"A": [("A", "True")]}, {"A_OnEntry": code}, includes="import threading\nimport time\n"
    )


@pytest.mark.parametrize("signame", list(SIGNALS))
@pytest.mark.parametrize("kind", list(STUCK))
def test_second_signal_stops_a_looping_or_blocking_section_at_once(tmp_path: Path, kind: str, signame: str) -> None:
    signum, status = SIGNALS[signame]
    m = _stuck_machine(tmp_path, kind)
    p = _spawn(["run", str(m), "--grace", "60s"], cwd=tmp_path)
    _wait_for_go(p)
    p.send_signal(signum)
    time.sleep(0.2)  # two separate signals, not one coalesced pending signal
    p.send_signal(signum)
    _out, err = _finish(p, timeout=10)  # the grace is 60 s: only the second signal can end it this soon
    assert p.returncode == status, err
    _code, line, text = STUCK[kind]
    first = err.strip().splitlines()[0]
    where = f"(machine {kind}, state A, OnEntry)"
    assert first == f"{kind}.machine/State_A_OnEntry.py:{line}: stopped by a second {signame} {where}"
    assert text in err and "Traceback" not in err


@pytest.mark.parametrize("kind", list(STUCK))
def test_first_signal_stops_a_stuck_section_once_the_grace_has_passed_in_real_time(tmp_path: Path, kind: str) -> None:
    m = _stuck_machine(tmp_path, kind)
    p = _spawn(["run", str(m), "--grace", "200ms"], cwd=tmp_path)
    _wait_for_go(p)
    p.send_signal(signal.SIGTERM)
    _out, err = _finish(p, timeout=10)
    assert p.returncode == 143, err
    _code, line, _text = STUCK[kind]
    assert err.startswith(f"{kind}.machine/State_A_OnEntry.py:{line}: stopped by SIGTERM: still running"), err
    assert "(machine " + kind + ", state A, OnEntry)" in err


def test_grace_is_bounded_in_real_time_under_a_fast_sim_clock(tmp_path: Path) -> None:
    """--period 1ns: a second of run time would be a billion rounds."""
    m = write_machine(tmp_path, "idle", {"A": [("A", "False")]}, {"A_OnEntry": "print('go', flush=True)"})
    p = _spawn(["run", "--clock", "sim", "--period", "1ns", "--grace", "300ms", str(m)], cwd=tmp_path)
    _wait_for_go(p)
    p.send_signal(signal.SIGTERM)
    _out, err = _finish(p, timeout=15)
    assert p.returncode == 143, err
    assert "interrupted; machines have 0.3 s" in err and "Traceback" not in err


def test_a_long_wait_between_rounds_does_not_hold_the_run_past_the_grace(tmp_path: Path) -> None:
    """Time-triggered rounds 30 s apart: the scheduler sleeps, no machine code runs, so the run
    ends as a grace time's end ends it, without a report of a place in machine code."""
    m = write_machine(tmp_path, "slow", {"A": [("A", "False")]}, {"A_OnEntry": "print('go', flush=True)"})
    p = _spawn(["run", "--period", "30s", "--grace", "200ms", str(m)], cwd=tmp_path)
    _wait_for_go(p)
    p.send_signal(signal.SIGINT)
    _out, err = _finish(p, timeout=10)
    assert p.returncode == 130, err
    assert "stopped by" not in err and "Traceback" not in err


def test_sighup_ends_a_run_like_sigterm_flushing_the_trace_and_writing_the_image(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "ticker",
        {"A": [("A", "after_ms(5)")]},
        {"A_OnEntry": "if not started:\n    print('go', flush=True)\nstarted = True"},
        variables="started: bool = False\n",
    )
    trace, image = tmp_path / "t.jsonl", tmp_path / "pic.png"
    p = _spawn(["run", str(m), "--node", "turtlesim", "--trace", str(trace), "--image", str(image)], cwd=tmp_path)
    _wait_for_go(p)
    p.send_signal(signal.SIGHUP)
    _out, err = _finish(p, timeout=15)
    assert p.returncode == 129, err
    lines = trace.read_text().splitlines()
    assert lines and all(json.loads(line) for line in lines)  # complete lines, flushed
    assert image.read_bytes().startswith(b"\x89PNG")


# -- 2. trusting what another user can write -------------------------------------------------------

PLANTED = "\nprint('PLANTED CODE RAN')\n"


def _fallback_env(tmp_path: Path) -> dict[str, str]:
    """The usual cache cannot be created (/proc), so the temporary folder's fallback is used."""
    tmp = tmp_path / "tmp"
    tmp.mkdir(exist_ok=True)
    return dict(os.environ, LLFSM_CACHE_DIR="/proc/llfsm-cannot-be-here", TMPDIR=str(tmp))


def _run_counter(env: dict[str, str]) -> subprocess.CompletedProcess[str]:
    m = REPO / "machines" / "counter.machine"
    return subprocess.run(
        [PY, "-m", "llfsm", "run", "--clock", "sim", "--duration", "50ms", str(m)],
        capture_output=True,
        text=True,
        env=env,
        timeout=60,
    )


@pytest.mark.skipif(os.getuid() != 0, reason="changing a folder's owner needs root")
@pytest.mark.parametrize("spoil", ["foreign_owner", "world_writable", "module_foreign", "module_writable"])
def test_a_cache_someone_else_could_write_is_never_used(tmp_path: Path, spoil: str) -> None:
    env = _fallback_env(tmp_path)
    first = _run_counter(env)
    assert first.returncode == 0, first.stderr
    root = tmp_path / "tmp" / f"llfsm-cache-{os.getuid()}"
    (key,) = root.iterdir()
    assert (root.stat().st_mode & 0o777) == 0o700 and (key.stat().st_mode & 0o077) == 0
    (module,) = key.glob("*.py")
    with module.open("a") as f:  # the fingerprint header still matches: only trust can refuse it
        f.write(PLANTED)
    target = {"foreign_owner": root, "world_writable": root, "module_foreign": module, "module_writable": module}
    if spoil.endswith("foreign") or spoil == "foreign_owner":
        os.chown(target[spoil], 4242, 4242)
    else:
        os.chmod(target[spoil], 0o777 if target[spoil].is_dir() else 0o666)
    again = _run_counter(env)
    assert again.returncode == 0, again.stderr
    assert "PLANTED" not in again.stdout and "count = 1" in again.stdout
    if spoil in ("foreign_owner", "world_writable"):
        assert f"llfsm: warning: not using the cache {root}:" in again.stderr
        assert ("belongs to uid 4242" if spoil == "foreign_owner" else "others can write to it") in again.stderr
    # the fresh private folder is gone once the run is over
    assert sorted(p.name for p in (tmp_path / "tmp").iterdir()) == [root.name]


def test_a_cache_folder_others_can_write_is_not_used_even_when_chosen(tmp_path: Path) -> None:
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    env = dict(_fallback_env(tmp_path), LLFSM_CACHE_DIR=str(shared))
    r = _run_counter(env)
    assert r.returncode == 0 and "count = 1" in r.stdout
    assert f"not using the cache {shared}: others can write to it (mode 0777)" in r.stderr
    assert list(shared.iterdir()) == []


def test_a_symlinked_cache_folder_is_not_followed(tmp_path: Path) -> None:
    env = _fallback_env(tmp_path)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir(mode=0o700)
    (tmp_path / "tmp" / f"llfsm-cache-{os.getuid()}").symlink_to(elsewhere)
    r = _run_counter(env)
    assert r.returncode == 0 and "it is a symbolic link" in r.stderr
    assert list(elsewhere.iterdir()) == []


@pytest.mark.skipif(os.getuid() != 0, reason="changing a folder's owner needs root")
@pytest.mark.parametrize("spoil", ["foreign_owner", "world_writable"])
def test_the_interface_cache_never_imports_an_init_it_cannot_trust(tmp_path: Path, spoil: str) -> None:
    ws = tmp_path / "ws" / "llfsm_trust_pkg" / "msg"
    ws.mkdir(parents=True)
    (ws / "Reading.msg").write_text("float32 value\n")
    cache = tmp_path / "cache"
    env = dict(os.environ, LLFSM_INTERFACE_PATH=str(tmp_path / "ws"), LLFSM_CACHE_DIR=str(cache))
    probe = "from llfsm.msgs.llfsm_trust_pkg.msg import Reading; print(Reading(value=2).value)"
    run = [PY, "-c", probe]
    first = subprocess.run(run, env=env, capture_output=True, text=True, timeout=60)
    assert first.stdout.strip() == "2.0", first.stderr
    (pkg,) = (cache / "interfaces").glob("llfsm_trust_pkg-*")
    with (pkg / "__init__.py").open("a") as f:
        f.write(PLANTED)
    if spoil == "foreign_owner":
        os.chown(pkg / "__init__.py", 4242, 4242)
    else:
        os.chmod(pkg, 0o777)
    again = subprocess.run(run, env=env, capture_output=True, text=True, timeout=60)
    assert again.stdout.strip() == "2.0" and "PLANTED" not in again.stdout, again.stderr
    assert f"not using the cache {pkg}" in again.stderr


def test_python_m_llfsm_does_not_import_modules_from_the_current_folder(tmp_path: Path) -> None:
    """A repository being checked may hold a `yaml.py` (or `click.py`...): it must not run."""
    for name in ("yaml", "click", "pydantic", "jinja2"):
        (tmp_path / f"{name}.py").write_text(f"print('{name}.py from the current folder ran')\n")
    m = write_machine(tmp_path, "fine", {"A": [("END", "True")], "END": None})
    for flags in ([], ["-P"]):
        r = subprocess.run(
            [PY, *flags, "-m", "llfsm", "check", str(m)], capture_output=True, text=True, cwd=tmp_path, timeout=60
        )
        assert r.returncode == 0, r.stderr
        assert "current folder ran" not in r.stdout + r.stderr


# -- 3. a clear message, not an internal error or a silent success -----------------------------------


@pytest.mark.parametrize(
    ("where", "code", "line"),
    [
        ("A_OnEntry", "x = 1\nraise SystemExit(5)", 2),
        ("A_OnEntry", "import sys\nsys.exit(0)", 2),
        ("A_Internal", "raise BrokenPipeError(32, 'Broken pipe')", 1),
        ("Variables.py", "n: int = exit(3)", 1),
    ],
    ids=["SystemExit", "sys.exit(0)", "BrokenPipeError", "exit-in-initialiser"],
)
def test_exits_and_broken_pipes_raised_by_machine_code_are_reported(
    tmp_path: Path, where: str, code: str, line: int
) -> None:
    m = write_machine(tmp_path, "quitter", {"A": [("A", "False")]}, {where: code})
    r = llfsm_process("run", "--clock", "sim", "--duration", "10ms", m, cwd=tmp_path)
    assert r.status == 1, (r.status, r.stderr)
    file = where if where.endswith(".py") else f"State_{where}.py"
    first = r.stderr.splitlines()[0]
    assert first.startswith(f"quitter.machine/{file}:{line}: error: "), first
    assert "(machine quitter" in first and "Traceback" not in r.stderr


def test_a_reentrant_service_call_names_the_line_and_the_service(tmp_path: Path) -> None:
    m = write_machine(
        tmp_path,
        "reent",
        {"A": [("END", "True")], "END": None},
        {
            "A_OnEntry": (
                "ros.init()\nnode = ros.Node('reent')\n"
                "def handle(req, resp):\n    client.call(Empty.Request())\n    return resp\n"
                "node.create_service(Empty, 'again', handle)\n"
                "client = node.create_client(Empty, 'again')\nclient.call(Empty.Request())\n"
            )
        },
        variables="node: object = None\nclient: object = None\n",
        includes="from llfsm import ros\nfrom llfsm.msgs.std_srvs.srv import Empty\n",
    )
    r = llfsm_process("run", "--clock", "sim", m, cwd=tmp_path)
    assert r.status == 1 and "Traceback" not in r.stderr
    first = r.stderr.splitlines()[0]
    assert first.startswith("reent.machine/State_A_OnEntry.py:4: error: RecursionError"), first
    assert "service /again is called synchronously from inside its own callback" in first


@pytest.fixture
def full_disk(tmp_path: Path) -> object:
    """A 64 KiB tmpfs, filled: every write into it fails with ENOSPC."""
    if os.getuid() != 0:
        pytest.skip("mounting a tmpfs needs root")
    d = tmp_path / "full"
    d.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(d)], capture_output=True).returncode:
        pytest.skip("cannot mount a tmpfs here")
    try:
        (d / "old.txt").write_text("the old content\n")
        with open(d / "filler", "wb") as f:
            try:
                f.write(b"\0" * 128 * 1024)
            except OSError:
                pass
        yield d
    finally:
        subprocess.run(["umount", str(d)], check=False)


COUNTER = REPO / "machines" / "counter.machine"
BOT = REPO / "machines" / "ros2_blind_turtle_bot.machine"
OUTPUTS = {
    "check -o": (["check", "--format", "json", "-o", "{}", str(COUNTER)], ".json"),
    "graph -o": (["graph", "-o", "{}", str(COUNTER)], ".mmd"),
    "--trace": (["run", "--clock", "sim", "--duration", "3s", "--trace", "{}", "{machine}"], ".jsonl"),
    "--image": (
        ["run", "--clock", "sim", "--duration", "1s", "--node", "turtlesim", "--image", "{}", str(BOT)],
        ".png",
    ),
}


@pytest.mark.parametrize("option", list(OUTPUTS))
def test_an_output_that_cannot_be_written_is_one_clear_line_and_nothing_half_written(
    full_disk: Path, option: str
) -> None:
    args, suffix = OUTPUTS[option]
    flag = option.split()[-1]
    ticker = write_machine(full_disk.parent, "ticker", {"A": [("A", "True")]})  # a long trace: 6000 events
    targets = [full_disk / f"new{suffix}", Path("/proc/version" if suffix != ".png" else "/proc/llfsm.png")]
    if suffix in (".json", ".mmd"):  # whole files: an old one is kept as it was (a stream replaces it)
        targets.append(full_disk / "old.txt")
    if suffix != ".png":  # --image needs a picture's suffix
        targets.append(Path("/dev/full"))
    for target in targets:
        r = llfsm_process(*[a.replace("{}", str(target)).replace("{machine}", str(ticker)) for a in args], timeout=60)
        assert r.status == 1, (target, r.status, r.stderr)
        mine = [line for line in r.stderr.splitlines() if line.startswith("llfsm:")]
        assert mine == [f"llfsm: {flag} {target}: cannot write: " + mine[0].split(": cannot write: ", 1)[1]], r.stderr
        assert "Traceback" not in r.stderr and "internal error" not in r.stderr
    assert sorted(p.name for p in full_disk.iterdir()) == ["filler", "old.txt"]  # no temporary or partial file
    assert (full_disk / "old.txt").read_text() == "the old content\n"


@pytest.mark.parametrize(
    "command",
    [
        ["check", "--format", "json", str(COUNTER)],
        ["graph", str(COUNTER)],
        ["schema"],
        [
            "run",
            "--clock",
            "sim",
            "--duration",
            "3s",
            "--echo",
            "/pingpong",
            str(REPO / "machines" / "ros2_ping_pong.machine"),
        ],
    ],
    ids=["check", "graph", "schema", "run-echo"],
)
def test_stdout_on_a_full_disk_is_one_clear_line(command: list[str]) -> None:
    with open("/dev/full", "w") as full:
        r = subprocess.run([PY, "-m", "llfsm", *command], stdout=full, stderr=subprocess.PIPE, text=True, timeout=60)
    assert r.returncode == 1
    assert r.stderr.splitlines()[-1] == "llfsm: cannot write the output: No space left on device"
    assert "Traceback" not in r.stderr and "internal error" not in r.stderr


@pytest.mark.parametrize("what", [["new", "machine", "blinky"], ["new", "package", "blinky_pkg"]])
def test_new_into_a_folder_that_cannot_be_written_is_one_clear_line(full_disk: Path, what: list[str]) -> None:
    for folder in (full_disk, Path("/proc")):
        r = llfsm_process(*what, "--dir", folder, timeout=60)
        assert r.status == 1 and r.stderr.startswith(f"llfsm: {folder}: cannot write: "), r.stderr
        assert len(r.stderr.splitlines()) == 1
    assert sorted(p.name for p in full_disk.iterdir()) == ["filler", "old.txt"]


def test_build_goes_on_when_the_reader_of_its_progress_goes_away(tmp_path: Path) -> None:
    machines = [write_machine(tmp_path / "src", f"m{i}", {"A": [("END", "True")], "END": None}) for i in range(4)]
    assert len(machines) == 4
    out = tmp_path / "out"
    cmd = f"{PY} -m llfsm build -o {out} {tmp_path / 'src'} 2>&1 | head -1; exit ${{PIPESTATUS[0]}}"
    r = subprocess.run(["bash", "-c", cmd], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and r.stdout.startswith("[1/4] m")
    assert sorted(p.name for p in out.iterdir()) == ["m0.py", "m1.py", "m2.py", "m3.py"]


@pytest.mark.parametrize(
    "command", [["run", "--clock", "sim", "--duration", "10ms", str(COUNTER)], ["check", str(COUNTER)]]
)
def test_a_closed_stdout_is_a_clear_usage_error(command: list[str]) -> None:
    shell = " ".join([PY, "-m", "llfsm", *command]) + " >&-"
    r = subprocess.run(["sh", "-c", shell], capture_output=True, text=True, timeout=60)
    assert r.returncode == 2
    assert r.stderr == "llfsm: standard output is closed; to discard the output, use >/dev/null\n"


@pytest.mark.parametrize("value", ["1e308min", "1e30", "99999999999999999999s"])
@pytest.mark.parametrize("option", ["--duration", "--grace", "--period", "--idle"])
def test_a_duration_too_long_is_a_usage_error(option: str, value: str) -> None:
    r = llfsm("run", "--clock", "sim", option, value, COUNTER)
    assert r.status == 2 and "too long (at most 100 years)" in r.stderr


# -- 4. the newcomer's rough edges ---------------------------------------------------------------------


def test_run_of_a_name_without_its_suffix_or_with_a_typo_suggests_the_machine(tmp_path: Path) -> None:
    write_machine(tmp_path, "pingpong", {"A": [("END", "True")], "END": None})
    r = llfsm("run", "--clock", "sim", tmp_path / "pingpong")
    assert r.status == 2
    said = f"llfsm: {tmp_path}/pingpong: no such machine directory or module; did you mean {tmp_path}/pingpong.machine?"
    assert r.stderr == said + "\n"
    r = llfsm("run", "--clock", "sim", tmp_path / "pinpong.machine")
    assert r.status == 2 and r.stderr.rstrip().endswith(f"did you mean {tmp_path}/pingpong.machine?")
    r = llfsm("run", "--clock", "sim", tmp_path / "unrelated.machine")
    assert r.status == 2 and "did you mean" not in r.stderr


def test_run_of_pkg_name_lists_the_package_machines(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    share = tmp_path / "install" / "share" / "turtle_pkg"
    write_machine(share / "machine", "leader", {"A": [("END", "True")], "END": None})
    (share / "llfsm").mkdir()
    (share / "llfsm" / "follower.py").write_text("# a built machine\n")
    monkeypatch.setenv("AMENT_PREFIX_PATH", str(tmp_path / "install"))
    r = llfsm("run", "--clock", "sim", "turtle_pkg/leadr")
    assert r.status == 2
    assert "package turtle_pkg has: follower, leader; did you mean leader?" in r.stderr
    r = llfsm("run", "--clock", "sim", "turtle_pgk/leader")
    assert (
        r.status == 2 and "no package turtle_pgk with machines" in r.stderr and "did you mean turtle_pkg?" in r.stderr
    )


def test_echo_of_a_topic_nobody_published_says_so_after_the_run() -> None:
    ping = REPO / "machines" / "ros2_ping_pong.machine"
    r = llfsm("run", "--clock", "sim", "--duration", "2s", "--echo", "/pingpog", ping)
    assert r.status == 0
    assert r.stderr.splitlines()[-1] == (
        "llfsm: --echo /pingpog: no node published or subscribed to /pingpog during the run; did you mean /pingpong?"
    )
    r = llfsm("run", "--clock", "sim", "--duration", "2s", "--echo", "/pingpong", ping)
    assert r.status == 0 and "--echo" not in r.stderr and "data: The count is 0" in r.stdout


def test_view_without_a_display_says_why(monkeypatch: pytest.MonkeyPatch) -> None:
    for var in ("DISPLAY", "WAYLAND_DISPLAY", "SDL_VIDEODRIVER"):
        monkeypatch.delenv(var, raising=False)
    r = llfsm("run", "--clock", "sim", "--duration", "1s", "--node", "turtlesim", "--view", BOT)
    assert r.status == 2
    assert r.stderr.startswith("llfsm: --view opens a window, but there is no display")


def test_helper_modules_beside_a_machine_import_without_pythonpath(tmp_path: Path) -> None:
    """A `helpers.py` in the folder that holds NAME.machine (docs/machine-format.md) imports from
    Includes.py, from any current folder, for a machine directory and for a built module."""
    src = tmp_path / "project"
    m = write_machine(
        src,
        "greeter",
        {"A": [("END", "True")], "END": None},
        {"A_OnEntry": "print(greeting_helpers.greet('turtle'))"},
        includes="import greeting_helpers\n",
    )
    (src / "greeting_helpers.py").write_text("def greet(who):\n    return f'hello, {who}'\n")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    r = llfsm_process("run", "--clock", "sim", m, cwd=elsewhere, env=env)
    assert (r.status, r.stdout) == (0, "hello, turtle\n"), r.stderr
    build = tmp_path / "build"
    assert llfsm_process("build", "-q", "-o", build, m, cwd=elsewhere, env=env).status == 0
    (build / "greeting_helpers.py").write_text((src / "greeting_helpers.py").read_text())
    r = llfsm_process("run", "--clock", "sim", build / "greeter.py", cwd=elsewhere, env=env)
    assert (r.status, r.stdout) == (0, "hello, turtle\n"), r.stderr


# -- issue 27, item 10: how a run ends, said -------------------------------------------------------


def test_a_run_ended_by_the_grace_time_says_which_machines_did_not_finish(tmp_path: Path) -> None:
    stubborn = write_machine(tmp_path, "stubborn", {"A": [("B", "after_ms(20)")], "B": [("A", "after_ms(20)")]},
                             {"A_OnEntry": "if not started:\n    print('go', flush=True)\nstarted = True"},
                             variables="started: bool = False\n")  # fmt: skip
    asleep = write_machine(tmp_path, "asleep", {"A": [("A", "False")]}, yaml_extra="suspended: A")
    polite = write_machine(tmp_path, "polite", {"A": [("END", "not ros.ok()")], "END": None},
                           {"A_OnEntry": "ros.init()"}, includes="from llfsm import ros\n")  # fmt: skip
    p = _spawn(["run", str(stubborn), str(asleep), str(polite), "--suspended", "asleep", "--grace", "300ms"],
               cwd=tmp_path)  # fmt: skip
    _wait_for_go(p)
    p.send_signal(signal.SIGINT)
    _out, err = _finish(p)
    assert p.returncode == 130, err
    last = err.strip().splitlines()[-1]
    assert last.startswith("llfsm: the grace time (0.3 s) ran out before stubborn (in ")
    assert last.endswith("), asleep (suspended in A) finished"), last  # polite reached END: not named


def test_nodes_on_their_own_end_with_status_0_on_ctrl_c(tmp_path: Path) -> None:
    """As `ros2 run turtlesim turtlesim_node` and as machine runs do (issue 27, item 10)."""
    p = _spawn(["run", "--node", "turtlesim", "--echo", "/turtle1/pose"], cwd=tmp_path)
    assert p.stdout is not None and p.stdout.readline().startswith("x: "), "turtlesim did not start"
    p.send_signal(signal.SIGINT)
    _out, err = _finish(p)
    assert p.returncode == 0, err
    assert "Traceback" not in err


def test_a_machine_loaded_twice_is_said_before_any_node_starts(tmp_path: Path) -> None:
    m = write_machine(tmp_path, "twice", {"A": [("A", "False")]})
    r = llfsm("run", "--clock", "sim", "--node", "turtlesim", m, m)
    assert r.status == 2
    assert r.stderr == "llfsm: machine twice is loaded twice; an arrangement addresses machines by name\n"
