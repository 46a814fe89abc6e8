# clfsm: #include "rclcpp/rclcpp.hpp", "std_msgs/msg/string.hpp", "CLMacros.h" (the macros need no import)
from llfsm import ros
from llfsm.msgs.std_msgs.msg import String
