msg.linear.x = 0.0
msg.angular.z = 0.0
publisher_.publish(msg)
request = TurtlePosition.Request()
result = client_.call_async(request)
I_wait = ros.spin_until_future_complete(node, result)
