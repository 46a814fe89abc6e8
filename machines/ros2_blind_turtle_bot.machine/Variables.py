publisher_: ros.Publisher
node: ros.Node
msg: Twist
