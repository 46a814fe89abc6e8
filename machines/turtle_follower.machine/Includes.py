import math

from llfsm import ros
from llfsm.msgs.geometry_msgs.msg import Twist
from llfsm.msgs.turtlesim.msg import Pose
from llfsm.msgs.turtlesim.srv import Spawn
