"""The `llfsm` command and `python -m llfsm`.

Kept apart from `llfsm.cli` so that nothing heavy is imported yet when it starts: a Ctrl-C
that lands while click, pydantic and the rest are still importing (the first tenth of a
second of every command) ends with status 130 and no output, exactly as one that lands later,
instead of a KeyboardInterrupt traceback.

Two things are settled here, before anything else is imported:
- `python -m llfsm` puts the current folder first on sys.path (unless `-P` / PYTHONSAFEPATH),
  so a `yaml.py` in a repository being checked would run in place of pyyaml.  llfsm's own
  modules are found through the package's `__path__`, so that entry is simply dropped.
- A standard stream that is closed (`llfsm run ... >&-`) has its file descriptor taken by
  /dev/null, so that no file opened later (a `--trace` file) gets number 1 or 2 and receives
  what was meant for the terminal; a closed stdout is then reported as a usage error.
"""

import os
import sys


def _drop_current_folder() -> None:
    """Remove what `-m` put at sys.path[0] (the current folder), unless -P already did not."""
    if getattr(sys.flags, "safe_path", False) or not sys.path:
        return
    first = sys.path[0]
    try:
        here = first == "" or os.path.samefile(first, os.getcwd())
    except OSError:
        here = False
    if here:
        del sys.path[0]
        # llfsm itself run from a checkout without being installed: keep it importable (by
        # worker processes too), but after every installed library, never before them
        if os.path.dirname(os.path.dirname(os.path.abspath(__file__))) == os.path.abspath(first or "."):
            sys.path.append(first)


if __name__ == "__main__":
    _drop_current_folder()


def _closed_standard_streams() -> list[int]:
    """Which of fds 0, 1, 2 are closed; each is reopened on /dev/null to hold its number."""
    closed = []
    for fd in (0, 1, 2):
        try:
            os.fstat(fd)
        except OSError:
            closed.append(fd)
    for fd in closed:
        devnull = os.open(os.devnull, os.O_RDWR)
        if devnull != fd:
            os.dup2(devnull, fd)
            os.close(devnull)
    return closed


def main() -> None:
    closed = _closed_standard_streams()
    if 1 in closed:
        # stdout was closed before we started (`>&-`): the output has nowhere to go.  Say so
        # on stderr (if that is open) rather than fail half-way or pretend it was written.
        if 2 not in closed:
            os.write(2, b"llfsm: standard output is closed; to discard the output, use >/dev/null\n")
        sys.exit(2)
    # deferred: start-up (nothing heavy until here, so a Ctrl-C while click loads ends with 130)
    try:
        from llfsm.cli import main as run_cli
    except KeyboardInterrupt:
        sys.exit(130)
    run_cli()


if __name__ == "__main__":
    main()
