auto message = std_msgs::msg::String();
std::stringstream ss;
ss << "The count is " << count;
message.data = ss.str();
RCLCPP_INFO(node->get_logger(), "Publishing: '%s'", message.data.c_str());
publisher_->publish(message);
