"""The session of one `llfsm run` (docs/cli.md, `llfsm run`): its options, everything that opens beside
the machines, opened in one place, in one order, and closed whatever happens.

- `RunOptions`: the options of `llfsm run` as one frozen value; both parsers build it (the
  click command, llfsm.cli.run, and the start-up fast path, llfsm.cli.run_args, from the same
  table of options: its fields are that table's keywords).  Defaults are those of `llfsm run`
  given no option, so a test names only what it changes:
  `RunOptions(("hello.machine",), clock="sim", duration=2_000_000_000)`.
- `Session`: loads the machines and opens the rest, in this order:
  1. the options are checked (`Session(...)`: before anything is loaded);
  2. the machines are loaded (a machine that fails validation is reported before anything opens);
  3. the outputs and the web address are checked (a usage error still costs nothing);
  4. the watchdog starts (llfsm.runtime.watchdog): with the machines loaded and before any of
     the below starts a thread;
  5. the transport, the bags (a bad bag to play must fail before a bag to record is created),
     the bus with its remaps, parameters and `--echo` readers, the `--node` nodes, and the
     bags' taps on it (set up before any machine runs, so that turtle1 exists and no message
     is missed); the `--trace` file and the tracer;
  6. the arrangement, the machines' state topics and control services (docs/view.md: with the bus,
     now if it is up, else at its first `ros.init()`), the web view (docs/view.md);
  7. the run; then, whatever happened: the web view stops, the trace file and the bag are
     closed, a transport the run never used is closed, and the watchdog ends.
- `SessionError` and its kinds: what a session raises instead of ending the process, so that a
  test can open one, see what went wrong and carry on; llfsm.cli._run prints them and exits
  with their status (docs/cli.md, "Exit statuses": 1 for an error in machine code or a lost output, 2 for bad input),
  byte for byte as `llfsm run` always has.

Start-up: one module, and plain classes rather than dataclasses (`dataclasses` imports
`inspect`, a fifth of a warm run's start-up; bench/run.py startup measures it).  A plain run
(no bus, no bag, no page) imports none of the bus, the messages, the bags, the nodes or the web
view: those imports sit in the steps that open them, and say so.  The other verbs never import
this module (the click command imports it when it runs).  The web view is a layer above the
session (llfsm.web): the command line hands it in as a `WebPage`, so the session names no
module of it.

The package: options.py (`RunOptions`, `FIELDS`), errors.py (`SessionError` and its kinds,
`RunOutcome`), run.py (`Session`); every name is imported from here.
"""

from .errors import MachineFailed, OutputFailed, RunOutcome, SessionError, UsageError
from .options import FIELDS, RunOptions
from .run import Session

TYPE_CHECKING = False  # not typing's own: importing typing would cost every run's start-up
if TYPE_CHECKING:
    from .run import Stoppable, WebPage

__all__ = [
    "FIELDS",
    "MachineFailed",
    "OutputFailed",
    "RunOptions",
    "RunOutcome",
    "Session",
    "SessionError",
    "Stoppable",
    "UsageError",
    "WebPage",
]
