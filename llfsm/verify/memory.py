"""How much memory an exploration may use (SPEC 18; docs/verify.md, "Limits"): `--max-memory
SIZE`, by default half of what this process may use, its own limits included: the smallest of
the machine's memory, the cgroup's limit (v2 `memory.max`, v1 `memory.limit_in_bytes`) and
RLIMIT_AS / RLIMIT_DATA.  The exploration looks at most every MAX_GAP new configurations (a
read of /proc/self/statm, a few microseconds), sooner as the configurations grow: the next look
comes before the memory they have been taking per configuration could use half of the room left
(`Meter.next_look`), so that a value growing megabytes a step (a list, a blob) is stopped near
the bound, not hundreds of configurations past it.  Then it stops like the state limit: status 3."""

from __future__ import annotations

import os
import re
import resource

_SIZE = re.compile(r"\s*([0-9]+(?:\.[0-9]*)?)\s*([kmgt]?i?b?)\s*", re.IGNORECASE)
_SCALE = {"": 1, "b": 1, "k": 1e3, "m": 1e6, "g": 1e9, "t": 1e12, "ki": 1 << 10, "mi": 1 << 20, "gi": 1 << 30}
_SCALE["ti"] = 1 << 40


def parse_size(text: str) -> int:
    """`200MB`, `2GiB`, `1.5G`, `500000000` -> bytes (ValueError otherwise)."""
    m = _SIZE.fullmatch(text)
    if m is None:
        raise ValueError(f"not a size: {text!r} (write 200MB, 2GB or 1GiB)")
    unit = m.group(2).lower().rstrip("b")
    if unit not in _SCALE:
        raise ValueError(f"not a size: {text!r} (write 200MB, 2GB or 1GiB)")
    value = int(float(m.group(1)) * _SCALE[unit])
    if value <= 0:
        raise ValueError(f"not a size: {text!r} (more than 0 bytes)")
    return value


def size_text(n: float) -> str:
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{int(n)} bytes"


def _cgroup_limit() -> int | None:
    for path in ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"):
        try:
            with open(path, encoding="ascii") as f:
                text = f.read().strip()
        except OSError:
            continue
        if text.isdigit() and int(text) < 1 << 60:
            return int(text)
    return None


def _address_limit() -> int | None:
    limits = []
    for which in (resource.RLIMIT_AS, resource.RLIMIT_DATA):
        soft, _hard = resource.getrlimit(which)
        if soft != resource.RLIM_INFINITY:
            limits.append(soft)
    return min(limits) if limits else None


def may_use() -> int:
    """What this process may use: the smallest of the machine's memory and its limits."""
    candidates = [os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")]
    for limit in (_cgroup_limit(), _address_limit()):
        if limit is not None:
            candidates.append(limit)
    return min(candidates)


def default_bound() -> int:
    return may_use() // 2


#: New configurations between two looks at the memory in use, at most.
MAX_GAP = 256


class Meter:
    """Whether the process stays within `bound` bytes of memory in use (resident), and, under an
    address-space limit, within three quarters of it (the address space runs out first)."""

    def __init__(self, bound: int) -> None:
        self.bound = bound
        self.page = os.sysconf("SC_PAGE_SIZE")
        limit = _address_limit()
        self.address = None if limit is None else limit * 3 // 4
        self.used = 0
        self.size = 0  # the address space in use at the last look
        self.ok()
        self._last = (0, self.used)  # (configurations, bytes in use) at the last look

    def ok(self) -> bool:
        try:
            with open("/proc/self/statm", encoding="ascii") as f:
                size, resident = (int(x) * self.page for x in f.read().split()[:2])
        except (OSError, ValueError):
            size = resident = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
        self.used, self.size = resident, size
        return resident < self.bound and (self.address is None or size < self.address)

    def next_look(self, count: int) -> int:
        """After a look (`ok`) at `count` configurations: the count at which to look again.  At
        most twice as far on as the last look was from the one before (configurations that grow
        grow faster: a value longer by a step each step takes memory in the square of the
        steps), at most MAX_GAP, and near enough that at the rate memory grew since the last
        look at most half of the room left is used before then."""
        last_count, last_used = self._last
        self._last = (count, self.used)
        gap = count - last_count
        if gap <= 0:
            return count + 1
        per = (self.used - last_used) / gap
        nxt = min(2 * gap, MAX_GAP)
        if per > 0:
            room = self.bound - self.used
            if self.address is not None:
                room = min(room, self.address - self.size)
            nxt = min(nxt, int(room / (2 * per)))
        return count + max(1, nxt)
