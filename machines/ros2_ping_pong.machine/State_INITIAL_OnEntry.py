# Set-up only: the C++ juggled argc/argv for rclcpp::init; ros.init() needs none of that.
node_name = "ros_ping_pong"
ros.init()
node = ros.Node(node_name)
publisher_ = node.create_publisher(String, "pingpong", 10)
count = 0
