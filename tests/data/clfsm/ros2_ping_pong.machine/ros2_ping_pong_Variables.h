//
// ros2_ping_pong_Variables.h
//
// Automatically created through MiCASE -- do not change manually!
//
int	count;	///<
rclcpp::Publisher<std_msgs::msg::String>::SharedPtr	publisher_;	///<
std::shared_ptr<rclcpp::Node>	node;	///<
