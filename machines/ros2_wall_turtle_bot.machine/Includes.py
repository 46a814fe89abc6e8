from llfsm import ros
from llfsm.msgs.geometry_msgs.msg import Twist
from llfsm.msgs.turtle_sensor_interface.srv import TurtlePosition
