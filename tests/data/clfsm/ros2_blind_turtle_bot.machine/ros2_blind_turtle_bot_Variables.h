//
// ros2_blind_turtle_bot_Variables.h
//
// Automatically created through MiCASE -- do not change manually!
//
std::shared_ptr<rclcpp::Node>	node;	///<
rclcpp::Publisher<geometry_msgs::msg::Twist>::SharedPtr	publisher_;	///<
geometry_msgs::msg::Twist	msg;	///<
