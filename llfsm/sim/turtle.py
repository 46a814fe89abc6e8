"""turtlesim's numbers and one turtle, as `turtle.cpp` and `turtle_frame.cpp` have them: the
canvas and the world's size (float32, as turtlesim computes them), the update period and the
command timeout, the pen's defaults, turtlesim's own PI and the angle normalisation that uses
it; the values the world (world.py) takes and gives (Pose, Segment, RotationEvent, TurtleError)
and a turtle's state (`_Turtle`, with its rotate_absolute goal).
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

_F32 = struct.Struct("<f")


def f32(value: float) -> float:
    """Round to float32, as storing into a `float` field or variable does in turtlesim."""
    try:
        rounded: float = _F32.unpack(_F32.pack(value))[0]
    except OverflowError:
        return math.copysign(math.inf, value)
    return rounded


CANVAS_PX = 500
"""Width and height of turtlesim's window and path image, in pixels."""
PIXELS_PER_METRE = 45.0
"""turtlesim's `meter_`: the height of its turtle images."""
WORLD_SIZE = f32((CANVAS_PX - 1) / PIXELS_PER_METRE)
"""`width_in_meters_` = `(width() - 1) / meter_`, a float: 11.088889122009277."""
CENTRE = f32(WORLD_SIZE / 2.0)
"""Where turtle1 is spawned on start and on reset: 5.544444561004639 (x and y)."""
UPDATE_PERIOD_NS = 16_000_000
"""turtlesim's update timer interval (16 ms)."""
UPDATE_DT = 0.001 * 16
"""The dt turtlesim integrates with: `0.001 * update_timer_->interval()`."""
COMMAND_TIMEOUT_NS = 1_000_000_000
"""A velocity command lapses when more than this has passed since it arrived."""
BACKGROUND = (0x45, 0x56, 0xFF)
"""Default background_r/g/b parameters."""
PEN_COLOR = (0xB3, 0xB8, 0xFF)
"""Default pen colour of every new turtle."""
PEN_WIDTH = 3
"""Default pen width of every new turtle, in pixels."""

# turtle.hpp: `#define PI 3.14159265` (not math.pi) -- theta is normalised with this value.
_PI = 3.14159265
_TWO_PI = 2.0 * _PI


class TurtleError(Exception):
    """A request turtlesim refuses.  For spawn and kill the message is turtlesim's own ERROR log
    line, so the node can log `str(err)` and answer as turtlesim does (spawn: empty name)."""


class RotationEvent(NamedTuple):
    """What an update did to a turtle's rotate_absolute goal: "feedback" (value: the remaining
    rotation), "succeeded" or "canceled" (value: the delta turned, the goal's result), all
    rounded to float32 as the action's fields hold them."""

    turtle: str
    kind: str
    value: float


class _Rotation:
    """One rotate_absolute goal: its heading, where the turtle started, a cancel request, and
    the delta turned so far (the result turtlesim keeps updating)."""

    __slots__ = ("canceling", "delta", "start", "theta")

    def __init__(self, theta: float, start: float) -> None:
        self.theta = theta
        self.start = start
        self.canceling = False
        self.delta = 0.0


class Pose(NamedTuple):
    """The fields of turtlesim/msg/Pose, already rounded to float32 as the message holds them."""

    x: float
    y: float
    theta: float
    linear_velocity: float
    angular_velocity: float


@dataclass(frozen=True, slots=True)
class Segment:
    """One pen stroke in pixel coordinates (y down), drawn with a square cap like a QPen."""

    x0: float
    y0: float
    x1: float
    y1: float
    color: tuple[int, int, int]
    width: int


# A stored stroke: x0, y0, x1, y1 (px), RGBA bytes, width (px).  Tuples keep `update` cheap.
_Stroke = tuple[float, float, float, float, bytes, int]


class _Turtle:
    """turtlesim's `Turtle`: position in the Qt frame (metres), heading, velocities, pen."""

    __slots__ = (
        "ang",
        "last_cmd",
        "last_stroke",
        "lin_x",
        "lin_y",
        "name",
        "orient",
        "pen_on",
        "pen_rgba",
        "pen_width",
        "qx",
        "qy",
        "rotation",
        "sensed",
        "sensed_at",
        "sensed_bg",
        "sensed_version",
        "sensed_x",
        "sensed_y",
        "teleports",
    )

    def __init__(self, name: str, qx: float, qy: float, orient: float) -> None:
        self.name = name
        self.qx = qx
        self.qy = qy
        self.orient = orient
        self.lin_x = 0.0
        self.lin_y = 0.0
        self.ang = 0.0
        self.last_cmd = 0
        self.pen_on = True
        self.pen_rgba = bytes((*PEN_COLOR, 255))
        self.pen_width = PEN_WIDTH
        # (relative, x_or_linear, y, theta): applied in order at the start of the next update.
        self.teleports: list[tuple[bool, float, float, float]] = []
        self.rotation: _Rotation | None = None
        # Index in the stroke list of this turtle's last motion stroke (to extend straight lines).
        self.last_stroke = -1
        self.sensed: tuple[int, int, int] = (255, 255, 255)
        self.sensed_at = -1
        # where `sensed` was read, and what the picture was then: a turtle standing still on a
        # picture that has not changed reads the same pixel again
        self.sensed_x = self.sensed_y = math.nan
        self.sensed_version = -1
        self.sensed_bg: tuple[int, int, int] | None = None


def _normalise(angle: float) -> float:
    """turtlesim's normalizeAngle: into [-PI, PI), with its PI."""
    return angle - _TWO_PI * math.floor((angle + _PI) / _TWO_PI)


def _check_u8(value: int, what: str) -> int:
    if isinstance(value, bool):
        value = int(value)
    if not isinstance(value, int) or not 0 <= value <= 255:
        raise TurtleError(f"{what} must be an integer from 0 to 255, not {value!r}")
    return value


def _check_rgb(rgb: Sequence[int], what: str) -> tuple[int, int, int]:
    if len(rgb) != 3:
        raise TurtleError(f"{what} must be three integers (r, g, b), not {rgb!r}")
    r, g, b = (_check_u8(v, what) for v in rgb)
    return (r, g, b)
