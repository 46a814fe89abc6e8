"""The turtle simulator behind `llfsm run --node turtlesim`: ROS 2 turtlesim's world without a
bus (`world`), its pictures (`draw`) and an optional live window (`view`, needs pygame)."""

from llfsm.sim.world import CENTRE, WORLD_SIZE, Pose, Segment, TurtleError, TurtleWorld

__all__ = ["CENTRE", "WORLD_SIZE", "Pose", "Segment", "TurtleError", "TurtleWorld"]
