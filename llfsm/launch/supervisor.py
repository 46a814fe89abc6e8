"""The processes of a launch: started, their lines prefixed, respawned, stopped, accounted for.

One thread, one loop (a selector over the processes' pipes and a self-pipe for signals), no
asyncio: the launcher stays small (its memory is measured by bench/launch.py) and every
decision is in one place.

- Each process starts in a process group of its own, with stdin on /dev/null (a launched
  process has no terminal, as under `ros2 launch`), so a Ctrl-C in the terminal reaches the
  launcher alone, which then stops everything in order.
- Output: stdout and stderr are read as they come, cut into lines and written whole with the
  `[NAME-N] ` prefix (llfsm.launch.logs routes them by `output`); a line longer than 64 KiB is
  cut, so a process that never ends a line costs bounded memory.
- A process that exits is said (`process has finished cleanly` / `process has died`, as launch
  says it); with `respawn` it starts again after `respawn_delay` (at most `respawn_max_retries`
  times, when that is set); with `on_exit="shutdown"` its exit stops the launch.
- Stopping (Ctrl-C, SIGTERM, SIGHUP, `on_exit="shutdown"`, or the end of the last process):
  SIGINT to every process group still holding a process, then SIGTERM to what is left after
  its `sigterm_timeout`, then SIGKILL after its `sigkill_timeout` (launch's 5 s and 5 s by
  default); a second Ctrl-C sends SIGTERM at once, a third SIGKILL.  Groups are signalled, not
  only the processes started, so what a process started itself is stopped too: the launch ends
  when no group it made holds a process.
- Exit status: 0 when every process ended well (status 0, or ended by the launch's SIGINT);
  1 when one failed (another status, or it had to be sent SIGTERM or SIGKILL).
"""

from __future__ import annotations

import os
import selectors
import signal
import subprocess
import time
from typing import IO, Any

from .logs import LaunchLog, _Sink
from .plan import ProcessSpec

#: Longest line kept whole; a longer one is written in pieces of this size.
MAX_LINE = 64 * 1024
#: How long the launch waits, after SIGKILL, for a group to be empty before it gives up on it.
KILL_WAIT = 2.0
#: Exit statuses that mean "ended because it was interrupted": by SIGINT itself, or as shells do.
_INTERRUPTED = (0, -signal.SIGINT, 128 + signal.SIGINT)
_STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
TELEOP_NOTE = (
    "a launched process cannot read this terminal (as under ros2 launch): to drive turtle1 with the "
    "arrow keys, run `llfsm run --transport dds --node teleop` in a second terminal"
)


class _Child:
    """One `node` or `executable`: its current process, and what is still to do for it."""

    def __init__(self, spec: ProcessSpec, routes: tuple[list[_Sink], list[_Sink]]) -> None:
        self.spec = spec
        self.routes = routes
        self.popen: subprocess.Popen[bytes] | None = None
        self.starts = 0
        self.respawn_at: float | None = None
        self.prefix = f"[{spec.label}] ".encode()


class _Group:
    """A process group the launch made (one per start), and how far stopping it has gone."""

    def __init__(self, child: _Child, pgid: int) -> None:
        self.child = child
        self.pgid = pgid
        self.sent: int | None = None  # the last signal sent to it
        self.term_at = 0.0
        self.kill_at = 0.0
        self.given_up_at = 0.0


class Supervisor:
    def __init__(self, specs: list[ProcessSpec], log: LaunchLog) -> None:
        self.log = log
        self.children = [_Child(s, log.routes(s)) for s in specs]
        self.groups: dict[int, _Group] = {}
        #: fd -> (its stream, whose it is, the partial line, where lines go)
        self.pipes: dict[int, tuple[IO[bytes], _Child, bytearray, list[_Sink]]] = {}
        self.selector = selectors.DefaultSelector()
        self.failed: set[str] = set()
        self.stopping = False
        self.hurries = 0  # stop signals received while stopping
        self._wake_r, self._wake_w = os.pipe2(os.O_NONBLOCK | os.O_CLOEXEC)
        self.selector.register(self._wake_r, selectors.EVENT_READ)

    # -- the loop ---------------------------------------------------------------------------------
    def run(self) -> int:
        """Start every process, supervise them until the launch ends; the exit status."""
        previous = self._install_signals()
        _become_subreaper()
        try:
            for child in self.children:
                self._start(child)
            while not self._finished():
                self._wait()
                self._reap()
                self._timers()
        finally:
            self._restore_signals(previous)
            for fd in list(self.pipes):
                self._drain(fd, final=True)
            self.selector.close()
            os.close(self._wake_r)
            os.close(self._wake_w)
        return 1 if self.failed else 0

    def _install_signals(self) -> tuple[int, dict[signal.Signals, Any]]:
        """The launch hears signals through its self-pipe: a handler that does nothing keeps
        Python from raising KeyboardInterrupt, and the wake-up fd carries the signal's number."""
        handlers = {sig: signal.signal(sig, _ignore) for sig in (*_STOP_SIGNALS, signal.SIGCHLD)}
        return signal.set_wakeup_fd(self._wake_w, warn_on_full_buffer=False), handlers

    def _restore_signals(self, previous: tuple[int, dict[signal.Signals, Any]]) -> None:
        wakeup, handlers = previous
        signal.set_wakeup_fd(wakeup)
        for sig, handler in handlers.items():
            signal.signal(sig, handler)

    def _wait(self) -> None:
        now = time.monotonic()
        deadlines = [c.respawn_at for c in self.children if c.respawn_at is not None]
        for g in self.groups.values():
            deadlines += [t for t in (g.term_at, g.kill_at, g.given_up_at) if t > now]
        timeout = min([max(0.0, t - now) for t in deadlines], default=0.5)
        for key, _ in self.selector.select(min(timeout, 0.5)):
            if key.fd == self._wake_r:
                self._signals()
            elif key.fd in self.pipes:  # not closed meanwhile (a signal's stop reaps and drains)
                self._drain(key.fd)

    def _signals(self) -> None:
        try:
            data = os.read(self._wake_r, 512)
        except BlockingIOError:
            return
        for number in data:
            if number in _STOP_SIGNALS:
                self._interrupted(number)

    def _interrupted(self, number: int) -> None:
        """The first stop signal stops the launch; one while it stops hurries it: SIGTERM now,
        then SIGKILL now."""
        name = signal.Signals(number).name
        if not self.stopping:
            what = "ctrl-c (SIGINT)" if number == signal.SIGINT else name
            self.log.message("WARNING", "launch", f"user interrupted with {what}")
            self._stop()
            return
        self.hurries += 1
        now = time.monotonic()
        hurry = signal.SIGTERM if self.hurries == 1 else signal.SIGKILL
        self.log.message("WARNING", "launch", f"{name} again: sending {signal.Signals(hurry).name} now")
        for g in self.groups.values():
            if hurry == signal.SIGTERM:
                g.term_at = min(g.term_at, now)
                g.kill_at = min(g.kill_at, now + g.child.spec.sigkill_timeout)
            else:
                g.term_at = g.kill_at = now

    def _finished(self) -> bool:
        running = any(c.popen is not None or c.respawn_at is not None for c in self.children)
        if running:
            return False
        if self.groups and not self.stopping:
            self._stop(quiet=True)  # every process has ended, but something one of them started has not
        self._prune_groups()
        return not self.groups

    # -- starting ----------------------------------------------------------------------------------
    def _start(self, child: _Child) -> None:
        spec = child.spec
        child.respawn_at = None
        child.starts += 1
        try:
            p = subprocess.Popen(
                spec.argv,
                stdin=subprocess.DEVNULL,
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                env=spec.env,
                cwd=spec.cwd,
                process_group=0,
            )
        except OSError as e:
            self.log.message("ERROR", spec.label, f"cannot start {spec.shown!r}: {e.strerror or e}")
            self.failed.add(spec.label)
            return
        child.popen = p
        self.groups[p.pid] = _Group(child, p.pid)
        out_sinks, err_sinks = child.routes
        for stream, sinks in ((p.stdout, out_sinks), (p.stderr, err_sinks)):
            assert stream is not None
            fd = stream.fileno()
            os.set_blocking(fd, False)
            self.pipes[fd] = (stream, child, bytearray(), sinks)
            self.selector.register(fd, selectors.EVENT_READ)
        self.log.message("INFO", spec.label, f"process started with pid [{p.pid}]")
        if spec.node == "teleop" and not spec.prefixed and child.starts == 1:
            self.log.message("WARNING", spec.label, TELEOP_NOTE)

    # -- output ------------------------------------------------------------------------------------
    def _drain(self, fd: int, final: bool = False) -> None:
        """Read what the pipe holds now; at its end (or `final`), write the last partial line."""
        _, child, buf, sinks = self.pipes[fd]
        for _ in range(64):  # a process that never stops talking gets a turn, not the launcher
            try:
                data = os.read(fd, 65536)
            except BlockingIOError:
                data = None
            except OSError:
                data = b""
            if data:
                buf += data
                self._lines(child, buf, sinks)
                continue
            if data == b"" or final:
                self._close(fd)
            return
        if final:
            self._close(fd)

    def _close(self, fd: int) -> None:
        """The pipe's end: its last partial line written, the pipe closed."""
        stream, child, buf, sinks = self.pipes.pop(fd)
        if buf:
            self._emit(child, bytes(buf), sinks)
        self.selector.unregister(fd)
        stream.close()

    def _lines(self, child: _Child, buf: bytearray, sinks: list[_Sink]) -> None:
        start = 0
        while True:
            end = buf.find(b"\n", start)
            if end < 0:
                break
            self._emit(child, bytes(buf[start:end]), sinks)
            start = end + 1
        del buf[:start]
        while len(buf) >= MAX_LINE:
            self._emit(child, bytes(buf[:MAX_LINE]), sinks)
            del buf[:MAX_LINE]

    def _emit(self, child: _Child, line: bytes, sinks: list[_Sink]) -> None:
        data = child.prefix + line.removesuffix(b"\r") + b"\n"
        for sink in sinks:
            sink.write(data)

    # -- exits -------------------------------------------------------------------------------------
    def _reap(self) -> None:
        for child in self.children:
            p = child.popen
            if p is None or p.poll() is None:
                continue
            for stream in (p.stdout, p.stderr):  # what it printed before it ended comes first
                if stream is not None and not stream.closed:
                    self._drain(stream.fileno())
            child.popen = None
            self._exited(child, p)

    def _exited(self, child: _Child, p: subprocess.Popen[bytes]) -> None:
        spec, code = child.spec, p.returncode
        if code == 0:
            self.log.message("INFO", spec.label, f"process has finished cleanly [pid {p.pid}]")
        else:
            self.log.message(
                "ERROR", spec.label, f"process has died [pid {p.pid}, exit code {code}, cmd '{spec.shown}']."
            )
        group = self.groups.get(p.pid)
        forced = group is not None and group.sent in (signal.SIGTERM, signal.SIGKILL)
        asked = group is not None and group.sent == signal.SIGINT
        if forced or not (code == 0 or (asked and code in _INTERRUPTED)):
            self.failed.add(spec.label)
        if self.stopping:
            return
        if spec.shutdown_on_exit:
            self.log.message("INFO", "launch", f'{spec.label} exited, and it is marked on_exit="shutdown": stopping')
            self._stop()
            return
        retries = spec.respawn_max_retries
        if spec.respawn and (retries < 0 or child.starts <= retries):
            child.respawn_at = time.monotonic() + spec.respawn_delay

    # -- stopping ----------------------------------------------------------------------------------
    def _stop(self, quiet: bool = False) -> None:
        """SIGINT to every group still holding a process; the timers escalate from there."""
        self.stopping = True
        now = time.monotonic()
        for child in self.children:
            child.respawn_at = None
        self._prune_groups()
        for g in self.groups.values():
            spec = g.child.spec
            g.term_at = now + spec.sigterm_timeout
            g.kill_at = g.term_at + spec.sigkill_timeout
            if not quiet or g.child.popen is None:
                who = f"process[{spec.label}]" if g.child.popen is not None else f"what {spec.label} started"
                self.log.message("INFO", spec.label, f"sending signal 'SIGINT' to {who}")
            self._signal(g, signal.SIGINT)

    def _timers(self) -> None:
        now = time.monotonic()
        for child in self.children:
            if child.respawn_at is not None and now >= child.respawn_at and not self.stopping:
                self._start(child)
        if not self.stopping:
            return
        self._prune_groups()
        for g in list(self.groups.values()):
            spec = g.child.spec
            # its own process, or what it started when it has ended itself
            who = f"process[{spec.label}]" if g.child.popen is not None else f"what {spec.label} started"
            if g.sent == signal.SIGINT and now >= g.term_at:
                self.log.message(
                    "ERROR",
                    spec.label,
                    f"{who} failed to terminate '{spec.sigterm_timeout}' seconds after receiving 'SIGINT', "
                    "escalating to 'SIGTERM'",
                )
                self._signal(g, signal.SIGTERM)
            if g.sent == signal.SIGTERM and now >= g.kill_at:
                self.log.message(
                    "ERROR",
                    spec.label,
                    f"{who} failed to terminate '{spec.sigterm_timeout + spec.sigkill_timeout}' seconds after "
                    "receiving 'SIGTERM', escalating to 'SIGKILL'",
                )
                self._signal(g, signal.SIGKILL)
                g.given_up_at = now + KILL_WAIT
            if g.sent == signal.SIGKILL and now >= g.given_up_at:
                self.log.message("ERROR", spec.label, f"{who} is still there after SIGKILL (process group {g.pgid})")
                del self.groups[g.pgid]

    def _signal(self, g: _Group, sig: int) -> None:
        g.sent = sig
        if sig != signal.SIGINT:
            self.failed.add(g.child.spec.label)  # it did not stop when asked
        try:
            os.killpg(g.pgid, sig)
        except ProcessLookupError:
            pass

    def _prune_groups(self) -> None:
        """Forget the groups that hold no process any more.  A group's id cannot be reused while
        it holds a process (POSIX), and a leader is reaped here before its group is checked, so
        a group that still answers is ours."""
        self._reap()
        for pgid, g in list(self.groups.items()):
            if g.child.popen is None or g.child.popen.pid != pgid:
                _reap_orphans(pgid)
            try:
                os.killpg(pgid, 0)
            except ProcessLookupError:
                del self.groups[pgid]
            except PermissionError:
                pass  # a process of the group changed its user: it is still there


def _become_subreaper() -> None:
    """What the launch's processes leave behind when they end (a shell's background job) becomes
    the launcher's child rather than init's (Linux's PR_SET_CHILD_SUBREAPER), so it is reaped as
    soon as it ends and its group is seen empty at once; elsewhere, init reaps it in its time."""
    try:
        import ctypes  # deferred: start-up (only a launch that starts processes needs prctl)

        ctypes.CDLL(None, use_errno=True).prctl(36, 1, 0, 0, 0)  # PR_SET_CHILD_SUBREAPER
    except (OSError, AttributeError):
        pass


def _reap_orphans(pgid: int) -> None:
    """Reap the ended processes of a group whose leader has been reaped (our orphans, as a
    subreaper); never a leader, which its Popen reaps."""
    while True:
        try:
            if os.waitid(os.P_PGID, pgid, os.WEXITED | os.WNOHANG) is None:
                return
        except ChildProcessError:
            return


def _ignore(signum: int, frame: object) -> None:
    """Signals are read from the wake-up fd; this handler only stops Python's default."""
