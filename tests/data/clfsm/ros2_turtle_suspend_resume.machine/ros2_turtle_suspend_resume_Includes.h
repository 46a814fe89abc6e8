#include "rclcpp/rclcpp.hpp"
#include "CLMacros.h"
