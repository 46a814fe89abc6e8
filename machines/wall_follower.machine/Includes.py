from llfsm import ros
from llfsm.msgs.geometry_msgs.msg import Twist
