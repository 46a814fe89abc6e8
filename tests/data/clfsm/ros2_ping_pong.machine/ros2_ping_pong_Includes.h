#include "rclcpp/rclcpp.hpp"
#include "std_msgs/msg/string.hpp"
#include "CLMacros.h"
