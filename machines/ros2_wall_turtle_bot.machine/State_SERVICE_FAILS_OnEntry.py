node.get_logger().error(f"/turtle_pose_service did not answer ({I_wait}): is turtle_sensor_poster running?")
