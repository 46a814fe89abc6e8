"""How a command ends, without click: exit statuses, `fail`, `echo`, what becomes of an exception
that escapes a command (a closed pipe, a full disk, an llfsm bug); and `duration_ns`, which both
parsers of `llfsm run`'s options use.

Kept free of click (and of everything else heavy) because `llfsm run`'s fast path
(llfsm.cli.main) runs a machine without importing click at all; the click commands use the
same functions, so a message reads the same whichever way it was reached.
"""

from __future__ import annotations

import errno
import os
import sys

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from collections.abc import Callable
    from typing import NoReturn

EXIT_OK, EXIT_ERRORS, EXIT_USAGE = 0, 1, 2
#: The longest duration accepted (100 years): run-time arithmetic stays in 64-bit nanoseconds.
MAX_DURATION_NS = 100 * 365 * 24 * 3600 * 1_000_000_000
#: Exit status of a command that ended because of an llfsm bug (BSD's EX_SOFTWARE).
EXIT_INTERNAL = 70


def echo(text: str = "", nl: bool = True, err: bool = True) -> None:
    """Write a line to stderr (or stdout) and flush it, as click.echo does for plain text."""
    stream = sys.stderr if err else sys.stdout
    stream.write(text + "\n" if nl else text)
    stream.flush()


def fail(message: str, status: int = EXIT_USAGE) -> NoReturn:
    echo(f"llfsm: {message}")
    sys.exit(status)


def duration_ns(text: str) -> int:
    """Seconds (`0.5`) or a number with a unit (`500ms`, `2s`), as nanoseconds; ValueError with
    the message to show when the text is not a duration, or one longer than 100 years."""
    from ..runtime.clock import parse_duration  # deferred: start-up (llfsm.runtime loads the scheduler)

    try:
        ns = parse_duration(text)
    except OverflowError:  # 1e308min: finite as a number, infinite in nanoseconds
        ns = MAX_DURATION_NS + 1
    if ns > MAX_DURATION_NS:
        raise ValueError(f"{text}: too long (at most 100 years)")
    return ns


def _quiet_broken_pipe() -> NoReturn:
    """Our reader went away (`llfsm run ... | head -1`): end quietly, as `cat` would."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    for stream in (sys.stdout, sys.stderr):
        try:
            os.dup2(devnull, stream.fileno())  # later flushes (and interpreter exit) write nowhere
        except (OSError, ValueError):
            pass
    sys.exit(EXIT_OK)


#: Errors that only a write can get: the output (stdout) could not be written.
_OUTPUT_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EIO})


def _output_failed(e: OSError) -> NoReturn:
    """One line on stderr, status 1; what is still buffered for stdout is dropped, so that
    Python's exit does not fail on it a second time."""
    try:
        os.write(2, f"llfsm: cannot write the output: {e.strerror or e}\n".encode())
    except OSError:
        pass
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass
    sys.exit(EXIT_ERRORS)


def output_errors(e: OSError) -> None:
    """A closed pipe ends quietly, a full disk under stdout is one line and status 1; any
    other OSError returns (for the caller to re-raise)."""
    if isinstance(e, BrokenPipeError):
        _quiet_broken_pipe()
    if e.errno in _OUTPUT_ERRNOS:  # stdout on a full disk, /dev/full: not an llfsm bug
        _output_failed(e)


def internal_error(exc: Exception) -> NoReturn:
    """An llfsm bug: say so plainly (a traceback with LLFSM_DEBUG=1)."""
    if os.environ.get("LLFSM_DEBUG"):
        raise exc
    echo(f"llfsm: internal error: {type(exc).__name__}: {exc} (set LLFSM_DEBUG=1 for a traceback)")
    sys.exit(EXIT_INTERNAL)


def run_guarded(command: Callable[[], object]) -> None:
    """Run a command so that whatever escapes it ends in a message and an exit status, never a
    traceback: the fast path of `llfsm run`, and every click command (llfsm.cli._commands.main),
    so that both say the same."""
    try:
        try:
            command()
        except OSError as e:  # what _Group.invoke does for a click command
            output_errors(e)
            raise
        except (EOFError, KeyboardInterrupt):  # what click's main does: a newline, then Abort
            echo()
            sys.exit(130)
    except BrokenPipeError:
        _quiet_broken_pipe()
    except KeyboardInterrupt:  # a second one, while the newline was written
        sys.exit(130)
    except SystemExit:
        raise
    except Exception as exc:
        internal_error(exc)
