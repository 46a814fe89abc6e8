"""Pictures of a `TurtleWorld`: turtlesim's window as a PNG (Pillow) or an SVG (plain text).

Both show what turtlesim's window shows: the background colour from the current parameters, the
pen trails, and each turtle at its pose.  The PNG's trails are the world's own path image, the
very pixels the colour sensor reads; the SVG draws the same strokes as vectors.  The y axis
points up as in turtlesim (pixel y = (height - y) * 45).  Files are written atomically: a
temporary file in the same folder, then `os.replace`, so a picture is never seen half-written.
"""

from __future__ import annotations

import math
import os
import zlib
from collections.abc import Callable
from pathlib import Path
from typing import IO, TYPE_CHECKING

from llfsm.sim.world import CANVAS_PX, TurtleWorld

if TYPE_CHECKING:
    from PIL import Image

__all__ = ["Shape", "render", "render_png", "render_svg", "to_image", "turtle_color", "turtle_shapes"]

Point = tuple[float, float]
RGB = tuple[int, int, int]
Shape = tuple[list[Point], RGB, RGB | None]
"""A filled polygon: points (pixels), fill colour, outline colour or None."""

_SKIN: RGB = (132, 186, 96)
_SKIN_LINE: RGB = (52, 92, 36)
_EYE: RGB = (20, 28, 20)
_SHELLS: tuple[RGB, ...] = (
    (46, 125, 50),
    (121, 85, 61),
    (0, 121, 107),
    (158, 105, 36),
    (85, 107, 47),
    (69, 90, 100),
)


def _ellipse(cu: float, cv: float, ru: float, rv: float, n: int = 20) -> list[Point]:
    return [(cu + ru * math.cos(2 * math.pi * k / n), cv + rv * math.sin(2 * math.pi * k / n)) for k in range(n)]


def _hexagon(cu: float, cv: float, r: float) -> list[Point]:
    return [(cu + r * math.cos(math.pi / 3 * k), cv + r * math.sin(math.pi / 3 * k)) for k in range(6)]


# The turtle in its own frame: u forward, v to its left, in pixels (turtlesim's images are
# 45 px, one metre); drawn in this order.
_BODY: tuple[tuple[str, list[Point]], ...] = (
    ("skin", _ellipse(9.0, 11.5, 4.5, 3.5, 12)),
    ("skin", _ellipse(9.0, -11.5, 4.5, 3.5, 12)),
    ("skin", _ellipse(-9.0, 11.0, 4.0, 3.5, 12)),
    ("skin", _ellipse(-9.0, -11.0, 4.0, 3.5, 12)),
    ("skin", [(-13.0, 3.0), (-20.0, 0.0), (-13.0, -3.0)]),
    ("skin", _ellipse(16.5, 0.0, 6.0, 5.0, 16)),
    ("shell", _ellipse(-1.0, 0.0, 14.0, 12.0, 28)),
    ("scute", _hexagon(-1.0, 0.0, 6.0)),
    ("eye", _ellipse(19.0, 2.6, 1.3, 1.3, 8)),
    ("eye", _ellipse(19.0, -2.6, 1.3, 1.3, 8)),
)


def turtle_color(name: str) -> RGB:
    """A shell colour per name, stable across runs, so that turtles can be told apart: numbered
    turtles (turtle1, turtle2, ...) take the colours in turn, other names by hash."""
    digits = name[len(name.rstrip("0123456789")) :]
    index = int(digits) - 1 if digits else zlib.crc32(name.encode())
    return _SHELLS[index % len(_SHELLS)]


def _paints(name: str) -> dict[str, tuple[RGB, RGB | None]]:
    shell = turtle_color(name)
    dark = (shell[0] * 3 // 5, shell[1] * 3 // 5, shell[2] * 3 // 5)
    light = (min(255, shell[0] + 40), min(255, shell[1] + 40), min(255, shell[2] + 40))
    return {"skin": (_SKIN, _SKIN_LINE), "shell": (shell, dark), "scute": (light, dark), "eye": (_EYE, None)}


def turtle_shapes(name: str, x: float, y: float, theta: float, scale: float = 1.0) -> list[Shape]:
    """The polygons of one turtle centred on pixel (x, y) (y down), head along `theta`
    (radians, counter-clockwise from +x as in turtlesim), for any drawing backend."""
    c = math.cos(theta) * scale
    s = math.sin(theta) * scale
    paints = _paints(name)
    shapes: list[Shape] = []
    for part, pts in _BODY:
        fill, line = paints[part]
        shapes.append(([(x + u * c - v * s, y - (u * s + v * c)) for u, v in pts], fill, line))
    return shapes


def to_image(world: TurtleWorld) -> Image.Image:
    """The picture as a Pillow RGB image, 500 x 500."""
    # deferred: start-up (Pillow, only for a PNG; an SVG needs none)
    from PIL import Image, ImageDraw

    size = (CANVAS_PX, CANVAS_PX)
    img = Image.new("RGB", size, world.background)
    path = Image.frombytes("RGBA", size, world.path_rgba())
    img.paste(path, (0, 0), path)
    # Each turtle is drawn 4x larger on its own patch and box-filtered down: smooth edges
    # without touching the trail pixels around it.
    ss = 4
    half = 32
    for name, x, y, theta in world.turtle_pixels():
        if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(theta)):
            continue
        ox = math.floor(x) - half
        oy = math.floor(y) - half
        patch = Image.new("RGBA", (2 * half * ss, 2 * half * ss), (0, 0, 0, 0))
        pen = ImageDraw.Draw(patch)
        for pts, fill, line in turtle_shapes(name, (x - ox) * ss, (y - oy) * ss, theta, ss):
            pen.polygon(pts, fill=(*fill, 255), outline=None if line is None else (*line, 255), width=ss)
        small = patch.resize((2 * half, 2 * half), Image.Resampling.BOX)
        img.paste(small, (ox, oy), small)
    return img


def render_png(world: TurtleWorld, path: str | os.PathLike[str]) -> Path:
    """Write the picture as a 500 x 500 PNG."""
    img = to_image(world)
    return _atomic_write(Path(path), lambda f: img.save(f, format="PNG"))


def _hex(rgb: RGB) -> str:
    r, g, b = rgb
    return f"#{r:02x}{g:02x}{b:02x}"


def _num(v: float) -> str:
    text = f"{v:.2f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def svg_text(world: TurtleWorld) -> str:
    """The picture as SVG source: strokes grouped by pen, in drawing order, then the turtles."""
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{CANVAS_PX}" height="{CANVAS_PX}" '
        f'viewBox="0 0 {CANVAS_PX} {CANVAS_PX}">',
        "<title>turtlesim</title>",
        f'<rect width="{CANVAS_PX}" height="{CANVAS_PX}" fill="{_hex(world.background)}"/>',
        '<g fill="none" stroke-linecap="square" stroke-linejoin="bevel">',
    ]
    # Consecutive strokes with the same pen become one <path>: their order among themselves
    # does not change the picture, and order between different pens is kept.
    pen: tuple[RGB, int] | None = None
    d: list[str] = []
    at: tuple[float, float] | None = None

    def close() -> None:
        if pen is not None and d:
            out.append(f'<path stroke="{_hex(pen[0])}" stroke-width="{pen[1]}" d="{" ".join(d)}"/>')

    for seg in world.segments:
        coords = (seg.x0, seg.y0, seg.x1, seg.y1)
        if not all(math.isfinite(v) for v in coords):
            continue
        if (seg.color, seg.width) != pen:
            close()
            pen, d, at = (seg.color, seg.width), [], None
        if at != (seg.x0, seg.y0):
            d.append(f"M{_num(seg.x0)} {_num(seg.y0)}")
        d.append(f"L{_num(seg.x1)} {_num(seg.y1)}")
        at = (seg.x1, seg.y1)
    close()
    out.append("</g>")
    for name, x, y, theta in world.turtle_pixels():
        if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(theta)):
            continue
        out.append(f'<g class="turtle" id="{_xml_attr(name)}">')
        out.append(f"<title>{_xml_attr(name)}</title>")
        for pts, fill, line in turtle_shapes(name, x, y, theta):
            stroke = f' stroke="{_hex(line)}" stroke-width="1"' if line is not None else ""
            points = " ".join(f"{_num(px)},{_num(py)}" for px, py in pts)
            out.append(f'<polygon points="{points}" fill="{_hex(fill)}"{stroke}/>')
        out.append("</g>")
    out.append("</svg>")
    return "\n".join(out) + "\n"


def render_svg(world: TurtleWorld, path: str | os.PathLike[str]) -> Path:
    """Write the picture as a 500 x 500 SVG."""
    data = svg_text(world).encode()
    return _atomic_write(Path(path), lambda f: f.write(data))


def render(world: TurtleWorld, path: str | os.PathLike[str]) -> Path:
    """`--image FILE`: PNG or SVG by the file's suffix."""
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix == ".png":
        return render_png(world, p)
    if suffix == ".svg":
        return render_svg(world, p)
    raise ValueError(f"{p}: the picture must be a .png or .svg file")


def _xml_attr(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;").replace('"', "&quot;")


def _atomic_write(path: Path, write: Callable[[IO[bytes]], object]) -> Path:
    """Through llfsm.outputs, as every file a user names: atomic, and an OSError (OutputError)
    with one clear message when it cannot be written."""
    # deferred: start-up (only writing a picture needs it)
    from ..outputs import write_file

    write_file(path, write, what="--image")
    return path
