"""The run's watchdog: ends a run whose machine code is stuck in a C call that holds the GIL.

`signals_handled` (llfsm.runtime.signals) stops machine code from a Python signal handler.
Python runs such a handler only between bytecodes, in the main thread, with the GIL: a section
inside one long C call that keeps the GIL (`sum(range(10**14))`, a C extension that never
releases it) runs no handler, so no number of SIGINTs or SIGTERMs stops it, and no Python
thread of the run can do anything about it either.  What still runs is C: CPython's own signal
handler (it sets a flag and writes the signal's number to the `signal.set_wakeup_fd` fd),
faulthandler's handlers (they write every thread's Python stack to an fd), and other processes.

So a run starts a small watchdog process once its machines are loaded (`Watchdog.start`).  While
the run's handlers are installed (`arm` .. `disarm`), the wakeup fd is a pipe the watchdog
reads: it sees every signal the run receives, when the kernel delivers it, GIL or not.  The
run's Python handlers write a byte to a second pipe each time they run (`answer`), so the
watchdog knows whether the run can still act on its signals.  When the run has owed an answer
for half a second (ANSWER_S), its grace time has passed, and either a second stop signal has
come or the grace time plus half a second (the slack the run itself gives a section that loops
in Python) has passed, the run cannot stop by itself, unless it was only waiting for the CPU
(its main thread waited, runnable, half a second and ran less since the signal: many runs
stopped at once on few cores; `cpu_and_wait`), which gets it up to STARVED_S more: the watchdog
asks it for its stacks
(SIGUSR2, which faulthandler answers from its C handler into a third pipe), turns the innermost
frame in a machine module into the usual report (machine, state, section, the user's file, line
and text: `locate` in llfsm.runtime.errors, as for an exception), prints it on stderr and kills
the run with SIGKILL.

The watchdog is a fresh interpreter (`python -I -S` running this module), started with
posix_spawn, not a fork of the run: a fork write-protects every page of the run, which then
pays a page fault for each page it writes while it lives and while it shuts down (measured: 5
to 7 ms on a 60 ms run of a trivial machine), and a fork of a process with threads (a test
runner, machine code that started some) copies locks other threads hold.  A spawn costs the
run a quarter of a millisecond; the new interpreter's own start (8 ms of CPU) runs beside the
run, and needs nothing of the run's memory: it is told the machines' module files, and finds
the user's lines from the pointer comments in them, as an import error's report does.

Exit status: a process cannot choose the status another one exits with, and every signal whose
default action would give the shell the run's usual 130/143/129 has the run's own handler on
it (handlers cannot be changed from outside), so a killed run ends as SIGKILL leaves it: the
shell says 137 (a Python parent sees -9).  The end-of-run work (a complete `--trace`, the
`--image`, a closed bag) cannot be done for a killed run; the report says so.  (The other way
round, the run in a child and a parent that chooses the status, would change the run's process
id and take it out of the terminal's foreground group, where a node reading the keyboard is
stopped: not worth a status number.)

The watchdog prints nothing unless it kills, and exits as soon as the run closes it or the
run's process is gone (end of file on its pipes, and a pidfd where the system has them), so it
does not outlive the run.  It blocks the stop signals: a Ctrl-C reaches the whole process group,
and the run, not the watchdog, decides what one means.  A dead watchdog cannot make the run print
anything either: the run keeps the pipes' read ends open, so neither the C signal handler nor
`answer` ever meets a broken pipe.
"""

from __future__ import annotations

import _signal as signal  # the signal module without its enums: enum is a tenth of a run's start-up
import os
import sys

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from _signal import _Handler
    from collections.abc import Sequence
    from threading import Event, Thread
    from types import FrameType

    from .machine import Machine

#: Seconds the run's own handler may take to answer a signal before the run counts as stuck: a
#: handler that can run at all runs within milliseconds, even on a loaded machine.
ANSWER_S = 0.5
#: A run with a single interrupt is stuck once it still runs this long after its grace time, as
#: in signals_handled (llfsm.runtime.signals.STUCK_SLACK_S).
SLACK_S = 0.5
#: A run that owes an answer but was waiting for the CPU (sixty runs stopped at once on two
#: cores) is not stuck; it is given up to this much longer after its grace time to answer.
STARVED_S = 10.0
#: How often an interrupted run's thread answers while its main thread ends it (keep_answering).
PROBE_S = 0.2
#: Seconds to wait for the run's stacks once asked for (they come from a C signal handler, at
#: once unless the machine is very loaded); the report is printed without a place after that.
DUMP_S = 3.0
#: The signal whose faulthandler handler writes the run's stacks to the watchdog's pipe.
DUMP_SIGNAL = signal.SIGUSR2
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


#: What the watchdog's interpreter runs: this module, imported from its own folder (so that its
#: cached bytecode is used: running the file as a script would compile it, 3 ms each run), then
#: that folder off the path again (its modules' names are not to shadow the standard library's).
#: The interpreter runs with -B: it reads the bytecode the run's own imports cached, and writes
#: none into the installed package itself (-I ignores PYTHONDONTWRITEBYTECODE; a package may be
#: read-only, or its owner may want it left as installed).
_ENTRY = "import sys; sys.path.insert(0, sys.argv[1]); import watchdog; del sys.path[0]; watchdog._main(sys.argv[2:])"


def _on_dump_signal(_signum: int, _frame: FrameType | None) -> None:
    """The Python handler behind faulthandler's on DUMP_SIGNAL.  Only its C part matters: once
    faulthandler has written the stacks it chains to it, and it writes DUMP_SIGNAL to the wakeup
    fd, which tells the watchdog the stacks are whole."""


class Watchdog:
    """The run's side of the watchdog (see the module's docstring)."""

    def __init__(self, pid: int, wake: tuple[int, int], answers: tuple[int, int], dump: int) -> None:
        self.pid = pid  # the watchdog process
        self.wake_r, self.wake_w = wake
        self.answer_r, self.answer_w = answers
        self.dump_w = dump
        self.armed = False
        self.closed = False
        self._old_wakeup = -1
        self._dump_registered = False
        self._old_dump_handler: _Handler = None
        self._answering: tuple[Event, Thread] | None = None  # keep_answering's stop and thread

    @classmethod
    def start(cls, grace_ns: int, machines: Sequence[type[Machine]]) -> Watchdog | None:
        """Start the watchdog of a run whose machines (in load order) are loaded; None where it
        cannot be started (no posix_spawn, no interpreter to start)."""
        exe = sys.executable
        if not exe or not hasattr(os, "posix_spawn") or not hasattr(signal, "set_wakeup_fd"):
            return None
        _reap()
        # deferred: start-up (only a run that starts its watchdog needs it)
        import _thread

        wake, answers, dump = os.pipe(), os.pipe(), os.pipe()  # close-on-exec: no other program gets them
        os.set_blocking(wake[1], False)  # written from a signal handler: never block
        os.set_blocking(answers[1], False)
        here = os.path.dirname(os.path.abspath(__file__))
        package_root = os.path.dirname(os.path.dirname(here))
        args = [exe, "-I", "-S", "-B", "-c", _ENTRY, here, str(os.getpid()), str(_thread.get_ident())]
        args += [str(grace_ns), str(wake[0]), str(answers[0]), str(dump[0]), package_root]
        for m in machines:
            args += [m.NAME, getattr(sys.modules.get(m.__module__), "__file__", None) or ""]
        reads = (wake[0], answers[0], dump[0])
        for fd in reads:  # for the watchdog alone: no other program run gets them
            os.set_inheritable(fd, True)
        try:
            pid: int | None = os.posix_spawn(
                exe,
                args,
                os.environ,
                file_actions=[
                    (os.POSIX_SPAWN_OPEN, 0, os.devnull, os.O_RDONLY, 0),  # never holds the run's stdin or
                    (os.POSIX_SPAWN_OPEN, 1, os.devnull, os.O_WRONLY, 0),  # stdout: their readers see the end
                ],
                setsigmask=STOP_SIGNALS,
            )
        except OSError:
            pid = None
        for fd in reads:
            os.set_inheritable(fd, False)
        if pid is None:
            for fd in (*wake, *answers, *dump):
                os.close(fd)
            return None
        os.close(dump[0])
        return cls(pid, wake, answers, dump[1])

    def arm(self) -> None:
        """Let the watchdog see the run's signals (while the run's own handlers are installed:
        signals_handled), and let it ask for the run's stacks.  From the main thread."""
        if self.armed or self.closed:
            return
        # deferred: start-up (only an armed watchdog asks for stacks)
        import faulthandler

        if not self._dump_registered:  # stays until close (see disarm)
            self._old_dump_handler = signal.signal(DUMP_SIGNAL, _on_dump_signal)
            faulthandler.register(DUMP_SIGNAL, file=self.dump_w, all_threads=True, chain=True)
            self._dump_registered = True
        self._old_wakeup = signal.set_wakeup_fd(self.wake_w, warn_on_full_buffer=False)
        self.armed = True

    def disarm(self) -> None:
        """The run's handlers are going: from now on its signals are not the watchdog's business.
        The stack dump stays registered until `close` has seen the watchdog end, so that a
        request already on its way never meets the signal's default action (the end of the run)."""
        self._stop_answering()
        if self.armed:
            signal.set_wakeup_fd(self._old_wakeup)
            self.armed = False

    def keep_answering(self, seconds: float) -> None:
        """After a first interrupt, while the run ends: a thread answers every PROBE_S for up to
        `seconds`, which it can only do while the main thread lets Python run.  So a main thread
        in a long call that releases the GIL (closing DDS while many peers leave at once: each
        writer waits up to a second for acknowledgements) is not taken for one stuck in a call
        that holds it, which is what the watchdog is for."""
        if self._answering is not None or self.closed:
            return
        # deferred: start-up (only an interrupted run answers from a thread)
        import threading
        import time

        stop = threading.Event()
        until = time.monotonic() + seconds

        def answer_meanwhile() -> None:
            while not stop.wait(PROBE_S) and time.monotonic() < until:
                self.answer()

        self._answering = (stop, threading.Thread(target=answer_meanwhile, name="llfsm-answer", daemon=True))
        self._answering[1].start()

    def _stop_answering(self) -> None:
        """Stop keep_answering's thread before the pipe it writes to can close."""
        if self._answering is not None:
            stop, thread = self._answering
            self._answering = None
            stop.set()
            thread.join()

    def answer(self) -> None:
        """Called by the run's Python signal handlers: the run can still act on its signals."""
        try:
            os.write(self.answer_w, b"!")
        except OSError:  # full (the watchdog is gone, or slow): it has seen an answer anyway
            pass

    def close(self) -> None:
        """End the watchdog: its pipes reach end of file, and it exits at once."""
        if self.closed:
            return
        self.disarm()
        self.closed = True
        os.close(self.wake_w)
        os.close(self.answer_w)
        _reap(self.pid)
        if self._dump_registered:
            # deferred: start-up, as in arm
            import faulthandler

            faulthandler.unregister(DUMP_SIGNAL)
            old = self._old_dump_handler  # None: a handler set from C, which Python cannot put back
            signal.signal(DUMP_SIGNAL, signal.SIG_DFL if old is None else old)
            self._dump_registered = False
        for fd in (self.wake_r, self.answer_r, self.dump_w):
            os.close(fd)


#: Watchdogs told to end whose exit status has not been collected yet (see _reap).
_ending: list[int] = []


def _reap(pid: int | None = None) -> None:
    """Collect the exit status of ended watchdogs, without waiting.  A watchdog ends within a
    millisecond of `close` (end of file on its pipes), while the run's own process goes on to
    end (the interpreter's clean-up): waiting for it would only put its exit on the run's path.
    One that has not ended yet is collected at the next run of the same process (a test's), or,
    once the run's process has ended, by whoever adopts it."""
    if pid is not None:
        _ending.append(pid)
    for p in list(_ending):
        try:
            done = os.waitpid(p, os.WNOHANG)[0] != 0
        except ChildProcessError:  # collected by someone else (a SIGCHLD handler of machine code)
            done = True
        if done:
            _ending.remove(p)


# -- the watchdog process: this module in `python -I -S` (_ENTRY), importing nothing else at first --


def _main(argv: list[str]) -> None:
    """The watchdog's entry point: the arguments `Watchdog.start` gives it."""
    parent, main, grace_ns, wake, answers, dump = (int(a) for a in argv[:6])
    package_root = argv[6]
    machines = list(zip(argv[7::2], argv[8::2], strict=True))  # (name, module file) in load order
    try:
        _watch(parent, main, grace_ns / 1e9, machines, wake, answers, dump, package_root)
    except KeyboardInterrupt:  # not ours to report (the stop signals are blocked here anyway)
        pass


def _watch(
    parent: int,
    main: int,
    grace: float,
    machines: list[tuple[str, str]],
    wake: int,
    answers: int,
    dump: int,
    package_root: str,
) -> None:
    """The watchdog's life: follow the run's signals and answers until the run closes the pipes
    or its process is gone; kill it, with a report, if it is stuck (see the module's docstring)."""
    # deferred: start-up (the watchdog process's own; the run imports this module without them)
    import select
    import time

    pidfd = _pidfd(parent)
    if os.getppid() != parent:
        return  # the run has already ended
    poller = select.poll()
    for fd in (wake, answers) if pidfd is None else (wake, answers, pidfd):
        poller.register(fd, select.POLLIN)
    first: float | None = None  # when the first stop signal came
    stops: list[int] = []
    owed: float | None = None  # since when the run owes an answer to a signal
    owed_at = (0.0, 0.0)  # the CPU time the run's main thread had used then, and waited for
    patience = 0.0  # not before then: the run was waiting for the CPU (STARVED_S)
    while True:
        due = None
        if first is not None and owed is not None:
            due = max(owed + ANSWER_S, first + grace + (0 if len(stops) > 1 else SLACK_S), patience)
        if due is not None:
            wait: int | None = max(0, int((due - time.monotonic()) * 1000) + 1)
        else:
            wait = 1000 if pidfd is None else None  # without a pidfd: look at the parent every second
        ready = {fd for fd, _ev in poller.poll(wait)}
        if (pidfd is None and os.getppid() != parent) or pidfd in ready:
            return
        if wake in ready:
            data = os.read(wake, 512)
            if not data:
                return
            now = time.monotonic()
            for signum in data:
                if signum in STOP_SIGNALS:
                    stops.append(signum)
                    first = now if first is None else first
                elif signum != signal.SIGALRM or first is None:
                    continue  # not a signal the run's handlers answer
                if owed is None:
                    owed, owed_at = now, cpu_and_wait(parent)
        if answers in ready:
            if not os.read(answers, 512):
                return
            owed = None
        if due is not None and owed is not None and time.monotonic() >= due:
            assert first is not None
            ran, waited = cpu_and_wait(parent)
            starved = waited - owed_at[1] >= ANSWER_S and ran - owed_at[0] < ANSWER_S
            if starved and time.monotonic() < first + grace + STARVED_S:
                patience = time.monotonic() + ANSWER_S  # it waited for the CPU, not in a call
                continue
            held = time.monotonic() - first
            _kill(parent, pidfd, main, machines, wake, dump, stops, held, grace, package_root)
            return


def cpu_and_wait(pid: int) -> tuple[float, float]:
    """Seconds the main thread of process `pid` has run on a CPU, and seconds its threads have
    waited, runnable, for one (their schedstat in /proc: the time a loaded host kept them
    waiting; a thread, keep_answering's, may wait for the CPU while the main thread waits in a
    call); (0.0, 0.0) where the kernel keeps none."""
    try:
        with open(f"/proc/{pid}/task/{pid}/schedstat", "rb") as f:
            ran = int(f.read().split()[0])
        waited = 0
        for tid in os.listdir(f"/proc/{pid}/task"):
            try:
                with open(f"/proc/{pid}/task/{tid}/schedstat", "rb") as f:
                    waited += int(f.read().split()[1])
            except (OSError, ValueError, IndexError):  # a thread that ended meanwhile
                continue
        return ran / 1e9, waited / 1e9
    except (OSError, ValueError, IndexError):
        return 0.0, 0.0


def _pidfd(pid: int) -> int | None:
    """A pidfd of the run's process (readable once it ends), or None where there are none."""
    try:
        return os.pidfd_open(pid)
    except (AttributeError, OSError):
        return None


def _kill(
    parent: int,
    pidfd: int | None,
    main: int,
    machines: list[tuple[str, str]],
    wake: int,
    dump: int,
    stops: list[int],
    held: float,
    grace: float,
    package_root: str,
) -> None:
    """Ask the stuck run for its stacks, print the report of where it is, and kill it."""
    stacks = _stacks(parent, pidfd, wake, dump)
    sys.path.insert(0, package_root)  # the run's llfsm: only now, when a report is due
    # deferred: start-up (in the watchdog process, from the run's llfsm, only when a report is due)
    from llfsm.runtime.errors import signal_name

    last = signal_name(stops[-1])
    if len(stops) > 1:
        what = f"killed after a second {last}"
    else:
        what = f"killed after {last}: still running {held:.1f} s after it (grace time {grace:g} s)"
    what += ", inside a call that never lets Python run"
    report = _report(what, stacks, main, machines)
    report += (
        "llfsm: the run was killed (exit status 137): it could not stop by itself, "
        "so its end-of-run work was not done\n"
    )
    data = report.encode("utf-8", "replace")
    while data:
        try:
            data = data[os.write(2, data) :]
        except OSError:
            break
    _signal(parent, pidfd, signal.SIGKILL)


def _signal(parent: int, pidfd: int | None, signum: int) -> None:
    """Signal the run's process, and no other: through its pidfd, or while it is our parent."""
    try:
        if pidfd is not None:
            signal.pidfd_send_signal(pidfd, signum)
        elif os.getppid() == parent:
            os.kill(parent, signum)
    except OSError:  # it has ended meanwhile
        pass


def _stacks(parent: int, pidfd: int | None, wake: int, dump: int) -> str:
    """The run's stacks as faulthandler writes them.  They are whole when DUMP_SIGNAL's number
    comes on the wakeup pipe (faulthandler chains to Python's C handler after writing them)."""
    # deferred: start-up, as in _watch (the watchdog process's own)
    import select
    import time

    os.set_blocking(dump, False)
    poller = select.poll()
    poller.register(dump, select.POLLIN)
    poller.register(wake, select.POLLIN)
    chunks: list[bytes] = []
    _signal(parent, pidfd, DUMP_SIGNAL)
    end = time.monotonic() + DUMP_S
    whole = False
    while not whole and (left := end - time.monotonic()) > 0:
        for fd, _ev in poller.poll(int(left * 1000) + 1):
            data = os.read(fd, 65536)
            if fd == wake:
                whole = whole or not data or DUMP_SIGNAL in data
            elif data:
                chunks.append(data)
    while True:  # what the dump wrote before its end was signalled
        try:
            data = os.read(dump, 65536)
        except BlockingIOError:
            break
        if not data:
            break
        chunks.append(data)
    return b"".join(chunks).decode("ascii", "replace")


def _report(what: str, stacks: str, main: int, machines: list[tuple[str, str]]) -> str:
    """The usual report for the innermost frame of machine code in the run's main thread (the
    thread that runs the rounds), or a report without a place when there is none (a --native
    build's compiled machine code has no Python frames)."""
    # deferred: start-up, as in _watch (the watchdog process, only when a report is due)
    import re

    from llfsm.runtime.errors import ErrorReport, locate

    files = {_as_dumped(file): (i, name, file) for i, (name, file) in enumerate(machines) if file}
    header = re.compile(r"^(?:Current thread|Thread) 0x([0-9a-f]+) \(most recent call first\):")
    frame = re.compile(r'^  File "(.*)", line (\d+) in ')
    places: list[tuple[bool, str, int]] = []  # (in the main thread, file, line), innermost first
    in_main = False
    for line in stacks.splitlines():
        if h := header.match(line):
            in_main = int(h[1], 16) == main
        elif (f := frame.match(line)) and f[1] in files:
            places.append((in_main, f[1], int(f[2])))
    rep = ErrorReport(exception=what, kind="stopped")
    if places:
        _main, dumped, lineno = sorted(places, key=lambda p: not p[0])[0]  # the main thread's first
        i, name, file = files[dumped]
        rep.machine, rep.machine_id = name, i
        locate(rep, file, lineno)  # the pointer comments: the module's own map is in the run
    return rep.format()


def _as_dumped(path: str) -> str:
    """A file name as faulthandler writes it: printable ASCII as is, anything else escaped, at
    most 500 characters (then `...`)."""
    out = []
    for ch in path[:500]:
        c = ord(ch)
        if 0x20 <= c <= 0x7E:
            out.append(ch)
        elif c <= 0xFF:
            out.append(f"\\x{c:02x}")
        elif c <= 0xFFFF:
            out.append(f"\\u{c:04x}")
        else:
            out.append(f"\\U{c:08x}")
    return "".join(out) + ("..." if len(path) > 500 else "")
