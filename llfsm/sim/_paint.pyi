# What type checkers know of llfsm.sim._paint, turtlesim's stroke painter in C (_paint.c): an
# extension module carries no annotations.  setup.py builds it where a C compiler is; where it
# is not built, llfsm.sim.world paints with its own _fill_stroke.

def fill_stroke(buf: bytearray, x0: float, y0: float, x1: float, y1: float, rgba: bytes, width: int, /) -> bool:
    """Paint one stroke as llfsm.sim.world._fill_stroke does; False, having painted nothing,
    to leave it to that function."""
