"""A private network namespace for DDS tests: several processes share one namespace (so they find
each other over multicast on its loopback), and nothing they send leaves this machine.

A holder process (`unshare -n`) sets the namespace up (lo up, multicast on, a multicast route)
and sleeps; every test process enters it with `nsenter --net=/proc/PID/ns/net`.  Where the
machine does not allow unshare (no root, no user namespaces) the fixture skips with the reason.
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import textwrap
import threading
import time
from collections.abc import Iterator, Sequence
from pathlib import Path

import pytest

#: Variables of the host that would change discovery: the tests set them explicitly or not at all.
ISOLATED = (
    "CYCLONEDDS_URI",
    "ROS_DOMAIN_ID",
    "ROS_AUTOMATIC_DISCOVERY_RANGE",
    "ROS_STATIC_PEERS",
    "ROS_LOCALHOST_ONLY",
)
SETUP = "ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo"

#: The prologue of a hostile peer (a `python -c` script): a participant, raw writers of llfsm's
#: DDS types (`writer(topic, cls, *qos)`, `write(w, payload)`: bytes of the peer's own making,
#: as a peer of any vendor could put on the wire), and CDR helpers (`string`, `HEAD`).
RAW_PEER = textwrap.dedent(
    """
    import struct, sys, time
    from cyclonedds._clayer import ddspy_write
    from cyclonedds.core import Policy, Qos
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.topic import Topic
    from llfsm.msgs._dds import dds_type
    from llfsm.msgs.std_msgs.msg import String
    from llfsm.msgs.rmw_dds_common.msg import ParticipantEntitiesInfo

    dp = DomainParticipant(0)
    XCDR1 = Policy.DataRepresentation(use_cdrv0_representation=True)

    def writer(name, cls, *extra):
        qos = Qos(Policy.Reliability.Reliable(max_blocking_time=10**8), XCDR1, *extra)
        return DataWriter(dp, Topic(dp, name, dds_type(cls)), qos=qos)

    def write(w, payload):
        payload = bytes(payload)
        payload += bytes(-len(payload) % 4)
        ddspy_write(w._ref, payload)

    def string(raw):
        return struct.pack("<I", len(raw) + 1) + raw + b"\\0"

    HEAD = b"\\0\\1\\0\\0"
    """
)


class NetNamespace:
    def __init__(self) -> None:
        self.holder = subprocess.Popen(
            ["unshare", "-n", "sh", "-c", f"{SETUP} && echo ready && exec sleep 900"],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        line = self.holder.stdout.readline() if self.holder.stdout else ""  # type: ignore[union-attr]
        if line.strip() != "ready":
            err = self.holder.stderr.read() if self.holder.stderr else ""  # type: ignore[union-attr]
            self.holder.kill()
            raise OSError(f"cannot make a private network namespace: {err.strip() or 'unshare failed'}")
        self.procs: list[subprocess.Popen[str]] = []

    def popen(
        self, args: Sequence[str | os.PathLike[str]], env: dict[str, str] | None = None, **kw: object
    ) -> subprocess.Popen[str]:
        """Start a process inside the namespace (stdout and stderr piped, text)."""
        cmd = ["nsenter", f"--net=/proc/{self.holder.pid}/ns/net", *map(str, args)]
        full_env = {k: v for k, v in os.environ.items() if k not in ISOLATED}  # the host's settings stay out
        full_env.update(env or {})
        p = subprocess.Popen(
            cmd,
            stdout=kw.pop("stdout", subprocess.PIPE),  # type: ignore[arg-type]
            stderr=kw.pop("stderr", subprocess.PIPE),  # type: ignore[arg-type]
            stdin=kw.pop("stdin", subprocess.DEVNULL),  # type: ignore[arg-type]
            text=True,
            env=full_env,
            **kw,  # type: ignore[arg-type]
        )
        self.procs.append(p)
        return p

    def llfsm(self, *args: str | os.PathLike[str], env: dict[str, str] | None = None) -> subprocess.Popen[str]:
        return self.popen([sys.executable, "-m", "llfsm", *map(str, args)], env=env)

    def python(
        self, code: str, *, python: str | Path = sys.executable, env: dict[str, str] | None = None
    ) -> subprocess.Popen[str]:
        return self.popen([str(python), "-c", code], env=env)

    def close(self) -> None:
        for p in self.procs:
            if p.poll() is None:
                p.kill()
            try:
                p.communicate(timeout=10)
            except subprocess.TimeoutExpired:
                pass
        self.holder.kill()
        self.holder.communicate(timeout=10)


def finish(p: subprocess.Popen[str], timeout: float) -> tuple[int, str, str]:
    """Wait for a process (killed after `timeout` s); its status, stdout and stderr."""
    try:
        out, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        p.kill()
        out, err = p.communicate(timeout=10)
        err += f"\n[killed after {timeout} s]"
    return p.returncode, out, err


def start_view(ns: NetNamespace, *args: str) -> tuple[subprocess.Popen[str], str, list[str]]:
    """`llfsm view` in the namespace (`args` after `--web 127.0.0.1:0`): the process, its page's
    URL, and its stderr as it comes (read on, and stdout drained, by threads)."""
    view = ns.llfsm("view", "--web", "127.0.0.1:0", *args, env={"PYTHONUNBUFFERED": "1"})
    assert view.stderr is not None
    err: list[str] = []
    url = ""
    for line in view.stderr:
        err.append(line)
        m = re.search(r"http://\S+", line)
        if m:
            url = m.group(0)
            break
    assert url, "llfsm view printed no address: " + "".join(err)
    threading.Thread(target=lambda: err.extend(view.stderr or []), daemon=True).start()
    if view.stdout is not None:
        threading.Thread(target=lambda: [None for _ in view.stdout or []], daemon=True).start()
    return view, url, err


class Watched:
    """A process's stdout and stderr read by threads as they come, so that a test waits for the
    line that says a thing happened (a state entered, a message echoed) instead of a fixed time,
    and never blocks on a full pipe.  Under load a process takes seconds to start: a test that
    counts time from its start races with it."""

    def __init__(self, p: subprocess.Popen[str]) -> None:
        self.p = p
        self.out: list[str] = []
        self.err: list[str] = []
        self._changed = threading.Condition()
        self._readers = [
            threading.Thread(target=self._read, args=(stream, into), daemon=True)
            for stream, into in ((p.stdout, self.out), (p.stderr, self.err))
            if stream is not None
        ]
        for t in self._readers:
            t.start()

    def _read(self, stream: Iterator[str], into: list[str]) -> None:
        for line in stream:
            with self._changed:
                into.append(line)
                self._changed.notify_all()
        with self._changed:
            self._changed.notify_all()

    def wait_for(self, pattern: str, *, stream: str = "err", count: int = 1, timeout: float = 90) -> str:
        """Until `count` lines of `stream` ("out" or "err") match `pattern` (a regular
        expression): the last of them.  Fails saying what the process wrote if it ends first
        or `timeout` seconds pass."""
        lines = self.out if stream == "out" else self.err
        deadline = time.monotonic() + timeout
        with self._changed:
            while True:
                hits = [line for line in lines if re.search(pattern, line)]
                if len(hits) >= count:
                    return hits[count - 1]
                gone = self.p.poll() is not None and not any(t.is_alive() for t in self._readers)
                left = deadline - time.monotonic()
                if gone or left <= 0:
                    why = f"ended ({self.p.returncode})" if gone else f"not within {timeout} s"
                    raise AssertionError(
                        f"{count} line(s) of std{stream} matching {pattern!r}: {why}; it wrote:\n"
                        + "".join(self.out)[-3000:]
                        + "\n-- stderr --\n"
                        + "".join(self.err)[-3000:]
                    )
                self._changed.wait(min(left, 0.5))

    def finish(self, timeout: float, sig: int | None = None) -> tuple[int, str, str]:
        """(`sig` sent first, if any) Wait for the process (killed after `timeout` s): its
        status, stdout and stderr."""
        if sig is not None and self.p.poll() is None:
            self.p.send_signal(sig)
        try:
            self.p.wait(timeout)
        except subprocess.TimeoutExpired:
            self.p.kill()
            self.p.wait(10)
            self.err.append(f"\n[killed after {timeout} s]")
        for t in self._readers:
            t.join(10)
        return self.p.returncode, "".join(self.out), "".join(self.err)


def until_shown(ns: NetNamespace, *args: str, needle: str, timeout: float = 60) -> str:
    """Repeat `llfsm ARGS` in the namespace until its standard output holds `needle` (discovery
    takes its time, the more so under load): that output.  Fails with the last one."""
    deadline = time.monotonic() + timeout
    while True:
        _status, out, err = finish(ns.llfsm(*args), timeout)
        if needle in out:
            return out
        assert time.monotonic() < deadline, (
            f"`llfsm {' '.join(args)}` never showed {needle!r} in {timeout} s: {out}{err}"
        )
        time.sleep(0.2)


def interrupt(p: subprocess.Popen[str], after: float, sig: int = signal.SIGINT) -> None:
    time.sleep(after)
    if p.poll() is None:
        p.send_signal(sig)


@pytest.fixture
def netns() -> Iterator[NetNamespace]:
    pytest.importorskip("cyclonedds", reason="the DDS transport needs the cyclonedds package")
    if not (shutil.which("unshare") and shutil.which("nsenter") and shutil.which("ip")):
        pytest.skip("DDS tests need unshare, nsenter and ip (util-linux, iproute2) for a private network")
    try:
        ns = NetNamespace()
    except OSError as e:
        pytest.skip(f"DDS tests run in a private network namespace, and this machine does not allow one: {e}")
    try:
        yield ns
    finally:
        ns.close()
