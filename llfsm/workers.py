"""Worker processes that never outlive the command that started them.

Light (os, signal, threading; ctypes in the worker): any command that forks a ProcessPoolExecutor (`llfsm check -j`,
a parallel build) passes `die_with_parent` as the pool's initializer and bounds its workers
by `usable_cores()`.
"""

from __future__ import annotations

import os
import signal
import threading
import time


def usable_cores() -> int:
    """The cores this process may run on (its affinity mask, as `taskset` or a container's
    cpuset sets it), not the machine's count."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


def die_with_parent(parent: int, signum: int | None = None) -> None:
    """Worker initializer: end this worker when the command that forked it ends, however it ends.

    A worker forked by ProcessPoolExecutor waits on a pipe whose writing end it inherited
    itself, so a parent killed by SIGKILL (or the OOM killer) would leave it waiting forever.
    Linux ends it by PR_SET_PDEATHSIG (`signum`, SIGKILL unless given: a build's workers ask
    for SIGTERM, which they hold back until the module they write is whole); elsewhere a
    thread watches for the parent's exit."""
    try:
        import ctypes  # deferred: optional (a Python may be built without it) and start-up (workers only)

        libc = ctypes.CDLL(None, use_errno=True)
        pr_set_pdeathsig = 1
        if libc.prctl(pr_set_pdeathsig, signal.SIGKILL if signum is None else signum, 0, 0, 0) != 0:
            raise OSError(ctypes.get_errno(), "prctl")
        watch = False
    except (OSError, AttributeError, ImportError):
        watch = True
    if os.getppid() != parent:  # the parent died before the signal was asked for
        os._exit(1)
    if watch:

        def watchdog() -> None:
            while os.getppid() == parent:
                time.sleep(0.5)
            os._exit(1)

        threading.Thread(target=watchdog, daemon=True, name="llfsm-parent-watch").start()
