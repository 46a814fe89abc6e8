msg.linear.x = 0.0;
msg.angular.z = 0.0;
publisher_->publish(msg);
auto request = std::make_shared<turtle_sensor_interface::srv::TurtlePosition::Request>();
result = client_->async_send_request(request);
I_wait = rclcpp::spin_until_future_complete(node, result) ;
