# The sensor may have changed since the ringlet that chose this state: never drive into a wall.
msg.linear.x = 0.0 if wall_close else 1.0
msg.angular.z = 0.0
cmd_vel.publish(msg)
