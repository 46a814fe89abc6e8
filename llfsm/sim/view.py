"""A live turtlesim window (`llfsm run --node turtlesim --view`), drawn with pygame.

pygame is an optional extra, so importing this module without it fails at once with the
command that installs it, rather than deep inside a run.  The run loop calls `Viewer.draw()` as
often as it likes; the window is repainted at most `fps` times per second of wall time, so a
fast simulated run is not slowed down by drawing.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from types import TracebackType

from llfsm.sim.draw import turtle_shapes
from llfsm.sim.world import CANVAS_PX, TurtleWorld

os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
try:
    import pygame
except ImportError as exc:  # pragma: no cover - exercised by a test that hides pygame
    raise ImportError("--view needs pygame: pip install 'llfsm[view]'") from exc

__all__ = ["Viewer"]


class Viewer:
    """One window showing a world: background, trails and turtles, like turtlesim's frame.

    Closing the window (or `close()`) ends the viewing only; the run goes on without it.
    """

    def __init__(
        self,
        world: TurtleWorld,
        *,
        title: str = "TurtleSim",
        fps: float = 30.0,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.world = world
        self._interval = 1.0 / fps if fps > 0 else 0.0
        self._clock = clock
        self._last = -float("inf")
        self._closed = False
        self._path: pygame.Surface | None = None
        self._path_version = -1
        self.frames = 0
        pygame.display.init()
        try:
            self._screen = pygame.display.set_mode((CANVAS_PX, CANVAS_PX))
            pygame.display.set_caption(title)
        except BaseException:
            pygame.display.quit()
            raise

    @property
    def closed(self) -> bool:
        return self._closed

    def draw(self, force: bool = False) -> bool:
        """Handle window events and repaint if a frame is due; False once the window is closed
        (by the user or by `close()`), so the caller can stop calling."""
        if self._closed:
            return False
        now = self._clock()
        if not force and now - self._last < self._interval:
            return True  # cheap when called every tick: events wait for the next frame
        self._last = now
        for event in pygame.event.get():
            if event.type == pygame.QUIT:
                self.close()
                return False
        self._paint()
        pygame.display.flip()
        self.frames += 1
        return True

    def _paint(self) -> None:
        world = self.world
        screen = self._screen
        screen.fill(world.background)
        if self._path is None or world.raster_version != self._path_version:
            self._path_version = world.raster_version
            self._path = pygame.image.frombytes(world.path_rgba(), (CANVAS_PX, CANVAS_PX), "RGBA")
        screen.blit(self._path, (0, 0))
        for name, x, y, theta in world.turtle_pixels():
            if not (x == x and y == y and theta == theta):  # NaN pose: nothing to draw
                continue
            for pts, fill, line in turtle_shapes(name, x, y, theta):
                pygame.draw.polygon(screen, fill, pts)
                if line is not None:
                    pygame.draw.aalines(screen, line, True, pts)

    def snapshot(self) -> pygame.Surface:
        """A copy of what the window shows (for tests and screenshots)."""
        return self._screen.copy()

    def close(self) -> None:
        """Close the window; safe to call twice."""
        if not self._closed:
            self._closed = True
            pygame.display.quit()

    def __enter__(self) -> Viewer:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()
