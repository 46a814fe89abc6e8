"""`--node teleop`: arrow keys from the terminal drive `/turtle1/cmd_vel`, as turtlesim's
turtle_teleop_key does (linear and angular scale 2.0; remap `teleop:turtle1/cmd_vel:=...` to
drive another turtle).  G, T, R, E, D, C, V and B send `/turtle1/rotate_absolute` goals to the
eight headings (0, 0.7854, ... radians, as turtle_teleop_key's keys do) and F cancels the last
goal.  `q` ends the run as Ctrl-C does, so machines still reach END.

Keys are read without blocking between rounds, one key per 100 ms of run time, from the
terminal (put in cbreak mode, restored at the end) or from a pipe (tests feed keys that way).
"""

from __future__ import annotations

import os
import select
import sys
from typing import IO, Any

from ..runtime.context import RunContext

NODE_NAME = "teleop_turtle"
TOPIC = "turtle1/cmd_vel"
SCALE_LINEAR = 2.0
SCALE_ANGULAR = 2.0
KEYS = {  # escape sequences of the arrow keys -> (linear, angular)
    "\x1b[A": (1.0, 0.0),
    "\x1b[B": (-1.0, 0.0),
    "\x1b[C": (0.0, -1.0),
    "\x1b[D": (0.0, 1.0),
}
#: turtle_teleop_key's keys for rotate_absolute goals: the heading each sends (float32 values).
HEADINGS = {
    "g": 0.0,
    "t": 0.7854,
    "r": 1.5708,
    "e": 2.3562,
    "d": 3.1416,
    "c": -2.3562,
    "v": -1.5708,
    "b": -0.7854,
}
CANCEL_KEY = "f"
ACTION = "turtle1/rotate_absolute"
BANNER = """Reading from keyboard
---------------------------
Use arrow keys to move the turtle.
Use G|B|V|C|D|E|R|T keys to rotate to absolute orientations. 'F' to cancel a rotation.
'Q' to quit.
"""


class Teleop:
    def __init__(self, ctx: RunContext, stream: IO[str] | None = None) -> None:
        # deferred: with the node (importing the node's module loads neither the bus nor its messages)
        from .. import ros
        from ..msgs.geometry_msgs.msg import Twist
        from ..msgs.turtlesim.action import RotateAbsolute

        self.ctx = ctx
        self.twist = Twist
        self.node = ros.Node(NODE_NAME)
        self.pub = self.node.create_publisher(Twist, TOPIC, 1)
        self.rotate = RotateAbsolute
        self.rotate_client = ros.ActionClient(self.node, RotateAbsolute, ACTION)
        #: The last goal the server accepted (turtle_teleop_key's goal_handle_): what F cancels.
        self.goal: Any = None
        self.stream = stream if stream is not None else sys.stdin
        self.pending = ""
        self.eof = False
        self._saved: Any = None
        try:
            self.fd: int | None = self.stream.fileno()
        except (OSError, ValueError, AttributeError):
            self.fd = None
        if self.fd is not None and os.isatty(self.fd):
            # deferred: optional (POSIX only), and only for a terminal
            import termios
            import tty

            self._saved = termios.tcgetattr(self.fd)
            tty.setcbreak(self.fd)
            ctx.at_end.append(self.restore)
        sys.stderr.write(BANNER)
        self.timer = self.node.create_timer(0.1, self.poll)

    def restore(self) -> None:
        if self._saved is not None and self.fd is not None:
            # deferred: optional (POSIX only), as in __init__
            import termios

            termios.tcsetattr(self.fd, termios.TCSADRAIN, self._saved)
            self._saved = None

    def _read_available(self) -> None:
        if self.eof or self.fd is None:
            return
        while select.select([self.fd], [], [], 0)[0]:
            data = os.read(self.fd, 64)
            if not data:
                self.eof = True
                return
            self.pending += data.decode("utf-8", "replace")

    def poll(self) -> None:
        self._read_available()
        if self.pending:
            for seq, (lin, ang) in KEYS.items():
                if self.pending.startswith(seq):
                    self.pending = self.pending[len(seq) :]
                    msg = self.twist()
                    msg.linear.x = SCALE_LINEAR * lin
                    msg.angular.z = SCALE_ANGULAR * ang
                    self.pub.publish(msg)
                    return  # one key per poll: movement follows the keys' rhythm
            key, self.pending = self.pending[0], self.pending[1:]
            heading = HEADINGS.get(key.lower())
            if heading is not None:
                self.send_goal(heading)
                return
            if key.lower() == CANCEL_KEY:
                self.cancel_goal()
                return
            if key in "qQ":
                arr = self.ctx.arrangement
                if arr is not None:
                    arr.interrupt(0)
                return
            if key == "\x1b" and len(self.pending) < 2:
                self.pending = key + self.pending  # an escape sequence still arriving
            return  # any other key is ignored, and takes its 100 ms as turtle_teleop_key's read does

    def send_goal(self, theta: float) -> None:
        """turtle_teleop_key's sendGoal: send and forget; the accepted goal is the one F cancels."""

        def answered(future: Any) -> None:
            self.goal = future.result()

        self.rotate_client.send_goal_async(self.rotate.Goal(theta=theta)).add_done_callback(answered)

    def cancel_goal(self) -> None:
        """turtle_teleop_key's cancelGoal: a cancel request for the last accepted goal, if any
        (one that has ended already is the server's to refuse)."""
        if self.goal is not None and self.goal.accepted:
            self.goal.cancel_goal_async()


def start(ctx: RunContext, options: object) -> Teleop:
    return Teleop(ctx)
