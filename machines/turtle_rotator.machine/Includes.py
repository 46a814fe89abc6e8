from llfsm import ros
from llfsm.msgs.action_msgs.msg import GoalStatus
from llfsm.msgs.turtlesim.action import RotateAbsolute
