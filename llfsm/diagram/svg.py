"""A machine's diagram as SVG, laid out in layers by llfsm.diagram.layout (no Graphviz, nothing
fetched): the web view's diagrams (docs/view.md).

States are boxes in ranks from the initial state down; each transition runs beside its label
`index: guard` (the guard text as written in the machine's files), an edge that loops back runs
up against the flow, a self-transition is a loop at its state's right.  The suspend state is
drawn with what enters and leaves it: a dashed "any state" above it, `suspend` into it and
`resume` back (a machine is suspended from whatever state it is in, and resumes there).

Every state is a `<g class="state" data-machine=M data-state=S aria-current=...>`: the page
moves `aria-current="true"` to the current state, and tests find states by these attributes.

Descriptions may come from any peer on a DDS domain (`llfsm view`), so (issue 18):

- a description is checked against llfsm.diagram.description before anything is drawn (an
  index is an integer, targets name states...), and every text in it is escaped, attributes
  included, with characters XML cannot carry replaced: nothing of a peer's making becomes markup;
- the layout's work grows with the edges and the ranks they span, so what is drawn is bounded (`MAX_DRAWN_STATES`,
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
from collections.abc import Mapping
from html import escape
from typing import Any

from .layout import MARGIN, EdgeSpec, Layout, NodeSpec, Route, layered, path

#: Advance of one character of the page's monospace fonts (DejaVu Sans Mono: 0.602 em) at the
#: 11 px of guard labels and the 13 px of state names (style.css sets both).
LABEL_CHAR_W = 6.7
STATE_CHAR_W = 7.9
STATE_H = 34.0
LABEL_H = 16.0
#: Room for the initial state's dot and arrow above the drawing.
TOP = 26.0
LABEL_MAX = 34  # characters of guard text shown on an arrow (the whole text is in its tooltip)
#: The id of the "any state" a suspend comes from (no state of a description is named so: a
#: name is a string).
ANY = ("any",)
#: At most this many states are drawn (a few dozen is what a diagram can show anyway).
MAX_DRAWN_STATES = 60
#: At most this many transitions are drawn (labels are placed in time quadratic in them).
MAX_DRAWN_TRANSITIONS = 160
#: Descriptions whose drawing is kept.
CACHE_SIZE = 32
TITLE_MAX = 400  # characters of guard text in a transition's tooltip

Point = tuple[float, float]

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


def svg(
    desc: dict[str, Any],
    current: str | None = None,
    *,
    positions: Mapping[str, Point] | None = None,
    labels: Mapping[tuple[str, int], Point] | None = None,
) -> str:
    """The diagram of one machine (the `description` structure of llfsm.ros.control), its
    `current` state marked.  A description that does not fit llfsm.diagram.description raises
    its DescriptionError before anything is drawn.  `positions` (state centres) and `labels`
    (the top-left corners of transition labels, by source state and index) are layout.yaml's
    (llfsm.lang.layout_file.Placement): what they place is drawn there, the rest is laid out."""
    placing = (dict(positions or {}), {f"{k[0]}#{k[1]}": v for k, v in (labels or {}).items()})
    key = _key([desc, placing] if positions or labels else desc)
    with _cache_lock:
        drawn = None
        if key is not None:
            drawn = _cache.get(key)
            if drawn is not None:
                _cache.move_to_end(key)
    if drawn is None:
        # deferred: pydantic is imported when a diagram is first drawn (on the drawing thread), not with --web
        from .description import validate

        drawn = _render(validate(desc), positions or {}, labels or {})
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


def _width(text: str, per_char: float) -> float:
    """Drawn width of monospace text: wide (East Asian) characters take two cells."""
    return per_char * sum(2 if ord(c) >= 0x1100 and _wide(c) else 1 for c in text)


def _wide(c: str) -> bool:
    import unicodedata  # deferred: only names beyond Latin get here

    return unicodedata.east_asian_width(c) in ("W", "F")


def layout(desc: dict[str, Any]) -> Layout:
    """The layered layout of a checked description: its states (the initial one first, so the
    depth-first search that finds the loops starts there), every transition with its label,
    and the suspend state's `suspend` and `resume` edges to "any state"."""
    states = desc["states"]
    order = sorted(range(len(states)), key=lambda i: states[i]["name"] != desc["initial"])
    nodes = []
    for i in order:
        s = states[i]
        loops = [t for t in s["transitions"] if t["target"] == s["name"]]
        after = 0.0
        if loops:
            after = 22.0 + 8.0 * (len(loops) - 1) + 10.0 + max(_label_w(t) for t in loops)
        nodes.append(NodeSpec(s["name"], _state_w(s["name"]), STATE_H, after))
    edges = [
        EdgeSpec(s["name"], t["target"], (_label_w(t), LABEL_H))
        for s in states
        for t in s["transitions"]
        if t["target"] != s["name"]
    ]
    suspend = desc.get("suspend")
    if suspend is not None:
        nodes.append(NodeSpec(ANY, _state_w("any state"), STATE_H - 6))
        edges.append(EdgeSpec(ANY, suspend, (_width("suspend", LABEL_CHAR_W) + 8, LABEL_H)))
        edges.append(EdgeSpec(suspend, ANY, (_width("resume", LABEL_CHAR_W) + 8, LABEL_H), back=True))
    return layered(nodes, edges)


def _state_w(name: str) -> float:
    return max(92.0, _width(name, STATE_CHAR_W) + 30)


def _label_w(t: dict[str, Any]) -> float:
    return _width(_label_text(t), LABEL_CHAR_W) + 8


def _label_text(t: dict[str, Any]) -> str:
    return _label(int(t["index"]), t["guard"]) if t["guard"] else str(int(t["index"]))


def _render(full: dict[str, Any], positions: Mapping[str, Point], corners: Mapping[tuple[str, int], Point]) -> str:
    """The SVG of a checked description, no state marked current."""
    desc, left_states, left_transitions = _select(full)
    machine = desc["name"]
    placed = layout(desc)
    if positions or corners:
        placed = _placed(desc, placed, positions, corners)
    mid = _esc(machine)
    marker = "arrow-" + hashlib.sha256(machine.encode("utf-8", "surrogatepass")).hexdigest()[:12]
    edges: list[str] = []
    labels: list[str] = []
    # the routes come in the order of the edges given: the transitions (self-loops left out),
    # then suspend and resume
    listed = [(s, t) for s in desc["states"] for t in s["transitions"] if t["target"] != s["name"]]
    for route in placed.routes:
        d = path(route.points)
        if route.edge < len(listed):
            s, t = listed[route.edge]
            index, guard = int(t["index"]), t["guard"]
            title = _title(s["name"], t["target"], index, guard)
            edges.append(
                f'<path class="transition" data-machine="{mid}" data-source="{_esc(s["name"])}" '
                f'data-target="{_esc(t["target"])}" data-index="{index:d}" d="{d}" '
                f'marker-end="url(#{marker})"><title>{title}</title></path>'
            )
            text = _label_text(t)
            attrs = f'data-source="{_esc(s["name"])}" data-index="{index:d}"'
        else:
            resume = route.edge > len(listed)
            suspend = desc["suspend"]
            source, target = (suspend, "") if resume else ("", suspend)
            text = "resume" if resume else "suspend"
            title = _esc(
                f"resume: {suspend} goes back to the state the machine was suspended in"
                if resume
                else f"suspend: from any state to {suspend}"
            )
            edges.append(
                f'<path class="suspend-edge" data-machine="{mid}" data-source="{_esc(source)}" '
                f'data-target="{_esc(target)}" d="{d}" marker-end="url(#{marker})"><title>{title}</title></path>'
            )
            attrs = f'data-command="{text}"'
        if route.label is not None:
            lx, ly = route.label
            tw = _width(text, LABEL_CHAR_W) + 8
            labels.append(
                f'<g class="guard" {attrs}><title>{title}</title>'
                f'<rect x="{lx:.1f}" y="{ly:.1f}" width="{tw:.1f}" height="{LABEL_H:.0f}" rx="3"/>'
                f'<text x="{lx + 4:.1f}" y="{ly + 12:.1f}">{_esc(text)}</text></g>'
            )
    right = placed.width
    for s in desc["states"]:
        loops = [t for t in s["transitions"] if t["target"] == s["name"]]
        if not loops:
            continue
        cx, cy = placed.centres[s["name"]]
        x0 = cx + _state_w(s["name"]) / 2
        tops = cy - LABEL_H * len(loops) / 2
        for k, t in enumerate(loops):
            reach = 22.0 + 8.0 * k
            ly = tops + LABEL_H * k
            d = (
                f"M{x0:.1f} {cy - 6 - 3 * k:.1f} C{x0 + reach:.1f} {cy - 18 - 4 * k:.1f} "
                f"{x0 + reach:.1f} {cy + 18 + 4 * k:.1f} {x0:.1f} {cy + 6 + 3 * k:.1f}"
            )
            index, guard = int(t["index"]), t["guard"]
            title = _title(s["name"], s["name"], index, guard)
            edges.append(
                f'<path class="transition" data-machine="{mid}" data-source="{_esc(s["name"])}" '
                f'data-target="{_esc(s["name"])}" data-index="{index:d}" d="{d}" '
                f'marker-end="url(#{marker})"><title>{title}</title></path>'
            )
            lx = x0 + 22.0 + 8.0 * (len(loops) - 1) + 6
            text = _label_text(t)
            tw = _width(text, LABEL_CHAR_W) + 8
            right = max(right, lx + tw + 8)
            labels.append(
                f'<g class="guard" data-source="{_esc(s["name"])}" data-index="{index:d}"><title>{title}</title>'
                f'<rect x="{lx:.1f}" y="{ly:.1f}" width="{tw:.1f}" height="{LABEL_H:.0f}" rx="3"/>'
                f'<text x="{lx + 4:.1f}" y="{ly + 12:.1f}">{_esc(text)}</text></g>'
            )
    init = placed.centres.get(desc["initial"])
    if init is not None:
        x, top = init[0], init[1] - STATE_H / 2
        edges.append(
            f'<circle class="initial-dot" cx="{x:.1f}" cy="{top - 20:.1f}" r="5"/>'
            f'<path class="transition initial" d="M{x:.1f} {top - 15:.1f} L{x:.1f} {top:.1f}" '
            f'marker-end="url(#{marker})"/>'
        )
    accepting = {s["name"] for s in desc["states"] if s.get("accepting")}
    parts: list[str] = []
    for s in desc["states"]:
        name = s["name"]
        cx, cy = placed.centres[name]
        w = _state_w(name)
        left, top = cx - w / 2, cy - STATE_H / 2
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
                f'<rect class="inner" x="{left + 4:.1f}" y="{top + 4:.1f}" width="{w - 8:.1f}" '
                f'height="{STATE_H - 8:.0f}" rx="7"/>'
            )
        parts.append(
            f'<g class="{" ".join(kind)}" data-machine="{mid}" data-state="{_esc(name)}" '
            f'aria-current="false" role="listitem" aria-label="state {_esc(name)}">'
            f'<rect x="{left:.1f}" y="{top:.1f}" width="{w:.1f}" height="{STATE_H:.0f}" rx="10"/>{inner}'
            f'<text x="{cx:.1f}" y="{cy + 4.5:.1f}">{_esc(name)}</text></g>'
        )
    if ANY in placed.centres:
        cx, cy = placed.centres[ANY]
        w, h = _state_w("any state"), STATE_H - 6
        parts.append(
            f'<g class="any-state"><title>a machine is suspended from whatever state it is in</title>'
            f'<rect x="{cx - w / 2:.1f}" y="{cy - h / 2:.1f}" width="{w:.1f}" height="{h:.0f}" rx="10"/>'
            f'<text x="{cx:.1f}" y="{cy + 4:.1f}">any state</text></g>'
        )
    height = placed.height
    width = max(right, placed.width)
    low_x, low_y = _low(placed) if positions or corners else (0.0, 0.0)
    note = ""
    if left_states or left_transitions:
        what = [f"{left_states:,} more states"] if left_states else []
        what += [f"{left_transitions:,} more transitions"] if left_transitions else []
        lines = [
            f"{' and '.join(what)} not drawn",
            f"(a diagram shows at most {MAX_DRAWN_STATES} states and {MAX_DRAWN_TRANSITIONS} transitions)",
        ]
        width = max(width, LABEL_CHAR_W * 1.1 * max(map(len, lines)) + 24)
        note = "".join(
            f'<text class="omitted" x="12" y="{TOP + height + 14 + 16 * i:.1f}">{_esc(line)}</text>'
            for i, line in enumerate(lines)
        )
        height += 44
    total = TOP + height
    return (
        f'<svg xmlns="http://www.w3.org/2000/svg" class="diagram" data-machine="{mid}" '
        f'viewBox="{low_x:.0f} {low_y:.0f} {width - low_x:.0f} {total - low_y:.0f}" '
        f'width="{width - low_x:.0f}" height="{total - low_y:.0f}" role="list" '
        f'aria-label="states of {mid}">'
        f'<defs><marker id="{marker}" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="7" markerHeight="7" '
        f'orient="auto-start-reverse"><path d="M0 0 L10 5 L0 10 z" class="arrowhead"/></marker></defs>'
        f'<g transform="translate(0 {TOP:.0f})"><g class="edges">{"".join(edges)}</g>'
        f'<g class="states">{"".join(parts)}</g><g class="labels">{"".join(labels)}</g></g>{note}</svg>'
    )


def _placed(
    desc: dict[str, Any], placed: Layout, positions: Mapping[str, Point], labels: Mapping[tuple[str, int], Point]
) -> Layout:
    """The layered layout with layout.yaml's places: a placed state's centre moves there, and
    every edge that touches a moved state runs straight between the two boxes' borders (two
    edges between one pair of states side by side), its label beside its middle; a placed
    label goes where it was put."""
    centres = dict(placed.centres)
    moved = {name for name, xy in positions.items() if name in centres and centres[name] != tuple(xy)}
    for name in moved:
        centres[name] = (float(positions[name][0]), float(positions[name][1]))
    listed = [(s["name"], t) for s in desc["states"] for t in s["transitions"] if t["target"] != s["name"]]
    ends: list[tuple[Any, Any]] = [(src, t["target"]) for src, t in listed]
    if desc.get("suspend") is not None:
        ends += [(ANY, desc["suspend"]), (desc["suspend"], ANY)]
    size = {s["name"]: (_state_w(s["name"]), STATE_H) for s in desc["states"]}
    size[ANY] = (_state_w("any state"), STATE_H - 6)
    pairs: dict[frozenset[Any], int] = {}
    routes = []
    for route in placed.routes:
        src, dst = ends[route.edge]
        label = route.label
        if src in moved or dst in moved:
            pair = frozenset((repr(src), repr(dst)))
            k = pairs[pair] = pairs.get(pair, -1) + 1
            a, b = centres[src], centres[dst]
            length = max(1e-6, ((b[0] - a[0]) ** 2 + (b[1] - a[1]) ** 2) ** 0.5)
            nx, ny = -(b[1] - a[1]) / length, (b[0] - a[0]) / length  # the normal, to the left
            off = 9.0 * k if repr(src) < repr(dst) else -9.0 * k
            a2, b2 = (a[0] + nx * off, a[1] + ny * off), (b[0] + nx * off, b[1] + ny * off)
            start, end = _border(a2, b2, size[src]), _border(b2, a2, size[dst])
            mx, my = (start[0] + end[0]) / 2, (start[1] + end[1]) / 2
            points = [start, end]
            if label is not None:
                label = (mx + 6.0, my - LABEL_H / 2)
            route = Route(route.edge, points, label, route.reversed)
        if route.edge < len(listed):
            src_name, t = listed[route.edge]
            corner = labels.get((src_name, int(t["index"])))
            if corner is not None and route.label is not None:
                route = Route(route.edge, route.points, (float(corner[0]), float(corner[1])), route.reversed)
        routes.append(route)
    xs = [c[0] + sign * size[n][0] / 2 for n, c in centres.items() for sign in (-1, 1)]
    ys = [c[1] + sign * size[n][1] / 2 for n, c in centres.items() for sign in (-1, 1)]
    for r in routes:
        xs += [p[0] for p in r.points]
        ys += [p[1] for p in r.points]
        if r.label is not None:
            xs += [r.label[0], r.label[0] + 120.0]
            ys += [r.label[1], r.label[1] + LABEL_H]
    return Layout(
        centres,
        routes,
        max(placed.width, max(xs) + MARGIN),
        max(placed.height, max(ys) + MARGIN),
        placed.direction,
        placed.ranks,
        placed.crossings,
    )


def _border(a: Point, b: Point, size: Point) -> Point:
    """Where the segment from a box's centre `a` towards `b` leaves the box (of `size`)."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    w, h = size[0] / 2, size[1] / 2
    scale = min(w / abs(dx) if dx else float("inf"), h / abs(dy) if dy else float("inf"), 1.0)
    return (a[0] + dx * scale, a[1] + dy * scale)


def _low(placed: Layout) -> Point:
    """The drawing's top-left corner: (0, 0) unless a placed state or edge reaches beyond it
    (the viewBox then starts there, so layout.yaml's coordinates are the drawing's own)."""
    xs, ys = [0.0], [0.0]
    for r in placed.routes:
        xs += [p[0] for p in r.points]
        ys += [p[1] for p in r.points]
    for name, c in placed.centres.items():
        xs.append(c[0] - _state_w(name if isinstance(name, str) else "any state") / 2)
        ys.append(c[1] - STATE_H / 2)
    low_x, low_y = min(xs), min(ys)
    return (min(0.0, low_x - MARGIN) if low_x < 0 else 0.0, min(0.0, low_y - MARGIN + TOP) if low_y < 0 else 0.0)


#: The look of the web view's diagrams (llfsm/web/static/style.css), for a drawing on its own.
STANDALONE_STYLE = """
svg.diagram { font-size: 13px; background: #fff; }
svg.diagram text { font-family: "DejaVu Sans Mono", ui-monospace, monospace; }
svg.diagram .state rect { fill: #e3f2fd; stroke: #1e3a5f; stroke-width: 1.4; }
svg.diagram .state rect.inner { fill: none; }
svg.diagram .state text { text-anchor: middle; fill: #1a1a1a; font-weight: 600; font-size: 13px; }
svg.diagram .suspend-state rect { stroke-dasharray: 5 3; fill: #f3e5f5; }
svg.diagram text.omitted { fill: #8d6e63; font-size: 12px; font-style: italic; }
svg.diagram .transition { fill: none; stroke: #455a64; stroke-width: 1.3; }
svg.diagram .arrowhead, svg.diagram .initial-dot { fill: #455a64; }
svg.diagram .guard rect { fill: #fff; fill-opacity: .9; stroke: none; }
svg.diagram .guard text { font-size: 11px; text-anchor: start; fill: #37474f; }
svg.diagram .suspend-edge { fill: none; stroke: #8e24aa; stroke-width: 1.2; stroke-dasharray: 5 3; }
svg.diagram .any-state rect { fill: #fff; stroke: #8e24aa; stroke-dasharray: 4 3; }
svg.diagram .any-state text { text-anchor: middle; fill: #8e24aa; font-style: italic; font-size: 12px; }
svg.diagram .guard[data-command] text { fill: #8e24aa; }
"""


def standalone(drawn: str) -> str:
    """A diagram of `svg` as a file of its own (`llfsm graph --format svg`): an XML declaration,
    and the page's look in a <style> element."""
    head, sep, rest = drawn.partition(">")
    return f'<?xml version="1.0" encoding="UTF-8"?>\n{head}{sep}<style>{STANDALONE_STYLE}</style>{rest}\n'


def _title(source: str, target: str, index: int, guard: str) -> str:
    shown = guard if len(guard) <= TITLE_MAX else guard[: TITLE_MAX - 1] + "…"
    return _esc(f"{source} → {target} (transition {index}): {shown}")
