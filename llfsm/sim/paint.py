"""The path image's painter: a pen stroke rasterised as Qt's aliased QPainter line with a
square cap, pixel for pixel, so that a colour sensor reads what turtlesim's would.  The C
painter (`_paint.c`, built by setup.py where a C compiler is) does it when present; `_fill_stroke`
is the same in Python, for installs without it (and the reference the tests hold it to).
"""

from __future__ import annotations

import math
from collections.abc import Callable

from .turtle import CANVAS_PX

_c_fill_stroke: Callable[[bytearray, float, float, float, float, bytes, int], bool] | None
try:  # the stroke painter in C (setup.py builds it where a C compiler is; optional)
    from ._paint import fill_stroke as _c_fill_stroke
except ImportError:  # pragma: no cover - installs without a compiler
    _c_fill_stroke = None

#: The path image before anything is drawn: qRgba(255, 255, 255, 0), as in turtlesim.
_TRANSPARENT = b"\xff\xff\xff\x00"


def _qround(v: float) -> int:
    """Qt's qRound for doubles: halves away from zero."""
    return int(v + 0.5) if v >= 0.0 else int(v - 0.5)


def _fill_stroke(buf: bytearray, x0: float, y0: float, x1: float, y1: float, rgba: bytes, width: int) -> None:
    """Paint one stroke as an aliased QPainter line with a square cap: the rectangle around the
    segment, `width` wide and extended `width/2` past both ends.  A pixel is painted when its
    centre lies inside; each pixel row is the intersection of the rectangle's two slabs.

    The colour sensor paints a stroke per turtle per update, so the common case (a slanted
    stroke) has its own branch: each slab's two edges come out of its division in an order
    fixed by the signs of the direction (rounding is monotonic), so it divides without the
    comparisons and swaps; the operations and their order are the general branch's, so every
    pixel is the same."""
    if not (math.isfinite(x0) and math.isfinite(y0) and math.isfinite(x1) and math.isfinite(y1)):
        return
    half = width / 2.0
    dx = x1 - x0
    dy = y1 - y0
    length = math.hypot(dx, dy)
    if length > 0.0:
        ux = dx / length
        uy = dy / length
    else:  # a zero-length line still paints its square cap
        ux, uy = 1.0, 0.0
    cx = (x0 + x1) / 2.0
    cy = (y0 + y1) / 2.0
    along = length / 2.0 + half  # half extent along the line, caps included
    # Vertical extent of the rectangle, then one span per row of pixel centres inside it.
    ey = abs(uy) * along + abs(ux) * half
    j0 = max(0, math.ceil(cy - ey - 0.5))
    j1 = min(CANVAS_PX - 1, math.ceil(cy + ey - 0.5) - 1)
    last = CANVAS_PX - 1
    ceil = math.ceil
    # Slab 1: |(x - cx) * ux + d * uy| <= along, edges (-along - d * uy) / ux and
    # (along - d * uy) / ux; slab 2: |-(x - cx) * uy + d * ux| <= half, edges
    # (half - d * ux) / -uy and (-half - d * ux) / -uy.
    slanted = ux != 0.0 and uy != 0.0
    if slanted:  # which edge of each slab is the lower one: lo1/hi1, lo2/hi2
        nuy = -uy
        lo1, hi1 = (-along, along) if ux > 0.0 else (along, -along)
        lo2, hi2 = (-half, half) if nuy > 0.0 else (half, -half)
    for j in range(j0, j1 + 1):
        d = j + 0.5 - cy
        if slanted:
            t1 = d * uy
            t2 = d * ux
            xl = (lo1 - t1) / ux
            a = (lo2 - t2) / nuy
            if a > xl:
                xl = a
            xr = (hi1 - t1) / ux
            b = (hi2 - t2) / nuy
            if b < xr:
                xr = b
        else:  # along an axis: one slab may hold every column, or none of this row
            xl = -math.inf
            xr = math.inf
            if ux != 0.0:
                a = (-along - d * uy) / ux
                b = (along - d * uy) / ux
                if a > b:
                    a, b = b, a
                xl, xr = a, b
            elif abs(d * uy) > along:
                continue
            if uy != 0.0:
                a = (half - d * ux) / -uy
                b = (-half - d * ux) / -uy
                if a > b:
                    a, b = b, a
                if a > xl:
                    xl = a
                if b < xr:
                    xr = b
            elif abs(d * ux) > half:
                continue
        i0 = ceil(cx + xl - 0.5)
        i1 = ceil(cx + xr - 0.5) - 1
        if i0 < 0:
            i0 = 0
        if i1 > last:
            i1 = last
        if i0 <= i1:
            base = j * CANVAS_PX
            buf[(base + i0) * 4 : (base + i1 + 1) * 4] = rgba * (i1 - i0 + 1)
