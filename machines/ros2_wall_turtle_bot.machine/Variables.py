node: ros.Node
publisher_: ros.Publisher
msg: Twist
client_: ros.Client
I_wait: ros.FutureReturnCode  # how the last request to the pose service ended
result: ros.Future  # the pending or answered request
position_x: float = 0.0
position_y: float = 0.0
