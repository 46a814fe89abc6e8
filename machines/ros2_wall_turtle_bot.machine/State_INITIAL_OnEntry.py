node_name = "ros2_wall_turtle_bot"
ros.init()
node = ros.Node(node_name)
publisher_ = node.create_publisher(Twist, "/turtle1/cmd_vel", 10)
client_ = node.create_client(TurtlePosition, "turtle_pose_service")
msg = Twist()
msg.linear.x = 0.0
msg.linear.y = 0.0
msg.angular.x = 0.0
msg.angular.y = 0.0
msg.angular.z = 0.0
