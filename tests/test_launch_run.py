"""`llfsm launch` running processes (plain commands, no DDS): prefixed output, the log folder,
respawn, on_exit, Ctrl-C and what it leaves behind (nothing), and the exit status.

These run real processes, so they wait on them (across processes, never a timed assert)."""

from __future__ import annotations

import os
import queue
import re
import signal
import subprocess
import sys
import threading
import time
import uuid
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO

import pytest

#: The environment variable every test launch carries, to find its processes in /proc.
MARK = "LLFSM_LAUNCH_TEST"


#: Every launch a test started, stopped at its end even when the test failed half-way.
STARTED: list[subprocess.Popen[str]] = []


@pytest.fixture(autouse=True)
def _stop_launches() -> Iterator[None]:
    yield
    while STARTED:
        p = STARTED.pop()
        if p.poll() is None:
            p.send_signal(signal.SIGINT)  # the launcher stops what it started
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()


class Launch:
    """`llfsm launch FILE` as a process of its own, its log folder under `logs`; its stdout and
    stderr read by threads as they come (so a waiting test never blocks on a pipe)."""

    def __init__(self, file: Path, logs: Path, *args: str, env: dict[str, str] | None = None) -> None:
        self.mark = uuid.uuid4().hex
        self.p = subprocess.Popen(
            [sys.executable, "-m", "llfsm", "launch", str(file), *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            stdin=subprocess.DEVNULL,
            text=True,
            env={**os.environ, "ROS_LOG_DIR": str(logs), MARK: self.mark, **(env or {})},
        )
        STARTED.append(self.p)
        self.err: queue.Queue[str | None] = queue.Queue()
        self.err_lines: list[str] = []
        self.out: list[str] = []
        threading.Thread(target=self._read, args=(self.p.stderr, self.err.put), daemon=True).start()
        self.out_done = threading.Thread(target=self._read, args=(self.p.stdout, self.out.append), daemon=True)
        self.out_done.start()

    @staticmethod
    def _read(stream: IO[str] | None, put: Callable[[str | None], None]) -> None:
        assert stream is not None
        for line in stream:
            put(line)
        put(None)

    def wait_for(self, pattern: str, count: int = 1, timeout: float = 120) -> None:
        """Read stderr until `count` lines match `pattern` (the launch's own lines are there)."""
        found = 0
        deadline = time.monotonic() + timeout
        while found < count:
            try:
                line = self.err.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                raise AssertionError(f"no {pattern!r} ({count}) in {timeout} s:\n" + "".join(self.err_lines)) from None
            assert line is not None, f"the launch ended before {pattern!r} ({count}):\n" + "".join(self.err_lines)
            self.err_lines.append(line)
            found += bool(re.search(pattern, line))

    def finish(self, timeout: float = 120) -> tuple[int, str, str]:
        try:
            self.p.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.p.kill()
            self.p.wait()
            raise AssertionError("the launch did not end:\n" + "".join(self.err_lines)) from None
        while (line := self.err.get(timeout=30)) is not None:
            self.err_lines.append(line)
        self.out_done.join(timeout=30)
        return self.p.returncode, "".join(x for x in self.out if x is not None), "".join(self.err_lines)

    def leftovers(self) -> list[str]:
        """Processes still running with this launch's mark in their environment."""
        out = []
        needle = f"{MARK}={self.mark}".encode()
        for pid in filter(str.isdigit, os.listdir("/proc")):
            try:
                with open(f"/proc/{pid}/environ", "rb") as f:
                    if needle in f.read().split(b"\0"):
                        out.append(Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode())
            except OSError:
                continue
        return out


def write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def test_output_is_prefixed_and_routed_by_output(tmp_path: Path) -> None:
    f = write(
        tmp_path / "out.launch.xml",
        """<launch>
  <executable cmd="sh -c 'echo to-out; echo to-err >&amp;2'" name="screen" output="screen"/>
  <executable cmd="sh -c 'echo log-out; echo log-err >&amp;2'" name="logged"/>
  <executable cmd="sh -c 'echo own-out; echo own-err >&amp;2'" name="own" output="own_log"/>
</launch>
""",
    )
    status, out, err = Launch(f, tmp_path / "logs").finish()
    assert status == 0, err
    assert sorted(out.splitlines()) == ["[screen-1] to-out"]
    assert "[screen-1] to-err\n" in err and "[logged-2] log-err\n" in err
    assert "log-out" not in out + err and "own-out" not in out + err and "own-err" not in out + err
    folder = next(x for x in err.splitlines() if "All log files can be found below" in x).rsplit(" ", 1)[1]
    assert Path(folder).parent == tmp_path / "logs" and (tmp_path / "logs" / "latest").resolve() == Path(folder)
    launch_log = (Path(folder) / "launch.log").read_text()
    assert re.search(r"^\d+\.\d{7} \[logged-2\] log-out$", launch_log, re.M)
    assert re.search(r"^\d+\.\d{7} \[INFO\] \[own-3\]: process started with pid \[\d+\]$", launch_log, re.M)
    assert (Path(folder) / "own-3-stdout.log").read_text() == "[own-3] own-out\n"
    assert (Path(folder) / "own-3-stderr.log").read_text() == "[own-3] own-err\n"
    assert sorted((Path(folder) / "own-3.log").read_text().splitlines()) == ["[own-3] own-err", "[own-3] own-out"]


def test_ros_home_is_honoured_when_ros_log_dir_is_not_set(tmp_path: Path) -> None:
    f = write(tmp_path / "a.launch.yaml", "launch:\n  - executable: {cmd: 'true'}\n")
    env = {"ROS_LOG_DIR": "", "ROS_HOME": str(tmp_path / "home")}
    status, _, err = Launch(f, tmp_path / "unused", env=env).finish()
    assert status == 0, err
    assert f"All log files can be found below {tmp_path / 'home' / 'log'}/" in err


def test_lines_of_busy_processes_never_mix(tmp_path: Path) -> None:
    script = write(
        tmp_path / "talk.py",
        "import sys\nw = sys.argv[1]\nfor i in range(2000):\n    print(w * 300 + str(i), flush=i % 7 == 0)\n",
    )
    f = write(
        tmp_path / "busy.launch.xml",
        f"""<launch>
  <executable cmd="{sys.executable} {script} a" name="a" output="screen"/>
  <executable cmd="{sys.executable} {script} b" name="b" output="screen"/>
</launch>
""",
    )
    status, out, err = Launch(f, tmp_path / "logs").finish()
    assert status == 0, err
    lines = out.splitlines()
    assert len(lines) == 4000
    pattern = re.compile(r"\[(a)-1\] a{300}\d+|\[(b)-2\] b{300}\d+")
    assert all(pattern.fullmatch(line) for line in lines)
    for who, n in (("a", 1), ("b", 2)):
        mine = [line for line in lines if line.startswith(f"[{who}-{n}]")]
        assert [int(line[len(who) * 300 + 6 :]) for line in mine] == list(range(2000))


def test_respawn_restarts_after_its_delay_up_to_its_retries(tmp_path: Path) -> None:
    counter = tmp_path / "starts"
    f = write(
        tmp_path / "respawn.launch.xml",
        f"""<launch>
  <executable cmd="sh -c 'echo started >> {counter}; exit 3'" name="flaky"
              respawn="true" respawn_delay="0.2" respawn_max_retries="2"/>
</launch>
""",
    )
    status, _, err = Launch(f, tmp_path / "logs").finish()
    assert status == 1  # it failed (three times)
    assert counter.read_text() == "started\n" * 3
    assert len(re.findall(r"\[ERROR\] \[flaky-1\]: process has died \[pid \d+, exit code 3, cmd", err)) == 3
    assert len(re.findall(r"\[INFO\] \[flaky-1\]: process started with pid", err)) == 3


def test_respawn_goes_on_until_ctrl_c(tmp_path: Path) -> None:
    f = write(
        tmp_path / "forever.launch.yaml",
        "launch:\n  - executable:\n      cmd: 'true'\n      name: tick\n"
        "      respawn: 'true'\n      respawn_delay: '0.1'\n",
    )
    run = Launch(f, tmp_path / "logs")
    run.wait_for(r"\[tick-1\]: process started", count=4)
    run.p.send_signal(signal.SIGINT)
    status, _, err = run.finish()
    assert status == 0, err
    assert "[WARNING] [launch]: user interrupted with ctrl-c (SIGINT)" in err
    assert run.leftovers() == []


def test_on_exit_shutdown_stops_the_others(tmp_path: Path) -> None:
    f = write(
        tmp_path / "shutdown.launch.xml",
        """<launch>
  <executable cmd="sleep 60" name="long"/>
  <executable cmd="sh -c 'sleep 0.5'" name="short" on_exit="shutdown"/>
</launch>
""",
    )
    run = Launch(f, tmp_path / "logs")
    status, _, err = run.finish()
    assert status == 0, err  # `short` ended well, `long` ended at the launch's SIGINT
    assert '[INFO] [launch]: short-2 exited, and it is marked on_exit="shutdown": stopping' in err
    assert "[INFO] [long-1]: sending signal 'SIGINT' to process[long-1]" in err
    assert re.search(r"\[ERROR\] \[long-1\]: process has died \[pid \d+, exit code -2, cmd 'sleep 60'\]", err)
    assert run.leftovers() == []


def test_a_process_that_exits_leaves_the_others_running(tmp_path: Path) -> None:
    f = write(
        tmp_path / "one.launch.xml",
        '<launch>\n  <executable cmd="sh -c \'exit 4\'" name="quits"/>\n'
        "  <executable cmd='sleep 60' name='stays'/>\n</launch>\n",
    )
    run = Launch(f, tmp_path / "logs")
    run.wait_for(r"\[quits-1\]: process has died \[pid \d+, exit code 4")
    assert run.p.poll() is None and run.leftovers()  # `stays` is still there
    run.p.send_signal(signal.SIGINT)
    status, _, err = run.finish()
    assert status == 1, err  # `quits` failed
    assert run.leftovers() == []


def test_ctrl_c_stops_everything_escalating_for_what_ignores_it(tmp_path: Path) -> None:
    """SIGINT to every process group, SIGTERM after sigterm_timeout, SIGKILL after sigkill_timeout:
    what a process started itself, and what ignores SIGINT and SIGTERM, is gone too."""
    f = write(
        tmp_path / "stubborn.launch.xml",
        """<launch>
  <executable cmd="sleep 60" name="polite"/>
  <executable cmd="sh -c 'sleep 60 &amp; sleep 60 &amp; wait'" name="parent" sigterm_timeout="0.5"/>
  <executable cmd="sh -c 'trap \\&quot;\\&quot; INT TERM; sleep 60 &amp; echo deaf >&amp;2; while :; do sleep 1; done'"
              name="deaf" sigterm_timeout="0.5" sigkill_timeout="0.5" output="screen"/>
</launch>
""",
    )
    run = Launch(f, tmp_path / "logs")
    run.wait_for(r"\[deaf-3\] deaf")  # its trap is set (a SIGINT before it would end it at once)
    deadline = time.monotonic() + 30
    while len(run.leftovers()) < 7 and time.monotonic() < deadline:  # the shells start their children
        time.sleep(0.05)
    assert len(run.leftovers()) >= 7  # the launcher, its three processes, and the four they started (less one)
    run.p.send_signal(signal.SIGINT)
    status, _, err = run.finish()
    assert status == 1, err  # `deaf` had to be killed
    # a shell's background jobs ignore SIGINT: the SIGTERM to its group ends them once the shell has gone
    assert "[ERROR] [parent-2]: what parent-2 started failed to terminate '0.5' seconds after receiving 'SIGINT'" in err
    assert (
        "[ERROR] [deaf-3]: process[deaf-3] failed to terminate '0.5' seconds after receiving 'SIGINT', "
        "escalating to 'SIGTERM'" in err
    )
    assert "escalating to 'SIGKILL'" in err
    assert run.leftovers() == []


def test_a_second_ctrl_c_does_not_wait_for_the_grace(tmp_path: Path) -> None:
    f = write(
        tmp_path / "grace.launch.xml",
        "<launch>\n  <executable cmd=\"sh -c 'trap &quot;&quot; INT; echo slow >&amp;2; sleep 60'\" name='slow'\n"
        "              sigterm_timeout='60' output='screen'/>\n"
        "</launch>\n",
    )
    run = Launch(f, tmp_path / "logs")
    run.wait_for(r"\[slow-1\] slow")  # its trap is set
    run.p.send_signal(signal.SIGINT)
    run.wait_for(r"sending signal 'SIGINT'")
    run.p.send_signal(signal.SIGINT)
    status, _, err = run.finish(timeout=30)  # not the 60 s of its sigterm_timeout
    assert "[WARNING] [launch]: SIGINT again: sending SIGTERM now" in err
    assert status == 1
    assert run.leftovers() == []


def test_the_launch_ends_when_its_processes_do(tmp_path: Path) -> None:
    f = write(
        tmp_path / "end.launch.xml",
        "<launch>\n  <executable cmd='true' name='a'/>\n  <executable cmd=\"sh -c 'sleep 0.2'\" name='b'/>\n"
        "</launch>\n",
    )
    status, _, err = Launch(f, tmp_path / "logs").finish()
    assert status == 0, err
    assert re.search(r"\[INFO\] \[a-1\]: process has finished cleanly \[pid \d+\]", err)
    assert re.search(r"\[INFO\] \[b-2\]: process has finished cleanly \[pid \d+\]", err)


def test_a_launch_with_no_option_starts_without_click(tmp_path: Path) -> None:
    """The launcher's start-up delays every process: `llfsm launch FILE [NAME:=VALUE]` takes the
    fast path (no click), and says what the click command says."""
    f = write(
        tmp_path / "a.launch.xml",
        "<launch>\n  <arg name='n'/>\n  <executable cmd='echo $(var n)' output='screen'/>\n</launch>\n",
    )
    env = {**os.environ, "ROS_LOG_DIR": str(tmp_path / "logs")}
    r = subprocess.run(
        [sys.executable, "-X", "importtime", "-m", "llfsm", "launch", str(f), "n:=7"],
        capture_output=True, text=True, env=env, timeout=60,
    )  # fmt: skip
    assert r.returncode == 0 and r.stdout == "[echo-1] 7\n", r.stderr
    assert not [line for line in r.stderr.splitlines() if line.startswith("import time:") and " click" in line]
    r = subprocess.run(
        [sys.executable, "-m", "llfsm", "launch", str(f)], capture_output=True, text=True, env=env, timeout=60
    )
    assert (r.returncode, r.stderr) == (2, f"llfsm: {f}:2: the launch argument 'n' is required: give it as n:=VALUE\n")
    r = subprocess.run(
        [sys.executable, "-m", "llfsm", "launch", str(f), "n=7"], capture_output=True, text=True, timeout=60
    )
    assert (r.returncode, r.stderr) == (
        2,
        "llfsm: malformed launch argument 'n=7', expected format '<name>:=<value>'\n",
    )
    r = subprocess.run(
        [sys.executable, "-m", "llfsm", "launch", str(tmp_path)], capture_output=True, text=True, timeout=60
    )
    assert r.returncode == 2 and "is a directory" in r.stderr  # click's own word for a folder
