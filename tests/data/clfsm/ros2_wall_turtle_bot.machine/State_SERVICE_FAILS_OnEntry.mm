RCLCPP_ERROR(node->get_logger(), "/turtle_pose_service did not answer: is turtle_sensor_poster running?");
