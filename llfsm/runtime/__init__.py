"""What generated machine modules import, and what `llfsm run` drives.

This package must stay light: it imports nothing from the compiler side (pydantic, yaml,
jinja2), so that running a machine does not pay for compiling one.
"""

import os as _os
import sys as _sys

_native = _os.environ.get("LLFSM_NATIVE")
if _native:  # a native build (`llfsm run --native`): its compiled runtime modules come first
    __path__.insert(0, _os.path.join(_native, "llfsm", "runtime"))
    _sys.path.insert(0, _native)

# ruff: noqa: E402 (the imports come after the native build is in place)
from .clock import Clock, SimClock, WallClock, parse_duration
from .context import RunContext, current
from .errors import ErrorReport, report_for
from .machine import FINISHED, MACROS, RESERVED, Machine, UnknownMachineError
from .scheduler import Arrangement, ArrangementError, RunResult
from .signals import signals_handled
from .trace import Tracer

__all__ = [
    "FINISHED",
    "MACROS",
    "RESERVED",
    "Arrangement",
    "ArrangementError",
    "Clock",
    "ErrorReport",
    "Machine",
    "RunContext",
    "RunResult",
    "SimClock",
    "Tracer",
    "UnknownMachineError",
    "WallClock",
    "current",
    "parse_duration",
    "report_for",
    "signals_handled",
]
