// rclcpp is up before the bot has run its own INITIAL
int argc = 0;
rclcpp::init(argc, nullptr);
suspend("ros2_blind_turtle_bot");
