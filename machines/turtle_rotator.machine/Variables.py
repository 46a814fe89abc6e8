node: ros.Node
client: ros.ActionClient  # of /turtle1/rotate_absolute, which turtlesim serves
headings: tuple = (1.5708, 3.1416, -1.5708, 0.0)  # radians: north, west, south, east
index: int = 0  # the heading being turned to
sent: ros.Future  # the goal's acceptance: a ClientGoalHandle once done
goal: ros.ClientGoalHandle = None  # the goal under way, if any
result: ros.Future  # the goal's result: .status and .result once done
