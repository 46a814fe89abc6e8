"""Turn an exception raised by machine code into a report about the user's own file and line.

Generated modules carry a pointer comment (`# State_PUBLISH_OnEntry.py:1`) before every block
of user code, keep that code line for line, and list the pointers in their source map
(llfsm.runtime.generated, which reads both).  So the innermost traceback frame in a generated
module, and the nearest pointer above its line, name the file and line the user wrote, even in
a module that failed half-way through being imported (a bad include).
"""

from __future__ import annotations

import errno
import os

from .generated import FILE_PATTERN, is_generated, map_line, source_dir_of, source_map_of
from .machine import Machine

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from re import Pattern
    from types import TracebackType

    from .generated import SourceMap

# re, linecache (and the tokenize module it imports), bisect and json are imported when an error
# is reported: a run that raises nothing does not pay for them at start-up.


def _compiled(pattern: str) -> Pattern[str]:
    import re  # deferred: start-up (error paths only; re caches what it compiles)

    return re.compile(pattern)


class RunStopped(BaseException):
    """Raised from a signal handler into whatever code is running, machine code included: the
    second interrupt, or a first one whose grace time has passed in real time while a section
    still loops or blocks.  A BaseException, as KeyboardInterrupt is, so that `except Exception`
    in machine code does not swallow it; the report then names where the run was stopped."""

    def __init__(self, signum: int, text: str, *, in_machine_code: bool = True) -> None:
        super().__init__(signum, text)
        self.signum = signum
        self.text = text
        self.in_machine_code = in_machine_code

    def __str__(self) -> str:
        return self.text


def signal_name(signum: int) -> str:
    # deferred: start-up (the signal module's enums; error paths only)
    import signal

    try:
        return signal.Signals(signum).name
    except ValueError:
        return f"signal {signum}"


def passes_through(exc: BaseException) -> bool:
    """True for what is not a fault of machine code even when raised inside it: a real Ctrl-C
    (KeyboardInterrupt, when no handler of ours is installed) and a write to our own stdout or
    stderr after its reader went away (`llfsm run ... | head -1`), which ends the run quietly.
    Anything else raised in machine code, SystemExit and a BrokenPipeError it raises itself
    included, is reported with the user's file and line."""
    if isinstance(exc, KeyboardInterrupt):
        return True
    if isinstance(exc, BrokenPipeError):
        return exc.errno == errno.EPIPE and _std_stream_broken()
    return False


def _std_stream_broken() -> bool:
    """Whether stdout or stderr is a pipe whose reader has gone (poll reports an error on it)."""
    # deferred: start-up (error paths only)
    import select

    if not hasattr(select, "poll"):
        return True
    poller = select.poll()
    for fd in (1, 2):
        poller.register(fd, select.POLLOUT)
    try:
        return any(ev & (select.POLLERR | select.POLLNVAL) for _fd, ev in poller.poll(0))
    except OSError:
        return True


class ErrorReport:
    """Where machine code failed, as the user wrote it.  (A plain class, not a dataclass:
    dataclasses imports inspect, a fifth of a run's start-up.)"""

    FIELDS = ("exception", "machine", "machine_id", "state", "section", "file", "line", "text", "kind")

    def __init__(
        self,
        exception: str,  # "ZeroDivisionError: division by zero"
        machine: str | None = None,
        machine_id: int | None = None,
        state: str | None = None,
        section: str | None = None,  # OnEntry, OnExit, Internal, OnSuspend, OnResume, Transition 0, Variables, Includes
        file: str | None = None,  # path of the user's file
        line: int | None = None,
        text: str | None = None,  # the line as the user wrote it
        kind: str = "error",  # "stopped" when an interrupt stopped the run there
    ) -> None:
        self.exception = exception
        self.machine = machine
        self.machine_id = machine_id
        self.state = state
        self.section = section
        self.file = file
        self.line = line
        self.text = text
        self.kind = kind

    def __repr__(self) -> str:
        return f"ErrorReport({', '.join(f'{k}={v!r}' for k, v in self.as_dict().items())})"

    def __eq__(self, other: object) -> bool:
        return isinstance(other, ErrorReport) and self.as_dict() == other.as_dict()

    __hash__ = None  # type: ignore[assignment]  # mutable, as a dataclass is

    def format(self) -> str:
        """Two lines: a compiler-style first line, then the offending source line."""
        where = []
        if self.machine:
            where.append(f"machine {self.machine}")
        if self.state:
            where.append(f"state {self.state}")
        if self.section:
            where.append(self.section)
        ctx = f" ({', '.join(where)})" if where else ""
        head = f"{self.file}:{self.line}: " if self.file else "llfsm: " if self.kind != "error" else ""
        what = f"error: {self.exception}" if self.kind == "error" else self.exception  # "stopped by ..."
        out = f"{head}{what}{ctx}\n"
        if self.text:
            out += f"    {self.text.strip()}\n"
        return out

    def as_dict(self) -> dict[str, object]:
        return {k: getattr(self, k) for k in self.FIELDS}


def _display(path: str) -> str:
    try:
        rel = os.path.relpath(path)
    except ValueError:
        return path
    return path if rel.startswith(os.pardir) else rel  # relative only below the current folder


def _exception_text(exc: BaseException) -> str:
    """`Type: message`, whatever the exception does: machine code may raise anything."""
    if isinstance(exc, RunStopped):
        return str(exc)
    try:
        msg = str(exc)
    except Exception:  # a broken __str__ must not hide the report of the error itself
        msg = "<exception str() failed>"
    return f"{type(exc).__name__}: {msg}" if msg else type(exc).__name__


def _reentrant_call_hint(tb: TracebackType | None) -> str:
    """Why a RecursionError happened when it is the classic one: a service callback that calls
    its own service synchronously (each call serves the request, which calls again...)."""
    seen: dict[str, int] = {}
    while tb is not None:
        code = tb.tb_frame.f_code
        if code.co_name == "call" and code.co_filename.endswith(os.path.join("llfsm", "ros", "client.py")):
            name = getattr(tb.tb_frame.f_locals.get("self"), "srv_name", None)
            if isinstance(name, str):
                seen[name] = seen.get(name, 0) + 1
        tb = tb.tb_next
    again = [n for n, k in seen.items() if k > 1]
    if not again:
        return ""
    return (
        f" (service {again[0]} is called synchronously from inside its own callback, which calls it again:"
        " answer without calling it, or use call_async)"
    )


def report_for(exc: BaseException, machine: Machine | None = None) -> ErrorReport | None:
    """The report for an exception raised in machine code, or None if no frame is the user's."""
    import linecache  # error paths only: a run's start-up does not pay for them

    tb: TracebackType | None = exc.__traceback__
    found = None
    while tb is not None:
        fname = tb.tb_frame.f_code.co_filename
        linecache.checkcache(fname)
        # a message class's module is generated too, but it is not the user's code: the report
        # names the machine line that led there (where the stack ends depends on its depth)
        if is_generated(fname) and not str(tb.tb_frame.f_globals.get("__name__")).startswith("llfsm.msgs."):
            found = tb
        tb = tb.tb_next
    if found is None:
        return None
    frame, lineno = found.tb_frame, found.tb_lineno
    fname = frame.f_code.co_filename
    rep = ErrorReport(exception=_exception_text(exc), kind="stopped" if isinstance(exc, RunStopped) else "error")
    if isinstance(exc, RecursionError):
        rep.exception += _reentrant_call_hint(exc.__traceback__)
    self_ = frame.f_locals.get("self")
    m = self_ if isinstance(self_, Machine) else machine
    if m is not None:
        rep.machine, rep.machine_id = m.NAME, m._id
        rep.state = m.STATES[m._state] if 0 <= m._state < len(m.STATES) else None
    return locate(rep, fname, lineno, source_map_of(frame.f_globals))


def locate(rep: ErrorReport, fname: str, lineno: int, source_map: SourceMap | None = None) -> ErrorReport:
    """Fill in the user's file, line, text, state and section of `rep` for a line of a generated
    module.  Apart from report_for, so that the run's watchdog (llfsm.runtime.watchdog), which
    knows a place only as a file and a line from a stack dump, reports it the same way."""
    import linecache  # error paths only: a run's start-up does not pay for them

    mapped = map_line(fname, lineno, source_map)
    if mapped is None:
        rep.text = linecache.getline(fname, lineno).strip() or None
        return rep
    user_file, user_line = mapped
    fm = _compiled(FILE_PATTERN).fullmatch(user_file)
    if fm:
        rep.state = fm["state"]
        rep.section = fm["section"].replace("_", " ")
    elif user_file == "machine.yaml":
        rep.section = "guard"  # an inline guard (docs/machine-format.md): of the state the machine is in
    else:
        rep.section = user_file.removesuffix(".py")
        rep.state = None  # Variables.py / Includes.py belong to the machine, not to a state
    src_dir = source_dir_of(fname)
    rep.line = user_line
    if src_dir:
        path = os.path.join(src_dir, user_file)
        rep.file = _display(path)
        text = linecache.getline(path, user_line) if os.path.exists(path) else ""
        rep.text = text.strip() or linecache.getline(fname, lineno).strip() or None
    else:
        rep.file = user_file
        rep.text = linecache.getline(fname, lineno).strip() or None
    if rep.machine is None and src_dir:
        base = os.path.basename(src_dir.rstrip("/"))
        rep.machine = base.removesuffix(".machine")
    return rep
