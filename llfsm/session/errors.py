"""How a session ends: `SessionError` and its kinds (what went wrong, with the exit status), and
`RunOutcome` (how a run that started ended).  The command line (llfsm.cli._run) prints them,
byte for byte as `llfsm run` always has; a test opens a session and reads them instead.
"""

from __future__ import annotations

from ..runtime.scheduler import EXIT_ERROR, EXIT_USAGE

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from typing import Any

    from ..runtime.errors import ErrorReport
    from ..runtime.scheduler import RunResult


# -- what goes wrong ------------------------------------------------------------------------------
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


class RunOutcome:
    """How a session ended, for the command line to report: the run's result, the outputs that
    could not be written whole, and the graph (`--introspect`).  (A plain class: dataclasses
    would cost a run's start-up.)"""

    def __init__(
        self,
        result: RunResult,
        failed_outputs: list[str],
        bag_error: str | None = None,
        graph: dict[str, Any] | None = None,
    ) -> None:
        self.result = result
        #: Messages about named outputs (`--trace`, `--image`) not written whole.
        self.failed_outputs = failed_outputs
        #: Why the recorded bag failed (it was reported when it happened), or None.
        self.bag_error = bag_error
        #: The bus's nodes, topics and services after the run, when `--introspect` asked.
        self.graph = graph

    @property
    def status(self) -> int:
        """The exit status: the run's own, or 1 when it succeeded but lost an output (a named
        output that could not be written whole is an error, never a silent success)."""
        if self.result.status or not (self.failed_outputs or self.bag_error):
            return self.result.status
        return EXIT_ERROR
