ros.init()
node = ros.Node("wall_follower")
cmd_vel = node.create_publisher(Twist, "/turtle1/cmd_vel", 10)
msg = Twist()
