msg.linear.x = 0.0
msg.angular.z = 0.0
cmd_vel.publish(msg)  # stop the turtle
