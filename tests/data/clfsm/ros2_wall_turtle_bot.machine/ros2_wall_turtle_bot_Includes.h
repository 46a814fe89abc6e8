#include "rclcpp/rclcpp.hpp"
#include "geometry_msgs/msg/twist.hpp"
#include "CLMacros.h"
#include "turtle_sensor_interface/srv/turtle_position.hpp"
