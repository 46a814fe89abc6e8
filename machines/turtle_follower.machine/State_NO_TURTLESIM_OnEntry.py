node.get_logger().error(f"cannot spawn turtle2 ({spawn_code}): run with --node turtlesim")
