"""Cache folders llfsm may trust, and the private fallback under the temporary folder.

Both caches (compiled machines, compiled interface packages) hold Python modules that llfsm
imports, so whoever can write a cache folder can make llfsm run their code.  A folder is used
only if it is a real directory (not a symbolic link, checked with lstat), owned by the user
running llfsm, and not writable by group or others.  The usual cache (~/.cache/llfsm, or
LLFSM_CACHE_DIR / XDG_CACHE_HOME) is used when it passes; when it cannot be written, the
fallback is TMPDIR/llfsm-cache-UID, created 0700; when that exists but fails the rule (another
user made it first, or opened it up), a fresh private folder (mkdtemp, removed at exit) is used
for this run and a warning says why.

This module imports nothing from llfsm: the message import hook and a warm `llfsm run` use it,
and must stay light.
"""

from __future__ import annotations

import os
import stat
import sys

TYPE_CHECKING = False  # not typing's own: `llfsm run` imports this module, and typing costs its start-up
if TYPE_CHECKING:
    from pathlib import Path

_fresh: str | None = None
_warned: set[str] = set()


def preferred_root() -> str:
    """The usual cache folder: LLFSM_CACHE_DIR, else XDG_CACHE_HOME/llfsm, else ~/.cache/llfsm.
    (Whether it may be trusted is `cache_dir`'s to decide, folder by folder.)"""
    env = os.environ.get("LLFSM_CACHE_DIR")
    if env:
        return env
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "llfsm")


def cache_root() -> Path:
    """`preferred_root()` as a Path, for the commands that keep their own folders in the cache
    (native builds, the build's stat records)."""
    from pathlib import Path  # deferred: start-up (a warm `llfsm run` never needs pathlib)

    return Path(preferred_root())


def problem(path: str | os.PathLike[str], *, directory: bool = True) -> str | None:
    """Why `path` must not be trusted as part of a cache, or None when it may be."""
    try:
        st = os.lstat(path)
    except OSError as e:
        return e.strerror or str(e)
    if stat.S_ISLNK(st.st_mode):
        return "it is a symbolic link"
    if directory and not stat.S_ISDIR(st.st_mode):
        return "it is not a directory"
    if not directory and not stat.S_ISREG(st.st_mode):
        return "it is not a regular file"
    uid = os.getuid()
    if st.st_uid != uid:
        return f"it belongs to uid {st.st_uid}, not to you (uid {uid})"
    if st.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        return f"others can write to it (mode {stat.S_IMODE(st.st_mode):04o})"
    return None


def warn(path: str, why: str) -> None:
    if path not in _warned:
        _warned.add(path)
        sys.stderr.write(f"llfsm: warning: not using the cache {path}: {why}; using a private temporary folder\n")


def fresh_private() -> str:
    """A new 0700 folder for this process only, removed when it exits."""
    global _fresh
    if _fresh is None:
        # deferred: start-up (only a cache that cannot be trusted needs a private folder)
        import atexit
        import shutil
        import tempfile

        _fresh = tempfile.mkdtemp(prefix="llfsm-cache-")
        atexit.register(shutil.rmtree, _fresh, True)
    return _fresh


def _make(path: str) -> str | None:
    """Create `path` (0700) if missing; why it may not be used, or None."""
    try:
        os.mkdir(path, 0o700)
    except FileExistsError:
        pass
    except OSError as e:
        return e.strerror or str(e)
    return problem(path)


def fallback_root() -> str:
    """TMPDIR/llfsm-cache-UID when it is this user's private folder, else a fresh private one."""
    import tempfile  # deferred: start-up (only when the usual cache cannot be written)

    root = os.path.join(tempfile.gettempdir(), f"llfsm-cache-{os.getuid()}")
    why = _make(root)
    if why is None:
        return root
    warn(root, why)
    return fresh_private()


def cache_dir(preferred_root: str, key: str) -> str:
    """`preferred_root/key`, created if needed, when it can be written and trusted; otherwise the
    same key under the fallback root (each level checked again)."""
    preferred = os.path.join(preferred_root, key)
    try:
        os.makedirs(preferred_root, 0o700, exist_ok=True)
        # the root too: whoever can write there can swap our folder for theirs after the check
        # (a link the user made to put the cache elsewhere is followed: its target is checked)
        bad = os.path.realpath(preferred_root)
        why = problem(bad)
        if why is None:
            bad, why = preferred, _make(preferred)
        if why is None and os.access(preferred, os.W_OK):
            return preferred
        if why is not None and os.path.lexists(bad):
            warn(bad, why)  # it exists but is not ours to trust: say so, do not use it
    except OSError:
        pass  # cannot be created (read-only, no home): the fallback, quietly
    out = os.path.join(fallback_root(), key)
    why = _make(out)
    if why is None:
        return out
    warn(out, why)
    out = os.path.join(fresh_private(), key)
    os.makedirs(out, 0o700, exist_ok=True)
    return out
