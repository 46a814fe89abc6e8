msg.linear.x = 0.0;
msg.angular.z = -2.0;
publisher_->publish(msg);
