"""A machine's diagram as SVG, on the boxes llfsm.diagram.layout places (no Graphviz, nothing
fetched): the web view's diagrams.

Edges: downward ones are vertical S-curves; upward ones (loops back) swing round the right
of everything they pass; same-layer ones dip below; a self-transition is a small loop.  Each
carries `index: guard`, the guard text as written in the machine's files.

Every state is a `<g class="state" data-machine=M data-state=S aria-current=...>`: the page
moves `aria-current="true"` to the current state, and tests find states by these attributes.

Descriptions may come from any peer on a DDS domain (`llfsm view`), so (issue 18):

- a description is checked against llfsm.diagram.description before anything is drawn (an
  index is an integer, targets name states...), and every text in it is escaped, attributes
  included, with characters XML cannot carry replaced: nothing of a peer's making becomes markup;
- the layout is quadratic in the edges, so what is drawn is bounded (`MAX_DRAWN_STATES`,
  `MAX_DRAWN_TRANSITIONS`: the states nearest the initial one first) and the diagram says what
  it left out;
- the SVG is cached per description (its content, not its object: a latched description
  delivered again is not laid out again), drawn once without a current state, which is marked
  afterwards by a string replacement of an attribute this module alone writes.
"""

from __future__ import annotations

import hashlib
import json
import re
import threading
from collections import OrderedDict
from html import escape
from typing import Any

from .layout import MARGIN, NODE_H, layout

LABEL_CHAR_W = 6.4  # of the 11 px guard labels
LABEL_MAX = 34  # characters of guard text shown on an arrow (the whole text is in its tooltip)
#: At most this many states are drawn (a few dozen is what a diagram can show anyway).
MAX_DRAWN_STATES = 60
#: At most this many transitions are drawn (labels are placed in time quadratic in them).
MAX_DRAWN_TRANSITIONS = 160
#: Descriptions whose drawing is kept.
CACHE_SIZE = 32
TITLE_MAX = 400  # characters of guard text in a transition's tooltip

#: What XML 1.0 cannot carry (control characters, lone surrogates): the page's parser would
#: refuse the whole diagram.
_NOT_XML = re.compile("[^\t\n\r\x20-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")
_cache: OrderedDict[bytes, str] = OrderedDict()
_cache_lock = threading.Lock()


def _esc(text: object) -> str:
    """Text of any origin, safe in element content and in a double-quoted attribute."""
    return escape(_NOT_XML.sub("\ufffd", str(text)), quote=True)


def _label(index: int, guard: str) -> str:
    text = " ".join(guard.split())
    if len(text) > LABEL_MAX:
        text = text[: LABEL_MAX - 1] + "…"
    return f"{index}: {text}"


def _bezier_mid(
    p0: tuple[float, float], c1: tuple[float, float], c2: tuple[float, float], p3: tuple[float, float]
) -> tuple[float, ...]:
    return tuple(0.125 * a + 0.375 * b + 0.375 * c + 0.125 * d for a, b, c, d in zip(p0, c1, c2, p3, strict=True))


def svg(desc: dict[str, Any], current: str | None = None) -> str:
    """The diagram of one machine (the `description` structure of llfsm.ros.control), its
    `current` state marked.  A description that does not fit llfsm.diagram.description raises
    its DescriptionError before anything is drawn."""
    key = _key(desc)
    with _cache_lock:
        drawn = None
        if key is not None:
            drawn = _cache.get(key)
            if drawn is not None:
                _cache.move_to_end(key)
    if drawn is None:
        # deferred: pydantic is imported when a diagram is first drawn (on the drawing thread), not with --web
        from .description import validate

        drawn = _render(validate(desc))
        if key is not None:
            with _cache_lock:
                _cache[key] = drawn
                while len(_cache) > CACHE_SIZE:
                    _cache.popitem(last=False)
    return mark(drawn, current)


def mark(drawn: str, current: str | None) -> str:
    """A diagram of `svg` with its `current` state marked (it is drawn with none marked)."""
    if current is None:
        return drawn
    # only this module writes `data-state="..." aria-current=`, and escaped text holds no quote
    attr = f'data-state="{_esc(current)}" aria-current='
    return drawn.replace(attr + '"false"', attr + '"true"', 1)


def _key(desc: Any) -> bytes | None:
    """A digest of the description's content (None if it is not even JSON: never cached)."""
    try:
        text = json.dumps(desc, sort_keys=True, separators=(",", ":"))
    except (TypeError, ValueError, RecursionError):
        return None
    return hashlib.sha256(text.encode("utf-8", "surrogatepass")).digest()


def _select(desc: dict[str, Any]) -> tuple[dict[str, Any], int, int]:
    """The part of a checked description that is drawn, and how many states and transitions
    are left out: the states nearest the initial one (breadth first, then the rest in order),
    the suspend state always, and the transitions between them in order, each within bounds."""
    states = desc["states"]
    total_t = sum(len(s["transitions"]) for s in states)
    if len(states) <= MAX_DRAWN_STATES and total_t <= MAX_DRAWN_TRANSITIONS:
        return desc, 0, 0
    by_name = {s["name"]: s for s in states}
    order: dict[str, None] = {desc["initial"]: None}
    frontier = [desc["initial"]]
    while frontier and len(order) < MAX_DRAWN_STATES:
        nxt = []
        for name in frontier:
            for t in by_name[name]["transitions"]:
                if t["target"] not in order:
                    order[t["target"]] = None
                    nxt.append(t["target"])
        frontier = nxt
    for s in states:
        if len(order) >= MAX_DRAWN_STATES:
            break
        order.setdefault(s["name"], None)
    chosen = list(order)[:MAX_DRAWN_STATES]
    suspend = desc.get("suspend")
    if suspend is not None and suspend not in chosen:
        chosen[-1] = suspend
    keep = set(chosen)
    budget = MAX_DRAWN_TRANSITIONS
    drawn_states = []
    for s in states:
        if s["name"] not in keep:
            continue
        ts = [t for t in s["transitions"] if t["target"] in keep][: max(0, budget)]
        budget -= len(ts)
        drawn_states.append({**s, "transitions": ts})
    drawn_t = MAX_DRAWN_TRANSITIONS - max(0, budget)
    return {**desc, "states": drawn_states}, len(states) - len(drawn_states), total_t - drawn_t


def _render(full: dict[str, Any]) -> str:
    """The SVG of a checked description, no state marked current."""
    desc, left_states, left_transitions = _select(full)
    machine = desc["name"]
    boxes, width, height = layout(desc)
    mid = _esc(machine)
    marker = "arrow-" + hashlib.sha256(machine.encode("utf-8", "surrogatepass")).hexdigest()[:12]
    parts: list[str] = []
    right_extent = width
    left_extent = 0.0
    placed: list[tuple[float, float, float]] = []  # guard labels: centre x, centre y, width
    edges: list[str] = []
    labels: list[str] = []
    pair_count: dict[tuple[str, str], int] = {}
    up_count = 0
    for s in desc["states"]:
        src = boxes[s["name"]]
        n_out = len(s["transitions"])
        for k, t in enumerate(s["transitions"]):
            dst = boxes.get(t["target"])
            if dst is None:
                continue
            key = (src.name, dst.name)
            dup = pair_count.get(key, 0)
            pair_count[key] = dup + 1
            spread = (k - (n_out - 1) / 2) * 12
            if dst is src:
                x0, y0 = src.right, src.mid - 8
                x1, y1 = src.right, src.mid + 8
                c1, c2 = (x0 + 44 + dup * 14, y0 - 22), (x1 + 44 + dup * 14, y1 + 22)
                right_extent = max(right_extent, x0 + 60 + dup * 14)
            elif dst.layer > src.layer:
                x0, y0 = src.x + spread, src.bottom
                x1, y1 = dst.x + dup * 10, dst.y
                dy = (y1 - y0) / 2
                c1, c2 = (x0, y0 + dy), (x1, y1 - dy)
            elif dst.layer == src.layer:
                x0, y0 = src.x + spread, src.bottom
                x1, y1 = dst.x + dup * 10, dst.bottom
                c1, c2 = (x0, y0 + 40 + dup * 10), (x1, y1 + 40 + dup * 10)
            else:  # back up: round the side where the target is open (the ends of its layer)
                between = [b for b in boxes.values() if dst.layer <= b.layer <= src.layer]
                row = sorted((b for b in boxes.values() if b.layer == dst.layer), key=lambda b: b.x)
                if row[0] is dst and row[-1] is not dst:
                    swing = min(b.left for b in between) - 40 - up_count * 18
                    x0, x1 = src.left, dst.left
                    left_extent = min(left_extent, swing - 20)
                else:
                    swing = max(b.right for b in between) + 40 + up_count * 18
                    x0, x1 = src.right, dst.right
                    right_extent = max(right_extent, swing + 20)
                up_count += 1
                y0, y1 = src.mid + (spread / 3), dst.mid + dup * 6
                c1, c2 = (swing, y0), (swing, y1)
            d = f"M{x0:.1f} {y0:.1f} C{c1[0]:.1f} {c1[1]:.1f} {c2[0]:.1f} {c2[1]:.1f} {x1:.1f} {y1:.1f}"
            guard, index = t["guard"], int(t["index"])
            shown = guard if len(guard) <= TITLE_MAX else guard[: TITLE_MAX - 1] + "…"
            title = _esc(f"{s['name']} → {t['target']} (transition {index}): {shown}")
            edges.append(
                f'<path class="transition" data-machine="{mid}" data-source="{_esc(s["name"])}" '
                f'data-target="{_esc(t["target"])}" data-index="{index:d}" d="{d}" '
                f'marker-end="url(#{marker})"><title>{title}</title></path>'
            )
            lx, ly = _bezier_mid((x0, y0), c1, c2, (x1, y1))
            text = _label(index, guard) if guard else str(index)
            tw = LABEL_CHAR_W * len(text) + 8
            for _ in range(8):  # step down past labels already placed (or past a state)
                hit = any(abs(lx - ox) < (tw + ow) / 2 + 2 and abs(ly - oy) < 17 for ox, oy, ow in placed) or any(
                    b.left - tw / 2 < lx < b.right + tw / 2 and b.y - 9 < ly < b.bottom + 9 for b in boxes.values()
                )
                if not hit:
                    break
                ly += 17
            placed.append((lx, ly, tw))
            right_extent = max(right_extent, lx + tw / 2 + 4)
            left_extent = min(left_extent, lx - tw / 2 - 4)
            labels.append(
                f'<g class="guard"><title>{title}</title>'
                f'<rect x="{lx - tw / 2:.1f}" y="{ly - 8:.1f}" width="{tw:.1f}" height="16" rx="3"/>'
                f'<text x="{lx:.1f}" y="{ly + 4:.1f}">{_esc(text)}</text></g>'
            )
    init = boxes.get(desc["initial"])
    if init is not None:
        edges.append(
            f'<circle class="initial-dot" cx="{init.x:.1f}" cy="{init.y - 26:.1f}" r="5"/>'
            f'<path class="transition initial" d="M{init.x:.1f} {init.y - 21:.1f} L{init.x:.1f} {init.y:.1f}" '
            f'marker-end="url(#{marker})"/>'
        )
    accepting = {s["name"] for s in desc["states"] if s.get("accepting")}
    for s in desc["states"]:
        b = boxes[s["name"]]
        name = s["name"]
        kind = ["state"]
        if name == desc.get("suspend"):
            kind.append("suspend-state")
        if name in accepting:
            kind.append("accepting")
        if name == desc["initial"]:
            kind.append("initial-state")
        inner = ""
        if name in accepting:
            inner = (
                f'<rect class="inner" x="{b.left + 4:.1f}" y="{b.y + 4:.1f}" width="{b.w - 8:.1f}" '
                f'height="{NODE_H - 8}" rx="7"/>'
            )
        parts.append(
            f'<g class="{" ".join(kind)}" data-machine="{mid}" data-state="{_esc(name)}" '
            f'aria-current="false" role="listitem" aria-label="state {_esc(name)}">'
            f'<rect x="{b.left:.1f}" y="{b.y:.1f}" width="{b.w:.1f}" height="{NODE_H}" rx="10"/>{inner}'
            f'<text x="{b.x:.1f}" y="{b.mid + 4.5:.1f}">{_esc(name)}</text></g>'
        )
    x0 = min(0.0, left_extent - MARGIN / 2)
    w = right_extent + MARGIN / 2 - x0
    height = max([height] + [ly + 12 for _, ly, _ in placed])
    note = ""
    if left_states or left_transitions:
        what = [f"{left_states:,} more states"] if left_states else []
        what += [f"{left_transitions:,} more transitions"] if left_transitions else []
        lines = [
            f"{' and '.join(what)} not drawn",
            f"(a diagram shows at most {MAX_DRAWN_STATES} states and {MAX_DRAWN_TRANSITIONS} transitions)",
        ]
        w = max(w, LABEL_CHAR_W * 1.1 * max(map(len, lines)) + MARGIN)
        note = "".join(
            f'<text class="omitted" x="{x0 + MARGIN / 2:.1f}" y="{height + 14 + 16 * i:.1f}">{_esc(line)}</text>'
            for i, line in enumerate(lines)
        )
        height += 44
    return (
        f'<svg xmlns="http://www.w3.org/2000/svg" class="diagram" data-machine="{mid}" '
        f'viewBox="{x0:.0f} 0 {w:.0f} {height:.0f}" width="{w:.0f}" height="{height:.0f}" role="list" '
        f'aria-label="states of {mid}">'
        f'<defs><marker id="{marker}" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="7" markerHeight="7" '
        f'orient="auto-start-reverse"><path d="M0 0 L10 5 L0 10 z" class="arrowhead"/></marker></defs>'
        f'<g class="edges">{"".join(edges)}</g><g class="states">{"".join(parts)}</g>'
        f'<g class="labels">{"".join(labels)}</g>{note}</svg>'
    )
