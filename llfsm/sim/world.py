"""The turtle world of ROS 2 turtlesim (humble), as plain Python values in and out.

No bus and no message classes here: the turtlesim node turns topics and services into calls
of `TurtleWorld` and its results back into messages.  Everything follows
`turtlesim/src/turtle.cpp` and `turtle_frame.cpp` of ros/ros_tutorials, down to the order of
floating-point operations, so that poses match a real turtlesim bit for bit:

* Positions are kept, like turtlesim's `pos_`, in the Qt frame (metres, y pointing *down*,
  origin top-left); the published pose flips y back (`y = height - pos_y`).  The wall warning
  prints Qt-frame coordinates, exactly as turtlesim does.
* The canvas is 500 x 500 px, 45 px per metre (the height of a turtle image); the world is
  `(500 - 1) / 45` m square, computed in float32 as turtlesim does (11.088889122009277 m).
* Service arguments that are float32 in the .srv files (spawn, teleports) are rounded to
  float32, and the pose is rounded to float32 like the fields of `turtlesim/msg/Pose`.
* Time `now` is the run time in integer nanoseconds (llfsm's clocks count in ns), so that the
  1 s command timeout (`now - last_command > 1 s`, strictly) is exact.

A turtle may have one `rotate_absolute` goal (humble's action): each update turns it at 1 rad/s
toward the goal heading, reports the `remaining` rotation and the `delta` turned so far, and
ends it within 0.02 rad; a velocity command or a new goal aborts it, a cancel request ends it at
the next update.  The goal's handle is the node's business: here a rotation is plain values,
and what happened to it comes back from `update` in `rotation_events`.

Drawing is recorded, not painted: every pen stroke is appended to a list of segments (pixel
coordinates, colour, width) and rasterised into an RGBA image only when a colour or a picture is
asked for, and then only the strokes added since the last time.  The path image starts
transparent white, qRgba(255, 255, 255, 0), as in turtlesim, and the background colour is
painted under it at display time from the current parameters.

turtle.py holds turtlesim's numbers and one turtle's state, paint.py the painter of the path
image; this module is the world that moves the turtles, draws their paths and answers the node.
"""

from __future__ import annotations

import math
import re
import struct
from collections.abc import Callable

from .paint import _TRANSPARENT, _c_fill_stroke, _fill_stroke, _qround
from .turtle import (
    _PI,
    _TWO_PI,
    BACKGROUND,
    CANVAS_PX,
    CENTRE,
    COMMAND_TIMEOUT_NS,
    PEN_COLOR,
    PEN_WIDTH,
    PIXELS_PER_METRE,
    UPDATE_DT,
    UPDATE_PERIOD_NS,
    WORLD_SIZE,
    Pose,
    RotationEvent,
    Segment,
    TurtleError,
    _check_rgb,
    _check_u8,
    _normalise,
    _Rotation,
    _Stroke,
    _Turtle,
    f32,
)

__all__ = [
    "BACKGROUND",
    "CANVAS_PX",
    "CENTRE",
    "COMMAND_TIMEOUT_NS",
    "PEN_COLOR",
    "PEN_WIDTH",
    "PIXELS_PER_METRE",
    "UPDATE_DT",
    "UPDATE_PERIOD_NS",
    "WORLD_SIZE",
    "Pose",
    "RotationEvent",
    "Segment",
    "TurtleError",
    "TurtleWorld",
    "f32",
]

_POSE32 = struct.Struct("<5f")

_WALL = "Oh no! I hit the wall! (Clamping from [x=%f, y=%f])"
_NAME_RE = re.compile(r"/?[A-Za-z_][A-Za-z0-9_]*(?:/[A-Za-z_][A-Za-z0-9_]*)*")


class TurtleWorld:
    """The state behind one turtlesim node: turtles, their pens and the path they drew.

    Deterministic and single-threaded: the same calls give the same poses and pixels.  Methods
    named after a turtlesim service behave as that service does; unknown turtles raise
    `TurtleError` (in turtlesim their per-turtle topics and services would not exist).
    """

    width: float = WORLD_SIZE
    height: float = WORLD_SIZE

    def __init__(
        self,
        background: tuple[int, int, int] = BACKGROUND,
        *,
        log: Callable[[str], object] | None = None,
        sensor_sees_background: bool = False,
    ) -> None:
        """`log` receives turtlesim's INFO lines (spawning, clearing, resetting); warnings come
        back from `update` and errors as `TurtleError`, so nothing is logged twice.

        `sensor_sees_background`: humble's path image is transparent white where nothing was
        drawn, so its colour sensor reads (255, 255, 255) there; set this to read the background
        colour instead (ROS 1 turtlesim painted the background into the path image)."""
        self._log = log
        self._sensor_sees_background = sensor_sees_background
        self._background = _check_rgb(background, "background")
        self._turtles: dict[str, _Turtle] = {}
        self._order: list[_Turtle] = []  # std::map order: sorted by name
        self._id_counter = 0
        self._strokes: list[_Stroke] = []
        self._raster = bytearray(_TRANSPARENT * (CANVAS_PX * CANVAS_PX))
        self._rastered = 0  # strokes already in the raster
        self._version = 0  # bumped by every change to the strokes
        self._updates = 0
        #: What the last `update` did to rotate_absolute goals, in turtle order.
        self.rotation_events: list[RotationEvent] = []
        self.spawn(CENTRE, CENTRE, 0.0)

    # --- parameters --------------------------------------------------------------------------

    @property
    def background(self) -> tuple[int, int, int]:
        return self._background

    def set_background(self, r: int, g: int, b: int) -> None:
        """The background_r/g/b parameters (integers 0..255, as their descriptors say).  Humble
        repaints with them at once; the trails stay."""
        self._background = _check_rgb((r, g, b), "background")

    # --- turtles -----------------------------------------------------------------------------

    def names(self) -> list[str]:
        """Live turtles, in turtlesim's update and paint order (sorted by name)."""
        return [t.name for t in self._order]

    def __contains__(self, name: object) -> bool:
        return name in self._turtles

    def spawn(self, x: float, y: float, theta: float, name: str = "") -> str:
        """The `spawn` service: returns the turtle's name.  An empty name takes `turtleN` with N
        one more than the last automatic number (skipping names in use); an existing name is
        refused with turtlesim's error text, and turtlesim's service then answers name ''."""
        if name:
            if name in self._turtles:
                raise TurtleError(f"A turtled named [{name}] already exists")
            if not _NAME_RE.fullmatch(name):
                raise TurtleError(f"Invalid turtle name [{name}]: its topics would not be valid ROS names")
            real = name
        else:
            while True:
                self._id_counter += 1
                real = f"turtle{self._id_counter}"
                if real not in self._turtles:
                    break
        x32, y32, a32 = f32(x), f32(y), f32(theta)
        # QPointF(x, height_in_meters_ - y): a float subtraction, then widened to double.
        turtle = _Turtle(real, x32, f32(f32(self.height) - y32), a32)
        self._turtles[real] = turtle
        self._order = sorted(self._turtles.values(), key=lambda t: t.name)
        self._info(f"Spawning turtle [{real}] at x=[{x32:f}], y=[{y32:f}], theta=[{a32:f}]")
        return real

    def kill(self, name: str) -> None:
        """The `kill` service.  Pending teleports die with the turtle; its trail stays."""
        if name not in self._turtles:
            raise TurtleError(f"Tried to kill turtle [{name}], which does not exist")
        del self._turtles[name]
        self._order = [t for t in self._order if t.name != name]

    def clear(self) -> None:
        """The `clear` service: wipes every trail (the background is painted from the current
        parameters whenever the picture is drawn)."""
        self._info("Clearing turtlesim.")
        self._wipe()

    def reset(self) -> None:
        """The `reset` service: kills every turtle, restarts automatic names at turtle1, spawns
        turtle1 at the centre and clears, in turtlesim's order."""
        self._info("Resetting turtlesim.")
        self._turtles.clear()
        self._order = []
        self._id_counter = 0
        self.spawn(CENTRE, CENTRE, 0.0)
        self._wipe()

    def set_pen(self, name: str, r: int, g: int, b: int, width: int, off: int | bool) -> None:
        """`<turtle>/set_pen`.  As turtlesim: `off` lifts the pen and keeps its old colour and
        width; otherwise a new pen (r, g, b) whose width is `width`, or 1 px when width is 0
        (a fresh QPen is 1 px wide)."""
        t = self._get(name)
        r, g, b = _check_rgb((r, g, b), "pen colour")
        width = _check_u8(width, "pen width")
        off = _check_u8(int(off), "off")
        t.pen_on = not off
        if off:
            return
        t.pen_rgba = bytes((r, g, b, 255))
        t.pen_width = width if width != 0 else 1
        t.last_stroke = -1

    def teleport_absolute(self, name: str, x: float, y: float, theta: float) -> None:
        """`<turtle>/teleport_absolute`: queued, applied at the start of the next update (then
        the move of that update follows).  y above the top wall is clamped silently; any other
        outside position is clamped by the update with the wall warning, as in turtlesim."""
        self._get(name).teleports.append((False, f32(x), f32(y), f32(theta)))

    def teleport_relative(self, name: str, linear: float, angular: float) -> None:
        """`<turtle>/teleport_relative`: queued like the absolute one; turns by `angular` first,
        then moves `linear` along the new heading."""
        self._get(name).teleports.append((True, f32(linear), 0.0, f32(angular)))

    def command(self, name: str, linear_x: float, linear_y: float, angular_z: float, now: int) -> float | None:
        """A Twist on `<turtle>/cmd_vel` received at run time `now` (ns).  linear.y moves
        sideways: humble's turtle is holonomic (the `holonomic` parameter came after humble).
        It aborts a rotate_absolute goal, as turtlesim's velocity callback does: the goal's
        delta so far is returned (the result of the aborted goal), None if there was none."""
        t = self._get(name)
        if not isinstance(now, int):
            raise TypeError(f"now is the run time in integer nanoseconds, not {now!r}")
        t.last_cmd = now
        t.lin_x = float(linear_x)
        t.lin_y = float(linear_y)
        t.ang = float(angular_z)
        return self._end_rotation(t)

    def rotate_absolute(self, name: str, theta: float) -> float | None:
        """Accept a rotate_absolute goal (heading `theta`, rounded to float32 as the goal holds
        it): from the next update the turtle turns toward it.  A goal still running is replaced
        (turtlesim aborts it): its delta is returned, None if there was none."""
        t = self._get(name)
        replaced = self._end_rotation(t)
        t.rotation = _Rotation(f32(theta), t.orient)
        return replaced

    def cancel_rotation(self, name: str) -> bool:
        """A cancel request for the turtle's goal: it ends (canceled, the turtle stopped) at the
        next update.  False if there is no goal."""
        t = self._get(name)
        if t.rotation is None:
            return False
        t.rotation.canceling = True
        return True

    def end_rotation(self, name: str) -> float | None:
        """End the turtle's rotate_absolute goal where it is (the turtle is killed or reset):
        its delta, None if there was none."""
        return self._end_rotation(self._get(name))

    def rotating(self, name: str) -> bool:
        """Whether the turtle has a rotate_absolute goal that has not ended."""
        return self._get(name).rotation is not None

    @staticmethod
    def _end_rotation(t: _Turtle) -> float | None:
        r = t.rotation
        t.rotation = None
        return None if r is None else r.delta

    # --- the 16 ms tick ----------------------------------------------------------------------

    def update(self, now: int, dt: float = UPDATE_DT, *, sense: bool = False) -> list[str]:
        """One tick of turtlesim's update timer at run time `now` (ns); returns the WARN lines it
        logs.  Per turtle, in name order: pending teleports; a command older than 1 s lapses;
        heading integrated and normalised to [-PI, PI) first, then the position moved along the
        NEW heading; clamped to the walls; a pen stroke from the old to the new position.

        `sense=True` samples each turtle's colour sensor the way turtlesim does, after the move
        and before its own new stroke is drawn; it rasterises, so ask only when someone listens."""
        if not isinstance(now, int):
            raise TypeError(f"now is the run time in integer nanoseconds, not {now!r}")
        warnings: list[str] = []
        strokes = self._strokes
        w = self.width
        h = self.height
        self._updates += 1
        self.rotation_events = []
        for t in self._order:
            if t.teleports:
                self._teleport(t)
            if t.rotation is not None:
                self._rotate(t, now)
            if now - t.last_cmd > COMMAND_TIMEOUT_NS:
                t.lin_x = t.lin_y = t.ang = 0.0
            ox = t.qx
            oy = t.qy
            lx = t.lin_x
            ly = t.lin_y
            o = t.orient + t.ang * dt
            o -= _TWO_PI * math.floor((o + _PI) / _TWO_PI)
            t.orient = o
            c = math.cos(o)
            s = math.sin(o)
            x = ox + (c * lx * dt - s * ly * dt)
            y = oy - (c * ly * dt + s * lx * dt)
            if x < 0 or x > w or y < 0 or y > h:
                warnings.append(_WALL % (x, y))
            # std::min(std::max(v, 0.0), w): NaN passes through, as in C++.
            if x < 0.0:
                x = 0.0
            if w < x:
                x = w
            if y < 0.0:
                y = 0.0
            if h < y:
                y = h
            t.qx = x
            t.qy = y
            if sense:
                if not (
                    x == t.sensed_x
                    and y == t.sensed_y
                    and t.sensed_version == self._version
                    and t.sensed_bg is self._background
                ):
                    t.sensed = self._pixel(x, y)
                    t.sensed_x = x
                    t.sensed_y = y
                    t.sensed_version = self._version
                    t.sensed_bg = self._background
                t.sensed_at = self._updates
            if (x != ox or y != oy) and t.pen_on:
                x0 = ox * PIXELS_PER_METRE
                y0 = oy * PIXELS_PER_METRE
                x1 = x * PIXELS_PER_METRE
                y1 = y * PIXELS_PER_METRE
                n = len(strokes)
                i = t.last_stroke
                if i == n - 1 and i >= self._rastered:
                    # Extend this turtle's previous stroke when the new one continues it straight.
                    p = strokes[i]
                    if p[2] == x0 and p[3] == y0:
                        ax = p[2] - p[0]
                        ay = p[3] - p[1]
                        bx = x1 - x0
                        by = y1 - y0
                        if ax * bx + ay * by > 0 and abs(ax * by - ay * bx) <= 1e-9 * (ax * ax + ay * ay):
                            strokes[i] = (p[0], p[1], x1, y1, p[4], p[5])
                            self._version += 1
                            continue
                strokes.append((x0, y0, x1, y1, t.pen_rgba, t.pen_width))
                t.last_stroke = n
                self._version += 1
        return warnings

    def _rotate(self, t: _Turtle, now: int) -> None:
        """turtlesim's rotate_absolute step, before the command timeout and the move: a cancel
        request ends the goal; else the delta and the remaining rotation are worked out (float
        casts where turtlesim casts), and the goal succeeds within 0.02 rad or the turtle turns
        at 1 rad/s toward it, the shorter way."""
        r = t.rotation
        assert r is not None
        events = self.rotation_events
        if r.canceling:
            events.append(RotationEvent(t.name, "canceled", f32(r.delta)))
            t.rotation = None
            t.lin_x = t.lin_y = t.ang = 0.0
            return
        theta = _normalise(r.theta)
        remaining = _normalise(theta - f32(t.orient))
        r.delta = f32(_normalise(f32(r.start - t.orient)))
        events.append(RotationEvent(t.name, "feedback", f32(remaining)))
        if abs(_normalise(f32(t.orient) - theta)) < 0.02:
            events.append(RotationEvent(t.name, "succeeded", r.delta))
            t.rotation = None
            t.lin_x = t.lin_y = t.ang = 0.0
        else:
            t.lin_x = t.lin_y = 0.0
            t.ang = -1.0 if remaining < 0.0 else 1.0
            t.last_cmd = now

    def _teleport(self, t: _Turtle) -> None:
        for relative, a, b, theta in t.teleports:
            ox, oy = t.qx, t.qy
            if relative:
                t.orient += theta
                t.qx += math.cos(t.orient) * a
                t.qy += -math.sin(t.orient) * a
            else:
                t.qx = a
                t.qy = max(0.0, self.height - b)
                t.orient = theta
            if t.pen_on:
                m = PIXELS_PER_METRE
                self._strokes.append((ox * m, oy * m, t.qx * m, t.qy * m, t.pen_rgba, t.pen_width))
                self._version += 1
            t.last_stroke = -1
        t.teleports.clear()

    # --- what the node publishes -------------------------------------------------------------

    def pose(self, name: str) -> Pose:
        """`<turtle>/pose` as turtlesim fills it: y flipped up, theta in [-PI, PI) after any
        update, linear_velocity = |(linear.x, linear.y)|, all rounded to float32."""
        t = self._turtles.get(name)
        if t is None:
            raise TurtleError(f"There is no turtle named [{name}]")
        lx = t.lin_x
        ly = t.lin_y
        values = (t.qx, self.height - t.qy, t.orient, math.sqrt(lx * lx + ly * ly), t.ang)
        try:
            return Pose._make(_POSE32.unpack(_POSE32.pack(*values)))
        except OverflowError:
            return Pose._make(map(f32, values))

    def color_under(self, name: str) -> tuple[int, int, int]:
        """`<turtle>/color_sensor`: the path image's pixel under the turtle's centre.  Right after
        an `update(..., sense=True)` this is the sample turtlesim would publish; otherwise it is
        read now from everything drawn so far."""
        t = self._get(name)
        if t.sensed_at == self._updates:
            return t.sensed
        return self._pixel(t.qx, t.qy)

    # --- drawing -----------------------------------------------------------------------------

    @property
    def segments(self) -> list[Segment]:
        """Every pen stroke since the last clear, in drawing order."""
        return [Segment(s[0], s[1], s[2], s[3], (s[4][0], s[4][1], s[4][2]), s[5]) for s in self._strokes]

    def turtle_pixels(self) -> list[tuple[str, float, float, float]]:
        """(name, x px, y px, theta) of each turtle in paint order: where turtlesim draws its
        image, centred on `pos_ * meter_` (y down)."""
        m = PIXELS_PER_METRE
        return [(t.name, t.qx * m, t.qy * m, t.orient) for t in self._order]

    @property
    def raster_version(self) -> int:
        """Changes whenever the path image may have changed (for viewers that cache it)."""
        return self._version

    def path_rgba(self) -> bytes:
        """The path image, 500 x 500 RGBA, row-major from the top-left corner; alpha 0 where
        nothing has been drawn.  Rasterises the strokes added since the last call."""
        self._flush()
        return bytes(self._raster)

    # --- internals ---------------------------------------------------------------------------

    def _get(self, name: str) -> _Turtle:
        t = self._turtles.get(name)
        if t is None:
            raise TurtleError(f"There is no turtle named [{name}]")
        return t

    def _info(self, text: str) -> None:
        if self._log is not None:
            self._log(text)

    def _wipe(self) -> None:
        self._strokes.clear()
        self._raster[:] = _TRANSPARENT * (CANVAS_PX * CANVAS_PX)
        self._rastered = 0
        self._version += 1
        for t in self._order:
            t.last_stroke = -1

    def _flush(self) -> None:
        strokes = self._strokes
        if self._rastered == len(strokes):
            return
        buf = self._raster
        fill = _c_fill_stroke
        for i in range(self._rastered, len(strokes)):
            s = strokes[i]
            if fill is None or not fill(buf, *s):
                _fill_stroke(buf, *s)
        self._rastered = len(strokes)

    def _pixel(self, qx: float, qy: float) -> tuple[int, int, int]:
        """`path_image.pixel((pos_ * meter_).toPoint())`: qRound of each coordinate."""
        fx = qx * PIXELS_PER_METRE
        fy = qy * PIXELS_PER_METRE
        if not (math.isfinite(fx) and math.isfinite(fy)):
            return (0, 0, 0)
        px = _qround(fx)
        py = _qround(fy)
        if not (0 <= px < CANVAS_PX and 0 <= py < CANVAS_PX):
            return (0, 0, 0)  # QImage::pixel outside the image
        self._flush()
        k = (py * CANVAS_PX + px) * 4
        raster = self._raster
        if raster[k + 3] == 0 and self._sensor_sees_background:
            return self._background
        return (raster[k], raster[k + 1], raster[k + 2])
