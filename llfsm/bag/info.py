"""`llfsm bag info DIR`: what `ros2 bag info` prints, from the bag's metadata.yaml.

Layout as rosbag2_py's format_bag_metadata.cpp: labels padded to 19 columns, times in local
time (`%b %e %Y %H:%M:%S.nnnnnnnnn (seconds.nanoseconds)`), sizes in KiB/MiB with one decimal,
topics sorted by name, service event topics counted apart.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from .errors import BagError

INDENT = 19  # the longest label ("Topics with Type:") and a space, as rosbag2 has it


def read_metadata(path: str | Path) -> dict[str, Any]:
    """The rosbag2_bagfile_information of a bag folder."""
    import yaml

    folder = Path(path)
    if not folder.exists():
        raise BagError(f"{path}: no such bag")
    meta_path = folder / "metadata.yaml"
    if not meta_path.is_file():
        raise BagError(f"{path}: not a bag (no metadata.yaml in it)")
    try:
        doc = yaml.safe_load(meta_path.read_text(encoding="utf-8"))
        info = doc["rosbag2_bagfile_information"]
        if not isinstance(info, dict):
            raise TypeError("not a mapping")
        return info
    except (yaml.YAMLError, KeyError, TypeError, UnicodeDecodeError) as e:
        what = " ".join(str(e).split()) or type(e).__name__
        raise BagError(f"{meta_path}: not rosbag2 metadata ({what})") from None


def _nanos(value: Any, key: str) -> int:
    return int(value.get(key, 0)) if isinstance(value, dict) else 0


def _seconds(ns: int) -> str:
    s, frac = divmod(ns, 1_000_000_000)
    return f"{s}.{frac:09d}"


def _time_point(ns: int) -> str:
    s, frac = divmod(ns, 1_000_000_000)
    t = time.localtime(s)
    return f"{time.strftime('%b %e %Y', t)} {time.strftime('%H:%M:%S', t)}.{frac:09d} ({_seconds(ns)})"


def _size(n: int) -> str:
    units = ("B", "KiB", "MiB", "GiB", "TiB")
    size, i = float(n), 0
    while size >= 1024 and i < 4:
        size /= 1024
        i += 1
    return f"{size:.0f} {units[i]}" if i == 0 else f"{size:.1f} {units[i]}"


def _is_service_event(name: str, type_name: str) -> bool:
    return name.endswith("/_service_event") and type_name.endswith("_Event")


def format_info(path: str | Path) -> str:
    """`ros2 bag info` for the bag at path (its output, trailing newline included)."""
    meta = read_metadata(path)
    folder = Path(path)
    files = [str(f) for f in meta.get("relative_file_paths") or []]
    size = sum((folder / f).stat().st_size for f in files if (folder / f).is_file())
    start = _nanos(meta.get("starting_time"), "nanoseconds_since_epoch")
    duration = _nanos(meta.get("duration"), "nanoseconds")
    topics = []
    services = []
    for entry in meta.get("topics_with_message_count") or []:
        tm = entry.get("topic_metadata", {})
        item = (str(tm.get("name", "")), str(tm.get("type", "")), int(entry.get("message_count", 0)))
        item += (str(tm.get("serialization_format", "")),)
        (services if _is_service_event(item[0], item[1]) else topics).append(item)
    pad = " " * INDENT
    out = ["", "Files:             " + (f"\n{pad}".join(files))]
    out.append(f"Bag size:          {_size(size)}")
    out.append(f"Storage id:        {meta.get('storage_identifier', '')}")
    out.append(f"ROS Distro:        {meta.get('ros_distro') or 'unknown'}")
    out.append(f"Duration:          {_seconds(duration)}s")
    out.append(f"Start:             {_time_point(start)}")
    out.append(f"End:               {_time_point(start + duration)}")
    out.append(f"Messages:          {int(meta.get('message_count', 0)) - sum(s[2] for s in services)}")
    lines = [f"Topic: {n} | Type: {t} | Count: {c} | Serialization Format: {f}" for n, t, c, f in sorted(topics)]
    out.append("Topic information: " + f"\n{pad}".join(lines))
    out.append(f"Service:           {len(services)}")
    svc = [
        f"Service: {n[: -len('/_service_event')]} | Type: {t[: -len('_Event')]} | Event Count: {c} | "
        f"Serialization Format: {f}"
        for n, t, c, f in sorted(services)
    ]
    out.append("Service information: " + f"\n{pad}  ".join(svc))
    return "\n".join(out) + "\n"
