msg.linear.x = 0.0
msg.angular.z = 1.5
cmd_vel.publish(msg)
