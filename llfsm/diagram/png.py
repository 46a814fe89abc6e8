"""`llfsm graph --format png`: the SVG diagram of llfsm.diagram.svg drawn into pixels with Pillow,
which llfsm already needs (turtlesim's pictures), and the font Pillow ships (Aileron, through its
bundled FreeType): no Graphviz, no Cairo, no system font, the same pixels on every machine.
(docs/machine-format.md says why; an SVG rasterizer from the registries would need fonts the
machine may not have for the labels.)

It reads only what llfsm.diagram.svg writes: `rect` (rounded), `path` of M, L and C commands with
an arrowhead at the end, `circle`, `text`, translations of `g`, and the look of the web view's
style sheet by class.  Drawn at four times the size and scaled down to `scale` times, so edges
and text are smooth.
"""

from __future__ import annotations

import io
import itertools
import math
import re
import xml.etree.ElementTree as ET
from functools import cache

from PIL import Image, ImageDraw, ImageFont

NS = "{http://www.w3.org/2000/svg}"
#: Pixels per SVG unit in the PNG, and the supersampling before the scale down.
SCALE = 2
SUPER = 4
#: Largest drawing drawn (SVG units): a bounded diagram is far smaller (llfsm.diagram.svg).
MAX_SIDE = 8000

Rgb = tuple[int, int, int]
INK, EDGE, SUSPEND = (26, 26, 26), (69, 90, 100), (142, 36, 170)
_NUMBER = re.compile(r"-?[0-9]*\.?[0-9]+(?:e-?[0-9]+)?")


class _Style:
    """What one element looks like (the web view's style sheet, by class)."""

    def __init__(
        self,
        fill: Rgb | None = None,
        stroke: Rgb | None = None,
        width: float = 1.0,
        dash: tuple[float, float] | None = None,
        size: float = 13.0,
        anchor: str = "start",
        bold: bool = False,
    ) -> None:
        self.fill, self.stroke, self.width, self.dash = fill, stroke, width, dash
        self.size, self.anchor, self.bold = size, anchor, bold


def _style(tag: str, classes: list[set[str]], attrs: dict[str, str]) -> _Style:
    """The style of an element from its own classes and those of its ancestors."""
    own = classes[-1]
    inside = set().union(*classes[:-1]) if len(classes) > 1 else set()
    if tag == "rect":
        if "guard" in inside:
            return _Style(fill=(255, 255, 255))
        if "any-state" in inside:
            return _Style(fill=(255, 255, 255), stroke=SUSPEND, width=1.0, dash=(4, 3))
        if "inner" in own:
            return _Style(stroke=(30, 58, 95), width=1.4)
        if "suspend-state" in inside:
            return _Style(fill=(243, 229, 245), stroke=(30, 58, 95), width=1.4, dash=(5, 3))
        return _Style(fill=(227, 242, 253), stroke=(30, 58, 95), width=1.4)
    if tag == "path":
        if "suspend-edge" in own:
            return _Style(stroke=SUSPEND, width=1.2, dash=(5, 3))
        return _Style(stroke=EDGE, width=1.3, fill=EDGE)  # fill: its arrowhead
    if tag == "circle":
        return _Style(fill=EDGE)
    if tag == "text":
        if "omitted" in own:
            return _Style(fill=(141, 110, 99), size=12)
        if "guard" in inside:
            return _Style(fill=SUSPEND if "data-command" in attrs else (55, 71, 79), size=11)
        if "any-state" in inside:
            return _Style(fill=SUSPEND, size=12, anchor="middle")
        return _Style(fill=INK, size=13, anchor="middle", bold=True)
    return _Style()


@cache
def _font(px: int) -> ImageFont.FreeTypeFont | ImageFont.ImageFont:
    return ImageFont.load_default(px)


def render(svg_text: str, scale: int = SCALE) -> bytes:
    """The PNG of a diagram that llfsm.diagram.svg drew."""
    root = ET.fromstring(svg_text)
    width = min(float(root.get("width", "100")), MAX_SIDE)
    height = min(float(root.get("height", "100")), MAX_SIDE)
    box = [float(v) for v in root.get("viewBox", "0 0 0 0").split()[:2]]  # a placed state may lie left of 0
    k = scale * SUPER
    image = Image.new("RGB", (max(1, round(width * k)), max(1, round(height * k))), (255, 255, 255))
    draw = ImageDraw.Draw(image)
    _walk(draw, root, (-box[0], -box[1]) if len(box) == 2 else (0.0, 0.0), [], k)
    out = image.resize((max(1, round(width * scale)), max(1, round(height * scale))), Image.Resampling.LANCZOS)
    buf = io.BytesIO()
    out.save(buf, "PNG", optimize=True)
    return buf.getvalue()


def _walk(
    draw: ImageDraw.ImageDraw, node: ET.Element, at: tuple[float, float], classes: list[set[str]], k: float
) -> None:
    for el in node:
        tag = el.tag.removeprefix(NS)
        if tag in ("defs", "title", "style"):
            continue
        mine = [*classes, set(el.get("class", "").split())]
        if tag == "g":
            here = at
            move = re.match(r"translate\(\s*(-?[\d.]+)[\s,]+(-?[\d.]+)\s*\)", el.get("transform", ""))
            if move:
                here = (at[0] + float(move[1]), at[1] + float(move[2]))
            if "guard" in mine[-1]:
                _fit_label(el, mine, k)
            _walk(draw, el, here, mine, k)
            continue
        style = _style(tag, mine, dict(el.attrib))
        if tag == "rect":
            _rect(draw, el, at, style, k)
        elif tag == "path":
            _path(draw, el.get("d", ""), at, style, k, arrow=el.get("marker-end") is not None)
        elif tag == "circle":
            x, y, r = (float(el.get(a, "0")) for a in ("cx", "cy", "r"))
            cx, cy = (x + at[0]) * k, (y + at[1]) * k
            draw.ellipse((cx - r * k, cy - r * k, cx + r * k, cy + r * k), fill=style.fill)
        elif tag == "text":
            _text(draw, el, at, style, k)


def _fit_label(g: ET.Element, classes: list[set[str]], k: float) -> None:
    """A transition's label: its white box as wide as its text in the font drawn here, with the
    margins svg gave it.  svg sizes the box for the page's monospace font (llfsm.diagram.svg,
    LABEL_CHAR_W), which is wider than the font Pillow ships: the box ran past the text, over
    the edges and labels beside it."""
    rect, text = g.find(f"{NS}rect"), g.find(f"{NS}text")
    if rect is None or text is None:
        return
    content = "".join(text.itertext())
    style = _style("text", [*classes, set(text.get("class", "").split())], dict(text.attrib))
    margin = float(text.get("x", "0")) - float(rect.get("x", "0"))
    width = _font(max(1, round(style.size * k))).getlength(content) / k + 2 * margin
    rect.set("width", f"{width:.2f}")


def _rect(draw: ImageDraw.ImageDraw, el: ET.Element, at: tuple[float, float], style: _Style, k: float) -> None:
    x, y, w, h = (float(el.get(a, "0")) for a in ("x", "y", "width", "height"))
    box = ((x + at[0]) * k, (y + at[1]) * k, (x + at[0] + w) * k, (y + at[1] + h) * k)
    radius = float(el.get("rx", "0")) * k
    width = max(1, round(style.width * k))
    if style.dash is None:
        draw.rounded_rectangle(box, radius, fill=style.fill, outline=style.stroke, width=width)
        return
    draw.rounded_rectangle(box, radius, fill=style.fill)
    if style.stroke is not None:  # a dashed outline: the rounded box as a polyline, dashed
        x0, y0, x1, y1 = box
        r = min(radius, (x1 - x0) / 2, (y1 - y0) / 2)
        corners = ((x1 - r, y0 + r, -90), (x1 - r, y1 - r, 0), (x0 + r, y1 - r, 90), (x0 + r, y0 + r, 180))
        points = []
        for cx, cy, start in corners:
            points += [
                (cx + r * math.cos(math.radians(start + 15 * i)), cy + r * math.sin(math.radians(start + 15 * i)))
                for i in range(7)
            ]
        points.append(points[0])
        _dashed(draw, points, style.stroke, width, (style.dash[0] * k, style.dash[1] * k))


def _path(draw: ImageDraw.ImageDraw, d: str, at: tuple[float, float], style: _Style, k: float, arrow: bool) -> None:
    tokens = re.findall(r"[MLC]|" + _NUMBER.pattern, d)
    points: list[tuple[float, float]] = []
    last_dir = (0.0, 1.0)
    i = 0
    while i < len(tokens):
        cmd = tokens[i]
        i += 1
        nums = []
        while i < len(tokens) and tokens[i] not in ("M", "L", "C"):
            nums.append(float(tokens[i]))
            i += 1
        xy = [((nums[j] + at[0]) * k, (nums[j + 1] + at[1]) * k) for j in range(0, len(nums) - 1, 2)]
        if cmd in ("M", "L") and xy:
            if points and cmd == "L":
                last_dir = (xy[0][0] - points[-1][0], xy[0][1] - points[-1][1])
            points += xy
        elif cmd == "C" and len(xy) == 3 and points:
            p0, c1, c2, p3 = points[-1], *xy
            for n in range(1, 17):
                t = n / 16
                u = 1 - t
                points.append(
                    (
                        u**3 * p0[0] + 3 * u * u * t * c1[0] + 3 * u * t * t * c2[0] + t**3 * p3[0],
                        u**3 * p0[1] + 3 * u * u * t * c1[1] + 3 * u * t * t * c2[1] + t**3 * p3[1],
                    )
                )
            last_dir = (p3[0] - c2[0], p3[1] - c2[1]) if (p3[0], p3[1]) != (c2[0], c2[1]) else last_dir
    if len(points) < 2 or style.stroke is None:
        return
    width = max(1, round(style.width * k))
    if style.dash is not None:
        _dashed(draw, points, style.stroke, width, (style.dash[0] * k, style.dash[1] * k))
    else:
        draw.line(points, fill=style.stroke, width=width, joint="curve")
    if arrow:
        _arrowhead(draw, points[-1], last_dir, style.stroke, k)


def _arrowhead(
    draw: ImageDraw.ImageDraw, tip: tuple[float, float], direction: tuple[float, float], colour: Rgb, k: float
) -> None:
    """The marker of llfsm.diagram.svg (a triangle 7 units long) at the end of a path."""
    length = math.hypot(*direction) or 1.0
    ux, uy = direction[0] / length, direction[1] / length
    size = 7.0 * k
    back = (tip[0] - ux * size, tip[1] - uy * size)
    half = size * 0.5
    draw.polygon(
        [tip, (back[0] - uy * half, back[1] + ux * half), (back[0] + uy * half, back[1] - ux * half)], fill=colour
    )


def _dashed(
    draw: ImageDraw.ImageDraw, points: list[tuple[float, float]], colour: Rgb, width: int, dash: tuple[float, float]
) -> None:
    on, off = dash
    drawing, left = True, on
    for (x0, y0), (x1, y1) in itertools.pairwise(points):
        seg = math.hypot(x1 - x0, y1 - y0)
        pos = 0.0
        while pos < seg:
            step = min(left, seg - pos)
            if drawing:
                a, b = pos / seg, (pos + step) / seg
                draw.line(
                    [(x0 + (x1 - x0) * a, y0 + (y1 - y0) * a), (x0 + (x1 - x0) * b, y0 + (y1 - y0) * b)],
                    fill=colour,
                    width=width,
                )
            pos += step
            left -= step
            if left <= 1e-9:
                drawing = not drawing
                left = on if drawing else off


def _text(draw: ImageDraw.ImageDraw, el: ET.Element, at: tuple[float, float], style: _Style, k: float) -> None:
    text = "".join(el.itertext())
    if not text:
        return
    x, y = (float(el.get("x", "0")) + at[0]) * k, (float(el.get("y", "0")) + at[1]) * k
    font = _font(max(1, round(style.size * k)))
    draw.text(
        (x, y),
        text,
        fill=style.fill,
        font=font,
        anchor="ms" if style.anchor == "middle" else "ls",
        stroke_width=round(0.35 * k) if style.bold else 0,
        stroke_fill=style.fill,
    )
