"""Why a run could not start, or could not go on, as the user is to be told it.

The session raises these instead of ending the process itself, so that a test can open a
session, see what went wrong, and carry on; the command line (llfsm.cli._run) prints them and
exits with their status (SPEC §2: 1 for an error in machine code or a lost output, 2 for bad
input), byte for byte as `llfsm run` always has.
"""

from __future__ import annotations

from ..runtime.scheduler import EXIT_ERROR, EXIT_USAGE

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from ..runtime.errors import ErrorReport


class SessionError(Exception):
    """What to print, in order: `details` as is (a machine's diagnostics or error report, each
    line ending in a newline), then `message` on a line of its own after `llfsm: ` (when there
    is one); and the exit status."""

    status = EXIT_USAGE

    def __init__(self, message: str = "", *, details: str = "") -> None:
        super().__init__(message or details)
        self.message = message
        self.details = details


class UsageError(SessionError):
    """Bad input: an option, a machine that fails validation, a node or bag that cannot open."""

    status = EXIT_USAGE


class OutputFailed(SessionError):
    """A file the user named for output cannot be written (`--trace`): the run would lose it."""

    status = EXIT_ERROR


class MachineFailed(SessionError):
    """Machine code raised before the run began (importing its module, a variable's initial
    value): the report says where, as the user wrote it."""

    status = EXIT_ERROR

    def __init__(self, report: ErrorReport) -> None:
        super().__init__(details=report.format())
        self.report = report
