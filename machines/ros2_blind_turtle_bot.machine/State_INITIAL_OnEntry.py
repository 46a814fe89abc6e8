node_name = "ros2_blind_turtle_bot"
ros.init()
node = ros.Node(node_name)
publisher_ = node.create_publisher(Twist, "/turtle1/cmd_vel", 10)
# The listing sets linear.x three times and angular.x three times: the intent is all six at 0.
msg = Twist()
msg.linear.x = 0.0
msg.linear.y = 0.0
msg.linear.z = 0.0
msg.angular.x = 0.0
msg.angular.y = 0.0
msg.angular.z = 0.0
publisher_.publish(msg)  # it already posts a message to halt the turtle
