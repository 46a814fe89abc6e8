ros.init()
node = ros.Node("turtle_rotator")
client = ros.ActionClient(node, RotateAbsolute, "/turtle1/rotate_absolute")
