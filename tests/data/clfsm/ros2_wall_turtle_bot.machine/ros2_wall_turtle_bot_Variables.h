//
// ros2_wall_turtle_bot_Variables.h
//
// Automatically created through MiCASE -- do not change manually!
//
std::shared_ptr<rclcpp::Node>	node;	///<
rclcpp::Publisher<geometry_msgs::msg::Twist>::SharedPtr	publisher_;	///<
geometry_msgs::msg::Twist	msg;	///<
rclcpp::Client<turtle_sensor_interface::srv::TurtlePosition>::SharedPtr	client_;	///<
rclcpp::FutureReturnCode	I_wait;	///<
rclcpp::Client<turtle_sensor_interface::srv::TurtlePosition>::SharedFuture	result;	///<
float	position_x;	///<
float	position_y;	///<
