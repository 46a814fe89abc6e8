node: ros.Node
cmd_vel: ros.Publisher
msg: Twist
