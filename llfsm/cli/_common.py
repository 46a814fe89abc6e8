"""What every command shares: the group, `fail`, durations, a closed pipe.

Each command imports what it needs when it runs: `llfsm run` must start fast and never load
the compiler's libraries when its cached modules are fresh.  Every failure the user can cause
ends in a one-line-per-problem message and an exit status (1 or 2), never a traceback.
"""

from __future__ import annotations

import contextlib
import errno
import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING, NoReturn

import click

from .. import __version__

if TYPE_CHECKING:
    pass

EXIT_OK, EXIT_ERRORS, EXIT_USAGE = 0, 1, 2
#: The longest duration accepted (100 years): run-time arithmetic stays in 64-bit nanoseconds.
MAX_DURATION_NS = 100 * 365 * 24 * 3600 * 1_000_000_000


def fail(message: str, status: int = EXIT_USAGE) -> NoReturn:
    click.echo(f"llfsm: {message}", err=True)
    sys.exit(status)


class Duration(click.ParamType):
    """Seconds (`0.5`) or a number with a unit (`500ms`, `2s`), as nanoseconds."""

    name = "duration"

    def convert(self, value: object, param: click.Parameter | None, ctx: click.Context | None) -> int:
        if isinstance(value, int):
            return value
        from ..runtime.clock import parse_duration

        try:
            ns = parse_duration(str(value))
        except ValueError as e:
            self.fail(str(e), param, ctx)
        except OverflowError:  # 1e308min: finite as a number, infinite in nanoseconds
            ns = MAX_DURATION_NS + 1
        if ns > MAX_DURATION_NS:
            self.fail(f"{value}: too long (at most 100 years)", param, ctx)
        return ns


DURATION = Duration()


def write_output(path: str, data: bytes, what: str) -> None:
    """Write a file the user named (`-o FILE`) through llfsm.outputs: atomically, and one clear
    line with exit status 1 if it cannot be written (full disk, /proc, a directory)."""
    from ..outputs import OutputError, write_file

    try:
        write_file(path, data, what=what, mkdirs=True)
    except OutputError as e:
        fail(f"{e}", EXIT_ERRORS)


def progress(text: str) -> None:
    """A progress line on stderr that cannot stop the work: when its reader has gone
    (`llfsm build 2>&1 | head -1`), later lines go nowhere and the work goes on to its end,
    so the exit status still says whether it succeeded."""
    try:
        click.echo(text, nl=False, err=True)
    except (BrokenPipeError, ValueError):
        devnull = os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(devnull, sys.stderr.fileno())
        except (OSError, ValueError):
            pass
        finally:
            os.close(devnull)


def _quiet_broken_pipe() -> NoReturn:
    """Our reader went away (`llfsm run ... | head -1`): end quietly, as `cat` would."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    for stream in (sys.stdout, sys.stderr):
        try:
            os.dup2(devnull, stream.fileno())  # later flushes (and interpreter exit) write nowhere
        except (OSError, ValueError):
            pass
    sys.exit(EXIT_OK)


def _existing(paths: tuple[str, ...]) -> list[Path]:
    out = []
    for p in paths:
        path = Path(p)
        if not path.exists():
            fail(f"{p}: no such file or directory")
        if not path.is_dir():
            fail(f"{p}: not a machine directory or a folder of machines")
        out.append(path)
    return out


class _Group(click.Group):
    """Handles a closed pipe before click does: click would turn it into exit status 1."""

    def invoke(self, ctx: click.Context) -> object:
        try:
            return super().invoke(ctx)
        except BrokenPipeError:
            _quiet_broken_pipe()
        except OSError as e:
            if e.errno in _OUTPUT_ERRNOS:  # stdout on a full disk, /dev/full: not an llfsm bug
                _output_failed(e)
            raise


#: Errors that only a write can get: the output (stdout) could not be written.
_OUTPUT_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EIO})


def _output_failed(e: OSError) -> NoReturn:
    """One line on stderr, status 1; what is still buffered for stdout is dropped, so that
    Python's exit does not fail on it a second time."""
    with contextlib.suppress(OSError):
        os.write(2, f"llfsm: cannot write the output: {e.strerror or e}\n".encode())
    devnull = os.open(os.devnull, os.O_WRONLY)
    with contextlib.suppress(OSError, ValueError):
        os.dup2(devnull, sys.stdout.fileno())
    sys.exit(EXIT_ERRORS)


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="llfsm")
def cli() -> None:
    """Logic-labelled finite-state machines: check, build and run them."""
