message = String()
message.data = f"The count is {count}"
node.get_logger().info(f"Publishing: '{message.data}'")
publisher_.publish(message)
